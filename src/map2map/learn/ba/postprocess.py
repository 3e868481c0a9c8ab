"""Model_32's post-processing (thesis sec. 3.1): from the 32 x 32 output (or the 64 x 64
one of the default model) back to the input's resolution, without the blur.

The network sees and writes 32 x 32 maps; a map at 256 px (or at its own resolution)
needs 8x (or more) upsampling, and plain upsampling gives grey, blurred walls.
:func:`postprocess` does exactly this, in this order:

1. **Upsampling** -- bilinear (``cv2.INTER_LINEAR``, pixel centres aligned) of the grey
   output to the working frame ``(H, W)``; a wall cell of the 32 map becomes a dark band
   centred on that cell.
2. **Snapping** to the three map values: ``< 96`` occupied (a third of the way from
   occupied 0 to free 255, past the occupied/unknown midpoint because blur only ever
   lightens a wall: a thin dark line of the output is a wall, not unknown space),
   ``>= 191`` free (halfway between unknown and free), unknown in between.
3. **Straightening of walls** (``straighten=True``,
   :func:`map2map.maps.segments.straight_segments`): the occupied pixels are thinned to
   their centre lines (``skimage.morphology.skeletonize``), the centre lines are cut into
   straight segments (probabilistic Hough transform, ``cv2.HoughLinesP``, segments at
   least half a model cell long); a segment within ``10`` degrees of horizontal or vertical
   is made exactly horizontal/vertical at its mean coordinate; collinear overlapping
   segments are merged; a segment end that stops short of (or overshoots) a
   perpendicular wall by less than a model cell is moved onto it, so corners and
   T-junctions close.
4. **Guided refinement** (when the input map is given as ``guide``): a model cell is
   ``f = H / s`` pixels (``s`` the model's size), so the network cannot place a wall
   closer than about ``f / 2``.
   Each axis-aligned segment is moved (across its direction only, by at most ``f / 2``)
   onto the mean position of the input map's occupied pixels in that band, when they
   cover at least 30 % of its length. The input's walls are bent, noisy and doubled in
   places; averaging them along a straight segment keeps only their mean position.
4b. **Anchored walls** (``anchor=True``, the default when a ``guide`` is given; replaces
   steps 4-5): a SLAM map's wall faces are already where the laser hit them, within a
   pixel or so of the plan's, and a 64 px network cannot place a wall better than a few
   pixels of a 256 map (docs/learn.md measures it). So the walls are the input's own,
   straightened at full resolution: its wall pixels are cut into straight segments
   (step 3 on the input, ``ANCHOR_CELL`` = 4 dataset pixels), and each wall is drawn
   with its faces at the **median** position of the input's faces along it
   (:func:`anchored_walls`, within ``ANCHOR_BAND`` = 3 dataset pixels): a noisy, jagged
   face becomes one straight face where it was seen; a wall seen from one side only
   gets the training targets' thickness behind its face (the plan's thick walls, so
   wall recall rises), never into space the input saw free. The network decides what
   the input does not show: its straight walls lying farther than ``ANCHOR_NEW`` (4
   dataset pixels) from any input wall over 70 % of their length are added (walls the
   robot never saw); one whose band (the network draws walls several model cells thick)
   comes within ``ANCHOR_NEW`` of an input wall seen from one side is that wall's body
   behind its face (the plans' thick outer walls) and is drawn with it as one wall,
   from the face to the band's far side (:func:`_join_backing`; drawn apart, the two
   were the demo's doubled outer walls, issue #14). Input wall pixels that no straight
   wall explains (corners, short
   pieces) are kept where the network has a wall within a model cell (elsewhere they
   are clutter: furniture, people); those a straight wall replaces take the value of
   their nearest non-wall pixel. Free and unknown space come from the input, except
   free space the network calls unknown more than two model cells from any wall (laser
   streaks through windows and open doors), which becomes unknown. Two more rules,
   measured on Table 5.3 (docs/learn.md, "Why 43 % of the maps were not improved"):
   free islands of the input smaller than ``ANCHOR_SPECK`` (30 dataset pixels squared)
   become unknown first (:func:`drop_free_specks`: rays that slipped through or past
   a wall, mostly beyond the outer walls; kept, they gave the anchored walls faces
   the plan does not have), and the faces are straight lines at the map's own wall
   angle, not along the pixel grid (``tilt``, :func:`anchored_walls`: a SLAM map is
   turned against its plan by its heading error, and a face made exactly horizontal on
   a wall turned by 2 degrees leaves it up to 1.7 px off across 100 px). Two more, for
   the walls that SLAM drift displaced (docs/learn.md, "Moving drifted walls"): faces
   of one orientation and side whose lines lie within ``ANCHOR_COLLINEAR`` (3 dataset
   pixels) of each other go to their length-weighted mean line
   (:func:`collinear_faces`: the pieces of one wall line, which the plan draws
   collinear), and a wall seen from both sides thinner than ``ANCHOR_MIN_THICK`` (5
   dataset pixels) is grown to it, both faces out by the same amount
   (:func:`thicken_two_sided`: an occupancy grid traces walls thinner than the plan's).
5. **Redrawing**: the segments are drawn with the thickness of the training targets'
   walls (``wall_px``, measured on the dataset at training time and scaled to the frame),
   occupied blobs of step 2 that no segment explains (columns, furniture) are kept when at
   least one model cell in area. Free and unknown come from the output with its wall
   cells replaced by their nearest non-wall cell, upsampled the same way and split at 191
   (halfway between unknown 127 and free 255): the grey halo that upsampling leaves beside
   every wall is not taken for unknown space. Last, unknown pockets enclosed by free space
   and walls become free (a plan has no unknown inside the building).

The result is a three-valued map plus its wall segments (pixel coordinates of the
working frame, ``x`` = column, ``y`` = row), which ``map2map autocorrect --dxf`` writes as
vector lines. With anchored walls the segments are exactly the walls drawn (issue #14):
each wall's centre line where that wall painted pixels on it, within a pixel
(:func:`_drawn_runs`; a wall that stops at free space is cut there, one drawn nowhere
has none), plus the straight pieces of the input's wall pixels kept as they are
(:func:`drawn_pieces`).

Examples
--------
>>> import numpy as np
>>> small = np.full((32, 32), 255.0, np.float32)
>>> small[10, 4:28] = 0.0                           # one horizontal wall at row 10
>>> out, seg = postprocess(small, (256, 256), wall_px=3)
>>> out.shape, sorted(np.unique(out).tolist())
((256, 256), [0, 255])
>>> seg.shape[1], bool(np.all(seg[:, 1] == seg[:, 3]))  # x0 y0 x1 y1, horizontal
(4, True)
"""

