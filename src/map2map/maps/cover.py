"""Keeping a map's straight wall runs inside the walls drawn for them (issue #32).

The plan drawer (:mod:`map2map.maps.vectorize`) places each straight wall on its
evidence's least-squares line. When that evidence is a corrector's walls (the classical
cleaning straightens every wall at the map's one angle, on the median of its faces), a
wall the SLAM map shows turned by drift, or bent, can be drawn across its own input: the
drawn wall covers the input's run at one end and leaves it at the other, and the
output breaks a wall the input shows whole (of the 160 input runs of 1 m or more that
``map2map autocorrect``'s default broke on 320 dev maps, the drawn wall ran more than a
degree off the run in 126, while a straight line within the pixels of 156 of them
existed).

This module moves such a wall as little as it must:

1. **Runs** (:func:`straight_runs`): the input's wall pixels lying in a straight run at
   least ``n`` pixels long along the rows of a canvas (the drawer's frame of one
   direction family), allowing a step of ``slack`` pixels across so that a wall a few
   degrees off the frame still counts as one run.
2. **Assignment**: each run goes to the wall of that orientation beside it (the run's
   least-squares line within ``band`` of the wall's line in the middle of where the two
   overlap, along at least half a run's minimum length; the nearest when there are
   several).
3. **Fit** (:func:`keep_runs_inside`): where the middle of the run's pixels, column by
   column, lies more than ``c`` from the wall's line, the wall's line moves, as little
   as it must at the run's two ends, into the band within which every column lies
   within ``c`` (:func:`_least_move`; a run too bent for any straight line: its own
   least-squares line).
4. **Bridges** (:func:`bridge_gaps`): where the walls drawn after all that still leave a
   run open (a gap of more than ``max_gap`` pixels with no drawn wall near the run,
   drawn wall along it on both sides, and along at least ``open_share`` of the gap none
   within ``open_`` across, nor within ``same`` with none of the input's free space
   between (the same wall): a jog SLAM drift put in a wall, a
   wall piece too short to keep, two pieces of a leaning wall drawn on two lines), a
   segment along the run's own pixels closes the gap. The input's wall is continuous
   there, so no door is closed. Optionally (``ends``) a run's end left open beyond its
   last covered column, and a run no drawn wall covers, are drawn the same way.

Examples
--------
>>> import numpy as np
>>> canvas = np.zeros((40, 120), bool)
>>> u = np.arange(10, 110)
>>> canvas[np.round(20 + 0.08 * (u - 60)).astype(int), u] = True   # turned 4.6 degrees
>>> lab, n = straight_runs(canvas, 20)
>>> n
1
>>> a0, a1 = keep_runs_inside(np.array([10.5]), np.array([109.5]), np.array([20.5]),
...                           np.array([20.5]), canvas, 20, band=6, c=2)
>>> [round(float(a0[0]), 1), round(float(a1[0]), 1)]       # the wall follows the run
[18.3, 22.6]
"""

from __future__ import annotations

import cv2
import numpy as np

from ..core.runs import open_runs, pixels

__all__ = ["straight_runs", "keep_runs_inside", "bridge_gaps"]


def straight_runs(canvas: np.ndarray, n: int, slack: int = 1) -> tuple[np.ndarray, int]:
    """Pixels of ``canvas`` (bool) in straight runs along its rows at least ``n`` long
    (``n`` rounded up to an odd number), steps of up to ``slack`` pixels across allowed:
    ``(labels, count)``, each run's pixels labelled ``1..count`` (8-connected after the
    step allowance), 0 elsewhere.

    >>> c = np.zeros((10, 30), bool); c[3, 2:20] = True; c[4, 20:28] = True; c[7, 5:9] = True
    >>> lab, k = straight_runs(c, 12)
    >>> k, int((lab > 0).sum())                       # the stepped run, not the short one
    (1, 26)
    """
    c = np.ascontiguousarray(canvas, bool)
    rr, cc, run, k = _runs(c, n, slack)
    lab = np.zeros(c.shape, np.int32)
    lab[rr, cc] = run + 1
    return lab, k


