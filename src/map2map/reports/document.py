"""A report document: one self-contained HTML page and its Markdown twin.

A :class:`Report` holds plain-words warnings (shown in a box at the top) and ordered
:class:`Section` s, each a list of blocks: paragraphs, italic notes, key numbers, tables
and figures. :meth:`Report.write` writes

- ``PATH.html``: one file with no external resource (inline CSS, figures as
  ``data:image/png;base64``), that opens offline in any browser and prints cleanly to
  PDF (``@media print``: no figure, table or key-number block split across pages, no
  dark backgrounds). Each figure is ``<figure><img alt=...><figcaption>``. A small
  inline script checks every ``<img>`` on ``load`` (``complete && naturalWidth > 0``),
  sets ``document.body.dataset.figures`` to ``"ok/total"`` and shows a red
  "figure failed to load" note beside any broken one, so that a headless browser
  (``tests/browser.py``) or a person sees at once whether every figure arrived. The
  footer gives the date and the map2map version.
- ``PATH.md``: the same content for diffs (tables as GitHub tables, figures as PNG
  files in ``PATH_files/`` linked relatively). It carries no date: the same report
  gives the same Markdown byte for byte (figure PNGs are written without a timestamp).

Everything is written atomically: the figures' folder is written into a temporary
sibling renamed whole, then the two pages under temporary names renamed into place.

Examples
--------
>>> import tempfile, pathlib
>>> import numpy as np
>>> r = Report("Inspection of floor 2", "as-built SLAM map against the plan")
>>> r.warn("The alignment is ambiguous: check the overlay before trusting the numbers.")
>>> s = r.section("Key numbers")
>>> s.numbers({"mean error": "1.2 cm", "max error": "4.0 cm"})
>>> s.table(["wall", "deviation (cm)"], [["W1", 1.5], ["W2", 3]], caption="Walls")
>>> s.figure(np.zeros((20, 30), np.uint8), "An empty picture", alt="black")
>>> s.note("skipped: ../shared/data absent")
>>> html_path, md_path = r.write(pathlib.Path(tempfile.mkdtemp()) / "report")
>>> html_path.name, md_path.name
('report.html', 'report.md')
>>> 'data:image/png;base64,' in html_path.read_text()
True
>>> print(md_path.read_text().splitlines()[0])
# Inspection of floor 2
>>> sorted(p.name for p in (html_path.parent / "report_files").iterdir())
['figure-01.png']
"""

from __future__ import annotations

import base64
import datetime as _dt
import html
import io
import os
import re
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from .._version import __version__
from ..core._io import atomic_dir, atomic_paths

__all__ = ["Report", "Section"]

_PNG_SIGNATURE = b"\x89PNG\r\n\x1a\n"


def _png_bytes(fig: Any, dpi: int) -> bytes:
    """PNG bytes of a matplotlib Figure, PNG bytes or a uint8 array (grey, RGB or RGBA)."""
    if isinstance(fig, bytes | bytearray | memoryview):
        data = bytes(fig)
        if not data.startswith(_PNG_SIGNATURE):
            raise ValueError("figure bytes are not a PNG image (bad signature)")
        return data
    if isinstance(fig, np.ndarray):
        if fig.dtype != np.uint8:
            raise ValueError(f"figure array must be uint8 (grey or RGB), got {fig.dtype}")
        if fig.ndim == 3 and fig.shape[2] == 1:
            fig = fig[:, :, 0]
        if fig.ndim not in (2, 3) or (fig.ndim == 3 and fig.shape[2] not in (3, 4)):
            raise ValueError(f"figure array must be H x W or H x W x 3/4, got shape {fig.shape}")
        if fig.size == 0:
            raise ValueError("figure array is empty")
        import cv2

        img = (
            fig
            if fig.ndim == 2
            else cv2.cvtColor(fig, cv2.COLOR_RGB2BGR if fig.shape[2] == 3 else cv2.COLOR_RGBA2BGRA)
        )
        ok, buf = cv2.imencode(".png", np.ascontiguousarray(img))
        if not ok:  # pragma: no cover - cv2 encodes any uint8 array of these shapes
            raise ValueError("figure array could not be encoded as PNG")
        return buf.tobytes()
    if hasattr(fig, "savefig"):
        buf = io.BytesIO()
        # no "Software" key: the same figure gives the same bytes with any matplotlib build
        fig.savefig(buf, format="png", dpi=dpi, bbox_inches="tight", metadata={"Software": None})
        return buf.getvalue()
    raise TypeError(
        f"figure must be a matplotlib Figure, PNG bytes or a uint8 array, not {type(fig).__name__}"
    )


