"""The runner of ``map2map reproduce``: every section, one report, one results.json.

Each section runs in turn (one progress line per section on stderr); a section that
raises :class:`~._base.Skipped` says "skipped: why" and counts as done, one that raises
anything else shows the error in plain words in its own section and a warning at the
top of the report, and the run goes on. The report is written at the end, atomically:
``OUT/report.html`` (self-contained), ``OUT/report.md`` + ``OUT/report_files/`` and
``OUT/results.json`` (every measured number, finite or null).
"""

from __future__ import annotations

import datetime as _dt
import json
import os
import platform
import shlex
import shutil
import sys
import tempfile
import time
import traceback
from dataclasses import dataclass, field
from importlib import import_module
from pathlib import Path
from typing import Any

from ...core._io import atomic_path
from ...core.errors import InputError
from ..document import Report
from ._base import Context, Output, Skipped, _finite

#: Section keys in report order, and their modules (one module per section).
SECTIONS: dict[str, str] = {
    "parametric_time": "parametric_time",
    "fig515": "fig515",
    "table2": "table2",
    "halmstad": "halmstad",
    "table53": "table53",
    "fig514": "fig514",
    "dataset": "dataset",
}

#: Exit status of ``map2map reproduce`` when the report was written but a section failed.
EXIT_SECTION_FAILED = 1


@dataclass
class SectionRecord:
    """How one section went: ``status`` is ``ok``, ``skipped`` or ``failed``."""

    key: str
    title: str
    status: str
    wall_s: float
    message: str = ""
    results: dict[str, Any] = field(default_factory=dict)


@dataclass
class ReproduceSummary:
    """What :func:`reproduce` wrote and how each section went."""

    out: Path
    html: Path
    markdown: Path
    results_json: Path
    sections: list[SectionRecord]
    wall_s: float
    report: Report

    @property
    def failed(self) -> list[str]:
        """Keys of the sections that failed."""
        return [s.key for s in self.sections if s.status == "failed"]

    @property
    def exit_code(self) -> int:
        """0 when no section failed, :data:`EXIT_SECTION_FAILED` otherwise."""
        return EXIT_SECTION_FAILED if self.failed else 0

    def lines(self) -> list[str]:
        """What the CLI prints at the end."""
        out = [f"{s.key:<16} {s.status:<8} {s.wall_s:7.1f} s  {s.message}".rstrip()
               for s in self.sections]  # fmt: skip
        out.append(f"total {self.wall_s:.1f} s; wrote {self.html}, {self.markdown}, "
                   f"{self.results_json}")  # fmt: skip
        return out


def default_data() -> Path | None:
    """``$MAP2MAP_SHARED_DATA`` or ``../shared/data`` beside the working folder, if present."""
    env = os.environ.get("MAP2MAP_SHARED_DATA")
    for cand in ([Path(env)] if env else []) + [Path.cwd().parent / "shared" / "data"]:
        if cand.is_dir():
            return cand
    return None


def _versions() -> dict[str, str]:
    from ..._version import __version__

    out = {"map2map": __version__, "python": platform.python_version()}
    for mod in ("numpy", "scipy", "numba", "cv2", "matplotlib", "sklearn", "torch"):
        m = sys.modules.get(mod)
        if m is None:
            continue
        out[mod] = getattr(m, "__version__", "?")
    return out


def _plain(exc: BaseException) -> str:
    msg = str(exc).strip() or type(exc).__name__
    return f"{type(exc).__name__}: {msg}" if not isinstance(exc, InputError) else msg