from __future__ import annotations

import cv2
import numpy as np
from numba import njit
from scipy import ndimage

from ...core.grid import FREE, OCCUPIED, UNKNOWN
from ...maps.segments import join_supported, straight_segments

__all__ = ["postprocess", "wall_thickness_px", "straight_segments", "anchored_walls",
           "map_tilt", "drop_free_specks", "collinear_faces", "thicken_two_sided",
           "drawn_pieces", "frontier_walls"]

#: Grey level below which an upsampled output pixel is wall (step 2).
WALL_BELOW = 96
#: Grey level from which it is free rather than unknown (step 2).
FREE_FROM = 191


def wall_thickness_px(maps: np.ndarray, limit: int = 64) -> float:
    """Median wall thickness (pixels) of ternary maps: occupied area / centre-line length.

    Examples
    --------
    >>> m = np.full((1, 40, 40), 255, np.uint8); m[0, 10:13, 5:35] = 0
    >>> round(wall_thickness_px(m), 1)       # a 3-px wall (its centre line is a bit short)
    3.1
    """
    from skimage.morphology import skeletonize

    out = []
    for m in np.asarray(maps)[:limit]:
        occ = m == OCCUPIED
        skel = skeletonize(occ).sum()
        if skel:
            out.append(occ.sum() / skel)
    return float(np.median(out)) if out else 1.0


def _refine(segs: np.ndarray, guide_occ: np.ndarray, shift: float) -> np.ndarray:
    """Move axis-aligned segments across onto the mean of the guide's walls (step 4)."""
    out = segs.copy()
    H, W = guide_occ.shape
    d = int(np.ceil(shift))
    for s in out:
        horiz, vert = s[1] == s[3], s[0] == s[2]
        if horiz == vert:
            continue
        if horiz:
            c = s[1]
            lo, hi = int(max(0, min(s[0], s[2]))), int(min(W, max(s[0], s[2]) + 1))
            r0, r1 = int(max(0, np.floor(c) - d)), int(min(H, np.ceil(c) + d + 1))
            band = guide_occ[r0:r1, lo:hi]
            offs = np.arange(r0, r1)
            counts = band.sum(axis=1)
        else:
            c = s[0]
            lo, hi = int(max(0, min(s[1], s[3]))), int(min(H, max(s[1], s[3]) + 1))
            r0, r1 = int(max(0, np.floor(c) - d)), int(min(W, np.ceil(c) + d + 1))
            band = guide_occ[lo:hi, r0:r1]
            offs = np.arange(r0, r1)
            counts = band.sum(axis=0)
        length = max(1, hi - lo)
        covered = band.any(axis=0 if horiz else 1).sum() if band.size else 0
        if covered < 0.3 * length or counts.sum() == 0:
            continue
        new = float(np.sum(offs * counts) / counts.sum())
        if abs(new - c) <= shift:
            if horiz:
                s[1] = s[3] = new
            else:
                s[0] = s[2] = new
    return out