def _cell(value: Any) -> str:
    """Text of a table cell: strings as they are, numbers as Python writes them."""
    if value is None:
        return ""
    if isinstance(value, bool):
        return "yes" if value else "no"
    if isinstance(value, float | np.floating):
        return f"{float(value):g}"
    return str(value)


_NUMBER = re.compile(r"^[-+]?(\d+\.?\d*|\.\d+)([eE][-+]?\d+)?\s*%?$")


def _is_number(value: Any) -> bool:
    """A number, or a string the caller formatted from one ("12.50", "83%")."""
    if isinstance(value, str):
        return bool(_NUMBER.match(value.strip()))
    return isinstance(value, int | float | np.integer | np.floating) and not isinstance(value, bool)


def _md_escape(text: str) -> str:
    """A table cell or inline text safe in GitHub Markdown (pipes and newlines)."""
    return text.replace("\\", "\\\\").replace("|", "\\|").replace("\n", " ")


@dataclass
class _Figure:
    png: bytes
    caption: str
    alt: str


@dataclass
class Section:
    """One titled section of a :class:`Report`: its blocks in the order they were added.

    Made by :meth:`Report.section`; its ``anchor`` is the HTML id of its heading
    (unique in the report).

    Examples
    --------
    >>> s = Report("R").section("Walls & doors")
    >>> s.anchor
    'walls-doors'
    >>> s.text("Two walls.")
    >>> s.table(["id", "length (m)"], [[1, 2.5], [2, 3.0]])
    >>> len(s.blocks)
    2
    """

    title: str
    anchor: str
    dpi: int = 110
    blocks: list[tuple] = field(default_factory=list)

    def text(self, text: str) -> None:
        """Add a paragraph of plain text (HTML is escaped; a blank line starts a new paragraph).

        Parameters
        ----------
        text : str
            The paragraph.
        """
        for para in re.split(r"\n\s*\n", str(text).strip()):
            if para.strip():
                self.blocks.append(("text", " ".join(para.split())))

    def note(self, text: str) -> None:
        """Add a remark shown in italics (e.g. ``"skipped: ../shared/data absent"``).

        Parameters
        ----------
        text : str
            The remark.
        """
        self.blocks.append(("note", " ".join(str(text).split())))

    def numbers(self, items: dict[str, str]) -> None:
        """Add key figures shown big: ``{label: already formatted value}``.

        Parameters
        ----------
        items : dict of str to str
            Labels and their values, in display order (e.g. ``{"mean error": "1.2 cm"}``).
        """
        self.blocks.append(("numbers", [(str(k), str(v)) for k, v in items.items()]))

    def table(self, columns: list[str], rows: list[list], caption: str | None = None) -> None:
        """Add a table. Cells are formatted by the caller (str, int or float accepted).

        Parameters
        ----------
        columns : list of str
            Column headers.
        rows : list of list
            One list per row, as long as ``columns``; ``None`` shows as an empty cell,
            floats as ``format(x, "g")``. Columns of numbers only (numbers formatted as
            strings, e.g. ``"12.50"`` or ``"83%"``, and blanks ``""``, ``"-"`` included)
            are right-aligned.
        caption : str, optional
            Caption above the table.

        Raises
        ------
        ValueError
            A row's length differs from the number of columns.
        """
        cols = [str(c) for c in columns]
        for i, row in enumerate(rows):
            if len(row) != len(cols):
                raise ValueError(f"table row {i} has {len(row)} cells, expected {len(cols)}")
        def blank(v: Any) -> bool:
            return v is None or (isinstance(v, str) and v.strip() in {"", "-", "n/a"})

        numeric = [
            any(_is_number(r[j]) for r in rows)
            and all(_is_number(r[j]) or blank(r[j]) for r in rows)
            for j in range(len(cols))
        ]
        cells = [[_cell(v) for v in row] for row in rows]
        self.blocks.append(("table", cols, cells, caption, numeric))

    def figure(self, fig: Any, caption: str, alt: str | None = None) -> None:
        """Add a figure, rendered to PNG at once (the caller may close or reuse ``fig``).

        Parameters
        ----------
        fig : matplotlib.figure.Figure, bytes or numpy.ndarray
            A matplotlib figure (saved at the section's ``dpi``, tight bounding box),
            PNG bytes, or a ``uint8`` picture (H x W grey, H x W x 3 RGB, H x W x 4 RGBA).
        caption : str
            Caption under the figure.
        alt : str, optional
            Text for readers who cannot see the picture; the caption by default.

        Raises
        ------
        TypeError, ValueError
            ``fig`` is none of the accepted kinds, or bytes that are not a PNG.
        """
        png = _png_bytes(fig, self.dpi)
        self.blocks.append(("figure", _Figure(png, str(caption), str(alt or caption))))


