"""Is an output map drawn like a plan? Four measurements (issue #32, item 3).

An auto-corrected map is compared with its input (the SLAM map) and its plan:

* **Wall components** (:func:`wall_components`): 8-connected components of occupied
  pixels. A plan's walls are a few connected networks; a dashed wall is many pieces.
  Target: the output has no more than its input.
* **Wall thickness** (:func:`median_wall_thickness`): the median, over the centre line
  of the walls, of twice the distance to the nearest non-wall pixel, measured on the
  map upsampled twice (so that an ``n`` pixel wide wall measures ``n``, odd or even).
  Target: within 1 pixel of the plan's.
* **Straight segments** (:func:`straight_wall_count`): the output's segments (its DXF
  lines when given) against the plan's straight walls
  (:func:`map2map.maps.segments.straight_segments` of the plan, cell 4 px).
  Target: at most 1.5 times the plan's.
* **Broken runs** (:func:`broken_runs`): the input's straight wall runs at least
  ``min_run`` metres long (rows or columns of consecutive occupied pixels; one wall's
  runs, 8-connected, are one run) that the output breaks: somewhere along the run no
  output wall lies within ``across`` pixels for more than ``max_gap`` consecutive
  pixels, with output wall along the run on both sides. Target: none. Runs whose output
  only stops short of an end (the drawer cuts a wall that overshoots a corner back onto
  the corner) are counted apart, as shortened.

Reported beside them, with no target: **unknown pockets** (:func:`unknown_pockets`),
unknown regions of the output enclosed between a wall and free space (a stripe along a
wall inside a room, a room's unseen corner), which a plan does not have.

:func:`drawing_report` gives the four at once, with the targets met.

Examples
--------
>>> import numpy as np
>>> plan = np.full((50, 80), 255, np.uint8); plan[20:22, 5:75] = 0
>>> slam = plan.copy(); slam[19, 5:75:3] = 0               # the same wall, ragged
>>> r = drawing_report(plan, slam, plan, 0.05)
>>> r["components"], r["components_input"], r["broken"], r["targets_met"]
(1, 1, 0, True)
"""

from __future__ import annotations

import cv2
import numpy as np

from ..core.grid import OCCUPIED
from ..core.runs import open_runs

__all__ = ["wall_components", "median_wall_thickness", "straight_wall_count",
           "broken_runs", "unknown_pockets", "drawing_report", "TARGETS"]

#: The issue's targets: output components <= input's, median thickness within 1 px of
#: the plan's, segments <= 1.5 x the plan's straight walls, no input run >= 1 m broken.
TARGETS = {"components": "<= input", "thickness_px": 1.0, "segments_ratio": 1.5,
           "broken": 0}


def _walls(m: np.ndarray) -> np.ndarray:
    m = np.asarray(m)
    return m if m.dtype == bool else m == OCCUPIED


def wall_components(m: np.ndarray) -> int:
    """Number of 8-connected components of occupied pixels (a map or a boolean mask).

    >>> m = np.full((10, 20), 255, np.uint8); m[2, 1:6] = 0; m[2, 8:12] = 0
    >>> wall_components(m)
    2
    """
    n, _ = cv2.connectedComponents(_walls(m).astype(np.uint8), connectivity=8)
    return int(n - 1)


def median_wall_thickness(m: np.ndarray) -> float:
    """Median wall thickness (pixels): twice the distance to the nearest non-wall pixel
    along the walls' centre lines, on the map upsampled twice; NaN without walls.

    >>> m = np.full((30, 40), 255, np.uint8)
    >>> for n in (1, 2, 3, 4):
    ...     m[:] = 255; m[10:10 + n, 5:35] = 0
    ...     print(n, median_wall_thickness(m))
    1 1.0
    2 2.0
    3 3.0
    4 4.0
    """
    from skimage.morphology import skeletonize

    w = _walls(m)
    if not w.any():
        return float("nan")
    up = np.pad(np.repeat(np.repeat(w, 2, axis=0), 2, axis=1), 1).astype(np.uint8)
    dt = cv2.distanceTransform(up, cv2.DIST_L2, cv2.DIST_MASK_PRECISE)
    sk = skeletonize(up > 0)
    # twice the distance in half pixels = the distance itself in pixels
    return float(np.median(dt[sk]))


