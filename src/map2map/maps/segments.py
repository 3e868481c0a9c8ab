"""Straight wall segments of a wall mask: centre lines cut into axis-aligned segments.

:func:`straight_segments` thins a boolean wall mask to its centre lines
(``skimage.morphology.skeletonize``), cuts them into straight segments (probabilistic
Hough transform, ``cv2.HoughLinesP``), makes a segment within
:data:`AXIS_TOLERANCE_DEG` of horizontal or vertical exactly so at its mean coordinate,
merges collinear overlapping segments and moves a segment end that stops short of (or
overshoots) a perpendicular wall onto it, so corners and T-junctions close. Step 3 of
Model_BA's post-processing (thesis sec. 3.1, :mod:`map2map.learn.ba.postprocess`) and the
wall segments of the as-built inspection report (:mod:`map2map.reports.inspection`)
both use it. Coordinates are pixels: ``x`` = column, ``y`` = row.

Examples
--------
>>> import numpy as np
>>> w = np.zeros((40, 60), bool); w[10:13, 5:55] = True
>>> straight_segments(w, 8.0).round(1).tolist()
[[5.0, 11.0, 52.0, 11.0]]
"""

from __future__ import annotations

import cv2
import numpy as np

__all__ = ["AXIS_TOLERANCE_DEG", "straight_segments", "join_supported", "merge_slanted"]

#: Segments within this angle (degrees) of horizontal or vertical are made exactly so.
AXIS_TOLERANCE_DEG = 10.0


def _merge(segs: np.ndarray, axis: int, tol: float, gap: float) -> np.ndarray:
    """Merge axis-aligned segments (axis 0: horizontal, y fixed) that are collinear within
    ``tol`` and overlap or leave less than ``gap`` between them along their length.

    Segments sorted by their fixed coordinate form a line group while consecutive ones lie
    within ``tol``; within a group, sorted by start, a run continues while a segment
    starts within ``gap`` of the furthest end so far. Each run becomes one segment at the
    length-weighted mean coordinate of its members (vectorised: no Python loop).
    """
    if len(segs) == 0:
        return np.zeros((0, 4))
    c = segs[:, 1] if axis == 0 else segs[:, 0]
    lo = np.minimum(segs[:, 0], segs[:, 2]) if axis == 0 else np.minimum(segs[:, 1], segs[:, 3])
    hi = np.maximum(segs[:, 0], segs[:, 2]) if axis == 0 else np.maximum(segs[:, 1], segs[:, 3])
    order = np.argsort(c)
    group = np.empty(len(c), np.int64)
    group[order] = np.concatenate([[0], np.cumsum(np.diff(c[order]) > tol)])
    o = np.lexsort((lo, group))  # by group, then by start (stable: ties keep c's order)
    g, lo_o, hi_o, c_o = group[o], lo[o], hi[o], c[o]
    # furthest end so far within the group: the running maximum of the ends' ranks, each
    # group lifted above the ones before it (integers: exact, no rounding of the ends)
    ends, rank = np.unique(hi_o, return_inverse=True)
    lift = g * len(ends)
    reach = ends[np.maximum.accumulate(rank + lift) - lift]
    new = np.ones(len(o), bool)
    new[1:] = (g[1:] != g[:-1]) | (lo_o[1:] > reach[:-1] + gap)
    first = np.flatnonzero(new)
    w = np.maximum(hi_o - lo_o, 1.0)
    k = np.add.reduceat(c_o * w, first) / np.add.reduceat(w, first)
    start = lo_o[first]
    stop = np.maximum.reduceat(hi_o, first)
    out = np.stack([start, k, stop, k] if axis == 0 else [k, start, k, stop], axis=1)
    return out.astype(float)