_CSS = """
:root{--ink:#1b1b1b;--muted:#5a5a5a;--rule:#d0d0d0}
body{font-family:system-ui,-apple-system,"Segoe UI",Roboto,"DejaVu Sans",sans-serif;
color:var(--ink);background:#fff;max-width:64em;margin:0 auto;padding:1.2em 1.5em;line-height:1.45}
h1{margin-bottom:.1em}.subtitle{color:var(--muted);margin-top:0}
h2{border-bottom:1px solid var(--rule);padding-bottom:.15em;margin-top:1.6em}
nav ol{columns:2;margin:.3em 0 1em}
.warnings{border:2px solid #b8860b;background:#fff8e1;padding:.6em 1em;margin:1em 0;
border-radius:4px}
.warnings h2{border:none;margin:0 0 .3em;font-size:1.1em;color:#7a4f00}
.warnings li{margin:.2em 0}
.note{font-style:italic;color:var(--muted)}
.numbers{display:flex;flex-wrap:wrap;gap:.8em;margin:.8em 0}
.number{border:1px solid var(--rule);border-radius:4px;padding:.4em .9em;min-width:8em}
.number .value{font-size:1.8em;font-weight:600;display:block}
.number .label{color:var(--muted);font-size:.9em}
table{border-collapse:collapse;margin:.8em 0;font-size:.92em}
caption{text-align:left;font-weight:600;padding-bottom:.3em}
th,td{border:1px solid var(--rule);padding:.2em .6em;text-align:left}
th{background:#f3f3f3}td.num{text-align:right;font-variant-numeric:tabular-nums}
figure{margin:1em 0}figure img{max-width:100%;height:auto;border:1px solid var(--rule)}
figcaption{color:var(--muted);font-size:.92em;margin-top:.3em}
.broken{color:#c00;font-weight:600;border:1px solid #c00;padding:.2em .5em;display:inline-block}
footer{margin-top:2em;border-top:1px solid var(--rule);padding-top:.4em;color:var(--muted);
font-size:.85em}
@page{margin:15mm}
@media print{body{max-width:none;padding:0;font-size:10.5pt}nav{display:none}
figure,table,.numbers,.warnings,tr{break-inside:avoid;page-break-inside:avoid}
table.long{break-inside:auto;page-break-inside:auto}thead{display:table-header-group}
.number{min-width:6em;padding:.3em .6em}.number .value{font-size:1.5em}
h2{break-after:avoid;page-break-after:avoid}figure img{max-height:22cm}
*{-webkit-print-color-adjust:exact;print-color-adjust:exact}a{color:inherit}}
""".strip()

_SCRIPT = (
    "window.addEventListener('load',function(){var imgs=document.images,ok=0,i;"
    "for(i=0;i<imgs.length;i++){var im=imgs[i];"
    "if(im.complete&&im.naturalWidth>0){ok++;}else{var p=document.createElement('p');"
    "p.className='broken';p.textContent='figure failed to load';"
    "im.parentNode.insertBefore(p,im.nextSibling);}}"
    "document.body.dataset.figures=ok+'/'+imgs.length;});"
)


