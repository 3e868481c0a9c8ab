"""What step 4b keeps of the input and leaves out of the network's output: free specks
dropped, the input's kept wall pieces where they are drawn, and the network's walls at
an open frontier (:mod:`~map2map.learn.ba.postprocess`)."""

from __future__ import annotations

import cv2
import numpy as np
from numba import njit

from ...core.grid import FREE, UNKNOWN
from .anchor import ANCHOR

__all__ = ["drop_free_specks", "drawn_pieces", "frontier_walls"]


def drop_free_specks(data: np.ndarray, min_area: float) -> np.ndarray:
    """``data`` with its free components (4-connected) smaller than ``min_area`` pixels
    made unknown.

    A SLAM map's free space is one region the robot's laser swept; small free islands
    apart from it are rays that slipped through a wall or past its end (most lie
    beyond the outer walls). Kept, each gives the wall beside it a face towards space
    the plan does not have (free on the far side of an outer wall) and the anchored
    walls of step 4b a second, spurious face. Measured on Table 5.3 (docs/autocorrect.md).

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
    (8-neighbourhood, the one-pixel tolerance of :func:`drawn_runs`); pieces shorter
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
                   share: float | None = None) -> np.ndarray:
    """Which segments (x0, y0, x1, y1) have no seen space on one of their sides: at more
    than ``share`` (default ``ANCHOR.frontier_share``) of 32 points along each, the ``guide`` is
    unknown (or outside it) at
    all of ``tol``, ``2 tol`` and ``3 tol`` pixels across the segment on one side.

    A wall the input does not show is drawn only over its unknown pixels (step 4b stops
    such walls at free space). Between two spaces the robot saw, it closes a gap the
    laser missed (free or walls on both sides: evidence). At the edge of the known area
    (seen space on one side, unknown beyond) or out in unknown space it closes an open
    frontier: on a partial map (a robot that drove the corridors and looked into some
    rooms) the edge of what it saw is not a wall, and the model, which learnt whole
    buildings, closes it (``git show e59abf4^:docs/learn.md``, "Real maps beyond the
    training scale"). Step 4b with ``open_frontiers`` leaves those out.

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
    return open_side.mean(axis=1) > (ANCHOR.frontier_share if share is None else share)