def straight_wall_count(m: np.ndarray, cell: float = 4.0) -> int:
    """Straight walls of a map: :func:`map2map.maps.segments.straight_segments` of its
    occupied pixels (``cell`` as there; 4 px: the anchored walls' cell at 256 px).

    >>> m = np.full((40, 60), 255, np.uint8); m[10:12, 5:55] = 0; m[10:35, 5:7] = 0
    >>> straight_wall_count(m)
    2
    """
    from ..maps.segments import straight_segments

    return int(len(straight_segments(_walls(m), cell)))


def _run_mask(w: np.ndarray, n: int, axis: int) -> np.ndarray:
    """Pixels in runs of at least ``n`` along rows (``axis`` 0) or columns (1), exactly
    (:func:`map2map.core.runs.open_runs`; OpenCV's opening shifts even lengths)."""
    return open_runs(w, n, axis=1 if axis == 0 else 0)


def broken_runs(inp: np.ndarray, out: np.ndarray, resolution: float, *,
                min_run: float = 1.0, max_gap: int = 2, across: int = 3,
                shortened: bool = False, opened: bool = False,
                wide: int = 9) -> tuple[int, ...]:
    """``(runs, broken)``: the input's straight wall runs at least ``min_run`` metres long
    (horizontal or vertical; the runs of one wall, 8-connected, count once) and how many
    of them the output breaks: more than ``max_gap`` consecutive pixels along the run
    without an output wall within ``across`` pixels across, with output wall along the
    run on both sides of that gap. With ``shortened=True`` also the number of runs whose
    output stops short of an end of the run by more than ``max_gap`` pixels (a corner
    whose overshoot the drawer cut back, a wall end drawn shorter): not breaks. With
    ``opened=True`` also (last) how many of the broken runs the output *opens*: a gap
    with no output wall within ``wide`` pixels across either (a wall drawn a few pixels
    beside the run, e.g. once between the two lines of a wall SLAM saved twice, breaks
    the run by this measure but opens nothing).

    Examples
    --------
    >>> inp = np.full((40, 100), 255, np.uint8); inp[20:22, 5:95] = 0
    >>> broken_runs(inp, inp, 0.05)
    (1, 0)
    >>> out = inp.copy(); out[20:22, 40:44] = 255            # a 4 px gap: broken
    >>> broken_runs(inp, out, 0.05, opened=True)              # and opened
    (1, 1, 1)
    >>> out = inp.copy(); out[20:22, 40:42] = 255            # 2 px: not broken
    >>> broken_runs(inp, out, 0.05)
    (1, 0)
    >>> out = inp.copy(); out[20:22, 85:95] = 255            # an end cut back
    >>> broken_runs(inp, out, 0.05, shortened=True)
    (1, 0, 1)
    """
    wi, wo = _walls(inp), _walls(out)
    n = max(2, int(round(min_run / float(resolution))))
    runs, broken, short, opens = 0, 0, 0, 0
    for axis in (0, 1):
        r = _run_mask(wi, n, axis)
        if not r.any():
            continue
        k = np.ones((2 * across + 1, 1) if axis == 0 else (1, 2 * across + 1), np.uint8)
        near = cv2.dilate(wo.astype(np.uint8), k) > 0
        kw = np.ones((2 * wide + 1, 1) if axis == 0 else (1, 2 * wide + 1), np.uint8)
        near_wide = cv2.dilate(wo.astype(np.uint8), kw) > 0 if opened else near
        miss = (r & ~near).astype(np.uint8)
        gap = _run_mask(miss, max_gap + 1, axis)
        cnt, lab = cv2.connectedComponents(r.astype(np.uint8), connectivity=8)
        runs += cnt - 1
        for i in np.unique(lab[gap]):               # the runs with a gap (a few)
            rr, cc = np.nonzero(lab == i)
            pos = cc if axis == 0 else rr
            hit = near[rr, cc]
            gp = np.unique(pos[gap[rr, cc]])
            covered = np.unique(pos[hit])
            inner = len(covered) and np.any((gp > covered.min()) & (gp < covered.max()))
            broken += bool(inner)
            short += bool(len(covered) == 0 or gp.min() < covered.min()
                          or gp.max() > covered.max())
            if inner and opened:
                g = gap[rr, cc] & (pos > covered.min()) & (pos < covered.max())
                opens += bool((~near_wide[rr[g], cc[g]]).any())
    out_ = (int(runs), int(broken)) + ((int(short),) if shortened else ())
    return out_ + ((int(opens),) if opened else ())


