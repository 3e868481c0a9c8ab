"""The walls of a plan judged against an as-built SLAM map: pass, uncertain, fail, not observed.

For a construction inspector (the appendix paper's purpose): the as-built SLAM map is
aligned to the as-planned drawing and the local error of every SLAM wall point is
measured (appendix paper, Fig. 1 and Algorithm 1; :func:`map2map.evaluate.pipeline.
evaluate_maps`). This module turns that evaluation into walls:

1. **Wall segments of the plan.** The plan's walls are cut into straight segments
   (:func:`map2map.maps.segments.straight_segments`: centre lines, axis snapping,
   merged collinear pieces; door openings of ``min_gap_m`` 0.4 m or more stay gaps;
   wall stubs shorter than that, beside a door or at a T, are cut at half that scale, so
   they are judged too), and a curved wall (an apse, a rotunda, a curved facade) is one
   arc (:func:`map2map.maps.curves.circle_arcs`), not the short chords a line detector
   cuts it into.
   Endpoints are given in plan metres (the map's ROS frame,
   :meth:`~map2map.core.grid.OccupancyMap.pixel_to_world`).
2. **As-built evidence of each segment.** Every SLAM wall point counted in the wall
   statistics (matched to a plan wall, not a corner: :data:`map2map.evaluate.metric.
   EXCLUDED_RULE`) has a correspondence ``X_corr`` on a plan wall surface (Algorithm 1,
   lines 1-13) and a local error ``|X_rigid - X_corr|`` (point to plane). It is given
   to the plan segment nearest its correspondence, within half the plan's wall
   thickness plus 1.5 px. Along an arc, or a straight wall more than 10 degrees off the
   plan's axes, the metric's axis-wise surfaces make a staircase (every point there is
   a "corner" to it), so such a wall takes the matched points whose optimised position
   lies that close to its centre line, within its extent, and their local error is
   measured to its own face (point to curve, point to line).
3. **Deviation of a segment.** ``p95`` of its points' local errors decides: 95 % of
   the wall's observed evidence lies within it. The maximum would let a single stray
   lidar return fail a wall; the mean would let a wall built right over most of its
   length but off by a hand's width over its last metre pass. ``mean``, ``max`` and the
   signed ``offset`` (the median displacement across the wall, + toward +y for an
   east-west wall and toward +x for a north-south one, + away from an arc's centre:
   where it was built) are given beside it. **Its uncertainty**
   (:func:`deviation_interval`): the distribution-free interval of the p95, one standard
   error either side, from the ranks of the wall's own points (the spread of its
   evidence: few or scattered points give a wide one), widened on both sides by half a
   plan pixel (the plan and the SLAM map each place a wall face only on their pixel grid).
4. **Status.** ``pass`` when the whole interval is within the tolerance, ``fail`` when
   the whole interval is beyond it, ``uncertain`` when the tolerance lies inside it (the
   map cannot tell: check on site or use a finer map), and ``not observed`` when the SLAM
   map holds too little evidence of the wall:
   fewer than ``min_points`` points, or less than ``min_coverage`` of its length
   (2-px bins) seen. A wall not observed is *never* counted as passed. When SLAM wall
   points that match no plan wall (more than 0.3 m from any, see the metric) lie
   within ``nearby_m`` of an unobserved segment, its note says so: the wall may have
   been built more than 0.3 m off, or clutter stands in front of it.

:func:`inspect_walls` computes the segments and their verdicts, :func:`write_segments_csv`
writes one row per segment (opens in a spreadsheet); :mod:`map2map.reports.inspection`
turns them into the inspection report.

Examples
--------
>>> import numpy as np
>>> from map2map.core.grid import OccupancyMap
>>> from map2map.evaluate.pipeline import evaluate_maps
>>> from map2map.maps.synthetic import draw_walls, office_walls
>>> plan = OccupancyMap(draw_walls((240, 300), office_walls(300, 240)), 0.05)
>>> built = draw_walls((240, 300), office_walls(300, 240, partition_shift=(2.0, 0.0)))
>>> ev = evaluate_maps(OccupancyMap(built, 0.05), plan, resolution=0.05)
>>> walls = inspect_walls(ev, plan, tolerance=0.05)
>>> walls.counts["fail"] >= 1, walls.counts["pass"] > walls.counts["fail"]
(True, True)
>>> worst = walls.worst(1)[0]                  # a partition built 10 cm off
>>> worst.status, round(worst.deviation_cm)    # the alignment absorbs about 1 cm
('fail', 9)
"""

