"""A scan matcher's pull on a room it enters: the walls it shares with the rooms mapped
before it (:func:`shared_walls`) and the shift that lays the new room's faces of them onto
the faces already mapped (:func:`collapse_shift`), for the room-wise drift's
``RoomDriftParams.collapse`` (:mod:`map2map.learn.ab.room_drift`).

A particle filter entering a room sees, from the room's side, walls it has already mapped
from the other side; matching the scan to the map lays the new face on the old one, so a
run's map draws a wall seen from both rooms as one line and the new room sits the wall's
thickness towards the rooms mapped before it (docs/synthesize.md, session 25).

Examples
--------
>>> import numpy as np
>>> p = np.full((30, 41), 255, np.uint8); p[:, 18:23] = 0
>>> lab = np.where(np.arange(41) < 20.5, 1, 2)[None, :].repeat(30, 0)
>>> collapse_shift(shared_walls(p, lab, shortest=5), 2, [1]).tolist()
[-5.0, 0.0]
"""

from __future__ import annotations

import numpy as np
from scipy import ndimage

from ...core.grid import OCCUPIED

__all__ = ["MAX_WALL_PX", "MIN_SHARED_PX", "shared_walls", "collapse_shift"]

#: Thickest wall and shortest shared wall [px of a 256 px square] a collapsing step uses.
MAX_WALL_PX, MIN_SHARED_PX = 10.0, 10.0


def shared_walls(plan: np.ndarray, rooms: np.ndarray, thickest: float = MAX_WALL_PX,
                 shortest: float = MIN_SHARED_PX) -> dict:
    """The walls two rooms share: ``{(a, b): (normal, thickness, length)}`` for every
    ordered pair of rooms whose labels (``rooms``, every pixel labelled) meet inside the
    plan's walls along at least ``shortest`` px, ``normal`` the unit vector (x, y) across
    the wall from room ``a`` into room ``b``, ``thickness`` the wall's median thickness
    there (px; at most ``thickest``, else the pair is left out), ``length`` the pixels
    along it.

    Examples
    --------
    >>> p = np.full((30, 41), 255, np.uint8); p[:, 18:23] = 0
    >>> lab = np.where(np.arange(41) < 20.5, 1, 2)[None, :].repeat(30, 0)
    >>> n, t, ln = shared_walls(p, lab, shortest=5)[(1, 2)]
    >>> n.round(3).tolist(), t, ln
    ([1.0, 0.0], 5.0, 30)
    """
    occ = np.asarray(plan) == OCCUPIED
    rooms = np.asarray(rooms)
    # distance from a wall pixel to the nearest non-wall pixel
    dist = ndimage.distance_transform_edt(occ)
    H, W = occ.shape
    parts = []                      # per 4-neighbour pair of wall pixels in two rooms
    for dr, dc in ((0, 1), (1, 0), (0, -1), (-1, 0)):
        here = np.s_[max(0, -dr):H - max(0, dr), max(0, -dc):W - max(0, dc)]
        there = np.s_[max(0, dr):H + min(0, dr), max(0, dc):W + min(0, dc)]
        la, lb = rooms[here], rooms[there]
        m = occ[here] & occ[there] & (la != lb) & (la > 0) & (lb > 0)
        # the two pixels either side of the rooms' boundary: their distances to the free
        # space on their own side add up to the wall's thickness
        h = dist[here][m] + dist[there][m]
        parts.append((la[m], lb[m], np.full(h.size, dc), np.full(h.size, dr), h))
    a, b, dx, dy, h = (np.concatenate(v) for v in zip(*parts, strict=True))
    if a.size == 0:
        return {}
    keys, inv, n = np.unique(np.stack([a, b], 1), axis=0, return_inverse=True,
                             return_counts=True)
    inv = inv.ravel()
    sx, sy = np.bincount(inv, dx, len(keys)), np.bincount(inv, dy, len(keys))
    order = np.lexsort((h, inv))                   # each pair's thicknesses, sorted
    start = np.r_[0, np.cumsum(n)[:-1]]
    hs = h[order]
    med = 0.5 * (hs[start + (n - 1) // 2] + hs[start + n // 2])
    norm = np.hypot(sx, sy)
    ok = (n >= shortest) & (med <= thickest) & (norm > 0)
    return {(int(k[0]), int(k[1])): (np.array([x / r, y / r]), float(t), int(c))
            for k, x, y, r, t, c in zip(keys[ok], sx[ok], sy[ok], norm[ok], med[ok], n[ok],
                                        strict=True)}


def collapse_shift(walls: dict, child: int, mapped) -> np.ndarray:
    """The shift (x, y) [px] that lays room ``child``'s face of every wall it shares with
    the rooms ``mapped`` onto those rooms' faces (least squares over the walls, weighted by
    their length, :func:`shared_walls`): a scan matcher's pull when the robot, entering
    the room, sees from its side walls already mapped from the other; zero when it shares
    none.

    Examples
    --------
    >>> w = {(1, 2): (np.array([1.0, 0.0]), 5.0, 30), (3, 2): (np.array([0.0, 1.0]), 3.0, 20)}
    >>> collapse_shift(w, 2, [1]).round(3).tolist(), collapse_shift(w, 2, [1, 3]).round(3).tolist()
    ([-5.0, 0.0], [-5.0, -3.0])
    """
    A, y = np.zeros((2, 2)), np.zeros(2)
    for r in mapped:
        e = walls.get((int(r), int(child)))
        if e is None:
            continue
        n, t, ln = e
        A += ln * np.outer(n, n)
        y += ln * t * n
    if not A.any():
        return np.zeros(2)
    # along a room's single shared wall the shift is free: the minimum-norm solution
    return -np.linalg.pinv(A, rcond=1e-6) @ y