def _runs(c: np.ndarray, n: int, slack: int
          ) -> tuple[np.ndarray, np.ndarray, np.ndarray, int]:
    """:func:`straight_runs` as pixel lists: rows, columns, run (0-based), count."""
    if n < 2 or not c.any():
        e = np.zeros(0, np.int64)
        return e, e, e, 0
    c8 = c.view(np.uint8)
    wide = cv2.dilate(c8, np.ones((2 * slack + 1, 1), np.uint8)) if slack > 0 else c8
    opened = open_runs(wide, int(n) | 1, axis=1)
    _, lab = cv2.connectedComponents(opened.view(np.uint8), connectivity=8)
    rr, cc = pixels(c & opened)
    # a component of the widened runs may hold none of the canvas's own pixels: runs
    # are numbered over those that do (no empty run, whose mean would be 0 / 0)
    ids, run = np.unique(lab[rr, cc], return_inverse=True)
    return rr, cc, run.astype(np.int64).reshape(-1), int(len(ids))


def keep_runs_inside(lo: np.ndarray, hi: np.ndarray, a0: np.ndarray, a1: np.ndarray,
                     canvas: np.ndarray, n: int, *, band: float, c: float,
                     slack: int = 1) -> tuple[np.ndarray, np.ndarray]:
    """Across-positions of horizontal walls moved so that the straight runs of
    ``canvas`` beside them lie within ``c`` of their lines (module doc, steps 1-3).

    Parameters
    ----------
    lo, hi : (K,) float
        The walls' ends along (continuous coordinates: pixel ``j``'s centre is
        ``j + 0.5``).
    a0, a1 : (K,) float
        Their lines' positions across at ``lo`` and ``hi``.
    canvas : (H, W) bool
        The input's wall pixels, in the same frame (walls along the rows).
    n : int
        Shortest run (pixels) a wall must keep inside.
    band : float
        A run belongs to a wall when its line lies within this of the wall's line (in
        the middle of their overlap).
    c : float
        How far from the line (pixels) the middle of a run's pixels may lie: the drawn
        wall's half thickness plus a tolerance.
    slack : int
        Steps across allowed within a run (:func:`straight_runs`).

    Returns
    -------
    a0, a1 : (K,) float
        The new positions (copies; unchanged where the runs already lie inside).
    """
    a0 = np.asarray(a0, float).copy()
    a1 = np.asarray(a1, float).copy()
    lo, hi = np.asarray(lo, float), np.asarray(hi, float)
    if len(a0) == 0:
        return a0, a1
    rr, cc, run, k = _runs(np.ascontiguousarray(canvas, bool), n, slack)
    if k == 0:
        return a0, a1
    u, v = cc + 0.5, rr + 0.5
    span = np.maximum(hi - lo, 1e-9)
    # each run's least-squares line v = vb + b (u - ub) and its extent along
    cnt = np.bincount(run, minlength=k).astype(float)
    su, sv = np.bincount(run, u, k), np.bincount(run, v, k)
    ub, vb = su / cnt, sv / cnt
    var = np.bincount(run, u * u, k) / cnt - ub**2
    cov = np.bincount(run, u * v, k) / cnt - ub * vb
    b = np.where(var > 1e-9, cov / np.maximum(var, 1e-9), 0.0)
    u0 = np.full(k, np.inf)
    u1 = np.full(k, -np.inf)
    np.minimum.at(u0, run, u)
    np.maximum.at(u1, run, u)
    # each (wall, run): how far apart their lines are in the middle of their overlap
    s0 = np.maximum(lo[:, None], u0[None, :])
    s1 = np.minimum(hi[:, None], u1[None, :])
    um = (s0 + s1) / 2
    wall_v = a0[:, None] + (a1 - a0)[:, None] * (um - lo[:, None]) / span[:, None]
    dist = np.abs(vb[None, :] + b[None, :] * (um - ub[None, :]) - wall_v)
    ok = (s1 - s0 >= max(2, n // 2)) & (dist <= band)
    dist = np.where(ok, dist, np.inf)
    owner = np.where(ok.any(axis=0), np.argmin(dist, axis=0), -1)
    # the runs' pixels along their walls, and the walls some of them lie too far from
    pw = owner[run]
    own = pw >= 0
    pw, pu, pv, pc = pw[own], u[own], v[own], cc[own]
    along = (pu >= lo[pw]) & (pu <= hi[pw])
    pw, pu, pv, pc = pw[along], pu[along], pv[along], pc[along]
    fp = (pu - lo[pw]) / span[pw]
    far = np.abs(pv - (a0[pw] + (a1 - a0)[pw] * fp)) > c
    for i in np.unique(pw[far]):                    # a few walls a map
        m = pw == i
        q, vm = pc[m], pv[m]
        o = np.lexsort((vm, q))                     # by column, then across
        q, vm = q[o], vm[o]
        first = np.flatnonzero(np.r_[True, q[1:] != q[:-1]])
        last = np.r_[first[1:] - 1, len(q) - 1]
        fi = (q[first] + 0.5 - lo[i]) / span[i]
        mid = (vm[first] + vm[last]) / 2            # the middle of each column's pixels
        line = a0[i] + (a1[i] - a0[i]) * fi
        if np.max(np.abs(mid - line)) > c:
            a0[i], a1[i] = _least_move(a0[i], a1[i], fi, mid, c)
    return a0, a1


def _least_move(a0: float, a1: float, f: np.ndarray, mid: np.ndarray, c: float
                ) -> tuple[float, float]:
    """End positions near ``(a0, a1)`` whose line lies within ``c`` of ``mid`` at every
    fraction ``f`` along (``f`` in [0, 1]).

    With ``r`` the largest distance of ``mid`` from its own least-squares line, every
    line within ``c - r`` of that line at the first and the last ``f`` lies within ``c``
    of every ``mid`` (it is linear in between): the current line's values there are
    clipped into those two intervals, the least move when ``mid`` lies on a line
    (``r = 0``). Where ``r >= c`` no straight line does better than about the
    least-squares line, which is taken.

    >>> f = np.linspace(0, 1, 11)
    >>> [round(x, 2) for x in _least_move(0.0, 0.0, f, 4 * f, 1.0)]   # a turned run
    [0.0, 3.0]
    >>> [round(x, 2) for x in _least_move(2.0, 2.0, f, 4 * f, 1.0)]
    [1.0, 3.0]
    """
    if len(f) < 2 or np.ptp(f) <= 0:
        return a0, a1
    slope, icpt = np.polyfit(f, mid, 1)
    r = float(np.max(np.abs(mid - (icpt + slope * f))))
    room = max(c - r, 0.0)
    f0, f1 = float(f.min()), float(f.max())
    ends = []
    for fe in (f0, f1):
        fit = icpt + slope * fe
        ends.append(float(np.clip(a0 + (a1 - a0) * fe, fit - room, fit + room)))
    k = (ends[1] - ends[0]) / (f1 - f0)
    return ends[0] - k * f0, ends[0] + k * (1.0 - f0)


def bridge_gaps(canvas: np.ndarray, drawn: np.ndarray, n: int, *, near: float,
                open_: float, open_share: float = 0.5, max_gap: int = 2,
                slack: int = 1, free: np.ndarray | None = None, same: float = 0.0,
                same_free: float = 0.25, end_near: float = 0.0, ends: float = 0.0
                ) -> np.ndarray:
    """Segments that close the gaps drawn walls leave in the straight runs of
    ``canvas`` (module doc, step 4), in the canvas frame (walls along the rows).

    Parameters
    ----------
    canvas : (H, W) bool
        The input's wall pixels.
    drawn : (H, W) bool
        The drawn walls, in the same frame.
    n : int
        Shortest run (pixels) kept whole.
    near : float
        A column of a run is covered where a drawn wall lies within this many pixels
        across of one of its pixels.
    open_, open_share : float
        A gap is bridged only where, in at least ``open_share`` of its columns, no drawn
        wall lies within ``open_`` pixels across: a wall drawn beside the run (between
        the two lines of a wall SLAM saved twice, or straight beside a run drift turned,
        leaving it at one end) is not doubled.
    max_gap : int
        Gaps of at most this many columns are left.
    slack : int
        Steps across allowed within a run (:func:`straight_runs`).
    free : (H, W) bool, optional
        The input's free pixels. With ``same``: a column of the gap is not open either
        where a drawn wall lies within ``same`` pixels across with at most a
        ``same_free`` share of free pixels between it and the run: that wall and the
        run are one wall (the other line of a wall SLAM saved twice, with the wall's
        unobserved inside between), however far drift put them apart.
    same, same_free : float
        See ``free`` (``same`` 0: off).
    end_near : float
        In a run's first and last ``end_near`` columns a column is covered where a
        drawn wall lies within ``end_near`` across (0: ``near`` there too): a
        perpendicular wall that ends that close to the run (the drawer passes half
        its wall thickness plus a pixel: it would touch the run's wall, had that been
        drawn) closes the run's corner, so the gap between that corner and the rest of
        the run is found (a run whose own piece was dropped between two corners).
    ends : float
        Also close a run's end that no drawn wall covers for more than ``ends`` columns
        (from the run's last covered column to its end), and a run no drawn wall covers
        at all, under the same tests (0: off): a short wall the cleaning dropped.

    Returns
    -------
    (K, 4) float
        ``u0, v0, u1, v1`` (continuous coordinates: pixel ``(r, c)``'s centre is
        ``(c + 0.5, r + 0.5)``), from the last covered column before each gap to the
        first after it, through the middle of the run's pixels there.

    Examples
    --------
    A wall drawn in two pieces on two lines, 4 pixels apart, that the input shows
    whole, with a step:

    >>> canvas = np.zeros((30, 60), bool); canvas[10, 5:30] = True; canvas[11, 30:55] = True
    >>> drawn = np.zeros((30, 60), bool); drawn[9:12, 5:24] = True; drawn[13:16, 36:55] = True
    >>> bridge_gaps(canvas, drawn, 20, near=2, open_=3).tolist()
    [[23.5, 10.5, 36.5, 11.5]]
    >>> drawn[13:16, 24:36] = True                   # a wall beside the gap: left as it is
    >>> bridge_gaps(canvas, drawn, 20, near=2, open_=3).tolist()
    []

    A run drawn only along its first 20 columns, its end closed with ``ends``:

    >>> canvas = np.zeros((30, 60), bool); canvas[10, 5:55] = True
    >>> drawn = np.zeros((30, 60), bool); drawn[9:12, 5:25] = True
    >>> bridge_gaps(canvas, drawn, 20, near=2, open_=6).tolist()
    []
    >>> bridge_gaps(canvas, drawn, 20, near=2, open_=6, ends=5).tolist()
    [[24.5, 10.5, 54.5, 10.5]]
    """
    c = np.ascontiguousarray(canvas, bool)
    rr, cc, run, k = _runs(c, n, slack)
    if k == 0:
        return np.zeros((0, 4))
    d8 = np.ascontiguousarray(drawn, bool).view(np.uint8)

    def within(r: float) -> np.ndarray:
        m = int(np.floor(r))
        return cv2.dilate(d8, np.ones((2 * m + 1, 1), np.uint8))[rr, cc] > 0 if m > 0 \
            else d8[rr, cc] > 0

    cov = within(near)
    if end_near > near:
        lo, hi = np.full(k, c.shape[1]), np.full(k, -1)
        np.minimum.at(lo, run, cc)
        np.maximum.at(hi, run, cc)
        end = (cc - lo[run] < end_near) | (hi[run] - cc < end_near)
        cov |= end & within(end_near)
    W = c.shape[1]
    # per (run, column): covered by a drawn wall; middle of the run's pixels there
    key = run * W + cc
    uk, inv = np.unique(key, return_inverse=True)
    kc = np.zeros(len(uk), bool)
    np.logical_or.at(kc, inv, cov)
    kr, kcol = uk // W, uk % W
    # consecutive covered (run, column) entries p < q of one run (the keys are sorted by
    # run, then column): a gap of more than max_gap columns, every one of them held by
    # the run (q - p - 1 entries between); the gap's entries are i0 = p + 1 .. i1 - 1
    p = np.flatnonzero(kc)
    p, q = p[:-1], p[1:]
    gap = kcol[q] - kcol[p] - 1
    ok = (kr[p] == kr[q]) & (gap > max_gap) & (q - p - 1 == gap)
    i0, i1 = p[ok] + 1, q[ok]
    first = np.r_[0, np.flatnonzero(np.diff(kr)) + 1]          # each run's entries:
    last = np.r_[first[1:], len(kr)]                           # first .. last - 1
    if ends > 0:
        # ... and (ends) a run's ends beyond its covered columns (the whole run where
        # none is covered), more than ``ends`` columns held by the run throughout
        cs = np.r_[0, np.cumsum(kc)]
        cov_run = cs[last] > cs[first]
        idx = np.r_[np.flatnonzero(kc), 0]                     # (one more: never empty)
        lo_c = np.where(cov_run, idx[np.minimum(cs[first], len(idx) - 1)], last)
        hi_c = idx[np.maximum(cs[last] - 1, 0)][cov_run]
        e0 = np.r_[first, hi_c + 1]                            # left ends, right ends
        e1 = np.r_[lo_c, last[cov_run]]
        ln = e1 - e0
        ok_e = (ln > ends) & (kcol[np.maximum(e1 - 1, 0)]
                              - kcol[np.minimum(e0, len(kcol) - 1)] + 1 == ln)
        i0, i1 = np.r_[i0, e0[ok_e]], np.r_[i1, e1[ok_e]]
    if not len(i0):
        return np.zeros((0, 4))
    gap = i1 - i0
    # ... open along at least open_share of them: nothing drawn within open_ across,
    # nor (free, same) the same wall; looked at only in the gaps' pixels
    inside = np.zeros(len(uk) + 1, np.int64)
    np.add.at(inside, i0, 1)
    np.add.at(inside, i1, -1)
    sel = np.cumsum(inside[:-1])[inv] > 0
    opn = np.ones(len(rr), bool)
    opn[sel] = ~within(open_)[sel]
    if free is not None and same > 0 and sel.any():
        opn[sel] &= ~_one_wall(d8 > 0, np.asarray(free, bool), rr[sel], cc[sel], same,
                               same_free)
    ko = np.ones(len(uk), bool)
    np.logical_and.at(ko, inv, opn)
    held = np.r_[0, np.cumsum(ko)]
    share = (held[i1] - held[i0]) / np.maximum(gap, 1)
    ok = share >= open_share
    mid = np.bincount(inv, rr + 0.5) / np.bincount(inv)
    # the segment: from the covered entry before the gap to the one after it (the
    # run's own end entry where there is none)
    i0, i1 = i0[ok], i1[ok]
    a = np.where(i0 > first[kr[i0]], i0 - 1, i0)
    b = np.where(i1 < last[kr[i0]], i1, i1 - 1)
    segs = np.stack([kcol[a] + 0.5, mid[a], kcol[b] + 0.5, mid[b]], 1).astype(float)
    if free is not None and same > 0 and len(segs) > 1:
        segs = segs[_one_of_each_wall(segs, np.asarray(free, bool), same, same_free)]
    return segs


def _one_of_each_wall(segs: np.ndarray, free: np.ndarray, same: float,
                      share: float) -> np.ndarray:
    """Which of ``bridge_gaps``' segments (along the rows) to keep: of two that overlap
    along at least half the shorter, lie within ``same`` rows of each other and have at
    most a ``share`` of free pixels between them (the two lines of a wall SLAM saved
    twice, both left open by the drawn walls), only the longer. A few segments: a loop
    over pairs.

    >>> free = np.zeros((30, 60), bool)
    >>> segs = np.array([[5.5, 10.5, 50.5, 10.5], [8.5, 16.5, 40.5, 16.5]])
    >>> _one_of_each_wall(segs, free, 8, 0.25).tolist()
    [True, False]
    >>> free[12:16] = True                          # a corridor between: two walls
    >>> _one_of_each_wall(segs, free, 8, 0.25).tolist()
    [True, True]
    """
    u0, u1 = np.minimum(segs[:, 0], segs[:, 2]), np.maximum(segs[:, 0], segs[:, 2])
    v = (segs[:, 1] + segs[:, 3]) / 2
    order = np.argsort(-(u1 - u0), kind="stable")
    keep = np.ones(len(segs), bool)
    H, W = free.shape
    for n, i in enumerate(order):                   # longest first
        for j in order[:n]:
            if not keep[j]:
                continue
            lo, hi = max(u0[i], u0[j]), min(u1[i], u1[j])
            if hi - lo < 0.5 * (u1[i] - u0[i]) or abs(v[i] - v[j]) > same:
                continue
            r0 = int(np.clip(np.floor(min(v[i], v[j])) + 1, 0, H))
            r1 = int(np.clip(np.floor(max(v[i], v[j])), 0, H))
            c0, c1 = int(np.clip(np.floor(lo), 0, W)), int(np.clip(np.ceil(hi), 0, W))
            between = free[r0:r1, c0:c1]
            if between.size == 0 or between.mean() <= share:
                keep[i] = False
                break
    return keep


def _one_wall(drawn: np.ndarray, free: np.ndarray, rr: np.ndarray, cc: np.ndarray,
              same: float, share: float) -> np.ndarray:
    """Whether pixel ``(rr[i], cc[i])`` has a drawn pixel within ``same`` rows of it,
    above or below in its column, with at most a ``share`` of free pixels between
    (:func:`bridge_gaps`' ``free``). Column-wise running maxima and sums, no loops.

    Examples
    --------
    >>> drawn = np.zeros((20, 3), bool); drawn[4] = True
    >>> free = np.zeros((20, 3), bool); free[10:, 2] = True; free[5:10, 1] = True
    >>> _one_wall(drawn, free, np.array([10, 10, 10, 16]), np.array([0, 1, 2, 0]), 8,
    ...           0.25).tolist()
    [True, False, True, False]
    """
    H = drawn.shape[0]
    cols, cc = np.unique(cc, return_inverse=True)  # only the columns asked about
    drawn, free = drawn[:, cols], free[:, cols]
    rows = np.arange(H)[:, None]
    F = np.vstack([np.zeros((1, len(cols)), np.int64), np.cumsum(free, 0)])
    # nearest drawn row at or above each pixel (-1: none), and at or below (H: none)
    up = np.maximum.accumulate(np.where(drawn, rows, -1), axis=0)[rr, cc]
    dn = np.minimum.accumulate(np.where(drawn, rows, H)[::-1], axis=0)[::-1][rr, cc]
    out = np.zeros(len(rr), bool)
    for near, lo, hi in ((up, up + 1, rr), (dn, rr + 1, dn)):
        ok = (near >= 0) & (near < H) & (np.abs(near - rr) <= same)
        lo_, hi_ = np.clip(lo, 0, H), np.clip(hi, 0, H)
        n_free = F[hi_, cc] - F[lo_, cc]
        out |= ok & (n_free <= share * np.maximum(np.abs(near - rr) - 1, 1))
    return out
