"""Observed wall faces of an input map and how anchored walls are drawn on them
(step 4b of :mod:`~map2map.learn.ba.postprocess`): numba kernels that find the faces along
a segment, fit their line, paint and trace the drawn walls, put collinear faces on one
line and grow thin two-sided walls."""

from __future__ import annotations

import numpy as np
from numba import njit

from ...core.grid import FREE, OCCUPIED

__all__ = ["collinear_faces", "thicken_two_sided"]


def surface_masks(data: np.ndarray) -> tuple[np.ndarray, ...]:
    """Occupied pixels with a free neighbour above, below, left, right (the wall surfaces
    a laser saw, facing that way)."""
    occ, free = data == OCCUPIED, data == FREE
    up, dn, lf, rt = (np.zeros_like(occ) for _ in range(4))
    up[1:] = occ[1:] & free[:-1]
    dn[:-1] = occ[:-1] & free[1:]
    lf[:, 1:] = occ[:, 1:] & free[:, :-1]
    rt[:, :-1] = occ[:, :-1] & free[:, 1:]
    return up, dn, lf, rt


@njit(cache=True, nogil=True)
def _median_round(v: np.ndarray, n: int) -> int:
    """``int(np.round(np.median(v[:n])))`` of integers (round half to even, as numpy)."""
    w = np.sort(v[:n])
    if n % 2:
        return int(w[n // 2])
    return int(np.round((w[n // 2 - 1] + w[n // 2]) / 2.0))


@njit(cache=True, nogil=True)
def _line_fit(x, y, n, trim):
    """Least-squares slope of ``y`` over ``x`` (first ``n`` entries), refitted once
    without the points farther than ``trim`` from the first line; (slope, points used)."""
    sx = sy = sxx = sxy = 0.0
    for i in range(n):
        sx += x[i]
        sy += y[i]
        sxx += x[i] * x[i]
        sxy += x[i] * y[i]
    var = sxx - sx * sx / n
    if var <= 0.0:
        return 0.0, 0
    q = (sxy - sx * sy / n) / var
    p = (sy - q * sx) / n
    sx = sy = sxx = sxy = 0.0
    m = 0
    for i in range(n):
        if abs(y[i] - p - q * x[i]) <= trim:
            sx += x[i]
            sy += y[i]
            sxx += x[i] * x[i]
            sxy += x[i] * y[i]
            m += 1
    if m < 2:
        return q, n
    var = sxx - sx * sx / m
    if var <= 0.0:
        return q, n
    return (sxy - sx * sy / m) / var, m


@njit(cache=True, nogil=True)
def faces_kernel(up, dn, lf, rt, horiz, a, b, lo, hi, min_cover, slope):
    """Face positions of every segment k (rows ``a[k]..b[k]`` across it, ``lo[k]..hi[k]``
    along it, clipped to the map), along the tilted line of ``slope[k]`` (pixels across
    per pixel along, about the segment's middle ``m``: at position ``j`` the rows are
    shifted by ``round(slope (j - m))``): at each position along it the first
    (``up``/``lf``) and the last (``dn``/``rt``) face pixel across it; per side, the
    median of those positions (minus the shift), rounded half to even, or -1 where under
    ``min_cover`` of the positions along the segment see one.

    Returns (K, 2) int64: (first, last), and (K, 2) float64: the least-squares slope of
    the face pixels about that tilted line (both sides together, each side with at least
    ``max(3, min_cover)`` of the positions; trimmed once at 1.5 px) and the number of
    pixels it rests on (0: none)."""
    H, W = up.shape
    K = horiz.shape[0]
    out = np.full((K, 2), -1, np.int64)
    fit = np.zeros((K, 2), np.float64)
    n_max = max(H, W)
    buf0 = np.empty(n_max, np.int64)
    buf1 = np.empty(n_max, np.int64)
    pos0 = np.empty(n_max, np.float64)
    pos1 = np.empty(n_max, np.float64)
    for k in range(K):
        lim = H if horiz[k] else W
        s0 = max(0, lo[k])
        s1 = min(W if horiz[k] else H, hi[k] + 1)
        length = max(0, s1 - s0)
        mid = (lo[k] + hi[k]) / 2.0
        n0 = 0
        n1 = 0
        for j in range(s0, s1):
            sh = int(np.round(slope[k] * (j - mid)))
            i0 = max(0, a[k] + sh)
            i1 = min(lim - 1, b[k] + sh)
            for i in range(i0, i1 + 1):  # first face pixel across the wall
                if (up[i, j] if horiz[k] else lf[j, i]):
                    buf0[n0] = i - a[k] - sh
                    pos0[n0] = j - mid
                    n0 += 1
                    break
            for i in range(i1, i0 - 1, -1):  # last face pixel
                if (dn[i, j] if horiz[k] else rt[j, i]):
                    buf1[n1] = i - a[k] - sh
                    pos1[n1] = j - mid
                    n1 += 1
                    break
        need = min_cover * max(1, length)
        if n0 > 0 and n0 >= need:
            out[k, 0] = a[k] + _median_round(buf0, n0)
        if n1 > 0 and n1 >= need:
            out[k, 1] = a[k] + _median_round(buf1, n1)
        num = den = 0.0
        if n0 >= 3 and n0 >= need:
            q0, m0 = _line_fit(pos0, buf0, n0, 1.5)
            num += q0 * m0
            den += m0
        if n1 >= 3 and n1 >= need:
            q1, m1 = _line_fit(pos1, buf1, n1, 1.5)
            num += q1 * m1
            den += m1
        if den > 0:
            fit[k, 0] = num / den
            fit[k, 1] = den
    return out, fit


@njit(cache=True, nogil=True)
def paint_walls(mask, free, horiz, r0, r1, lo, hi, stop_at_free, slope):
    """Fill each wall's box (rows ``r0..r1`` across, ``lo..hi`` along; negative starts
    clip to 0) in ``mask``, its rows shifted at position ``j`` along it by
    ``round(slope (j - m))`` (``m`` its middle; slope 0: an axis-aligned box); where
    ``stop_at_free``, only its non-free pixels (a wall extended behind a face stops at
    space the input saw free)."""
    H, W = mask.shape
    for k in range(horiz.shape[0]):
        mid = (lo[k] + hi[k]) / 2.0
        n_along = W if horiz[k] else H
        n_across = H if horiz[k] else W
        for j in range(max(0, lo[k]), min(n_along, max(0, hi[k] + 1))):
            sh = int(np.round(slope[k] * (j - mid)))
            for i in range(max(0, r0[k] + sh), min(n_across, max(0, r1[k] + sh + 1))):
                if horiz[k]:
                    if not (stop_at_free[k] and free[i, j]):
                        mask[i, j] = True
                elif not (stop_at_free[k] and free[j, i]):
                    mask[j, i] = True


@njit(cache=True, nogil=True)
def drawn_runs(free, horiz, r0, r1, lo, hi, stop_at_free, slope):
    """Where along each wall of :func:`paint_walls` it was drawn, as straight centre
    lines: ``(runs, centre)``, ``runs`` (R, 3) int64 rows ``(k, j0, j1)`` and
    ``centre`` (K,) float64.

    Wall ``k``'s centre line crosses position ``j`` at ``centre[k] + slope (j - m)``
    (``m`` its middle along it); ``centre[k]`` is the median, over the positions where
    it painted anything, of the middle of the pixels it painted there (its box's middle
    ``(r0 + r1) / 2`` where it painted the whole box; a wall that stops at space the
    input saw free (``stop_at_free``) may paint only part of its box). The runs are the
    maximal stretches ``j0..j1`` (``j1 > j0``: a run of one position, a segment of
    length 0, is left out) at which one of the pixels it painted lies within one pixel
    across of the pixel holding its centre line, ``floor(c + 0.5)`` (pixel ``i`` spans
    ``[i - 0.5, i + 0.5)``). A wall drawn nowhere (a network wall across a room the
    robot saw empty) has none."""
    H, W = free.shape
    K = horiz.shape[0]
    rows = np.empty((K + 1 + (max(H, W) + 1) // 2 * K, 3), np.int64)
    centre = np.empty(K, np.float64)
    mids = np.empty(max(H, W) + 1, np.float64)
    n = 0
    for k in range(K):
        mid = (lo[k] + hi[k]) / 2.0
        n_along = W if horiz[k] else H
        n_across = H if horiz[k] else W
        j_start = max(0, lo[k])
        j_end = min(n_along, max(0, hi[k] + 1))
        m = 0
        for j in range(j_start, j_end):
            sh = int(np.round(slope[k] * (j - mid)))
            first = -1
            last = -1
            for i in range(max(0, r0[k] + sh), min(n_across, max(0, r1[k] + sh + 1))):
                if not stop_at_free[k] or not (free[i, j] if horiz[k] else free[j, i]):
                    if first < 0:
                        first = i
                    last = i
            if first >= 0:
                mids[m] = (first + last) / 2.0 - sh
                m += 1
        centre[k] = np.median(mids[:m]) if m else (r0[k] + r1[k]) / 2.0
        start = -1
        for j in range(j_start, j_end + 1):
            hit = False
            if j < j_end:
                sh = int(np.round(slope[k] * (j - mid)))
                cc = int(np.floor(centre[k] + slope[k] * (j - mid) + 0.5))
                i0 = max(max(0, r0[k] + sh), cc - 1)
                i1 = min(min(n_across - 1, r1[k] + sh), cc + 1)
                for i in range(i0, i1 + 1):
                    if not stop_at_free[k] or not (free[i, j] if horiz[k] else free[j, i]):
                        hit = True
                        break
            if hit and start < 0:
                start = j
            elif not hit and start >= 0:
                if j - 1 > start:
                    rows[n, 0] = k
                    rows[n, 1] = start
                    rows[n, 2] = j - 1
                    n += 1
                start = -1
    return rows[:n].copy(), centre


def align_faces(found: list, tol: float) -> None:
    """Put faces of one orientation and side that lie within ``tol`` of each other on one
    line (in place): their length-weighted median, rounded."""
    for horiz in (True, False):
        for k in (1, 2):  # the first (top/left) faces, then the last (bottom/right) ones
            items = [f for f in found if f[0] == horiz and f[k] is not None]
            items.sort(key=lambda f: f[k])
            group: list = []
            for f in items + [None]:
                if f is not None and group and f[k] - group[0][k] <= tol:
                    group.append(f)
                    continue
                if len(group) > 1:
                    pos = np.array([g[k] for g in group], float)
                    w = np.array([g[4] - g[3] + 1 for g in group], float)
                    order = np.argsort(pos)
                    cum = np.cumsum(w[order])
                    med = pos[order][np.searchsorted(cum, cum[-1] / 2)]
                    for g in group:
                        g[k] = int(med)
                group = [f] if f is not None else []


def collinear_faces(horiz: np.ndarray, side: np.ndarray, face: np.ndarray,
                    lo: np.ndarray, hi: np.ndarray, slope: np.ndarray,
                    tol: float) -> np.ndarray:
    """Observed wall faces that lie on one line, put on it: the length-weighted **mean**
    line of each group (step 4b, ``ANCHOR.collinear``).

    A CAD plan draws the pieces of one wall line (a corridor wall cut by doors, the
    walls of a row of rooms) exactly collinear; a SLAM map's drift displaces the pieces
    by different amounts, each by a pixel or two. Faces of one orientation and side
    (``horiz``, ``side`` 0: top/left, 1: bottom/right) are compared by where their
    line crosses the map's axis (``face - slope * m``, ``m`` the face's middle
    ``(lo + hi) / 2``: the faces are tilted by the map's common ``slope``); sorted by
    it, consecutive faces within ``tol`` pixels form a group, wherever they lie along
    the line. Every face of a group moves to the group's line, weighted by its length
    ``hi - lo + 1`` (long pieces dominate), rounded to whole pixels. The mean, not the
    median: the pieces' drift scatters them about the plan's line; measured on the
    gen6300 val split (``git show e59abf4^:docs/learn.md``, "Moving drifted walls"), the
    mean line is closer to the plan's (median: no closer than the pieces themselves).

    Parameters
    ----------
    horiz, side : ndarray (K,) bool, int
        The faces' orientation and side.
    face : ndarray (K,) int
        Row (horizontal) or column (vertical) of each face pixel at the face's middle.
    lo, hi : ndarray (K,) int
        The face's extent along it.
    slope : ndarray (K,) float
        Pixels across per pixel along (:func:`map_tilt`, the vertical faces' sign turned).
    tol : float
        Grouping distance, pixels.

    Returns
    -------
    ndarray (K,) int
        The faces, moved (a face alone in its group stays).

    Examples
    --------
    >>> h = np.array([True, True, True]); side = np.zeros(3, int)
    >>> face = np.array([20, 22, 40]); lo = np.array([0, 60, 0]); hi = np.array([49, 69, 49])
    >>> collinear_faces(h, side, face, lo, hi, np.zeros(3), tol=3).tolist()
    [20, 20, 40]
    """
    face = np.asarray(face, np.int64)
    if len(face) < 2:
        return face.copy()
    lo, hi = np.asarray(lo), np.asarray(hi)
    slope = np.asarray(slope, float)
    length = (hi - lo + 1).astype(float)
    mid = (lo + hi) / 2.0
    icpt = face - slope * mid
    kind = 2 * np.asarray(horiz, np.int64) + np.asarray(side, np.int64)
    o = np.lexsort((icpt, kind))
    k, x = kind[o], icpt[o]
    new = np.ones(len(o), bool)
    new[1:] = (k[1:] != k[:-1]) | (np.diff(x) > tol)
    group = np.cumsum(new) - 1
    line = np.bincount(group, x * length[o]) / np.bincount(group, length[o])
    out = np.round(line[group] + slope[o] * mid[o]).astype(np.int64)
    alone = np.bincount(group)[group] == 1
    out[alone] = face[o][alone]
    res = np.empty_like(face)
    res[o] = out
    return res


def thicken_two_sided(first: np.ndarray, last: np.ndarray, width: int) -> tuple[np.ndarray,
                                                                              np.ndarray]:
    """Walls seen from both sides that are thinner than ``width`` pixels, grown to it by
    moving both faces out by the same whole number of pixels (step 4b,
    ``ANCHOR.min_thick``).

    A wall seen from two rooms has both faces in the map, but an occupancy grid traces
    it thinner than it is: measured on the gen6300 val split (docs/autocorrect.md, "Moving
    drifted walls"), the plan's faces of such walls lie 0.63 px (median) further out
    than the map's on each side -- the plan's walls are 4-6 px thick where the map's
    are 2-4. A wall ``d = width - (last - first + 1)`` pixels too thin gets
    ``d // 2`` pixels on each side (an odd pixel is left out: moving one face only would
    move the wall's centre).

    Parameters
    ----------
    first, last : ndarray (K,) int
        The two face pixels' positions across each wall (``first <= last``).
    width : int
        The thickness to grow to, pixels (the plan's walls; 0: off).

    Examples
    --------
    >>> f, l = thicken_two_sided(np.array([10, 10, 10]), np.array([11, 12, 16]), 5)
    >>> f.tolist(), l.tolist()          # 2 px -> 4 (3 missing, 1 each side), 3 -> 5, 7 stays
    ([9, 9, 10], [12, 13, 16])
    """
    first, last = np.asarray(first, np.int64), np.asarray(last, np.int64)
    grow = np.maximum(0, int(width) - (last - first + 1)) // 2
    return first - grow, last + grow