def _surface_masks(data: np.ndarray) -> tuple[np.ndarray, ...]:
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
def _faces_kernel(up, dn, lf, rt, horiz, a, b, lo, hi, min_cover, slope):
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
def _paint_walls(mask, free, horiz, r0, r1, lo, hi, stop_at_free, slope):
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
def _drawn_runs(free, horiz, r0, r1, lo, hi, stop_at_free, slope):
    """Where along each wall of :func:`_paint_walls` it was drawn, as straight centre
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


def _align_faces(found: list, tol: float) -> None:
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
    line of each group (step 4b, ``ANCHOR_COLLINEAR``).

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
    gen6300 val split (docs/learn.md, "Moving drifted walls"), the mean line is closer
    to the plan's (median: no closer than the pieces themselves).

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
    ``ANCHOR_MIN_THICK``).

    A wall seen from two rooms has both faces in the map, but an occupancy grid traces
    it thinner than it is: measured on the gen6300 val split (docs/learn.md, "Moving
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


def _axis_aligned(segs: np.ndarray) -> np.ndarray:
    """Which segments (x0, y0, x1, y1) are horizontal or vertical (those step 4b uses)."""
    s = np.asarray(segs, float).reshape(-1, 4)
    return (s[:, 1] == s[:, 3]) != (s[:, 0] == s[:, 2])


def _join_backing(walls: np.ndarray, faces: np.ndarray, backing: np.ndarray,
                  reach: float) -> list[tuple[int, int]]:
    """Walls of the network that back an input wall seen from one side, joined to it
    (in place): each ``backing`` wall's box is stretched across to the nearest observed
    face in front of it (same orientation, within ``reach`` of the backing wall's box
    middle, the two side by side along at least half of the shorter), so that face and band
    are drawn as one wall, not as two with a gap between them.

    ``walls`` (K, 6): horiz, r0, r1, lo, hi, stop_at_free; ``faces`` (K, 2) the observed
    faces (-1: none) of the same walls. Returns the pairs (backing wall, face wall)
    joined."""
    pairs = []
    one = (faces[:, 0] >= 0) != (faces[:, 1] >= 0)          # seen from one side only
    face = np.where(faces[:, 0] >= 0, faces[:, 0], faces[:, 1])
    behind = np.where(faces[:, 0] >= 0, 1, -1)             # where its body lies
    for k in np.flatnonzero(backing & ~(faces >= 0).any(axis=1)):
        h, r0, r1, lo, hi = walls[k, :5]
        c = (r0 + r1) / 2.0
        dist = behind * (c - face)                          # backing wall behind the face
        overlap = np.minimum(walls[:, 4], hi) - np.maximum(walls[:, 3], lo)
        ok = one & ~backing & (walls[:, 0] == h) & (dist > 0) & (dist <= reach) \
            & (overlap >= 0.5 * np.minimum(hi - lo, walls[:, 4] - walls[:, 3]))
        if ok.any():
            j = np.flatnonzero(ok)[np.argmin(dist[ok])]
            if behind[j] > 0:
                walls[k, 1] = min(r0, face[j])
            else:
                walls[k, 2] = max(r1, face[j])
            pairs.append((int(k), int(j)))
    return pairs


def _cut_runs(runs: np.ndarray, pairs: list[tuple[int, int]], walls: np.ndarray) -> np.ndarray:
    """Runs (k, j0, j1) of :func:`_drawn_runs` without the stretches of a face wall that a
    backing wall joined to it covers along (its centre line there is the joined wall's:
    one wall, one line)."""
    runs = [tuple(r) for r in runs]
    for k, j in pairs:
        lo, hi = walls[k, 3], walls[k, 4]
        out = []
        for r in runs:
            if r[0] != j or r[2] < lo or r[1] > hi:
                out.append(r)
                continue
            if r[1] < lo - 1:
                out.append((j, r[1], lo - 1))
            if r[2] > hi + 1:
                out.append((j, hi + 1, r[2]))
        runs = out
    return np.array(runs, np.int64).reshape(-1, 3)


def _observed_faces(guide: np.ndarray, segs: np.ndarray, band: float, min_cover: float,
                    tilt: bool) -> tuple[np.ndarray, ...]:
    """The guide's observed faces of each axis-aligned segment, before any rule moves
    them (:func:`anchored_walls`' first step): ``(horiz, faces (K, 2), lo, hi, centre,
    slope)``; a face is -1 where none was found."""
    H, W = guide.shape
    up, dn, lf, rt = _surface_masks(guide)
    s = np.asarray(segs, float).reshape(-1, 4)
    horiz, vert = s[:, 1] == s[:, 3], s[:, 0] == s[:, 2]
    s, horiz = s[horiz != vert], horiz[horiz != vert]  # axis-aligned segments only
    c = np.where(horiz, s[:, 1], s[:, 0])
    # np.round as Python's round on these floats: both round half to even
    lo = np.round(np.where(horiz, np.minimum(s[:, 0], s[:, 2]),
                           np.minimum(s[:, 1], s[:, 3]))).astype(np.int64)
    hi = np.round(np.where(horiz, np.maximum(s[:, 0], s[:, 2]),
                           np.maximum(s[:, 1], s[:, 3]))).astype(np.int64)
    lim = np.where(horiz, H, W)
    a = np.maximum(0, np.floor(c - band)).astype(np.int64)
    b = np.minimum(lim - 1, np.ceil(c + band)).astype(np.int64)
    slope = np.zeros(len(s))
    f, fit = _faces_kernel(up, dn, lf, rt, horiz, a, b, lo, hi, float(min_cover), slope)
    if tilt:
        g = map_tilt(np.where(horiz, fit[:, 0], -fit[:, 0]), hi - lo + 1, fit[:, 1] > 0)
        if g != 0.0:
            slope = np.where(horiz, g, -g)
            f, _ = _faces_kernel(up, dn, lf, rt, horiz, a, b, lo, hi, float(min_cover),
                                 slope)
    return horiz, f, lo, hi, c, slope


def anchored_walls(guide: np.ndarray, segs: np.ndarray, *, band: float, wall_px: float,
                   min_cover: float = 0.3, align: float = 0.0, grow: int = 0,
                   tilt: bool = True, collinear: float = 0.0,
                   min_thick: int = 0, backing: np.ndarray | None = None,
                   reach: float = 0.0) -> tuple[np.ndarray, np.ndarray]:
    """Walls of axis-aligned segments placed on the guide's observed surfaces (step 4b).

    For each segment, the guide's (input map's) wall surfaces facing free space within
    ``band`` pixels across it are found column by column (row by row for a vertical
    one); when they cover at least ``min_cover`` of its length, the wall face on that
    side is put at their **median** position (a straight face through the noisy,
    observed one). A wall seen from both sides spans its two faces; a wall seen from one
    side gets ``wall_px`` of thickness behind its face, stopping at space the input saw
    free; a wall with no observed face keeps the segment's position and ``wall_px``.

    With ``tilt`` (default), the faces are straight lines at the **map's own wall
    angle** rather than along the pixel grid: a SLAM map is turned against its plan by
    its heading error (the metric's rigid alignment turns 22 of the 38 val maps of the
    gen6300 build by 1 to 7.6 degrees; :func:`~map2map.learn.ba.autocorrect.autocorrect`
    deskews anchored maps only beyond 6), and a face made exactly horizontal on a wall
    turned by 2 degrees leaves it, across a 100 px wall, up to 1.7 px off at its ends.
    The angle is one for the map (the building's walls are parallel or perpendicular,
    so one rotation turns them all): each segment's observed faces get a least-squares slope
    (trimmed once at 1.5 px), and the length-weighted median over the segments (a
    vertical wall's slope counted with its sign turned) is the map's, limited to
    :data:`ANCHOR_TILT_MAX_DEG`; the faces are then found again along lines of that
    slope and drawn along them, rasterised (the shift across a wall at position ``j``
    is ``round(slope (j - m))``, ``m`` its middle). A map whose walls run along the grid
    gets slope 0: the walls of ``tilt=False``.

    With ``align > 0``, faces of one orientation and side within ``align`` pixels of each
    other (pieces of one wall line cut by doors, bent apart by drift) are put on one
    line, their length-weighted median. ``grow`` moves every observed face that many
    pixels out into the free space it faces (a plan drawn with thicker walls than the
    laser sees). Both were measured worse (docs/learn.md) and are off by default.

    With ``collinear > 0``, observed faces whose lines lie within ``collinear`` pixels of
    each other go to their length-weighted mean line (:func:`collinear_faces`); with
    ``min_thick > 0``, walls seen from both sides thinner than ``min_thick`` pixels are
    grown to it (:func:`thicken_two_sided`). Their defaults (0) are the walls before
    2026-11-25's "Moving drifted walls"; :func:`postprocess` passes
    ``ANCHOR_COLLINEAR`` and ``ANCHOR_MIN_THICK``.

    ``backing`` (bool per segment) marks the network's walls that back an input wall:
    each is drawn from the nearest face seen from one side in front of it (within
    ``reach`` pixels of its middle) to its own far side, as one wall with it
    (:func:`_join_backing`), and that face's wall has no centre line of its own there.

    Returns
    -------
    mask : ndarray (H, W) bool
        The walls.
    centre : ndarray (R, 4)
        Their centre lines (x0, y0, x1, y1) in pixels where they were drawn
        (:func:`_drawn_runs`): a wall cut by free space gives several, one drawn
        nowhere none.

    Examples
    --------
    >>> g = np.full((20, 30), 255, np.uint8)
    >>> g[9:11, 2:28] = 0; g[11, 2:28:3] = 0            # a noisy wall: faces rows 9, 10
    >>> m, c = anchored_walls(g, np.array([[2.0, 11.0, 27.0, 11.0]]), band=3, wall_px=2)
    >>> sorted(set(np.nonzero(m)[0].tolist())), np.round(c[0], 1).tolist()
    ([9, 10], [2.0, 9.5, 27.0, 9.5])
    >>> t = np.full((40, 80), 255, np.uint8)             # a wall turned by 2 degrees
    >>> for x in range(5, 75): t[18 + int(round((x - 40) * np.tan(np.radians(2)))), x] = 0
    >>> seg = np.array([[5.0, 18.0, 74.0, 18.0]])
    >>> m, c = anchored_walls(t, seg, band=3, wall_px=1)
    >>> int((m & (t != 0)).sum()), np.round(c[0], 1).tolist()   # 1 of 70 pixels off
    (1, [5.0, 16.8, 74.0, 19.2])
    >>> m, c = anchored_walls(t, seg, band=3, wall_px=1, tilt=False)
    >>> int((m & (t != 0)).sum())                      # along the grid: 41 off
    41
    """
    H, W = guide.shape
    free = guide == FREE
    t = max(1, int(round(wall_px)))
    horiz, f, lo, hi, c, slope = _observed_faces(guide, segs, band, min_cover, tilt)
    if collinear > 0:
        f = f.copy()
        for k in (0, 1):
            seen = f[:, k] >= 0
            f[seen, k] = collinear_faces(horiz[seen], np.full(seen.sum(), k), f[seen, k],
                                         lo[seen], hi[seen], slope[seen], collinear)
    if min_thick > 0:
        both = (f[:, 0] >= 0) & (f[:, 1] >= 0) & (f[:, 0] <= f[:, 1])
        f = f.copy()
        f[both, 0], f[both, 1] = thicken_two_sided(f[both, 0], f[both, 1], min_thick)
    found = [[bool(h), None if f0 < 0 else int(f0) - grow, None if f1 < 0 else int(f1) + grow,
              int(lo_), int(hi_), float(c_)]
             for h, (f0, f1), lo_, hi_, c_ in zip(horiz, f, lo, hi, c, strict=True)]
    if align > 0:
        _align_faces(found, align)
    boxes = []
    for horiz_k, f0, f1, lo_k, hi_k, c_k in found:
        if f0 is not None and f1 is not None and f0 <= f1:
            r0, r1, ext = f0, f1, False
        elif f0 is not None:
            r0, r1, ext = f0, f0 + t - 1, True
        elif f1 is not None:
            r0, r1, ext = f1 - t + 1, f1, True
        else:
            r0 = int(round(c_k - (t - 1) / 2))
            r1, ext = r0 + t - 1, True
        boxes.append((horiz_k, r0, r1, lo_k, hi_k, ext))
    walls = np.array(boxes, np.int64).reshape(-1, 6)
    joined = _join_backing(walls, f, np.asarray(backing, bool)[_axis_aligned(segs)], reach) \
        if backing is not None and len(walls) else []
    mask = np.zeros((H, W), bool)  # painting is an OR: order is free
    args = (walls[:, 0].astype(bool), walls[:, 1], walls[:, 2], walls[:, 3], walls[:, 4],
            walls[:, 5].astype(bool), np.asarray(slope, float))
    _paint_walls(mask, free, *args)
    # the centre lines where each wall was drawn: a wall that stops at free space is cut
    # there, one that was drawn nowhere (a network wall across a room seen empty) has none
    runs, across = _drawn_runs(free, *args)
    if joined:
        runs = _cut_runs(runs, joined, walls)
    k, j0, j1 = runs[:, 0], runs[:, 1].astype(float), runs[:, 2].astype(float)
    across = across[k]
    mid = (walls[k, 3] + walls[k, 4]) / 2.0
    q = np.asarray(slope, float)[k]
    c0, c1 = across + q * (j0 - mid), across + q * (j1 - mid)
    h = walls[k, 0].astype(bool)
    centres = np.where(h[:, None], np.stack([j0, c0, j1, c1], 1),
                       np.stack([c0, j0, c1, j1], 1))
    return mask, centres.reshape(-1, 4)


def map_tilt(slopes: np.ndarray, lengths: np.ndarray, ok: np.ndarray | None = None) -> float:
    """The map's common wall slope (pixels across per pixel along, horizontal walls'
    sign): the length-weighted median of the segments' fitted slopes (``ok`` those
    with a fit), limited to :data:`ANCHOR_TILT_MAX_DEG`; 0 without any.

    Examples
    --------
    >>> float(map_tilt(np.array([0.03, 0.035, 0.5, 0.0]), np.array([50, 80, 5, 10]),
    ...                np.array([True, True, True, False])))
    0.035
    """
    q = np.asarray(slopes, float)
    w = np.asarray(lengths, float)
    if ok is not None:
        q, w = q[ok], w[ok]
    if not len(q) or w.sum() <= 0:
        return 0.0
    o = np.argsort(q, kind="stable")
    cum = np.cumsum(w[o])
    med = float(q[o][np.searchsorted(cum, cum[-1] / 2)])
    m = float(np.tan(np.radians(ANCHOR_TILT_MAX_DEG)))
    return float(np.clip(med, -m, m))


#: Anchoring scales in pixels of the dataset's 256 px maps (multiplied by ``data_px``).
ANCHOR_CELL, ANCHOR_BAND, ANCHOR_NEW = 4.0, 3.0, 4.0
#: Faces closer than this (dataset pixels) are put on one line (0: off).
ANCHOR_ALIGN = 0.0
#: Observed faces whose lines lie within this (dataset pixels) of each other are put on
#: their length-weighted mean line (:func:`collinear_faces`; 0: off).
ANCHOR_COLLINEAR = 3.0
#: Walls seen from both sides are grown to this thickness (dataset px, rounded;
#: :func:`thicken_two_sided`; 0: off).
ANCHOR_MIN_THICK = 5.0
#: Unknown pockets of the anchored output that free space or walls enclose go back to free
#: where the input shows free (:func:`_anchored`; False: off).
ANCHOR_FILL_POCKETS = True
#: Pixels (dataset) each observed face moves out into its free space.
ANCHOR_GROW = 0.0
#: Largest map wall angle (degrees) the anchored faces follow (:func:`anchored_walls`).
ANCHOR_TILT_MAX_DEG = 6.0
#: Gaps (dataset pixels) across which collinear pieces of an input wall are joined when
#: the input shows the wall there and a perpendicular wall ends in the gap (a T-junction,
#: where the Hough transform cuts a wall; :func:`~map2map.maps.segments.join_supported`;
#: 0: off). Session 13: gen1500 val 96 -> 97 of 101 maps improved, test 95 -> 95 of 99
#: (without the T-junction condition: test 91, not kept); docs/learn.md, "Joining walls
#: Hough cut".
ANCHOR_JOIN = 16.0
#: Free components of the input smaller than this (dataset pixels squared) are unknown.
ANCHOR_SPECK = 30.0
#: With ``open_frontiers``: a network wall with more than this share of its length
#: without seen space on one side is left out (:func:`frontier_walls`).
ANCHOR_FRONTIER_SHARE = 0.5


def drop_free_specks(data: np.ndarray, min_area: float) -> np.ndarray:
    """``data`` with its free components (4-connected) smaller than ``min_area`` pixels
    made unknown.

    A SLAM map's free space is one region the robot's laser swept; small free islands
    apart from it are rays that slipped through a wall or past its end (most lie
    beyond the outer walls). Kept, each gives the wall beside it a face towards space
    the plan does not have (free on the far side of an outer wall) and the anchored
    walls of step 4b a second, spurious face. Measured on Table 5.3 (docs/learn.md).

    Examples
    --------
    >>> d = np.full((12, 20), 127, np.uint8); d[1:6, 1:19] = 255; d[6, 1:19] = 0
    >>> d[8, 4] = d[8, 12] = 255                      # two free specks beyond the wall
    >>> out = drop_free_specks(d, 4)
    >>> int((out == 255).sum()), int(out[8, 4]), int(out[2, 2])
    (90, 127, 255)
    """
    free = (np.asarray(data) == FREE).astype(np.uint8)
    n, lab = cv2.connectedComponents(free, connectivity=4)
    small = np.bincount(lab.ravel(), minlength=n) < min_area
    small[0] = False  # label 0: the pixels that are not free
    if not small.any():
        return np.asarray(data)
    out = np.array(data, copy=True)
    out[small[lab]] = UNKNOWN
    return out


def drawn_pieces(segs: np.ndarray, occ: np.ndarray) -> np.ndarray:
    """The pieces of segments (x0, y0, x1, y1; pixel ``i`` spans ``[i - 0.5, i + 0.5)``)
    that lie on ``occ``: every point of a piece falls in a pixel of ``occ`` or next to one
    (8-neighbourhood, the one-pixel tolerance of :func:`_drawn_runs`); pieces shorter
    than a pixel are left out.

    Exact, not sampled: each segment is cut where it crosses a pixel border, and each
    stretch between two crossings lies in one pixel (a piece's ends are moved inwards
    by ``1e-6`` of the segment, so that none lies on a border).

    Examples
    --------
    >>> occ = np.zeros((10, 30), bool); occ[4, 2:10] = occ[4, 20:28] = True
    >>> np.round(drawn_pieces(np.array([[2.0, 4.0, 27.0, 4.0]]), occ), 3).tolist()
    [[2.0, 4.0, 10.5, 4.0], [18.5, 4.0, 27.0, 4.0]]
    """
    s = np.asarray(segs, float).reshape(-1, 4)
    occ = np.asarray(occ, bool)
    if not len(s) or not occ.any():
        return np.zeros((0, 4))
    near = cv2.dilate(occ.astype(np.uint8), np.ones((3, 3), np.uint8)) > 0
    return _drawn_pieces(np.ascontiguousarray(s), near)


@njit(cache=True, nogil=True)
def _drawn_pieces(s: np.ndarray, near: np.ndarray) -> np.ndarray:
    """Kernel of :func:`drawn_pieces` (``near``: ``occ`` dilated by one pixel); the same
    arithmetic, in the same order, as the NumPy version it replaced (tested equal)."""
    H, W = near.shape
    out = np.empty((0, 4))
    rows = []
    eps = 1e-6
    for i in range(s.shape[0]):
        x0, y0, x1, y1 = s[i, 0], s[i, 1], s[i, 2], s[i, 3]
        n = 2
        for a, b in ((x0, x1), (y0, y1)):
            if b != a:
                n += max(0, int(np.floor(max(a, b) - 0.5) - np.ceil(min(a, b) - 0.5)) + 1)
        ts = np.empty(n)
        ts[0], ts[1] = 0.0, 1.0
        j = 2
        for a, b in ((x0, x1), (y0, y1)):  # borders at k + 0.5 crossed between a and b
            if b != a:
                k0 = np.ceil(min(a, b) - 0.5)
                for q in range(int(np.floor(max(a, b) - 0.5) - k0) + 1):
                    ts[j] = ((k0 + q) + 0.5 - a) / (b - a)
                    j += 1
        t = np.unique(np.minimum(np.maximum(ts[:j], 0.0), 1.0))
        if len(t) < 2:
            continue
        on = np.zeros(len(t) + 1, np.bool_)     # one point inside each stretch
        for q in range(len(t) - 1):
            m = (t[q] + t[q + 1]) / 2
            r = np.int64(np.floor(y0 + m * (y1 - y0) + 0.5))
            c = np.int64(np.floor(x0 + m * (x1 - x0) + 0.5))
            on[q] = 0 <= r < H and 0 <= c < W and near[r, c]
        q = 0
        while q < len(t) - 1:
            if not on[q]:
                q += 1
                continue
            a = q
            while on[q]:
                q += 1
            ta, tb = t[a] + eps, t[q] - eps
            p0, p1 = x0 + ta * (x1 - x0), y0 + ta * (y1 - y0)
            p2, p3 = x0 + tb * (x1 - x0), y0 + tb * (y1 - y0)
            if np.hypot(p2 - p0, p3 - p1) >= 1.0:
                rows.append((p0, p1, p2, p3))
    if len(rows):
        out = np.empty((len(rows), 4))
        for q in range(len(rows)):
            out[q, 0], out[q, 1], out[q, 2], out[q, 3] = rows[q]
    return out


def frontier_walls(segs: np.ndarray, guide: np.ndarray, tol: float,
                   share: float = ANCHOR_FRONTIER_SHARE) -> np.ndarray:
    """Which segments (x0, y0, x1, y1) have no seen space on one of their sides: at more
    than ``share`` of 32 points along each, the ``guide`` is unknown (or outside it) at
    all of ``tol``, ``2 tol`` and ``3 tol`` pixels across the segment on one side.

    A wall the input does not show is drawn only over its unknown pixels (step 4b stops
    such walls at free space). Between two spaces the robot saw, it closes a gap the
    laser missed (free or walls on both sides: evidence). At the edge of the known area
    (seen space on one side, unknown beyond) or out in unknown space it closes an open
    frontier: on a partial map (a robot that drove the corridors and looked into some
    rooms) the edge of what it saw is not a wall, and the model, which learnt whole
    buildings, closes it (docs/learn.md, "Real maps beyond the training scale"). Step
    4b with ``open_frontiers`` leaves those out.

    Examples
    --------
    >>> g = np.full((40, 60), 127, np.uint8); g[5:35, 5:30] = 255   # known: left part
    >>> g[5:35, 17:19] = 127                  # a strip the laser missed inside it
    >>> segs = np.array([[18.0, 5, 18, 34],   # in that strip: seen space on both sides
    ...                  [30.0, 5, 30, 34],   # along the edge of the known area
    ...                  [45.0, 5, 45, 34]])  # in unknown space
    >>> frontier_walls(segs, g, tol=3).tolist()
    [False, True, True]
    """
    s = np.asarray(segs, float).reshape(-1, 4)
    if not len(s):
        return np.zeros(0, bool)
    known = np.asarray(guide) != UNKNOWN
    H, W = known.shape
    t = np.linspace(0.0, 1.0, 32)
    px = s[:, 0, None] + t * (s[:, 2, None] - s[:, 0, None])          # (K, 32)
    py = s[:, 1, None] + t * (s[:, 3, None] - s[:, 1, None])
    d = np.hypot(s[:, 2] - s[:, 0], s[:, 3] - s[:, 1])
    d = np.where(d > 0, d, 1.0)
    nx, ny = -(s[:, 3] - s[:, 1]) / d, (s[:, 2] - s[:, 0]) / d          # unit normals
    open_side = np.zeros(px.shape, bool)
    for sign in (-1.0, 1.0):
        seen = np.zeros(px.shape, bool)
        for k in (1, 2, 3):
            x = np.round(px + sign * k * tol * nx[:, None]).astype(np.int64)
            y = np.round(py + sign * k * tol * ny[:, None]).astype(np.int64)
            ok = (x >= 0) & (x < W) & (y >= 0) & (y < H)
            hit = np.zeros(px.shape, bool)
            hit[ok] = known[y[ok], x[ok]]
            seen |= hit
        open_side |= ~seen
    return open_side.mean(axis=1) > share


def _anchored(output_segs: np.ndarray, guide: np.ndarray, wall_px: float, data_px: float,
              net_walls: np.ndarray | None = None, net_space: np.ndarray | None = None,
              cell: float = 8.0, thick_px: float | None = None,
              open_frontiers: bool = False) -> tuple[np.ndarray, np.ndarray]:
    """Step 4 in ``anchor`` mode: the guide's own walls straightened at full resolution,
    plus the network's walls the guide does not show (module docstring)."""
    thick_px = data_px if thick_px is None else thick_px
    guide = drop_free_specks(guide, ANCHOR_SPECK * data_px * data_px)
    occ = guide == OCCUPIED
    own = straight_segments(occ, ANCHOR_CELL * data_px)
    if ANCHOR_JOIN > 0:
        own = join_supported(own, occ, max(1.5, ANCHOR_CELL * data_px / 4),
                             ANCHOR_JOIN * data_px, junction=ANCHOR_CELL * data_px)
    segs = own
    backing = None
    if len(output_segs):
        d = cv2.distanceTransform((~occ).astype(np.uint8), cv2.DIST_L2, 5) if occ.any() \
            else np.full(occ.shape, np.inf)
        o = np.asarray(output_segs, float).reshape(-1, 4)
        t = np.linspace(0.0, 1.0, 32)
        ys = np.clip(np.round(o[:, 1, None] + t * (o[:, 3, None] - o[:, 1, None])).astype(int),
                     0, occ.shape[0] - 1)
        xs = np.clip(np.round(o[:, 0, None] + t * (o[:, 2, None] - o[:, 0, None])).astype(int),
                     0, occ.shape[1] - 1)
        far = np.mean(d[ys, xs] > ANCHOR_NEW * data_px, axis=1) > 0.7
        apart = far
        if net_walls is not None and net_walls.any():
            # the network draws a wall as a band several model cells thick: measured
            # from the band's edge, not from its centre line (half its thickness away),
            # a network wall over an input wall is that wall, not a second one beside it
            # (drawn apart, the two are the doubled walls of issue #14); where the input
            # saw the wall from one side only, the band shows how far its body reaches
            # behind the face (the plans' outer walls are thicker than the rest)
            half = cv2.distanceTransform(net_walls.astype(np.uint8), cv2.DIST_L2, 5)
            apart = np.mean(d[ys, xs] - half[ys, xs] > ANCHOR_NEW * data_px, axis=1) > 0.7
        if open_frontiers:
            # a wall of the network's alone (not the body behind an input wall) at the
            # edge of the known area or beyond it is not evidence: left out
            far &= ~(apart & frontier_walls(o, guide, ANCHOR_NEW * data_px))
        new = o[far]
        if len(new):
            segs = np.concatenate([own, new])
            backing = np.concatenate([np.zeros(len(own), bool), ~apart[far]])
    mask, centres = anchored_walls(guide, segs, band=ANCHOR_BAND * data_px, wall_px=wall_px,
                                   align=ANCHOR_ALIGN * data_px,
                                   grow=int(round(ANCHOR_GROW * data_px)),
                                   collinear=ANCHOR_COLLINEAR * data_px,
                                   min_thick=int(round(ANCHOR_MIN_THICK * thick_px)),
                                   backing=backing, reach=max(1, int(round(wall_px)))
                                   + (ANCHOR_BAND + ANCHOR_NEW) * data_px)
    # the input's walls: replaced by their nearest non-wall value where a straight wall
    # explains them, kept where none does (corners, short pieces, what Hough missed).
    # (Free within 2 px, else unknown, was measured worse: 48 vs 56 of 104 improved --
    # it opens free pixels beside the straight faces, i.e. new wall faces.)
    if occ.any() and not occ.all():
        _, (ri, ci) = ndimage.distance_transform_edt(occ, return_indices=True)
        data = np.asarray(guide)[ri, ci]
    else:
        data = np.asarray(guide).copy()
    near = cv2.dilate(mask.astype(np.uint8), np.ones((5, 5), np.uint8)) > 0
    keep = occ & ~near
    if net_walls is not None and net_space is not None:
        # the network cleans what the input shows but a plan does not: unexplained wall
        # pixels (clutter, furniture) are kept only within a model cell of its walls, and
        # free space it calls unknown (laser streaks through windows and doors) becomes
        # unknown when farther than two model cells from any wall
        k = 2 * int(np.ceil(cell)) + 1
        keep &= cv2.dilate(net_walls.astype(np.uint8), np.ones((k, k), np.uint8)) > 0
        far = cv2.distanceTransform((~(net_walls | mask)).astype(np.uint8), cv2.DIST_L2, 5)
        data[(data == FREE) & (net_space == UNKNOWN) & (far > 2 * cell)] = UNKNOWN
    data[keep] = OCCUPIED
    data[mask] = OCCUPIED
    if ANCHOR_FILL_POCKETS:
        # ... but not a pocket the input shows free and free space or walls enclose (the
        # network's unknown inside a room, e.g. where it imagined a wall): a plan has none
        pocket = ndimage.binary_fill_holes(data != UNKNOWN) & (data == UNKNOWN)
        data[pocket & (guide == FREE)] = FREE
    # the input's wall pixels kept as they are (no straight wall replaced them) are walls
    # of the output too: their straight pieces, where drawn, go with the straight walls
    kept = keep & ~mask
    pieces = straight_segments(kept, ANCHOR_CELL * data_px) if kept.any() \
        else np.zeros((0, 4))
    return data, np.concatenate([centres, drawn_pieces(pieces, data == OCCUPIED)])


