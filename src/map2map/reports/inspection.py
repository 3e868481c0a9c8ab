"""The as-built inspection report: a SLAM map of the building against its plan, wall by wall.

For a construction inspector (the appendix paper's purpose): the walls of the plan are
judged against the aligned SLAM map by :func:`map2map.evaluate.walls.inspect_walls` (pass,
uncertain, fail or not observed, each with its deviation and interval); this module
turns that into a page. :func:`inspection_report` builds the
:class:`~map2map.reports.document.Report` (warnings on top, key numbers, aligned overlay,
error heat map in cm, walls by status, the walls that deviate most, every segment) and
:func:`write_inspection` writes ``REPORT.html``, ``REPORT.md`` and ``REPORT.csv``.

Examples
--------
>>> from map2map.evaluate.pipeline import evaluate_maps
>>> from map2map.maps.floorplan import generate_floorplan
>>> plan = generate_floorplan(3, size=(10, 8))
>>> report = inspection_report(evaluate_maps(plan, plan, resolution=0.05), plan)
>>> report.title, len(report.sections) > 3
('As-built inspection', True)
"""

from __future__ import annotations

import math
import os
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from ..core.errors import InputError
from ..core.grid import OCCUPIED, UNKNOWN, OccupancyMap
from ..evaluate.walls import (
    STATUSES,
    WallInspection,
    check_tolerance,
    inspect_walls,
    write_segments_csv,
)
from .document import Report

__all__ = [
    "inspection_report",
    "InspectionFiles",
    "write_inspection",
    "write_run_inspections",
    "check_report_path",
]

STATUS_COLOURS = {"pass": "#1a9850", "uncertain": "#f39c12", "fail": "#d73027",
                  "not observed": "#8c8c8c"}


def _cm(v: float | None) -> str:
    return "n/a" if v is None or not math.isfinite(v) else f"{v:.1f} cm"


def _num(v: float, nd: int = 1) -> str:
    """A figure with ``nd`` decimals, ``-`` when not measured."""
    return f"{v:.{nd}f}" if math.isfinite(v) else "-"


def status_figure(plan: OccupancyMap, inspection: WallInspection):
    """The plan with its wall segments coloured by status (ids of failed walls written).

    Parameters
    ----------
    plan : OccupancyMap
        The plan.
    inspection : WallInspection
        Its segments.

    Returns
    -------
    matplotlib.figure.Figure
        The figure (the caller closes it).
    """
    from matplotlib.lines import Line2D

    from ..core.viz import add_scale_bar, new_figure

    known = plan.data != UNKNOWN
    rows = np.flatnonzero(known.any(1))
    cols = np.flatnonzero(known.any(0))
    if rows.size:
        r0, r1 = max(0, rows[0] - 10), min(plan.height, rows[-1] + 11)
        c0, c1 = max(0, cols[0] - 10), min(plan.width, cols[-1] + 11)
    else:
        r0, r1, c0, c1 = 0, plan.height, 0, plan.width
    view = plan.data[r0:r1, c0:c1]
    bg = np.ones((*view.shape, 3))
    bg[view == UNKNOWN] = 0.93
    bg[view == OCCUPIED] = 0.75
    fig, ax = new_figure(OccupancyMap(view.copy(), plan.resolution), panel_inches=7.0)
    ax.imshow(bg, interpolation="antialiased", extent=(c0, c1, r1, r0))
    style = {"pass": ("-", 2.2), "uncertain": ("-", 2.6), "fail": ("-", 3.4),
             "not observed": ((0, (2, 1.5)), 1.6)}
    for s in inspection.segments:
        ls, lw = style[s.status]
        xy = s.polyline_px()
        ax.plot(xy[:, 0], xy[:, 1], color=STATUS_COLOURS[s.status], ls=ls, lw=lw,
                solid_capstyle="butt")  # fmt: skip
    for s in inspection.segments:  # every failed wall, numbered
        if s.status == "fail":
            xy = s.polyline_px(2)
            mid = xy[1] if len(xy) == 3 else xy.mean(axis=0)
            ax.annotate(
                str(s.id), (float(mid[0]), float(mid[1])), fontsize=8, ha="center",
                va="center", color="white", fontweight="bold",
                bbox={"boxstyle": "round,pad=0.15", "fc": STATUS_COLOURS["fail"], "lw": 0},
            )  # fmt: skip
    counts = inspection.counts
    handles = [
        Line2D([], [], color=STATUS_COLOURS[k], ls=style[k][0], lw=style[k][1],
               label=f"{k} ({counts[k]})")  # fmt: skip
        for k in STATUSES
    ]
    ax.legend(handles=handles, loc="upper right", fontsize=8, framealpha=0.9)
    ax.set_xlim(c0, c1)
    ax.set_ylim(r1, r0)
    ax.set_xlabel("plan x (px)")
    ax.set_ylabel("plan y (px)")
    ax.set_title(
        f"Plan wall segments against a tolerance of {inspection.tolerance_m * 100:g} cm "
        "(failed walls numbered)",
        fontsize=10,
    )
    if plan.scale_known:
        add_scale_bar(ax, plan.resolution, c1 - c0)
    return fig