def reproduce(
    out: str | os.PathLike,
    quick: bool = False,
    sections: list[str] | None = None,
    seed: int = 0,
    *,
    data: str | os.PathLike | None = None,
    tiny: bool = False,
    progress: bool = True,
    command: str | None = None,
) -> ReproduceSummary:
    """Re-run the thesis's and the appendix paper's results and write the report.

    Parameters
    ----------
    out : path-like
        Report folder (created; files in it are replaced): ``report.html``,
        ``report.md``, ``report_files/``, ``results.json``.
    quick : bool
        Reduced sizes (under 5 minutes on 2 cores).
    sections : list of str, optional
        Keys of :data:`SECTIONS` to run (default all), in report order.
    seed : int
        Seed of every generated plan, trajectory and noise.
    data : path-like, optional
        The real data folder (default :func:`default_data`); sections that need it are
        skipped without it.
    tiny : bool
        Test-only: even smaller than ``quick`` (the structure, not the numbers).
    progress : bool
        One line per section on stderr.
    command : str, optional
        The command line shown in the footer (default ``sys.argv``).

    Returns
    -------
    ReproduceSummary

    Raises
    ------
    InputError
        An unknown section key, an unwritable output folder, a ``data`` folder that
        does not exist.

    Examples
    --------
    >>> import tempfile, pathlib
    >>> s = reproduce(pathlib.Path(tempfile.mkdtemp()) / "r", sections=["fig515"],
    ...               tiny=True, progress=False)
    >>> [(r.key, r.status) for r in s.sections], s.exit_code
    ([('fig515', 'ok')], 0)
    """
    keys = list(SECTIONS) if not sections else list(sections)
    bad = [k for k in keys if k not in SECTIONS]
    if bad:
        raise InputError("only", f"unknown section {', '.join(bad)}; "
                         f"known: {', '.join(SECTIONS)}")  # fmt: skip
    keys = [k for k in SECTIONS if k in keys]
    if data is not None and not Path(data).is_dir():
        raise InputError(data, "the real data folder (`data`) does not exist")
    out = Path(out)
    try:
        out.mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        raise InputError(out, f"cannot create the report folder ({exc.strerror})") from None
    if not os.access(out, os.W_OK):
        raise InputError(out, "the report folder is not writable")
    data_dir = Path(data) if data is not None else default_data()
    mode = "tiny (test)" if tiny else ("quick" if quick else "full")
    report = Report("map2map reproduce: the thesis and its appendix paper, re-run",
                    f"{mode} run, seed {seed}: every quantitative result of the thesis "
                    "(Map to Map, 2022) and its appendix paper (Automated Robotic Assessment "
                    "of 2D As-built Floor Plans) beside ours")  # fmt: skip
    summary_sec = report.section("Summary: thesis vs map2map")
    records: list[SectionRecord] = []
    outputs: list[Output] = []
    t_all = time.perf_counter()
    with tempfile.TemporaryDirectory(prefix="map2map-reproduce-") as tmp:
        for i, key in enumerate(keys, 1):
            mod = import_module(f".{SECTIONS[key]}", __package__)
            title = mod.TITLE
            o = Output(key, report.section(title))
            work = Path(tmp) / key
            work.mkdir()
            ctx = Context(quick=quick, seed=seed, work=work, data=data_dir, tiny=tiny)
            if progress:
                print(f"[{i}/{len(keys)}] {title} ...", file=sys.stderr, flush=True)
            t0 = time.perf_counter()
            status, message = "ok", ""
            try:
                mod.run(ctx, o)
            except Skipped as exc:
                status, message = "skipped", str(exc)
                o.note(f"skipped: {exc}")
            except (KeyboardInterrupt, SystemExit):
                raise
            except BaseException as exc:  # a failed section must not kill the report
                status, message = "failed", _plain(exc)
                o.text(f"This section failed: {message}")
                o.note("The traceback is in results.json (sections.{key}.traceback).".replace(
                    "{key}", key))  # fmt: skip
                report.warn(f"Section '{title}' failed: {message}")
                o.results["traceback"] = traceback.format_exc(limit=8)
            wall = time.perf_counter() - t0
            for w in o.warnings:
                report.warn(f"{title}: {w}")
            o.note(f"section wall time {wall:.1f} s")
            records.append(SectionRecord(key, title, status, wall, message, o.results))
            outputs.append(o)
            if progress:
                print(f"[{i}/{len(keys)}] {status} in {wall:.1f} s"
                      + (f": {message}" if message else ""), file=sys.stderr, flush=True)
            shutil.rmtree(work, ignore_errors=True)
    wall_all = time.perf_counter() - t_all
    _summary(summary_sec, outputs, records, wall_all, mode)
    _footer(report, records, wall_all, command, mode)
    html, md = report.write(out / "report")
    results = {
        "mode": mode,
        "seed": seed,
        "command": command or shlex.join(sys.argv),
        "wall_s": wall_all,
        "cpu_count": os.cpu_count(),
        "created_utc": _dt.datetime.now(_dt.UTC).isoformat(timespec="seconds"),
        "versions": _versions(),
        "sections": {r.key: {"title": r.title, "status": r.status, "wall_s": r.wall_s,
                             "message": r.message, "results": r.results} for r in records},
    }  # fmt: skip
    rj = out / "results.json"
    with atomic_path(rj) as tmp_path:
        Path(tmp_path).write_text(json.dumps(_finite(results), indent=1, allow_nan=False))
    return ReproduceSummary(out, html, md, rj, records, wall_all, report)


def _summary(sec, outputs, records, wall_all, mode) -> None:
    rows = [[o.section.title.split(":")[0], *c] for o in outputs for c in o.comparisons]
    sec.text(f"Every section below re-runs one table or figure with this project's code. "
             f"This {mode} run took {wall_all:.0f} s; sections: "
             + ", ".join(f"{r.key} {r.status}" for r in records) + ".")  # fmt: skip
    if rows:
        sec.table(["result", "quantity", "thesis / paper", "map2map", "difference"], rows,
                  caption="Each difference in one sentence; details in the sections")
    else:
        sec.note("no section produced a comparison")


def _footer(report, records, wall_all, command, mode) -> None:
    sec = report.section("About this run")
    sec.numbers({
        "command": command or shlex.join(sys.argv),
        "mode": mode,
        "wall time": f"{wall_all:.1f} s",
        "machine": f"{platform.machine()}, {os.cpu_count()} CPUs, {platform.system()}",
        "versions": ", ".join(f"{k} {v}" for k, v in _versions().items()),
    })  # fmt: skip
    sec.table(["section", "status", "wall s", "message"],
              [[r.key, r.status, f"{r.wall_s:.1f}", r.message] for r in records],
              caption="Wall time per section (a loaded machine runs slower)")
