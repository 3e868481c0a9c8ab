"""Do the turns of a SLAM map's own walls say where they belong? (issue #32: undoing each
wall's turn against the map's dominant direction with a near-rigid displacement field.)

A particle filter's heading error turns what the robot mapped while it lasted: on the
``rbpf`` maps of the datasets, straight wall pieces lie a degree or so off the map's
dominant direction, where the same plans mapped at the true poses lie on it. A field that
turns them back, as rigidly as the walls allow, is the one correction of drift the map
itself shows. :func:`piece_turns` measures the turns, :func:`unturn_field` builds the
field (a sparse least-squares problem on a coarse grid), and ``__main__`` measures on
held-out pairs whether it lowers Table 5.3's error (README.md of ``table53``).

Examples
--------
A room whose right half turned by 2 degrees: the pieces there say so, and the field turns
them back.

>>> import cv2
>>> m = np.full((256, 256), 255, np.uint8)
>>> m[40:42, 20:236] = 0; m[200:202, 20:236] = 0
>>> m[40:202, 20:22] = 0; m[40:202, 234:236] = 0; m[40:202, 128:130] = 0
>>> turn = cv2.getRotationMatrix2D((130.0, 120.0), 2.0, 1.0)
>>> half = cv2.warpAffine(m, turn, (256, 256), flags=cv2.INTER_NEAREST, borderValue=255)
>>> m[:, 131:] = half[:, 131:]
>>> dev, w = piece_turns(m == 0, 0.0)
>>> right = (w > 0) & (np.arange(256)[None, :] > 140)
>>> round(float(np.median(dev[right])), 1), float(np.median(dev[(w > 0) & ~right]))
(-1.8, 0.0)
>>> from map2map.learn.ba.field import warp
>>> after, w2 = piece_turns(warp(m, unturn_field(m == 0, 0.0)) == 0, 0.0)
>>> bool(abs(np.median(after[(w2 > 0) & right])) < 0.5)
True
"""

from __future__ import annotations

import math

import cv2
import numpy as np

__all__ = ["piece_turns", "unturn_field"]


def piece_turns(walls: np.ndarray, dominant_deg: float, *, min_len: int = 20,
                open_len: int = 15, chunk: int = 48, max_deg: float = 5.0
                ) -> tuple[np.ndarray, np.ndarray]:
    """Each straight wall piece's turn against the dominant direction.

    The wall mask is turned onto the dominant direction; in each of the two families, a
    morphological opening with a ``open_len`` px line keeps the straight walls, whose
    8-connected pieces are cut into ``chunk`` px lengths (a wall crossing two rooms
    that turned differently gives one turn per part); each part at least ``min_len`` px
    long gets the angle of its pixels' least-squares line.

    Parameters
    ----------
    walls : (H, W) bool
    dominant_deg : float
        The map's dominant wall direction (degrees, image frame;
        :func:`map2map.maps.vectorize.dominant_angle`).

    Returns
    -------
    turn_deg, weight : (H, W) float32
        The turn of the piece each wall pixel belongs to (degrees; rows point down, a
        positive turn is clockwise on screen) and 1 where a piece gives one (turns over
        ``max_deg`` are not drift: left out), else 0.
    """
    H, W = walls.shape
    to_axes = cv2.getRotationMatrix2D((W / 2, H / 2), dominant_deg, 1.0)
    back = cv2.invertAffineTransform(to_axes)
    straight = cv2.warpAffine(walls.astype(np.uint8), to_axes, (W, H),
                              flags=cv2.INTER_NEAREST)
    turn = np.zeros((H, W), np.float32)
    weight = np.zeros((H, W), np.float32)
    for axis in (0, 1):                                   # 0: along rows, 1: along columns
        k = np.ones((1, open_len) if axis == 0 else (open_len, 1), np.uint8)
        n, lab = cv2.connectedComponents(cv2.morphologyEx(straight, cv2.MORPH_OPEN, k),
                                         connectivity=8)
        if n <= 1:
            continue
        r, c = np.nonzero(lab)
        along, across = (c, r) if axis == 0 else (r, c)
        key = lab[r, c].astype(np.int64) * (max(H, W) + 1) + along // chunk
        order = np.argsort(key, kind="stable")
        key, along, across = key[order], along[order].astype(float), across[order].astype(float)
        first = np.r_[0, np.flatnonzero(np.diff(key)) + 1]
        cnt = np.diff(np.r_[first, len(key)])
        da = along - np.repeat(np.add.reduceat(along, first) / cnt, cnt)
        dc = across - np.repeat(np.add.reduceat(across, first) / cnt, cnt)
        slope = np.add.reduceat(da * dc, first) / np.maximum(np.add.reduceat(da * da, first),
                                                             1e-9)
        deg = np.degrees(np.arctan(slope)) * (1.0 if axis == 0 else -1.0)
        span = np.maximum.reduceat(along, first) - np.minimum.reduceat(along, first) + 1
        ok = (span >= min_len) & (np.abs(deg) < max_deg)
        per = np.repeat(np.where(ok, deg, np.nan), cnt)
        good = np.isfinite(per)
        rr = (across if axis == 0 else along)[good].astype(int)
        cc = (along if axis == 0 else across)[good].astype(int)
        turn[rr, cc] = per[good]
        weight[rr, cc] = 1.0
    turn = cv2.warpAffine(turn, back, (W, H), flags=cv2.INTER_NEAREST)
    weight = cv2.warpAffine(weight, back, (W, H), flags=cv2.INTER_NEAREST)
    return turn, weight