def _png_of(draw, *args, **kwargs) -> bytes:
    """PNG bytes of one of the figure functions that write to a path."""
    import tempfile

    with tempfile.TemporaryDirectory(prefix="map2map-report-") as d:
        path = Path(d) / "figure.png"
        draw(*args, path, **kwargs)
        return path.read_bytes()


def inspection_report(
    evaluation,
    plan: OccupancyMap,
    *,
    tolerance: float = 0.05,
    inspection: WallInspection | None = None,
    warnings: list[str] | None = None,
    overlay_png: bytes | None = None,
    error_map_png: bytes | None = None,
    csv_name: str | None = None,
    max_table_rows: int = 300,
) -> Report:
    """The as-built inspection report of an evaluation (see the module docstring).

    Parameters
    ----------
    evaluation : map2map.evaluate.pipeline.Evaluation
        The SLAM map evaluated against ``plan``.
    plan : OccupancyMap
        The plan (its resolution gives centimetres, its origin plan metres).
    tolerance : float
        Largest acceptable deviation of a wall, metres.
    inspection : WallInspection, optional
        The wall segments, when already computed with :func:`inspect_walls`.
    warnings : list of str, optional
        Warnings of the alignment and evaluation (``EvaluateRun.warnings``; the
        evaluation's own by default), printed at the top with the wall verdicts' own.
    overlay_png, error_map_png : bytes, optional
        The figures ``map2map evaluate`` already wrote (drawn again when absent).
    csv_name : str, optional
        Name of the CSV beside the report, mentioned in the text.
    max_table_rows : int
        Rows of the table of every segment (the CSV has them all).

    Returns
    -------
    Report
        Ready to :meth:`~map2map.reports.document.Report.write`.
    """
    import matplotlib.pyplot as plt

    from ..evaluate.figures import error_map_figure, overlay_figure

    insp = inspection or inspect_walls(evaluation, plan, tolerance=tolerance)
    rep = evaluation.report
    chain = evaluation.chosen
    e = rep["errors"][chain]
    res = float(plan.resolution)
    src, tgt = rep.get("source") or "SLAM map", rep.get("target") or "plan"
    r = Report("As-built inspection", f"{src} (as built) against {tgt} (as planned)")
    doubts = list(rep["warnings"] if warnings is None else warnings)
    if doubts:
        r.warn(
            "The alignment of the SLAM map to the plan is doubtful (the points below): every "
            "error and wall verdict in this report depends on it. Check the aligned overlay "
            "before acting on any of them."
        )
    for w in doubts:
        r.warn(f"Alignment: {w}")
    for w in insp.warnings:
        r.warn(w)
    notes = rep.get("notes", [])
    counts = insp.counts

    def cm(key: str) -> float:
        v = e.get(f"{key}_px")
        return float(v) * res * 100.0 if v is not None else math.nan

    s = r.section("Summary")
    s.numbers(
        {
            "mean wall error": _cm(cm("mean")),
            "p95 wall error": _cm(cm("p95")),
            "max wall error": _cm(cm("max")),
            "walls pass": str(counts["pass"]),
            "walls uncertain": str(counts["uncertain"]),
            "walls fail": str(counts["fail"]),
            "walls not observed": str(counts["not observed"]),
        }
    )
    n_arcs = sum(w.shape == "arc" for w in insp.segments)
    cut = (f"{len(insp.segments)} straight wall segments were" if not n_arcs else
           f"{len(insp.segments)} wall segments ({n_arcs} of them arcs along curved walls, "
           "their error measured to the curved face) were")
    s.text(
        f"{cut} cut from the plan and judged "
        f"against a tolerance of {insp.tolerance_m * 100:g} cm. A segment's deviation is "
        "the 95th percentile of the local errors of the as-built wall evidence matched to "
        "it, given with its uncertainty: one standard error either side of that "
        "percentile, from the ranks of the wall's own points, widened by half a plan pixel "
        f"({50 * res:g} cm; a whole pixel along a curve or a wall off the pixel grid's "
        "axes, a staircase in both maps) where neither map can place a wall face. A "
        "segment passes "
        "when the whole interval is within the tolerance, fails when the whole interval "
        "is beyond it, and is uncertain when the tolerance falls inside it (the map cannot "
        "tell: check on site, or measure with a finer map); it is not observed when the "
        f"SLAM map saw too little of it (fewer than {insp.min_points} wall points or under "
        f"{insp.min_coverage:.0%} of its length): a wall not observed is never counted as "
        "passed."
    )
    s.text(
        f"Errors are those of the {chain} chain ({rep['chosen_reason']}; appendix paper, "
        f"Fig. 1), over the {e['points']} SLAM wall points matched to a plan wall; "
        f"{e['unmatched_points']} points ({100 * e['unmatched_share']:.1f} %) match no "
        "plan wall (clutter, furniture or structure not in the plan, or walls built more "
        f"than 0.3 m off) and {e['corner_points_excluded']} corner points are left out. "
        f"Plan resolution {res * 100:g} cm per pixel."
    )
    n_own = sum(w.shape == "arc" or w.oblique for w in insp.segments)
    if n_own:
        s.note(
            f"Walls curved or more than 10 degrees off the plan's axes: {n_own}. The "
            "metric's plan surfaces run along the axes, so the points on them count as "
            "corners in the figures above; the tables below judge those walls on their "
            "own faces."
        )
    for n in notes:  # facts that limit what the figures describe, not doubts
        s.note(f"Note: {n}.")
    if csv_name:
        s.note(f"Every segment, one row each, is in {csv_name} beside this report.")

    s = r.section("Aligned overlay")
    if overlay_png is None:
        overlay_png = _png_of(
            overlay_figure, plan, evaluation.warped[chain],
            title=f"SLAM map aligned to the plan ({chain} chain)",
        )  # fmt: skip
    s.figure(
        overlay_png,
        "The as-built SLAM map aligned to the plan: plan walls in blue, SLAM walls in "
        "orange, black where they agree.",
        alt="overlay of the aligned SLAM map on the plan",
    )

    s = r.section("Local error heat map")
    if error_map_png is None:
        ch = evaluation.errors[chain]
        error_map_png = _png_of(
            error_map_figure, plan, ch.X_rigid, ch.distances, resolution=res,
            excluded=ch.corner, unmatched=ch.unmatched,
            title=f"Local error, {chain} chain (Algorithm 1)",
        )  # fmt: skip
    s.figure(
        error_map_png,
        "Local error of every SLAM wall point in centimetres (colour bar): its distance "
        "across the plan wall it matches. Magenta crosses match no plan wall; grey dots "
        "are corners, left out.",
        alt="heat map of the local wall error in centimetres",
    )

    s = r.section("Walls by status")
    fig = status_figure(plan, insp)
    s.figure(
        fig,
        "Plan wall segments: green pass, orange uncertain, red fail (every failed wall "
        "numbered with its id), grey dashed not observed.",
        alt="plan with wall segments coloured by pass, uncertain, fail, not observed",
    )
    plt.close(fig)
    total = max(1, len(insp.segments))
    length = {k: sum(w.length_m for w in insp.segments if w.status == k) for k in STATUSES}
    s.table(
        ["status", "segments", "share", "length (m)"],
        [[k, counts[k], f"{counts[k] / total:.0%}", _num(length[k], 2)] for k in STATUSES],
        caption="Segments per status",
    )

    s = r.section("Walls that deviate most")
    worst = insp.worst(10)
    if worst:
        s.table(
            ["id", "centre x (m)", "centre y (m)", "length (m)", "deviation (cm)",
             "interval (cm)", "mean (cm)", "max (cm)", "offset (cm)", "status"],  # fmt: skip
            [
                [w.id, _num(w.centre_m[0], 2), _num(w.centre_m[1], 2), _num(w.length_m, 2),
                 _num(w.deviation_cm), f"{_num(w.deviation_lo_cm)}-{_num(w.deviation_hi_cm)}",
                 _num(w.mean_cm), _num(w.max_cm), _num(w.offset_cm), w.status]  # fmt: skip
                for w in worst
            ],
            caption=f"The {len(worst)} observed wall segments with the largest deviation",
        )
        s.note(
            "Location in plan metres (the plan's ROS frame). Offset: the median "
            "displacement of the built wall across the planned one, + toward +y for an "
            "east-west wall, toward +x for a north-south wall"
            + (", + away from an arc's centre." if n_arcs else ".")
        )
    else:
        s.note("No wall segment was observed: nothing to rank.")

    s = r.section("Every wall segment")
    rows = [
        [w.id, _num(w.x0_m, 3), _num(w.y0_m, 3), _num(w.x1_m, 3), _num(w.y1_m, 3),
         _num(w.length_m, 2), w.status, _num(w.deviation_cm), w.points,
         f"{w.coverage:.0%}", _shape_note(w)]  # fmt: skip
        for w in insp.segments
    ]
    s.table(
        ["id", "x0 (m)", "y0 (m)", "x1 (m)", "y1 (m)", "length (m)", "status",
         "deviation (cm)", "points", "seen", "note"],  # fmt: skip
        rows[:max_table_rows],
    )
    if len(rows) > max_table_rows:
        s.note(f"{len(rows) - max_table_rows} more segments in the CSV.")
    return r


