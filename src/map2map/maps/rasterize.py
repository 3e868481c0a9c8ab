"""Vector geometry onto the pixel grid: exact centre sampling and unbroken outlines.

Coordinates here are *continuous pixel coordinates*: ``u`` = column, ``v`` = row,
pixel ``(r, c)`` covers ``[c, c + 1) x [r, r + 1)`` and its centre is
``(c + 0.5, r + 0.5)`` (the convention of :mod:`map2map.maps.grid`). OpenCV does the
bulk of the drawing (fixed-point vertices, 8 fractional bits); where OpenCV only
approximates, an exact test decides.

Examples
--------
>>> square = np.array([[1.0, 1.0], [4.0, 1.0], [4.0, 3.0], [1.0, 3.0]])
>>> fill_exact((5, 6), [square]).astype(int)
array([[0, 0, 0, 0, 0, 0],
       [0, 1, 1, 1, 0, 0],
       [0, 1, 1, 1, 0, 0],
       [0, 0, 0, 0, 0, 0],
       [0, 0, 0, 0, 0, 0]])
>>> trace((3, 4), [np.array([[0.2, 0.5], [3.8, 2.5]])]).astype(int)
array([[1, 1, 0, 0],
       [0, 1, 1, 0],
       [0, 0, 1, 1]])
>>> trace((3, 3), [np.array([[0.5, 0.5], [2.5, 2.5]])]).astype(int)  # through corners
array([[1, 1, 0],
       [0, 1, 1],
       [0, 0, 1]])
"""

from __future__ import annotations

from collections.abc import Callable, Sequence

import cv2
import numpy as np

__all__ = ["to_fixed", "fill_exact", "segment_pixels", "trace"]

SHIFT = 8
_SCALE = 1 << SHIFT


def to_fixed(uv: np.ndarray) -> np.ndarray:
    """Continuous pixel coordinates -> OpenCV fixed-point points (pixel centres at integers)."""
    uv = np.asarray(uv, float)
    return np.round((uv - 0.5) * _SCALE).astype(np.int32)


def _even_odd(rings: Sequence[np.ndarray]) -> Callable[[np.ndarray], np.ndarray]:
    from matplotlib.path import Path as MplPath

    paths = [MplPath(np.asarray(r, float)) for r in rings if len(r) >= 3]

    def inside(points: np.ndarray) -> np.ndarray:
        count = np.zeros(len(points), np.int64)
        for path in paths:
            count += path.contains_points(points)
        return count % 2 == 1

    return inside


def fill_exact(
    shape: tuple[int, int],
    rings: Sequence[np.ndarray],
    contains: Callable[[np.ndarray], np.ndarray] | None = None,
) -> np.ndarray:
    """Boolean mask of the pixels whose centre lies inside the rings (even-odd rule).

    ``cv2.fillPoly`` fills fast but also takes some pixels its edges merely touch;
    every pixel within a pixel of an edge is re-decided by an exact test of its
    centre: ``contains(points (N, 2) u, v) -> bool (N,)`` if given (e.g.
    ``shapely.contains_xy`` of a geometry), else an even-odd point-in-polygon test
    (``matplotlib.path.Path``, which also copes with self-touching rings).
    """
    rings = [np.asarray(r, float) for r in rings if len(r) >= 3]
    mask = np.zeros(shape, np.uint8)
    if not rings:
        return mask.astype(bool)
    fixed = [to_fixed(r) for r in rings]
    cv2.fillPoly(mask, fixed, 1, lineType=cv2.LINE_8, shift=SHIFT)
    band = np.zeros(shape, np.uint8)
    cv2.polylines(band, fixed, True, 1, thickness=3, lineType=cv2.LINE_8, shift=SHIFT)
    rows, cols = np.nonzero(band)
    centres = np.stack([cols + 0.5, rows + 0.5], axis=1)
    test = contains if contains is not None else _even_odd(rings)
    mask[rows, cols] = np.asarray(test(centres), bool)
    return mask.astype(bool)


def segment_pixels(starts: np.ndarray, ends: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(rows, cols) of every pixel that segments pass through, 4-connected per segment.

    Exact grid traversal (a "supercover", Amanatides & Woo 1987), vectorised over all
    segments: each segment is cut where it crosses the integer grid lines, and every
    piece marks the pixel containing its midpoint. Where a segment passes exactly
    through a pixel corner, one of the two side pixels is added, so consecutive
    pixels always share an edge.
    """
    p0 = np.asarray(starts, float).reshape(-1, 2)
    p1 = np.asarray(ends, float).reshape(-1, 2)
    n = len(p0)
    if n == 0:
        return np.zeros(0, np.int64), np.zeros(0, np.int64)
    d = p1 - p0
    seg_ids, ts = [np.arange(n), np.arange(n)], [np.zeros(n), np.ones(n)]
    for axis in (0, 1):
        lo = np.floor(np.minimum(p0[:, axis], p1[:, axis])) + 1
        hi = np.ceil(np.maximum(p0[:, axis], p1[:, axis])) - 1
        count = np.maximum(hi - lo + 1, 0).astype(np.int64)
        ids = np.repeat(np.arange(n), count)
        if ids.size == 0:
            continue
        first = np.cumsum(count) - count
        k = np.arange(ids.size) - np.repeat(first, count)
        grid = lo[ids] + k
        seg_ids.append(ids)
        ts.append((grid - p0[ids, axis]) / d[ids, axis])
    seg = np.concatenate(seg_ids)
    t = np.concatenate(ts)
    order = np.lexsort((t, seg))
    seg, t = seg[order], t[order]
    same = seg[1:] == seg[:-1]
    mid_seg = seg[:-1][same]
    tm = 0.5 * (t[:-1][same] + t[1:][same])
    pts = p0[mid_seg] + tm[:, None] * d[mid_seg]
    cols = np.floor(pts[:, 0]).astype(np.int64)
    rows = np.floor(pts[:, 1]).astype(np.int64)
    # close diagonal steps (segment through a pixel corner) with a side pixel
    step = (mid_seg[1:] == mid_seg[:-1]) & (rows[1:] != rows[:-1]) & (cols[1:] != cols[:-1])
    extra_r, extra_c = rows[:-1][step], cols[1:][step]
    return np.concatenate([rows, extra_r]), np.concatenate([cols, extra_c])


def trace(
    shape: tuple[int, int], lines: Sequence[np.ndarray], *, closed: bool = False
) -> np.ndarray:
    """Boolean mask of the pixels polylines pass through (see :func:`segment_pixels`).

    The pixels of each polyline form a 4-connected chain, which no 8-connected path
    can cross: a wall traced this way is an unbroken barrier however thin it is in
    the drawing.
    """
    mask = np.zeros(shape, bool)
    starts, ends = [], []
    for line in lines:
        pts = np.asarray(line, float)
        if len(pts) < 2:
            continue
        if closed:
            pts = np.vstack([pts, pts[:1]])
        starts.append(pts[:-1])
        ends.append(pts[1:])
    if not starts:
        return mask
    rows, cols = segment_pixels(np.concatenate(starts), np.concatenate(ends))
    ok = (rows >= 0) & (rows < shape[0]) & (cols >= 0) & (cols < shape[1])
    mask[rows[ok], cols[ok]] = True
    return mask