def unturn_field(walls: np.ndarray, dominant_deg: float, *, step: int = 4,
                 data: float = 100.0, rigid_walls: float = 1.0, rigid_free: float = 0.01,
                 gauge: float = 1e-6) -> np.ndarray:
    """(2, H, W) displacement (x, y px) that turns each wall piece back onto the dominant
    direction as rigidly as the walls allow.

    On a grid of nodes ``step`` px apart, the displacement ``u`` minimises, summed over the
    cells, ``data * w (omega - t)^2`` (``omega`` the cell's rotation ``(d uy/dx -
    d ux/dy) / 2``, ``t`` minus the mean turn of the pieces in it, ``w`` their share of
    its pixels) plus the strain ``(d ux/dx)^2 + (d uy/dy)^2 + 2 e_xy^2`` weighted by
    ``rigid_free + rigid_walls * (wall share of the cell)`` (walls keep their shape, free
    space gives) plus ``gauge * |u|^2`` (fixes the free rigid motion); the nodes are
    interpolated bilinearly to the pixels.

    Examples
    --------
    >>> w = np.zeros((64, 64), bool); w[20, 5:60] = True
    >>> float(np.abs(unturn_field(w, 0.0)).max()) < 1e-6        # nothing turned
    True
    """
    import scipy.sparse as sp
    from scipy import ndimage
    from scipy.sparse.linalg import spsolve

    H, W = walls.shape
    turn, wt = piece_turns(walls, dominant_deg)
    gh, gw = H // step + 1, W // step + 1
    ch, cw = gh - 1, gw - 1
    share = cv2.resize(wt, (cw, ch), interpolation=cv2.INTER_AREA)
    summed = cv2.resize(wt * turn, (cw, ch), interpolation=cv2.INTER_AREA)
    target = -np.radians(np.where(share > 0, summed / np.maximum(share, 1e-12), 0.0))
    n, m = gh * gw, ch * cw
    idx = np.arange(n).reshape(gh, gw)
    corners = [idx[:-1, :-1], idx[:-1, 1:], idx[1:, :-1], idx[1:, 1:]]
    rows = np.tile(np.arange(m), 4)
    cols = np.concatenate([c.ravel() for c in corners])
    h = np.full(m, 0.5 / step)
    dx = sp.csr_matrix((np.concatenate([-h, h, -h, h]), (rows, cols)), shape=(m, n))
    dy = sp.csr_matrix((np.concatenate([-h, -h, h, h]), (rows, cols)), shape=(m, n))
    zero = sp.csr_matrix((m, n))
    wall_share = cv2.resize(walls.astype(np.float32), (cw, ch), interpolation=cv2.INTER_AREA)
    stiff = sp.diags(np.sqrt(rigid_free + rigid_walls * wall_share.ravel()))
    fit = sp.diags(np.sqrt(data * share.ravel()))
    A = sp.vstack([fit @ sp.hstack([-0.5 * dy, 0.5 * dx]),
                   stiff @ sp.hstack([dx, zero]), stiff @ sp.hstack([zero, dy]),
                   math.sqrt(2.0) * stiff @ sp.hstack([0.5 * dy, 0.5 * dx]),
                   math.sqrt(gauge) * sp.identity(2 * n)]).tocsr()
    b = np.concatenate([np.sqrt(data * share.ravel()) * target.ravel(), np.zeros(3 * m + 2 * n)])
    u = spsolve((A.T @ A).tocsc(), A.T @ b)
    # node (j, i) sits on pixel (j * step, i * step): bilinear with the corners aligned
    at = np.mgrid[0:H, 0:W].astype(float) / step
    return np.stack([ndimage.map_coordinates(u[k * n:(k + 1) * n].reshape(gh, gw), at, order=1)
                     for k in (0, 1)]).astype(np.float32)