def _shape_note(w) -> str:
    """A segment's note, an arc's centre and radius first."""
    if w.arc_m is None:
        return w.note
    cx, cy, r = w.arc_m
    arc = f"arc: centre ({cx:.2f}, {cy:.2f}) m, radius {r:.2f} m"
    return f"{arc}; {w.note}" if w.note else arc


def _report_paths(path: str | os.PathLike) -> tuple[Path, Path]:
    p = Path(path)
    if p.suffix.lower() in {".html", ".htm", ".md"}:
        p = p.with_suffix("")
    return p.with_name(p.name + ".html"), p.with_name(p.name + ".csv")


def check_report_path(path: str | os.PathLike, name: str = "report") -> Path:
    """Check, before any work, that a report can be written at ``path`` (nothing created).

    Parameters
    ----------
    path : path-like
        ``REPORT.html`` (or ``REPORT``); ``.md`` and ``.csv`` go beside it.
    name : str
        The option named in the error.

    Returns
    -------
    pathlib.Path
        The HTML path.

    Examples
    --------
    >>> import tempfile, pathlib
    >>> check_report_path(pathlib.Path(tempfile.mkdtemp()) / "new" / "insp.html").name
    'insp.html'
    """
    html_path, _ = _report_paths(path)
    suffix = Path(path).suffix.lower()
    if suffix not in {"", ".html", ".htm"}:
        raise InputError(name, f"{path}: the report is an HTML file (.html), not {suffix}")
    if html_path.is_dir():
        raise InputError(name, f"{html_path} is a folder")
    anc = html_path.parent.resolve()
    while not anc.exists():
        anc = anc.parent
    if not anc.is_dir() or not os.access(anc, os.W_OK | os.X_OK):
        raise InputError(name, f"{path}: {anc} is not a writable folder")
    try:  # os.access says yes to root everywhere: try it (the probe is removed at once)
        import tempfile

        with tempfile.TemporaryFile(dir=anc):
            pass
    except OSError as exc:
        raise InputError(name, f"{path}: cannot write in {anc} ({exc.strerror})") from None
    return html_path