from __future__ import annotations

import csv
import math
import os
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from ..core._io import atomic_path
from ..core.errors import InputError
from ..core.geometry import point_segment_distances
from ..core.grid import OCCUPIED, OccupancyMap
from ..maps.curves import circle_arcs
from ..maps.segments import merge_slanted, straight_segments
from ..maps.solids import solid_cores

__all__ = ["STATUSES", "CSV_COLUMNS", "WallSegment", "WallInspection", "check_tolerance",
           "inspect_walls", "deviation_interval", "write_segments_csv"]


#: The statuses of a wall segment, in the order they are counted.
STATUSES = ("pass", "uncertain", "fail", "not observed")


CSV_COLUMNS = [
    "id",
    "x0_m",
    "y0_m",
    "x1_m",
    "y1_m",
    "length_m",
    "status",
    "deviation_cm",
    "deviation_lo_cm",
    "deviation_hi_cm",
    "mean_cm",
    "max_cm",
    "offset_cm",
    "points",
    "coverage",
    "unmatched_nearby",
    "note",
    "shape",
    "centre_x_m",
    "centre_y_m",
    "radius_m",
]


@dataclass
class WallSegment:
    """One straight wall segment of the plan and its as-built evidence.

    ``x0_m .. y1_m`` are the endpoints in plan metres (ROS frame), ``px`` the same in
    plan pixels (x = column, y = row, continuous: a pixel's centre is at +0.5).
    ``deviation_cm`` (p95 of the local errors of its points) and its interval
    ``deviation_lo_cm .. deviation_hi_cm`` (:func:`deviation_interval`) decide the status;
    ``mean_cm``, ``max_cm`` and ``offset_cm`` (signed, median across the wall) are
    given beside it; all four are NaN for a wall not observed. ``coverage`` is the
    share of its length seen, ``points`` the SLAM wall points matched to it,
    ``unmatched_nearby`` SLAM points that match no plan wall within ``nearby_m``.

    A curved wall is an arc (``shape`` ``"arc"``): ``x0_m .. y1_m`` are its ends,
    ``length_m`` its length along the curve, ``arc_m`` its centre line's centre and
    radius (metres) and ``arc_px`` its circle in plan pixels (``xc, yc, r, a0, span``,
    radians in the image frame, as :func:`map2map.maps.curves.circle_arcs` gives it).
    """

    id: int
    x0_m: float
    y0_m: float
    x1_m: float
    y1_m: float
    length_m: float
    status: str
    deviation_cm: float
    deviation_lo_cm: float
    deviation_hi_cm: float
    mean_cm: float
    max_cm: float
    offset_cm: float
    points: int
    coverage: float
    unmatched_nearby: int
    note: str
    px: np.ndarray = field(repr=False)
    arc_m: tuple[float, float, float] | None = None
    arc_px: tuple[float, float, float, float, float] | None = field(default=None, repr=False)
    mid_m: tuple[float, float] | None = None
    #: a straight wall more than 10 degrees off the plan's axes, judged by geometry
    oblique: bool = False

    @property
    def shape(self) -> str:
        """``"line"`` or ``"arc"``."""
        return "line" if self.arc_px is None else "arc"

    @property
    def centre_m(self) -> tuple[float, float]:
        """The segment's midpoint in plan metres (an arc's: halfway along it)."""
        if self.mid_m is not None:
            return self.mid_m
        return (0.5 * (self.x0_m + self.x1_m), 0.5 * (self.y0_m + self.y1_m))

    def polyline_px(self, n: int = 48) -> np.ndarray:
        """(K, 2) points along the wall in plan pixels (a line's two ends; an arc's
        ``n`` + 1 points)."""
        if self.arc_px is None:
            return np.asarray(self.px, float).reshape(2, 2)
        xc, yc, r, a0, span = self.arc_px
        a = a0 + np.linspace(0.0, span, n + 1)
        return np.stack([xc + r * np.cos(a), yc + r * np.sin(a)], 1)

    def row(self) -> dict[str, Any]:
        """The CSV row: metres to 3 decimals, centimetres to 2, NaN as an empty cell."""

        def f(v: float, nd: int) -> str:
            return "" if not math.isfinite(v) else f"{v:.{nd}f}"

        return {
            "id": self.id,
            "x0_m": f(self.x0_m, 3),
            "y0_m": f(self.y0_m, 3),
            "x1_m": f(self.x1_m, 3),
            "y1_m": f(self.y1_m, 3),
            "length_m": f(self.length_m, 3),
            "status": self.status,
            "deviation_cm": f(self.deviation_cm, 2),
            "deviation_lo_cm": f(self.deviation_lo_cm, 2),
            "deviation_hi_cm": f(self.deviation_hi_cm, 2),
            "mean_cm": f(self.mean_cm, 2),
            "max_cm": f(self.max_cm, 2),
            "offset_cm": f(self.offset_cm, 2),
            "points": self.points,
            "coverage": f(self.coverage, 2),
            "unmatched_nearby": self.unmatched_nearby,
            "note": self.note,
            "shape": self.shape,
            "centre_x_m": "" if self.arc_m is None else f(self.arc_m[0], 3),
            "centre_y_m": "" if self.arc_m is None else f(self.arc_m[1], 3),
            "radius_m": "" if self.arc_m is None else f(self.arc_m[2], 3),
        }


