"""Straight wall segments of a wall mask: centre lines cut into axis-aligned segments.

:func:`straight_segments` thins a boolean wall mask to its centre lines
(``skimage.morphology.skeletonize``), cuts them into straight segments (probabilistic
Hough transform, ``cv2.HoughLinesP``), makes a segment within
:data:`AXIS_TOLERANCE_DEG` of horizontal or vertical exactly so at its mean coordinate,
merges collinear overlapping segments and moves a segment end that stops short of (or
overshoots) a perpendicular wall onto it, so corners and T-junctions close. Step 3 of
Model_BA's post-processing (thesis sec. 3.1, :mod:`map2map.learn.postprocess`) and the
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

__all__ = ["AXIS_TOLERANCE_DEG", "straight_segments"]

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