@dataclass
class InspectionFiles:
    """What :func:`write_inspection` wrote, and the wall verdicts behind it."""

    html: Path
    md: Path
    csv: Path
    inspection: WallInspection

    def summary(self) -> str:
        """``"12 pass, 4 uncertain, 2 fail, 3 not observed at 5 cm"``."""
        c = self.inspection.counts
        return (
            f"{c['pass']} pass, {c['uncertain']} uncertain, {c['fail']} fail, "
            f"{c['not observed']} not observed "
            f"at {self.inspection.tolerance_m * 100:g} cm"
        )


def write_inspection(
    evaluation,
    plan: OccupancyMap,
    path: str | os.PathLike,
    *,
    tolerance: float = 0.05,
    warnings: list[str] | None = None,
    overlay_png: bytes | None = None,
    error_map_png: bytes | None = None,
) -> InspectionFiles:
    """Write ``PATH.html``, ``PATH.md`` (+ ``PATH_files/``) and ``PATH.csv`` of an evaluation.

    Parameters
    ----------
    evaluation : map2map.evaluate.pipeline.Evaluation
        The SLAM map evaluated against ``plan``.
    plan : OccupancyMap
        The plan.
    path : path-like
        The report (``inspection.html``).
    tolerance : float
        Largest acceptable deviation of a wall, metres.
    warnings : list of str, optional
        Warnings of the alignment and evaluation (the evaluation's own by default).
    overlay_png, error_map_png : bytes, optional
        Figures already drawn by ``map2map evaluate``.

    Returns
    -------
    InspectionFiles
        The three paths and the wall verdicts.
    """
    html_path, csv_path = _report_paths(path)
    insp = inspect_walls(evaluation, plan, tolerance=tolerance)
    report = inspection_report(
        evaluation, plan, tolerance=tolerance, inspection=insp, warnings=warnings,
        overlay_png=overlay_png, error_map_png=error_map_png, csv_name=csv_path.name,
    )  # fmt: skip
    try:
        write_segments_csv(insp, csv_path)
        h, m = report.write(html_path)
    except OSError as exc:
        raise InputError(html_path, f"cannot write the report ({exc.strerror})") from None
    return InspectionFiles(h, m, csv_path, insp)