@dataclass
class WallInspection:
    """Every wall segment of a plan with its status, and how they were judged."""

    segments: list[WallSegment]
    tolerance_m: float
    resolution: float
    min_points: int
    min_coverage: float
    warnings: list[str] = field(default_factory=list)

    @property
    def counts(self) -> dict[str, int]:
        """Segments per status (every status present, zero included)."""
        out = dict.fromkeys(STATUSES, 0)
        for s in self.segments:
            out[s.status] += 1
        return out

    def worst(self, n: int = 10) -> list[WallSegment]:
        """The ``n`` observed segments that deviate most (largest deviation first)."""
        seen = [s for s in self.segments if s.status != "not observed"]
        return sorted(seen, key=lambda s: (-s.deviation_cm, s.id))[:n]


def check_tolerance(tolerance: float, name: str = "tolerance") -> float:
    """A tolerance in metres: finite, > 0 and under 10 m; :class:`InputError` otherwise.

    Examples
    --------
    >>> check_tolerance(0.05)
    0.05
    >>> check_tolerance(-1)
    Traceback (most recent call last):
    ...
    map2map.core.errors.InputError: tolerance: must be a length in metres > 0 and < 10, got -1
    """
    try:
        t = float(tolerance)
    except (TypeError, ValueError):
        raise InputError(name, f"must be a number of metres, got {tolerance!r}") from None
    if not (math.isfinite(t) and 0.0 < t < 10.0):
        raise InputError(name, f"must be a length in metres > 0 and < 10, got {tolerance!r}")
    return t


def _cut_walls(plan: OccupancyMap) -> np.ndarray:
    """The plan's wall pixels its walls are cut from: solid regions by a rim along
    their faces (:func:`~map2map.maps.solids.solid_cores`)."""
    walls = plan.data == OCCUPIED
    return walls & ~solid_cores(walls, float(plan.resolution))


def _plan_segments(plan: OccupancyMap, min_gap_m: float, min_length_m: float,
                   walls: np.ndarray | None = None) -> np.ndarray:
    """Straight segments (K, 4) of the plan's walls in continuous pixels (centre +0.5);
    solid regions by their faces (:func:`~map2map.maps.solids.solid_cores`: a line
    detector cuts a block along its medial axis, where no laser ever looked; ``walls``:
    :func:`_cut_walls`'s, when already made)."""
    walls = _cut_walls(plan) if walls is None else walls
    if not walls.any():
        return np.zeros((0, 4))
    cell = max(2.0, min_gap_m / plan.resolution)
    min_len = max(2.0, min_length_m / plan.resolution)
    segs = _long_enough(straight_segments(walls, cell) + 0.5, min_len)
    # wall stubs (beside a door, at a T) are shorter than a cell: at the door's scale their
    # free end snaps onto the wall they stand on and they vanish. Cut again at half the
    # scale and keep the pieces no segment already covers, so every stub is judged.
    fine = _long_enough(straight_segments(walls, max(2.0, cell / 2)) + 0.5, min_len)
    if len(fine) and len(segs):
        mid = 0.5 * (fine[:, :2] + fine[:, 2:])
        _, dist, _ = _to_segments(mid, segs)
        fine = fine[dist > 2.0]
    segs = np.concatenate([segs, fine]) if len(fine) else segs
    # a wall off the grid's axes (a wing at 30 or 45 degrees) is a staircase the line
    # detector cuts into overlapping pieces: one segment per wall line
    segs = _long_enough(merge_slanted(segs, 1.5, cell), min_len)
    # a stable, readable order: top to bottom, then left to right (ids follow it)
    key = np.round(np.minimum(segs[:, 1], segs[:, 3])) * 1e6 + np.minimum(segs[:, 0], segs[:, 2])
    return segs[np.argsort(key, kind="stable")]