class Report:
    """A report: title, plain-words warnings on top, ordered sections.

    Parameters
    ----------
    title : str
        The report's title (``<h1>`` and ``<title>``).
    subtitle : str
        A line under the title (what was compared, with what).
    created : datetime.datetime, optional
        The date shown in the HTML footer (now, UTC, by default); the Markdown twin
        carries no date.
    dpi : int
        Resolution of matplotlib figures.

    Examples
    --------
    >>> r = Report("Demo", "one section")
    >>> r.section("Results").numbers({"pairs": "12"})
    >>> html_text = r.to_html()
    >>> "<h1>Demo</h1>" in html_text and 'id="results"' in html_text
    True
    >>> r.to_markdown()[0].splitlines()[:3]
    ['# Demo', '', 'one section']
    """

    def __init__(
        self,
        title: str,
        subtitle: str = "",
        *,
        created: _dt.datetime | None = None,
        dpi: int = 110,
    ) -> None:
        self.title = str(title)
        self.subtitle = str(subtitle)
        self.created = created
        self.dpi = int(dpi)
        self.warnings: list[str] = []
        self.sections: list[Section] = []

    def warn(self, text: str) -> None:
        """Add a plain-words warning, shown in a box at the top of the report.

        Parameters
        ----------
        text : str
            The warning (one or two sentences a reader can act on).
        """
        text = " ".join(str(text).split())
        if text and text not in self.warnings:
            self.warnings.append(text)

    def section(self, title: str) -> Section:
        """Start a new section (sections keep the order they were made in).

        Parameters
        ----------
        title : str
            Section heading; its HTML anchor is derived from it (made unique).

        Returns
        -------
        Section
            The section, to add blocks to.
        """
        base = re.sub(r"[^a-z0-9]+", "-", str(title).lower()).strip("-") or "section"
        taken = {s.anchor for s in self.sections}
        anchor, k = base, 2
        while anchor in taken:
            anchor, k = f"{base}-{k}", k + 1
        s = Section(str(title), anchor, dpi=self.dpi)
        self.sections.append(s)
        return s

    def figures(self) -> list[_Figure]:
        """Every figure of the report, in order (for counting and tests)."""
        return [b[1] for s in self.sections for b in s.blocks if b[0] == "figure"]

    # -- HTML -------------------------------------------------------------------------------

    def to_html(self) -> str:
        """The self-contained HTML page (figures embedded as base64 PNG).

        Returns
        -------
        str
            The page.
        """
        e = html.escape
        created = self.created or _dt.datetime.now(_dt.UTC)
        h = [
            "<!DOCTYPE html>",
            '<html lang="en"><head><meta charset="utf-8">',
            '<meta name="viewport" content="width=device-width, initial-scale=1">',
            f'<meta name="generator" content="map2map {e(__version__)}">',
            f"<title>{e(self.title)}</title>",
            f"<style>{_CSS}</style>",
            f"<script>{_SCRIPT}</script>",
            "</head><body>",
            f"<h1>{e(self.title)}</h1>",
        ]
        if self.subtitle:
            h.append(f'<p class="subtitle">{e(self.subtitle)}</p>')
        if self.warnings:
            h.append('<section class="warnings" id="warnings" role="alert">')
            word = "Warning" if len(self.warnings) == 1 else f"{len(self.warnings)} warnings"
            h.append(f"<h2>{word}: read before trusting the numbers</h2><ul>")
            h += [f"<li>{e(w)}</li>" for w in self.warnings]
            h.append("</ul></section>")
        if len(self.sections) > 1:
            h.append("<nav><ol>")
            h += [f'<li><a href="#{s.anchor}">{e(s.title)}</a></li>' for s in self.sections]
            h.append("</ol></nav>")
        for s in self.sections:
            h.append(f'<section id="{s.anchor}"><h2>{e(s.title)}</h2>')
            for block in s.blocks:
                h.append(self._html_block(block))
            h.append("</section>")
        h.append(
            f"<footer>Written {e(created.strftime('%Y-%m-%d %H:%M %Z').strip())} "
            f"by map2map {e(__version__)}.</footer>"
        )
        h.append("</body></html>")
        return "\n".join(h) + "\n"

    @staticmethod
    def _html_block(block: tuple) -> str:
        e = html.escape
        kind = block[0]
        if kind == "text":
            return f"<p>{e(block[1])}</p>"
        if kind == "note":
            return f'<p class="note"><em>{e(block[1])}</em></p>'
        if kind == "numbers":
            items = "".join(
                f'<div class="number"><span class="value">{e(v)}</span>'
                f'<span class="label">{e(k)}</span></div>'
                for k, v in block[1]
            )
            return f'<div class="numbers">{items}</div>'
        if kind == "table":
            _, cols, cells, caption, numeric = block
            # a table longer than a page breaks between rows (its header repeats)
            out = ['<table class="long">' if len(cells) > 25 else "<table>"]
            if caption:
                out.append(f"<caption>{e(caption)}</caption>")
            out.append("<thead><tr>" + "".join(f"<th>{e(c)}</th>" for c in cols) + "</tr></thead>")
            out.append("<tbody>")
            for row in cells:
                tds = "".join(
                    f'<td class="num">{e(v)}</td>' if numeric[j] else f"<td>{e(v)}</td>"
                    for j, v in enumerate(row)
                )
                out.append(f"<tr>{tds}</tr>")
            out.append("</tbody></table>")
            return "\n".join(out)
        if kind == "figure":
            f: _Figure = block[1]
            data = base64.b64encode(f.png).decode("ascii")
            return (
                f'<figure><img src="data:image/png;base64,{data}" alt="{e(f.alt, quote=True)}">'
                f"<figcaption>{e(f.caption)}</figcaption></figure>"
            )
        raise ValueError(f"unknown block {kind!r}")  # pragma: no cover

    # -- Markdown ---------------------------------------------------------------------------

    def to_markdown(self, files_dir: str = "report_files") -> tuple[str, list[tuple[str, bytes]]]:
        """The Markdown twin and its figures.

        Parameters
        ----------
        files_dir : str
            Folder name (relative to the Markdown file) the figures are linked from.

        Returns
        -------
        text : str
            The Markdown (no date: deterministic).
        figures : list of (str, bytes)
            File name in ``files_dir`` and PNG bytes of every figure, in order.
        """
        md = [f"# {self.title}", ""]
        if self.subtitle:
            md += [self.subtitle, ""]
        for w in self.warnings:
            md += [f"> **Warning:** {w}", ">"]
        if self.warnings:
            md[-1] = ""
        figures: list[tuple[str, bytes]] = []
        for s in self.sections:
            md += [f"## {s.title}", ""]
            for block in s.blocks:
                kind = block[0]
                if kind == "text":
                    md += [block[1], ""]
                elif kind == "note":
                    md += [f"*{block[1]}*", ""]
                elif kind == "numbers":
                    md += ["| key figure | value |", "|---|---:|"]
                    md += [f"| {_md_escape(k)} | **{_md_escape(v)}** |" for k, v in block[1]]
                    md.append("")
                elif kind == "table":
                    _, cols, cells, caption, numeric = block
                    if caption:
                        md += [f"**{_md_escape(caption)}**", ""]
                    md.append("| " + " | ".join(_md_escape(c) for c in cols) + " |")
                    md.append("|" + "|".join("---:" if n else "---" for n in numeric) + "|")
                    md += ["| " + " | ".join(_md_escape(v) for v in row) + " |" for row in cells]
                    md.append("")
                elif kind == "figure":
                    f: _Figure = block[1]
                    name = f"figure-{len(figures) + 1:02d}.png"
                    figures.append((name, f.png))
                    alt = f.alt.replace("[", "(").replace("]", ")")
                    md += [f"![{alt}]({files_dir}/{name})", "", f"*{f.caption}*", ""]
        md.append(f"<!-- map2map {__version__} -->")
        return "\n".join(md).rstrip() + "\n", figures

    # -- files ------------------------------------------------------------------------------

    def write(self, path: str | os.PathLike) -> tuple[Path, Path]:
        """Write ``PATH.html`` and its Markdown twin ``PATH.md`` (figures in ``PATH_files/``).

        A ``.html`` or ``.md`` suffix on ``path`` is dropped first. The figures' folder is
        replaced whole (written as a temporary sibling, then renamed); the two pages are
        written under temporary names and renamed together. Nothing half-written is left.

        Parameters
        ----------
        path : path-like
            The report's path, with or without ``.html``.

        Returns
        -------
        tuple of pathlib.Path
            The HTML and the Markdown file.

        Raises
        ------
        map2map.core.errors.InputError
            The folder cannot be written.
        """
        p = Path(path)
        if p.suffix.lower() in {".html", ".htm", ".md"}:
            p = p.with_suffix("")
        html_path, md_path = p.with_name(p.name + ".html"), p.with_name(p.name + ".md")
        files_name = p.name + "_files"
        text_md, figures = self.to_markdown(files_name)
        text_html = self.to_html()
        if figures:
            with atomic_dir(p.with_name(files_name)) as tmp:
                for name, png in figures:
                    (tmp / name).write_bytes(png)
        with atomic_paths(html_path, md_path) as (th, tm):
            th.write_text(text_html, encoding="utf-8")
            tm.write_text(text_md, encoding="utf-8")
        return html_path, md_path
