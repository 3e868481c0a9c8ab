"""Drift room by room: how much of the error is each room's own translation, and does
the map show it? (issue #32; docs/autocorrect.md, "Why no network moves the walls").

A particle filter's pose error changes slowly while the robot maps a room, so much of a
SLAM map's remaining error could be one translation per room. This diagnostic cuts the
map's free space into rooms (:func:`rooms`: the watershed of the distance transform
that Model_AB's room drift cuts plans with), gives every pixel to its nearest room (a
wall face to the room it faces), and moves each room by one translation:

- :func:`fit_rooms` fits each room's translation **knowing the plan** (the plan's
  same-side face distances, :func:`map2map.learn.ba.field.face_distances`, Charbonnier,
  a grid search within 3 px): the ceiling of any room-wise correction;
- :func:`solve_rooms` estimates them **from the map alone**, by robust least squares
  over the rooms (x and y apart): the two faces of an interior wall lie a thickness
  apart (the map's median), faces looking the same way on one line across rooms are
  collinear, and a weak pull towards zero.

Examples
--------
Two rooms side by side; the right one mapped 2 px too far right:

>>> import numpy as np
>>> m = np.full((60, 100), 127, np.uint8)
>>> m[10:50, 10:48] = 255; m[10:50, 52:90] = 255
>>> m[8:10, 8:92] = 0; m[50:52, 8:92] = 0; m[8:52, 8:10] = 0; m[8:52, 48:52] = 0
>>> m[8:52, 90:92] = 0
>>> lab, near = rooms(m)
>>> int(lab.max()), int(near[30, 50]) in (1, 2)
(2, True)
"""

from __future__ import annotations

import numpy as np
from scipy import ndimage as ndi

__all__ = ["rooms", "fit_rooms", "solve_rooms", "room_field"]

#: (dx, dy) towards the free neighbour of a face in each channel of
#: :func:`map2map.learn.ba.field.face_sets` (+x, +y, -x, -y).
_STEP = {0: (1, 0), 1: (0, 1), 2: (-1, 0), 3: (0, -1)}


def rooms(m: np.ndarray, h_px: float = 4.0) -> tuple[np.ndarray, np.ndarray]:
    """``(labels, nearest)``: the map's free space cut into rooms by the same watershed
    of its distance transform that cuts a plan's (:func:`map2map.learn.ab.room_drift.
    segment_rooms`; labels 0 outside the free space), and every pixel's nearest room."""
    from map2map.learn.ab.room_drift import segment_rooms

    near = segment_rooms(m, h_px=h_px)
    return np.where(m == 255, near, 0), near


def room_field(nearest: np.ndarray, shifts: dict | np.ndarray) -> np.ndarray:
    """(2, H, W) displacement field: every pixel moved by its room's (dx, dy)."""
    u = np.zeros((2,) + nearest.shape, np.float32)
    items = shifts.items() if isinstance(shifts, dict) else enumerate(shifts)
    for r, (dx, dy) in items:
        sel = nearest == r
        u[0][sel], u[1][sel] = dx, dy
    return u


def fit_rooms(slam: np.ndarray, plan_b: np.ndarray, nearest: np.ndarray,
              reach: float = 3.0, step: float = 0.5, lam: float = 0.02) -> dict:
    """Each room's translation fitted to the plan (in the SLAM map's pixels): the grid
    point within ``reach`` px whose moved faces lie closest to the plan's faces looking
    the same way (Charbonnier, clipped at 4 px) plus ``lam`` |t|^2; rooms with fewer than
    10 face pixels stay."""
    from map2map.learn.ba.field import face_distances, face_sets

    fs, d = face_sets(slam), face_distances(plan_b)
    cand = np.arange(-reach, reach + 1e-9, step)
    out = {}
    for r in np.unique(nearest):                  # a few dozen rooms
        pts = [np.nonzero(fs[k] & (nearest == r)) for k in range(4)]
        n = sum(len(p[0]) for p in pts)
        best, bt = np.inf, (0.0, 0.0)
        if n >= 10:
            for dx in cand:
                for dy in cand:
                    c = 0.0
                    for k in range(4):
                        ys, xs = pts[k]
                        v = ndi.map_coordinates(d[k], [ys + dy, xs + dx], order=1,
                                                mode="nearest")
                        c += (np.sqrt(np.minimum(v, 4.0) ** 2 + 0.04) - 0.2).sum()
                    c = c / n + lam * (dx * dx + dy * dy)
                    if c < best:
                        best, bt = c, (float(dx), float(dy))
        out[int(r)] = bt
    return out