def _long_enough(segs: np.ndarray, min_len: float) -> np.ndarray:
    length = np.hypot(segs[:, 2] - segs[:, 0], segs[:, 3] - segs[:, 1])
    return segs[length >= min_len]


def _to_segments(
    points: np.ndarray, segs: np.ndarray, chunk: int = 4096
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Nearest segment of every point, its distance and position along it (pixels)."""
    n = len(points)
    best = np.full(n, -1, np.int64)
    dist = np.full(n, np.inf)
    along = np.zeros(n)
    if n == 0 or len(segs) == 0:
        return best, dist, along
    d = segs[:, 2:] - segs[:, :2]
    ll = np.maximum((d**2).sum(1), 1e-12)
    for i in range(0, n, chunk):
        r, t = point_segment_distances(points[i : i + chunk], segs)
        k = np.argmin(r, axis=1)
        rows = np.arange(len(k))
        best[i : i + chunk] = k
        dist[i : i + chunk] = r[rows, k]
        along[i : i + chunk] = t[rows, k] * np.sqrt(ll[k])
    return best, dist, along


def inspect_walls(
    evaluation,
    plan: OccupancyMap,
    *,
    tolerance: float = 0.05,
    min_points: int = 5,
    min_coverage: float = 0.3,
    min_gap_m: float = 0.4,
    min_length_m: float = 0.2,
    nearby_m: float = 0.6,
) -> WallInspection:
    """Wall segments of ``plan`` with their deviation and pass / fail / not observed status.

    Parameters
    ----------
    evaluation : map2map.evaluate.pipeline.Evaluation
        The evaluation of the SLAM map against ``plan`` (its chosen chain is used).
    plan : OccupancyMap
        The plan it was evaluated against (its resolution and origin give metres).
    tolerance : float
        Largest acceptable deviation, metres.
    min_points : int
        Fewest matched SLAM wall points for a segment to count as observed.
    min_coverage : float
        Smallest share of a segment's length (2-px bins) with evidence to count as observed.
    min_gap_m : float
        Wall openings (doors) at least this wide split segments; shorter gaps are bridged.
    min_length_m : float
        Shorter segments (furniture corners, wall stubs) are left out.
    nearby_m : float
        Radius around an unobserved segment in which unmatched SLAM points are counted.

    Returns
    -------
    WallInspection
        The segments (ids from top to bottom, left to right), counts, warnings.

    Raises
    ------
    InputError
        A bad tolerance.
    """
    tol = check_tolerance(tolerance)
    res = float(plan.resolution)
    ch = evaluation.errors[evaluation.chosen]
    walls = _cut_walls(plan)
    segs = _plan_segments(plan, min_gap_m, min_length_m, walls)
    arcs, drop = circle_arcs(walls, res, segs)
    segs = segs[~drop]
    fields_ = evaluation.registration.fields
    thick = float(fields_.wall_thickness)
    half = 0.5 * thick + 1.5
    unm = np.zeros(len(ch.distances), bool) if ch.unmatched is None else ch.unmatched
    # the metric's plan surfaces are axis-wise (at the plan's angle): along an arc or an
    # oblique wall they make a staircase, and it calls every point there a corner. Those
    # walls take their evidence by geometry (the metric's corners included) and measure
    # it to their own face; the axis-wise walls take the metric's points from the rest
    oblique = _oblique(segs, (float(fields_.theta), *fields_.families), 0.5 / res)
    # a wall off the pixel grid's axes is a staircase in both rasters (a wing at 30 or 45
    # degrees, measured by the metric along its family's surfaces): its grid term is a
    # pixel, as an arc's (built right, the 30-degree wing's outer walls of a map drawn at
    # the true poses measured p95 8.6 cm, interval 6.0-11.1 at half a pixel: "failed")
    stair = _oblique(segs, (0.0,), 0.0)
    ka, ea, aa, oa = _on_arcs(ch.X_optimised, ch.X_rigid, ~unm, arcs, half, thick)
    kl, el, al, ol = _on_lines(ch.X_optimised, ch.X_rigid, ~unm & (ka < 0), segs[oblique],
                               half, thick)
    if oblique.any():                      # indices into segs (-1: none)
        kl = np.where(kl >= 0, np.flatnonzero(oblique)[np.maximum(kl, 0)], -1)
    valid = ch.valid & (ka < 0) & (kl < 0)
    corr = ch.X_corr[valid]
    err_px = ch.distances[valid]
    disp = ch.X_rigid[valid] - corr
    k, dist, along = _to_segments(corr, segs)
    k[dist > half] = -1
    if len(segs):
        k[oblique[np.maximum(k, 0)]] = -1               # theirs are taken above
    ku, du, _ = _to_segments(ch.X_rigid[unm], segs)
    ku[du > nearby_m / res] = -1
    kau = _on_arcs(ch.X_rigid[unm], ch.X_rigid[unm], np.ones(int(unm.sum()), bool), arcs,
                   nearby_m / res, thick)[0]
    judge = _Judge(tol, res, min_points, min_coverage, nearby_m)

    walls = [("line", i, s) for i, s in enumerate(segs)]
    walls += [("arc", j, a) for j, a in enumerate(arcs)]
    out: list[WallSegment] = []
    for kind, i, s in sorted(walls, key=lambda w: _order_key(w[0], w[2])):
        if kind == "line":
            length_px = float(np.hypot(s[2] - s[0], s[3] - s[1]))
            # world endpoints: continuous pixel x -> column index x - 0.5 (centres are
            # integers)
            wx, wy = plan.pixel_to_world(s[[1, 3]] - 0.5, s[[0, 2]] - 0.5)
            u = np.array([wx[1] - wx[0], wy[1] - wy[0]])
            u = u / max(np.hypot(*u), 1e-12)
            normal = np.array([-u[1], u[0]])  # world normal; + toward +y (E-W) or +x (N-S)
            if abs(normal[1]) >= abs(normal[0]):
                normal = normal if normal[1] >= 0 else -normal
            else:
                normal = normal if normal[0] >= 0 else -normal
            to_world = _pixel_to_world_linear(plan)
            if oblique[i]:
                # by geometry, and a staircase in both rasters, as an arc is (below)
                sel = kl == i
                left = np.array([s[3] - s[1], -(s[2] - s[0])]) / length_px  # pixels
                offsets = ol[sel] * float(left @ to_world @ normal)
                fields = judge(el[sel] * res * 100.0, al[sel], length_px,
                               offsets * res * 100.0, int((ku == i).sum()), grid_px=1.0)
            else:
                sel = k == i
                # displacement in world axes: columns to the right are +x, rows down -y
                offsets = disp[sel] @ to_world @ normal
                fields = judge(err_px[sel] * res * 100.0, along[sel], length_px,
                               offsets * res * 100.0, int((ku == i).sum()),
                               grid_px=1.0 if stair[i] else 0.5)
            extra = {"oblique": bool(oblique[i])}
            px = s.copy()
        else:
            sel = ka == i
            xc, yc, r, a0, span = s
            length_px = float(span * r)
            a = a0 + np.array([0.0, span / 2, span])
            ex, ey = xc + r * np.cos(a), yc + r * np.sin(a)
            wx, wy = plan.pixel_to_world(ey - 0.5, ex - 0.5)
            cx, cy = plan.pixel_to_world(np.array([yc - 0.5]), np.array([xc - 0.5]))
            # a curve on a pixel grid is a staircase, in the plan and in the map: each
            # lies up to half a pixel across its circle (built right, the same raster
            # measures 0.6 px at p95 against it), so an arc's grid term is a pixel
            fields = judge(ea[sel] * res * 100.0, aa[sel], length_px, oa[sel] * res * 100.0,
                           int((kau == i).sum()), grid_px=1.0)
            extra = {"arc_m": (float(cx[0]), float(cy[0]), float(r * res)),
                     "arc_px": tuple(float(v) for v in s),
                     "mid_m": (float(wx[1]), float(wy[1]))}
            wx, wy = wx[[0, 2]], wy[[0, 2]]
            px = np.array([ex[0], ey[0], ex[2], ey[2]])
        out.append(WallSegment(id=len(out) + 1, x0_m=float(wx[0]), y0_m=float(wy[0]),
                               x1_m=float(wx[1]), y1_m=float(wy[1]),
                               length_m=length_px * res, px=px, **fields, **extra))
    insp = WallInspection(out, tol, res, min_points, min_coverage)
    insp.warnings = _judgement_warnings(insp)
    return insp


class _Judge:
    """A wall's status, figures and note from its evidence (``inspect_walls``'s steps
    3-4): local errors and signed offsets in cm, positions along it in pixels."""

    def __init__(self, tol: float, res: float, min_points: int, min_coverage: float,
                 nearby_m: float):
        self.tol, self.res, self.nearby_m = tol, res, nearby_m
        self.min_points, self.min_coverage = min_points, min_coverage

    def __call__(self, e: np.ndarray, along: np.ndarray, length_px: float,
                 offsets: np.ndarray, n_unm: int, grid_px: float = 0.5) -> dict[str, Any]:
        bins = max(1, int(math.ceil(length_px / 2.0)))
        hit = np.unique(np.clip((along / 2.0).astype(np.int64), 0, bins - 1))
        coverage = len(hit) / bins
        if e.size >= self.min_points and coverage >= self.min_coverage:
            dev = float(np.percentile(e, 95))
            lo, hi = deviation_interval(e, grid_px * self.res * 100.0)
            t = self.tol * 100.0
            status = "pass" if hi <= t + 1e-9 else "fail" if lo > t + 1e-9 else "uncertain"
            stats = (dev, lo, hi, float(e.mean()), float(e.max()), float(np.median(offsets)))
            note = f"only {coverage:.0%} of its length seen" if coverage < 0.6 else ""
        else:
            status = "not observed"
            stats = (math.nan,) * 6
            note = (
                "no SLAM wall evidence"
                if e.size == 0
                else f"too little SLAM evidence ({e.size} points, {coverage:.0%} of its length)"
            )
            if n_unm >= self.min_points:
                note += (
                    f"; {n_unm} SLAM points within {self.nearby_m:g} m match no plan wall: "
                    "built more than 0.3 m off, or clutter in front of it? check on site"
                )
        keys = ("deviation_cm", "deviation_lo_cm", "deviation_hi_cm", "mean_cm", "max_cm",
                "offset_cm")
        return {"status": status, **dict(zip(keys, stats, strict=True)),
                "points": int(e.size), "coverage": coverage, "unmatched_nearby": n_unm,
                "note": note}


def _order_key(kind: str, w: np.ndarray) -> float:
    """Walls top to bottom, then left to right (ids follow): a line's upper end, an
    arc's topmost point."""
    if kind == "line":
        return float(np.round(min(w[1], w[3])) * 1e6 + min(w[0], w[2]))
    xc, yc, r, a0, span = w
    a = a0 + np.linspace(0.0, span, 65)
    x, y = xc + r * np.cos(a), yc + r * np.sin(a)
    return float(np.round(y.min()) * 1e6 + x.min())