def write_run_inspections(
    run, path: str | os.PathLike, *, tolerance: float = 0.05
) -> list[InspectionFiles]:
    """The inspection report of every pair of a ``map2map evaluate`` run.

    One pair: ``PATH.html``, ``PATH.md`` and ``PATH.csv``, the run's warnings on top and
    the figures it wrote embedded. A pairs file: one report per pair,
    ``PATH_<pair>.html`` (and ``.md``, ``.csv``) with that pair's warnings.

    Parameters
    ----------
    run : map2map.jobs.evaluate.EvaluateRun
        What :func:`map2map.jobs.evaluate.evaluate` returned (errors in metres).
    path : path-like
        The report (``inspection.html``).
    tolerance : float
        Largest acceptable deviation of a wall, metres.

    Returns
    -------
    list of InspectionFiles
        Per pair, the paths written and the wall verdicts.

    Raises
    ------
    InputError
        A bad tolerance, or a run without what a report needs.
    """
    tol = check_tolerance(tolerance)
    if len(run.plans) != len(run.evaluations) or not run.evaluations:
        raise InputError("report", "the evaluation run carries no plan to report against")
    html_path, _ = _report_paths(path)
    stem = html_path.with_suffix("")

    def png(key: str) -> bytes | None:
        p = run.written.get(key)
        return Path(p).read_bytes() if p is not None and Path(p).is_file() else None

    if not run.rows:
        ev, plan = run.evaluations[0], run.plans[0]
        return [
            write_inspection(
                ev, plan, html_path, tolerance=tol, warnings=run.warnings,
                overlay_png=png("overlay"), error_map_png=png("error_map"),
            )  # fmt: skip
        ]
    out = []
    for row, ev, plan in zip(run.rows, run.evaluations, run.plans, strict=True):
        name = row["pair"]
        out.append(
            write_inspection(
                ev, plan, stem.with_name(f"{stem.name}_{name}.html"), tolerance=tol,
                overlay_png=png(f"{name}/overlay"), error_map_png=png(f"{name}/error_map"),
            )  # fmt: skip
        )
    return out
