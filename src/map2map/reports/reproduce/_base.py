"""What every section of ``map2map reproduce`` gets and gives: a context and an output.

A section is a function ``run(ctx, out)``: :class:`Context` says how big to run (quick or
full, the seed, a scratch folder, where the real data is), :class:`Output` wraps the
report's :class:`~map2map.reports.document.Section` and also records every number the
section measured (for ``results.json``) and every thesis-vs-ours comparison (for the
summary table at the top of the report).

Examples
--------
>>> from map2map.reports.document import Report
>>> out = Output("demo", Report("r").section("Demo"))
>>> out.result("pairs_per_hour", 123.4)
>>> out.compare("pairs per hour", "86", "123", "faster")
>>> out.results, len(out.comparisons)
({'pairs_per_hour': 123.4}, 1)
"""

from __future__ import annotations

import io
import math
import os
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from ..document import Section

THESIS = "thesis"
APPENDIX = "appendix paper"


class Skipped(Exception):
    """Raised by a section that cannot run here (no data, no ``learn`` extra): not a failure."""


@dataclass
class Context:
    """How a section runs.

    ``quick`` selects the reduced sizes; ``tiny`` (tests only) shrinks them further;
    ``work`` is a scratch folder removed after the run; ``data`` the real data folder
    (``../shared/data``) or None.
    """

    quick: bool
    seed: int
    work: Path
    data: Path | None = None
    tiny: bool = False

    def size(self, full, quick, tiny=None):
        """The full, quick or tiny value of a size."""
        if self.tiny and tiny is not None:
            return tiny
        return quick if (self.quick or self.tiny) else full


def _finite(value: Any) -> Any:
    """``value`` with every float made finite-or-None (JSON has no NaN)."""
    if isinstance(value, dict):
        return {str(k): _finite(v) for k, v in value.items()}
    if isinstance(value, list | tuple):
        return [_finite(v) for v in value]
    if isinstance(value, np.generic):
        value = value.item()
    if isinstance(value, float) and not math.isfinite(value):
        return None
    return value


@dataclass
class Output:
    """A section of the report plus the numbers and comparisons it produced."""

    key: str
    section: Section
    results: dict[str, Any] = field(default_factory=dict)
    comparisons: list[tuple[str, str, str, str]] = field(default_factory=list)
    warnings: list[str] = field(default_factory=list)

    # -- the document API, passed through --------------------------------------------------
    def text(self, text: str) -> None:
        self.section.text(text)

    def note(self, text: str) -> None:
        self.section.note(text)

    def numbers(self, items: dict[str, str]) -> None:
        self.section.numbers(items)

    def table(self, columns, rows, caption=None) -> None:
        self.section.table(columns, rows, caption=caption)

    def figure(self, fig, caption: str, alt: str | None = None) -> None:
        self.section.figure(fig, caption, alt=alt)

    def figure_file(self, path: str | os.PathLike, caption: str, alt: str | None = None) -> None:
        """A PNG written by a library figure function, embedded."""
        self.section.figure(Path(path).read_bytes(), caption, alt=alt)

    # -- what the runner collects ----------------------------------------------------------
    def result(self, key: str, value: Any) -> None:
        """Record a measured number (or a small dict/list of them) for ``results.json``.

        A non-finite float is recorded as ``null`` and noted as a warning of the section
        (a number the run could not measure must not look measured).
        """
        clean = _finite(value)
        if clean != _finite_marker(value):
            self.warnings.append(f"{key}: some values could not be measured (recorded as null)")
        self.results[key] = clean

    def compare(self, quantity: str, thesis: str, ours: str, difference: str) -> None:
        """One thesis-vs-ours row: shown in the section and in the report's summary."""
        self.comparisons.append((quantity, thesis, ours, difference))

    def comparison_table(self, caption: str | None = None) -> None:
        """The section's comparison rows as a table (call after the last compare)."""
        if self.comparisons:
            self.section.table(["quantity", "thesis / paper", "map2map", "difference"],
                               [list(r) for r in self.comparisons], caption=caption)  # fmt: skip


def _finite_marker(value: Any) -> Any:
    """``value`` converted like :func:`_finite` but keeping non-finite floats (to compare)."""
    if isinstance(value, dict):
        return {str(k): _finite_marker(v) for k, v in value.items()}
    if isinstance(value, list | tuple):
        return [_finite_marker(v) for v in value]
    if isinstance(value, np.generic):
        return value.item()
    return value


def png_of(fig) -> bytes:
    """PNG bytes of a matplotlib figure (closed afterwards)."""
    import matplotlib.pyplot as plt

    buf = io.BytesIO()
    fig.savefig(buf, format="png", dpi=100, metadata={"Software": None})
    plt.close(fig)
    return buf.getvalue()


def show_overlay(ax, plan: np.ndarray, other: np.ndarray, title: str, fontsize: int = 8) -> None:
    """Draw plan walls black and ``other``'s walls red on white into ``ax``, no ticks."""
    from map2map.core.grid import OCCUPIED

    rgb = np.full((*plan.shape, 3), 255, np.uint8)
    rgb[plan == OCCUPIED] = (0, 0, 0)
    rgb[other == OCCUPIED] = (220, 30, 30)
    ax.imshow(rgb, interpolation="nearest")
    ax.set_title(title, fontsize=fontsize)
    ax.set_xticks([])
    ax.set_yticks([])


def fmt(v: float, digits: int = 2) -> str:
    """A number for a table (``-`` when not finite)."""
    if v is None or not np.isfinite(v):
        return "-"
    return f"{v:.{digits}f}"