def _oblique(segs: np.ndarray, families: tuple[float, ...], min_len: float,
             min_deg: float = 10.0) -> np.ndarray:
    """Which segments lie more than ``min_deg`` off every direction family of the plan
    (``families``, radians: each angle and a right angle to it) over at least
    ``min_len`` pixels: walls the metric's surfaces make a staircase of. (Shorter
    slanted segments are the line detector's, across a wall stub's end: 0.21-0.25 m in
    4 of 24 generated plans.)"""
    if not len(segs):
        return np.zeros(0, bool)
    a = np.arctan2(segs[:, 3] - segs[:, 1], segs[:, 2] - segs[:, 0])
    a = a[:, None] - np.asarray(families, float)[None, :]
    off = np.abs(np.mod(a + math.pi / 4, math.pi / 2) - math.pi / 4).min(axis=1)
    length = np.hypot(segs[:, 2] - segs[:, 0], segs[:, 3] - segs[:, 1])
    return (off > math.radians(min_deg)) & (length >= min_len)


def _on_lines(X_opt: np.ndarray, X_rig: np.ndarray, ok: np.ndarray, segs: np.ndarray,
              reach: float, thick: float
              ) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """:func:`_on_arcs` for straight walls: per point, the segment (index, or -1) whose
    centre line its optimised position lies within ``reach`` pixels of (``ok`` points,
    within its length; the nearest), its local error (the rigidly aligned point to the
    line through the face's pixel centres on its side), its position along the segment
    and its signed offset (+ to the segment's left, in pixels: x right, y down)."""
    n = len(X_opt)
    k = np.full(n, -1, np.int64)
    err, along, off = np.zeros(n), np.zeros(n), np.zeros(n)
    best = np.full(n, np.inf)
    face = _face_px(thick)
    for j, (x0, y0, x1, y1) in enumerate(np.asarray(segs, float).reshape(-1, 4)):
        L = max(math.hypot(x1 - x0, y1 - y0), 1e-9)
        u = np.array([x1 - x0, y1 - y0]) / L
        nrm = np.array([u[1], -u[0]])                # the left, in pixels (y down)
        q = X_opt - (x0, y0)
        t, d = q @ u, q @ nrm
        sel = ok & (np.abs(d) <= reach) & (t >= 0) & (t <= L) & (np.abs(d) < best)
        # across from the face on the point's side, + to the left on either side
        o = (X_rig - (x0, y0)) @ nrm - np.where(d >= 0, face, -face)
        k[sel], best[sel] = j, np.abs(d[sel])
        err[sel], along[sel], off[sel] = np.abs(o[sel]), t[sel], o[sel]
    return k, err, along, off