def _two_sided(fs, lab, axis: int, maxsep: int = 8) -> list[tuple[int, int, float, int]]:
    """(room A, room B, median separation, count) of the walls between two rooms: A's
    face looking -axis, B's looking +axis, at most ``maxsep`` px further."""
    ka, kb = (2, 0) if axis == 0 else (3, 1)
    fa, fb, L = (fs[ka], fs[kb], lab) if axis == 0 else (fs[ka].T, fs[kb].T, lab.T)
    W = fa.shape[1]
    ys, xs = np.nonzero(fa)
    found = []
    for s in range(maxsep + 1):
        ok = xs + s < W
        hit = np.zeros(len(ys), bool)
        hit[ok] = fb[ys[ok], xs[ok] + s]
        found.append(np.column_stack([ys[hit], xs[hit], np.full(hit.sum(), s)]))
        ys, xs = ys[~hit], xs[~hit]
    r = np.concatenate(found)
    if not len(r):
        return []
    y, x, s = r.T
    A = L[y, np.clip(x - 1, 0, W - 1)]
    B = L[y, np.clip(x + s + 1, 0, W - 1)]
    out = []
    for a, b in sorted(set(zip(A.tolist(), B.tolist(), strict=True))):
        if a != b and a and b:
            sel = (A == a) & (B == b)
            out.append((a, b, float(np.median(s[sel])), int(sel.sum())))
    return out


def _pieces(fs, lab, k: int, min_len: int = 8) -> list[tuple[int, float, int, int, int]]:
    """Face pieces looking along channel ``k``, per room: (room, position across, first,
    last along, pixels)."""
    H, W = lab.shape
    dx, dy = _STEP[k]
    ys, xs = np.nonzero(fs[k])
    room = lab[np.clip(ys + dy, 0, H - 1), np.clip(xs + dx, 0, W - 1)]
    mask = np.zeros((H, W), np.int32)
    mask[ys, xs] = room
    out = []
    for r in np.unique(room[room > 0]):
        cc, _ = ndi.label(mask == r, np.ones((3, 3)))
        for j, sl in enumerate(ndi.find_objects(cc), 1):
            py, px = np.nonzero(cc[sl] == j)
            if len(py) < min_len:
                continue
            py, px = py + sl[0].start, px + sl[1].start
            if k in (0, 2):
                out.append((int(r), float(np.median(px)), py.min(), py.max(), len(py)))
            else:
                out.append((int(r), float(np.median(py)), px.min(), px.max(), len(py)))
    return out


def solve_rooms(slam: np.ndarray, lab: np.ndarray, tol: float = 3.0, gap: int = 40,
                prior: float = 0.05, delta: float = 1.0, iters: int = 10,
                clip: float = 4.0) -> np.ndarray:
    """(rooms + 1, 2) translations from the map alone (module doc): Huber IRLS over the
    two-sided walls and the collinear faces, ``prior`` x the median weight towards 0."""
    from map2map.learn.ba.field import face_sets

    fs = face_sets(slam)
    R = int(lab.max()) + 1
    shifts = np.zeros((R, 2))
    for axis in (0, 1):
        rows, rhs, w = [], [], []
        ts = _two_sided(fs, lab, axis)
        if ts:
            t0 = float(np.median(np.repeat([t[2] for t in ts], [t[3] for t in ts])))
            for a, b, sep, n in ts:
                if n >= 4:
                    rows.append((b, a)); rhs.append(t0 - sep); w.append(np.sqrt(n))  # noqa: E702
        for k in ((0, 2) if axis == 0 else (1, 3)):
            P = _pieces(fs, lab, k)
            for i in range(len(P)):
                for j in range(i + 1, len(P)):
                    r1, c1, l1, h1, n1 = P[i]
                    r2, c2, l2, h2, n2 = P[j]
                    g = max(l1, l2) - min(h1, h2)
                    if r1 != r2 and abs(c1 - c2) <= tol and -2 <= g <= gap:
                        rows.append((r2, r1)); rhs.append(c1 - c2)  # noqa: E702
                        w.append(np.sqrt(min(n1, n2)))
        if not rows:
            continue
        M = np.zeros((len(rows) + R, R))
        for e, (p, q) in enumerate(rows):
            M[e, p] += 1
            M[e, q] -= 1
        M[len(rows):] = np.eye(R)
        y = np.concatenate([rhs, np.zeros(R)])
        w0 = np.concatenate([w, np.full(R, prior * np.median(w))])
        s = np.zeros(R)
        for _ in range(iters):
            res = np.abs(M @ s - y)
            hub = np.where(res <= delta, 1.0, delta / np.maximum(res, 1e-9))
            hub[len(rows):] = 1.0
            ww = w0 * hub
            s = np.linalg.lstsq(M * ww[:, None], y * ww, rcond=None)[0]
        shifts[:, axis] = np.clip(s, -clip, clip)
    return shifts