def unknown_pockets(m: np.ndarray) -> int:
    """Unknown regions of a three-valued map enclosed between a wall and free space
    (:func:`map2map.maps.vectorize.enclosed_unknown`): a stripe along a wall inside a
    room, an unseen corner of a room.

    >>> m = np.full((12, 20), 127, np.uint8); m[2:10, 2:18] = 255; m[9:11, 1:19] = 0
    >>> m[1, 1:19] = 0; m[1:11, 1] = 0; m[1:11, 18] = 0
    >>> unknown_pockets(m)
    0
    >>> m[7:9, 4:15] = 127                        # a stripe between the room and a wall
    >>> unknown_pockets(m)
    1
    """
    from ..maps.vectorize import enclosed_unknown

    return int(enclosed_unknown(m)[1].sum())


def drawing_report(out: np.ndarray, inp: np.ndarray, plan: np.ndarray, resolution: float,
                   segments: np.ndarray | None = None) -> dict:
    """The four measurements of the module doc for one output map, and the targets met.

    Parameters
    ----------
    out, inp, plan : (H, W) uint8 (or boolean wall masks)
        The output, its input (the SLAM map) and the plan, in one frame.
    resolution : float
        Metres per pixel.
    segments : (K, 4) float, optional
        The output's segments (its DXF lines); default: ``straight_segments`` of ``out``.

    Returns
    -------
    dict
        ``components``, ``components_input``, ``thickness_px``, ``thickness_plan_px``,
        ``segments``, ``plan_walls``, ``segments_ratio``, ``runs``, ``broken``,
        ``shortened`` (runs whose output stops short of an end: reported, no target),
        ``opened`` (broken runs with no output wall within 9 pixels at a gap: reported),
        ``pockets`` (:func:`unknown_pockets` of the output: reported) and
        ``ok_components``, ``ok_thickness``, ``ok_segments``, ``ok_broken``,
        ``targets_met``; ``ok_opened`` (no run opened) and ``targets_met_opened`` (the
        four with ``ok_opened`` for ``ok_broken``): the break target read as "no wall
        the input shows whole is opened", which a wall saved twice and drawn once
        between its two lines meets though its runs count as broken.
    """
    c_out, c_in = wall_components(out), wall_components(inp)
    t_out, t_plan = median_wall_thickness(out), median_wall_thickness(plan)
    n_seg = int(len(segments)) if segments is not None else straight_wall_count(out)
    n_plan = straight_wall_count(plan)
    runs, broken, short, opens = broken_runs(inp, out, resolution, shortened=True,
                                             opened=True)
    r = {"components": c_out, "components_input": c_in, "thickness_px": t_out,
         "thickness_plan_px": t_plan, "segments": n_seg, "plan_walls": n_plan,
         "segments_ratio": n_seg / n_plan if n_plan else float("inf"),
         "runs": runs, "broken": broken, "shortened": short, "opened": opens,
         "pockets": unknown_pockets(out) if np.asarray(out).dtype != bool else 0}
    r["ok_components"] = c_out <= c_in
    r["ok_thickness"] = bool(abs(t_out - t_plan) <= TARGETS["thickness_px"])
    r["ok_segments"] = bool(r["segments_ratio"] <= TARGETS["segments_ratio"])
    r["ok_broken"] = broken == 0
    r["targets_met"] = bool(r["ok_components"] and r["ok_thickness"] and r["ok_segments"]
                            and r["ok_broken"])
    r["ok_opened"] = opens == 0
    r["targets_met_opened"] = bool(r["ok_components"] and r["ok_thickness"]
                                   and r["ok_segments"] and r["ok_opened"])
    return r