def _face_px(thick: float) -> float:
    """How far a wall's face pixel centres lie from its centre line (pixels; ``thick``
    its thickness), where a straight wall's correspondences are: half a pixel inside
    the wall's edge."""
    return max(0.0, 0.5 * thick - 0.5)


def _on_arcs(X_opt: np.ndarray, X_rig: np.ndarray, ok: np.ndarray, arcs: np.ndarray,
             reach: float, thick: float
             ) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Per point, the arc (index, or -1) whose centre line its optimised position lies
    within ``reach`` pixels of (``ok`` points only, inside the arc's angles; the nearest
    arc), its local error across the wall (pixels: the rigidly aligned point to the
    arc's face on its side, the circle through the face's pixel centres, ``thick`` the
    plan's wall thickness), its position along the arc and its signed offset (+ away
    from the centre)."""
    n = len(X_opt)
    k = np.full(n, -1, np.int64)
    err, along, off = np.zeros(n), np.zeros(n), np.zeros(n)
    best = np.full(n, np.inf)
    for j, (xc, yc, r, a0, span) in enumerate(np.asarray(arcs, float).reshape(-1, 5)):
        d = np.hypot(X_opt[:, 0] - xc, X_opt[:, 1] - yc) - r
        t = np.mod(np.arctan2(X_opt[:, 1] - yc, X_opt[:, 0] - xc) - a0, 2 * math.pi)
        sel = ok & (np.abs(d) <= reach) & (t <= span) & (np.abs(d) < best)
        face = r + np.where(d >= 0, 1.0, -1.0) * _face_px(thick)
        o = np.hypot(X_rig[:, 0] - xc, X_rig[:, 1] - yc) - face
        k[sel], best[sel] = j, np.abs(d[sel])
        err[sel], along[sel], off[sel] = np.abs(o[sel]), t[sel] * r, o[sel]
    return k, err, along, off


def deviation_interval(errors_cm: np.ndarray, grid_cm: float, q: float = 0.95,
                       z: float = 1.0) -> tuple[float, float]:
    """The interval of a wall's deviation (its points' ``q`` quantile): the distribution-free
    confidence interval of that quantile from the order statistics of the points (ranks
    ``n q -+ z sqrt(n q (1 - q))``), widened by ``grid_cm`` on both sides (where the plan
    and the map can place a wall face at all), clipped at 0.

    Parameters
    ----------
    errors_cm : ndarray
        The local errors of the wall's points, cm.
    grid_cm : float
        Half a plan pixel, cm.
    q, z : float
        The quantile, and the half-width of the interval in standard errors (1: the 68 %
        interval; 1.96, the 95 % one, reaches a wall's largest error with about 100
        points, so one stray point of a pixel off on a perfect wall made it uncertain).

    Returns
    -------
    (float, float)
        Lower and upper bound, cm.

    Examples
    --------
    >>> e = np.linspace(0.0, 4.0, 200)            # 200 points, p95 3.8 cm
    >>> [round(v, 2) for v in deviation_interval(e, 2.5)]
    [1.22, 6.38]
    >>> [round(v, 2) for v in deviation_interval(e[::20], 2.5)]   # 10 points: wider
    [0.31, 6.12]
    """
    e = np.sort(np.asarray(errors_cm, float))
    n = e.size
    half = z * math.sqrt(n * q * (1.0 - q))
    lo = e[int(np.clip(math.floor(n * q - half) - 1, 0, n - 1))]
    hi = e[int(np.clip(math.ceil(n * q + half) - 1, 0, n - 1))]
    return max(0.0, float(lo) - grid_cm), float(hi) + grid_cm


def _pixel_to_world_linear(plan: OccupancyMap) -> np.ndarray:
    """2x2 matrix taking a pixel displacement (dx columns, dy rows) to world axes (in px)."""
    yaw = float(plan.origin[2])
    c, s = math.cos(yaw), math.sin(yaw)
    # (dx, dy_rows) -> local (dx, -dy) -> rotated by yaw; row vector convention: v @ M
    return np.array([[c, s], [s, -c]])


def _judgement_warnings(insp: WallInspection) -> list[str]:
    """Plain-words warnings about the wall verdicts themselves."""
    w = []
    c = insp.counts
    n = len(insp.segments)
    if n == 0:
        w.append("No wall segment was found in the plan: there is nothing to pass or fail.")
        return w
    if c["not observed"] > 0.5 * n:
        w.append(
            f"{c['not observed']} of {n} plan wall segments were not observed by the SLAM map: "
            "the pass and fail counts cover only part of the building."
        )
    if insp.tolerance_m < insp.resolution:
        w.append(
            f"The tolerance ({insp.tolerance_m * 100:g} cm) is finer than one plan pixel "
            f"({insp.resolution * 100:g} cm): the plan itself cannot place a wall that "
            "precisely, so walls near the tolerance may pass or fail by chance."
        )
    seen = n - c["not observed"]
    if seen and c["fail"] > 0.5 * seen:
        w.append(
            f"{c['fail']} of the {seen} observed wall segments fail. Before concluding that "
            "they were built off, consider the SLAM map's own error: its drift bends and "
            "shifts walls too (see the heat map: a smooth trend across the building points "
            "to the map, single walls off to the building), and a map can only judge a "
            "tolerance a few times coarser than its accuracy."
        )
    return w


def write_segments_csv(inspection: WallInspection, path: str | os.PathLike) -> Path:
    """One row per wall segment (:data:`CSV_COLUMNS`), written atomically.

    Parameters
    ----------
    inspection : WallInspection
        The segments.
    path : path-like
        The CSV file.

    Returns
    -------
    pathlib.Path
        ``path``.

    Examples
    --------
    >>> import tempfile, pathlib
    >>> insp = WallInspection([], 0.05, 0.05, 5, 0.3)
    >>> p = write_segments_csv(insp, pathlib.Path(tempfile.mkdtemp()) / "walls.csv")
    >>> p.read_text().split(",")[:3]
    ['id', 'x0_m', 'y0_m']
    """
    p = Path(path)
    with atomic_path(p) as tmp, open(tmp, "w", newline="", encoding="utf-8") as fh:
        w = csv.DictWriter(fh, fieldnames=CSV_COLUMNS)
        w.writeheader()
        for s in inspection.segments:
            w.writerow(s.row())
    return p