def postprocess(output: np.ndarray, shape: tuple[int, int], guide: np.ndarray | None = None,
                *, wall_px: float = 2.0, straighten: bool = True, anchor: bool = True,
                data_px: float = 1.0, thick_px: float | None = None,
                open_frontiers: bool = False) -> tuple[np.ndarray, np.ndarray]:
    """Model output (grey, [0, 255], model size) -> (ternary uint8 map of ``shape``,
    wall segments (K, 4) in its pixels); the steps are in the module docstring.

    Parameters
    ----------
    output : ndarray (s, s) float
        The generator's output as grey values (:func:`map2map.learn.nets.networks.from_unit`).
    shape : (H, W)
        The working frame to return to.
    guide : ndarray (H, W) uint8, optional
        The input map in that frame (step 4).
    wall_px : float
        Thickness of the redrawn walls, pixels of the frame.
    straighten : bool
        Steps 3-5; False stops after snapping.
    anchor : bool
        With a ``guide``: step 4b (anchored walls) instead of 4-5.
    data_px : float
        Pixels of the frame per pixel of the dataset's maps (scales step 4b).
    thick_px : float, optional
        The same, for the thickness two-sided walls are grown to in step 4b
        (``ANCHOR_MIN_THICK``; default ``data_px``): with ``wall_px`` what
        :func:`~map2map.learn.ba.autocorrect.autocorrect`'s ``thickness`` sets.
    open_frontiers : bool
        Step 4b leaves out the network's walls at the edge of the input's known area or
        beyond it (:func:`frontier_walls`).
    """
    H, W = shape
    low = np.asarray(output, np.float32)
    up = cv2.resize(low, (W, H), interpolation=cv2.INTER_LINEAR)
    walls = up < WALL_BELOW
    # free vs unknown from the output with its wall cells replaced by their nearest
    # non-wall cell: a wall's grey halo (between 64 and 191 after upsampling) is not unknown
    low_walls = low < WALL_BELOW
    if low_walls.any() and not low_walls.all():
        _, (ri, ci) = ndimage.distance_transform_edt(low_walls, return_indices=True)
        low = low[ri, ci]
    up_space = cv2.resize(low, (W, H), interpolation=cv2.INTER_LINEAR)
    data = np.where(up_space >= FREE_FROM, FREE, UNKNOWN).astype(np.uint8)
    if not straighten:
        data[walls] = OCCUPIED
        return data, np.zeros((0, 4))
    cell = H / low.shape[0]
    segs = straight_segments(walls, cell)
    if guide is not None and anchor:
        return _anchored(segs, np.asarray(guide), wall_px, data_px, walls, data, cell,
                         thick_px, open_frontiers)
    if guide is not None and len(segs):
        segs = _refine(segs, np.asarray(guide) == OCCUPIED, cell / 2)
    drawn = np.zeros((H, W), np.uint8)
    t = max(1, int(round(wall_px)))
    for x0, y0, x1, y1 in segs:
        cv2.line(drawn, (int(round(x0)), int(round(y0))), (int(round(x1)), int(round(y1))),
                 1, thickness=t)
    if t % 2 == 0 and len(segs):  # cv2 draws odd widths; even ones get one more pixel row
        drawn = cv2.dilate(drawn, np.ones((2, 2), np.uint8))
    near = cv2.dilate(drawn, np.ones((3, 3), np.uint8), iterations=max(1, int(cell)))
    blobs, n = ndimage.label(walls & ~near.astype(bool))
    if n:
        area = np.bincount(blobs.ravel())
        keep = np.flatnonzero(area >= cell * cell)
        keep = keep[keep > 0]
        data[np.isin(blobs, keep)] = OCCUPIED
    wall = drawn.astype(bool)
    data[wall] = OCCUPIED
    # a plan has no unknown pockets inside the building: fill what walls and free enclose
    inside = ndimage.binary_fill_holes((data == FREE) | (data == OCCUPIED))
    data[inside & (data == UNKNOWN)] = FREE
    return data, segs