def straight_segments(walls: np.ndarray, cell: float) -> np.ndarray:
    """Straight wall segments (K, 4: x0, y0, x1, y1) of a boolean wall mask (steps 3 of
    the module doc); ``cell`` is the size in pixels of one model output cell.

    Examples
    --------
    >>> w = np.zeros((64, 64), bool); w[30:33, 5:60] = True; w[5:60, 40:43] = True
    >>> s = straight_segments(w, 8.0)
    >>> len(s), sorted({"h" if a[1] == a[3] else "v" for a in s})
    (2, ['h', 'v'])
    """
    from skimage.morphology import skeletonize

    skel = skeletonize(walls).astype(np.uint8) * 255
    min_len = max(3, int(round(cell / 2)))
    lines = cv2.HoughLinesP(skel, 1, np.pi / 180, threshold=max(3, min_len // 2),
                            minLineLength=min_len, maxLineGap=max(2, int(round(cell / 2))))
    if lines is None:
        return np.zeros((0, 4))
    s = np.asarray(lines).reshape(-1, 4).astype(float)
    ang = np.degrees(np.arctan2(s[:, 3] - s[:, 1], s[:, 2] - s[:, 0])) % 180
    horiz = (ang < AXIS_TOLERANCE_DEG) | (ang > 180 - AXIS_TOLERANCE_DEG)
    vert = np.abs(ang - 90) < AXIS_TOLERANCE_DEG
    h = s[horiz].copy()
    h[:, [1, 3]] = h[:, [1, 3]].mean(axis=1, keepdims=True)
    v = s[vert].copy()
    v[:, [0, 2]] = v[:, [0, 2]].mean(axis=1, keepdims=True)
    tol = max(1.5, cell / 4)
    hs = _merge(h, 0, tol, cell)
    vs = _merge(v, 1, tol, cell)
    other = [row for row in s[~horiz & ~vert]]
    hs, vs = _join(hs, vs, cell)
    return np.concatenate([hs, vs, np.array(other).reshape(-1, 4)])


def merge_slanted(segs: np.ndarray, tol: float, gap: float, angle_deg: float = 3.0
                  ) -> np.ndarray:
    """Segments off the grid's axes that lie on one line merged into one: within
    ``angle_deg`` of each other's direction and ``tol`` pixels of the longest one's line,
    overlapping or leaving less than ``gap`` pixels between them along it.
    :func:`straight_segments` merges the axis-aligned ones; a wall at 30 or 45 degrees
    is a staircase of pixels that the Hough transform cuts into several overlapping
    pieces. Axis-aligned segments (within :data:`AXIS_TOLERANCE_DEG`) are returned as
    they are. Each merged line is the length-weighted mean of its pieces' offsets, from
    the first to the last of their ends along it.

    Examples
    --------
    >>> s = np.array([[0.0, 0, 20, 20], [18, 18.5, 40, 40.5], [60, 60, 80, 80],
    ...               [0, 50, 30, 50]])
    >>> merge_slanted(s, 1.5, 4.0).round(1).tolist()
    [[0.0, 50.0, 30.0, 50.0], [-0.1, 0.1, 40.1, 40.4], [60.0, 60.0, 80.0, 80.0]]
    """
    segs = np.asarray(segs, float).reshape(-1, 4)
    if len(segs) < 2:
        return segs
    d = segs[:, 2:] - segs[:, :2]
    L = np.hypot(d[:, 0], d[:, 1])
    ang = np.degrees(np.arctan2(d[:, 1], d[:, 0])) % 180.0
    axis = (ang < AXIS_TOLERANCE_DEG) | (ang > 180 - AXIS_TOLERANCE_DEG) | (
        np.abs(ang - 90) < AXIS_TOLERANCE_DEG)
    idx = np.flatnonzero(~axis & (L > 0))
    if len(idx) < 2:
        return segs
    out = [segs[axis | (L == 0)]]
    left = set(idx.tolist())
    for i in idx[np.argsort(-L[idx], kind="stable")]:     # lines, longest first: a few
        if i not in left:
            continue
        u = d[i] / L[i]
        n = np.array([-u[1], u[0]])
        cand = np.array(sorted(left))
        da = np.abs((ang[cand] - ang[i] + 90.0) % 180.0 - 90.0)
        mid = 0.5 * (segs[cand, :2] + segs[cand, 2:])
        off = (mid - segs[i, :2]) @ n
        mem = cand[(da <= angle_deg) & (np.abs(off) <= tol)]
        t0 = (segs[mem, :2] - segs[i, :2]) @ u
        t1 = (segs[mem, 2:] - segs[i, :2]) @ u
        lo, hi = np.minimum(t0, t1), np.maximum(t0, t1)
        order = np.argsort(lo, kind="stable")
        groups, cur = [], [order[0]]
        end = hi[order[0]]
        for k in order[1:]:                                # the line's pieces: a few
            if lo[k] <= end + gap:
                cur.append(k)
                end = max(end, hi[k])
            else:
                groups.append(cur)
                cur, end = [k], hi[k]
        groups.append(cur)
        for g in groups:
            g = np.asarray(g)
            w = L[mem[g]]
            c = float((((0.5 * (segs[mem[g], :2] + segs[mem[g], 2:])) - segs[i, :2]) @ n
                       * w).sum() / w.sum())
            a, b = lo[g].min(), hi[g].max()
            base = segs[i, :2] + c * n
            out.append(np.array([[*(base + a * u), *(base + b * u)]]))
        left -= set(mem.tolist())
    return np.concatenate(out)


def _join(h: np.ndarray, v: np.ndarray, reach: float) -> tuple[np.ndarray, np.ndarray]:
    """Move segment ends onto a perpendicular segment within ``reach`` pixels."""
    h, v = h.copy(), v.copy()
    for a, b, ax in ((h, v, 0), (v, h, 1)):
        if len(a) == 0 or len(b) == 0:
            continue
        # a's ends (along its axis) vs b's fixed coordinate; b's extent must cover a's line
        pos_idx = (0, 2) if ax == 0 else (1, 3)
        line = a[:, 1] if ax == 0 else a[:, 0]                     # a's fixed coordinate
        bc = b[:, 0] if ax == 0 else b[:, 1]                       # b's fixed coordinate
        blo = np.minimum(b[:, 1], b[:, 3]) if ax == 0 else np.minimum(b[:, 0], b[:, 2])
        bhi = np.maximum(b[:, 1], b[:, 3]) if ax == 0 else np.maximum(b[:, 0], b[:, 2])
        covers = (blo[None, :] - reach <= line[:, None]) & (line[:, None] <= bhi[None, :] + reach)
        for j in pos_idx:
            d = np.abs(a[:, j][:, None] - bc[None, :])
            d[~covers] = np.inf
            k = np.argmin(d, axis=1)
            ok = d[np.arange(len(a)), k] <= reach
            a[ok, j] = bc[k[ok]]
    return h, v


def join_supported(segs: np.ndarray, walls: np.ndarray, tol: float, max_gap: float,
                   min_cover: float = 0.8, junction: float | None = None) -> np.ndarray:
    """Join collinear axis-aligned segments across a gap the wall mask fills.

    :func:`straight_segments` merges collinear pieces only across gaps shorter than a
    model cell; the Hough transform also cuts a continuous wall at T-junctions and
    where its thinned centre line wobbles. Two consecutive segments of one line (fixed
    coordinates within ``tol`` and in the same ``tol``-wide bin of that coordinate, the
    order they are scanned in) whose gap is at most ``max_gap`` pixels long become one
    when ``walls`` holds a pixel within ``tol`` of the line at ``min_cover`` of the
    gap's positions or more (the input shows a wall there: not a door). The joined
    segment lies at the pieces' length-weighted mean coordinate. Other segments are
    returned as they are (axis-aligned first, then the rest). With ``junction``, only
    gaps where a perpendicular segment ends (within ``junction`` pixels of the line) are
    joined: the T-junctions at which the Hough transform cuts a wall.

    Parameters
    ----------
    segs : (K, 4) float
        ``x0, y0, x1, y1`` in pixels (x: column, y: row).
    walls : (H, W) bool
    tol : float
    max_gap : float
    min_cover : float
    junction : float, optional

    Returns
    -------
    (K', 4) float

    Examples
    --------
    >>> w = np.zeros((30, 60), bool); w[10, 2:58] = True      # one wall, cut by Hough
    >>> s = np.array([[2.0, 10, 25, 10], [33, 10.4, 57, 10.4]])
    >>> join_supported(s, w, 1.5, 20).round(1).tolist()
    [[2.0, 10.2, 57.0, 10.2]]
    >>> w[10, 26:33] = False                                  # a door: left apart
    >>> len(join_supported(s, w, 1.5, 20))
    2
    """
    segs = np.asarray(segs, float).reshape(-1, 4)
    walls = np.asarray(walls, bool)
    horiz = np.abs(segs[:, 1] - segs[:, 3]) < 1e-9
    vert = np.abs(segs[:, 0] - segs[:, 2]) < 1e-9
    out = []
    for axis, sel in ((0, horiz & ~vert), (1, vert & ~horiz)):
        a = segs[sel]
        if len(a) < 2:
            out.append(a)
            continue
        # the ends of the perpendicular segments as rows (along, across) of this axis
        p = segs[vert & ~horiz] if axis == 0 else segs[horiz & ~vert]
        ends = np.concatenate([p[:, [0, 1]], p[:, [2, 3]]]) if axis == 0 else \
            np.concatenate([p[:, [1, 0]], p[:, [3, 2]]])
        c = a[:, 1] if axis == 0 else a[:, 0]
        lo = np.minimum(a[:, 0], a[:, 2]) if axis == 0 else np.minimum(a[:, 1], a[:, 3])
        hi = np.maximum(a[:, 0], a[:, 2]) if axis == 0 else np.maximum(a[:, 1], a[:, 3])
        order = np.lexsort((lo, np.round(c / max(tol, 1e-9))))
        merged = []
        cur = None
        for i in order:                      # one pass over the segments, not pixels
            if cur is not None and abs(c[i] - cur[0]) <= tol and \
                    0 < lo[i] - cur[2] <= max_gap and \
                    (junction is None or _junction(ends, cur[0], cur[2], lo[i], junction)) and \
                    _covered(walls, axis, cur[0], c[i], cur[2], lo[i], tol) >= min_cover:
                w0, w1 = max(cur[2] - cur[1], 1.0), max(hi[i] - lo[i], 1.0)
                cur = [(cur[0] * w0 + c[i] * w1) / (w0 + w1), cur[1], max(cur[2], hi[i])]
                continue
            if cur is not None:
                merged.append(cur)
            cur = [c[i], lo[i], hi[i]]
        merged.append(cur)
        m = np.array(merged, float)
        out.append(np.stack([m[:, 1], m[:, 0], m[:, 2], m[:, 0]] if axis == 0 else
                            [m[:, 0], m[:, 1], m[:, 0], m[:, 2]], axis=1))
    out.append(segs[~(horiz ^ vert)])
    return np.concatenate(out).reshape(-1, 4)


def _junction(ends: np.ndarray, c: float, g0: float, g1: float, reach: float) -> bool:
    """Whether a perpendicular segment ends within ``reach`` of the line at ``c`` (its
    ``y`` for a horizontal line) between ``g0`` and ``g1`` along it: ``ends`` rows
    ``(along, across)`` = ``(x, y)`` of vertical segments' ends for a horizontal line."""
    if len(ends) == 0:
        return False
    along, across = ends[:, 0], ends[:, 1]
    return bool(np.any((np.abs(across - c) <= reach) & (along >= g0 - reach)
                       & (along <= g1 + reach)))


def _covered(walls, axis, c0, c1, g0, g1, tol) -> float:
    """Share of the positions strictly between ``g0`` and ``g1`` along a line at
    ``(c0 + c1) / 2`` where ``walls`` has a pixel within ``tol`` across."""
    H, W = walls.shape
    c = (c0 + c1) / 2.0
    j0, j1 = int(np.floor(g0)) + 1, int(np.ceil(g1))
    i0, i1 = int(np.floor(c - tol)), int(np.ceil(c + tol)) + 1
    n_along, n_across = (W, H) if axis == 0 else (H, W)
    j0, j1 = max(0, j0), min(n_along, j1)
    i0, i1 = max(0, i0), min(n_across, i1)
    if j1 <= j0 or i1 <= i0:
        return 0.0 if j1 > j0 else 1.0
    band = walls[i0:i1, j0:j1] if axis == 0 else walls[j0:j1, i0:i1].T
    return float(band.any(axis=0).mean())
