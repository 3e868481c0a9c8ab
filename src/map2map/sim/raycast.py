"""Exact 2-D ray casting on an occupancy grid (Amanatides & Woo grid traversal).

Amanatides, J. and Woo, A. (1987), *A fast voxel traversal algorithm for ray
tracing*, Eurographics. The ray visits every cell it passes through, in order,
stepping from one cell boundary to the next (a DDA over cells). The distance
returned is the exact parameter ``t`` at which the ray enters the first solid
cell, i.e. the distance to that cell's boundary: a wall one pixel thick is hit
exactly where its square begins.

When the ray passes exactly through a cell corner (``tMaxX == tMaxY`` within
``1e-9`` pixels), both side cells touching that corner are tested as well as the
diagonal one, so a ray can never slip between two solid cells that meet only at a
corner: diagonal walls one pixel thick do not leak.

Units and frame: everything here is in *continuous pixel coordinates* of the
grid (x = column to the right, y = row downwards, cell ``(r, c)`` covers
``[c, c+1) x [r, r+1)``, see :mod:`map2map.core.grid`). Angles are measured in
that frame (direction ``(cos a, sin a)``, so positive angles turn clockwise on
screen). Conversions from metric poses live in :mod:`map2map.sim.lidar`.

Examples
--------
>>> import numpy as np
>>> solid = np.zeros((10, 10), np.bool_)
>>> solid[:, 7] = True                      # a vertical wall at columns 7
>>> d = cast_rays(make_cast_grid(solid), 2.5, 4.5, np.array([0.0, np.pi]), 100.0)
>>> float(d[0])                              # from x=2.5 to the wall face x=7
4.5
>>> bool(np.isinf(d[1]))                     # leaves the grid: no return
True
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

__all__ = ["make_cast_grid", "cast_rays", "cast_scan", "cast_rays_many", "TIE_EPS"]

#: Two boundary crossings closer than this (pixels) count as one corner crossing.
TIE_EPS = 1e-9


def make_cast_grid(
    solid: np.ndarray, within: tuple[int, int, int, int] | None = None
) -> np.ndarray:
    """Prepare a boolean grid for casting: one ``float32`` field with a one-cell border.

    A cell holds -1 if solid, -2 outside the grid (the border, so the traversal
    stops at the grid edge), and otherwise a safe jump length in pixels: the
    Euclidean distance from the cell centre to the nearest solid or border cell
    centre minus ``sqrt(2)`` (half a diagonal at each end). Empty-space skipping
    with it never jumps over a cell the ray would touch, so results stay exact;
    one load per step tells both whether a cell blocks and how far one may jump.
    Coordinates into the field are shifted by one cell; the ``cast_*`` functions
    take the unshifted coordinates of the original grid.

    With ``within`` (half-open ``(r0, r1, c0, c1)`` of ``solid``) the distances are
    taken inside that box only, as if its edge were the grid's border, and cells
    outside it get 0 (no skipping): both only shorten jumps, so casts stay exact, and
    the field costs the box's size rather than the grid's (:class:`~map2map.sim.lidar.Scene`
    boxes the plan's known cells plus more than the lidar's range).

    Parameters
    ----------
    solid : (H, W) bool array
        Cells that stop a ray.
    within : (r0, r1, c0, c1), optional
        Where jumps are wanted (clipped to the grid); default everywhere.

    Returns
    -------
    (H + 2, W + 2) float32 array

    Examples
    --------
    >>> g = make_cast_grid(np.zeros((3, 3), bool))
    >>> g.shape, float(g[0, 0]), float(g[2, 2]) > 0
    ((5, 5), -2.0, True)
    """
    from scipy.ndimage import distance_transform_edt

    s = np.asarray(solid, bool)
    h, w = s.shape
    r0, r1, c0, c1 = within or (0, h, 0, w)
    r0, c0 = max(r0, 0), max(c0, 0)
    r1, c1 = max(min(r1, h), r0), max(min(c1, w), c0)
    box = np.full((r1 - r0 + 2, c1 - c0 + 2), 2, np.uint8)  # with its own border ring
    box[1:-1, 1:-1] = s[r0:r1, c0:c1]
    skip = distance_transform_edt(box == 0) - math.sqrt(2.0) - 1e-6
    field = np.zeros((h + 2, w + 2), np.float32)  # outside the box: no skipping
    field[r0 + 1 : r1 + 1, c0 + 1 : c1 + 1] = np.maximum(skip[1:-1, 1:-1], 0.0)
    field[1:-1, 1:-1][s] = -1.0
    field[[0, -1], :] = -2.0
    field[:, [0, -1]] = -2.0
    return field


@njit(cache=True)
def _traverse(field, x0, y0, dx, dy, max_dist):
    """Amanatides-Woo traversal from a point inside the grid (original coordinates)."""
    inf = np.inf
    t_base = 0.0
    while True:  # one pass per (re)start of the DDA after an empty-space jump
        c = int(math.floor(x0))
        r = int(math.floor(y0))
        jump = field[r + 1, c + 1]
        if jump == -1.0:
            return t_base
        if dx > 0.0:
            step_c = 1
            t_max_x = (c + 1 - x0) / dx
            t_dx = 1.0 / dx
        elif dx < 0.0:
            step_c = -1
            t_max_x = (c - x0) / dx
            t_dx = -1.0 / dx
        else:
            step_c = 0
            t_max_x = inf
            t_dx = inf
        if dy > 0.0:
            step_r = 1
            t_max_y = (r + 1 - y0) / dy
            t_dy = 1.0 / dy
        elif dy < 0.0:
            step_r = -1
            t_max_y = (r - y0) / dy
            t_dy = -1.0 / dy
        else:
            step_r = 0
            t_max_y = inf
            t_dy = inf
        r += 1  # padded-grid indices from here on
        c += 1
        if jump > 1.5:
            if t_base + jump > max_dist:
                return inf
            t_base += jump
            x0 += jump * dx
            y0 += jump * dy
            continue
        restart = False
        while True:
            diff = t_max_x - t_max_y
            if diff < -TIE_EPS:
                t = t_max_x
                c += step_c
                t_max_x += t_dx
            elif diff > TIE_EPS:
                t = t_max_y
                r += step_r
                t_max_y += t_dy
            else:  # through a corner: the two side cells touch the ray at one point
                t = t_max_x if t_max_x < t_max_y else t_max_y
                if t_base + t > max_dist:
                    return inf
                if field[r, c + step_c] == -1.0 or field[r + step_r, c] == -1.0:
                    return t_base + t
                c += step_c
                r += step_r
                t_max_x += t_dx
                t_max_y += t_dy
            v = field[r, c]
            if v < 0.0:
                if v == -1.0 and t_base + t <= max_dist:
                    return t_base + t
                return inf
            if t_base + t > max_dist:
                return inf
            if v > 3.0:
                # far from everything again: jump from the cell entry point
                t_base += t
                x0 += t * dx
                y0 += t * dy
                # keep the entry point inside the cell just entered
                x0 = min(max(x0, c - 1.0), c - 1e-9)
                y0 = min(max(y0, r - 1.0), r - 1e-9)
                restart = True
                break
        if not restart:
            return inf


@njit(cache=True)
def _cast_one(field, x0, y0, dx, dy, max_dist):
    """Distance along unit direction (dx, dy) to the first solid cell, or inf."""
    h = field.shape[0] - 2
    w = field.shape[1] - 2
    if 0.0 <= x0 < w and 0.0 <= y0 < h:
        return _traverse(field, x0, y0, dx, dy, max_dist)
    # outside: clip the ray to the grid box, then traverse from the entry point
    t0 = 0.0
    t1 = max_dist
    if dx == 0.0:
        if x0 < 0.0 or x0 >= w:
            return np.inf
    else:
        ta = (0.0 - x0) / dx
        tb = (w - x0) / dx
        t0 = max(t0, min(ta, tb))
        t1 = min(t1, max(ta, tb))
    if dy == 0.0:
        if y0 < 0.0 or y0 >= h:
            return np.inf
    else:
        ta = (0.0 - y0) / dy
        tb = (h - y0) / dy
        t0 = max(t0, min(ta, tb))
        t1 = min(t1, max(ta, tb))
    if t0 >= t1:
        return np.inf
    xe = min(max(x0 + t0 * dx, 0.0), w - 1e-9)
    ye = min(max(y0 + t0 * dy, 0.0), h - 1e-9)
    return t0 + _traverse(field, xe, ye, dx, dy, max_dist - t0)


@njit(cache=True)
def cast_rays(field, x0, y0, angles, max_dist):
    """Cast rays from one point; distance (pixels) to the first solid cell per angle.

    Parameters
    ----------
    field : (H+2, W+2) float32 array
        The prepared grid from :func:`make_cast_grid`.
    x0, y0 : float
        Ray origin in continuous pixel coordinates of the original grid.
    angles : (B,) float array
        Beam directions in the pixel frame (radians).
    max_dist : float
        Largest distance of interest (pixels); farther hits return ``inf``.

    Returns
    -------
    (B,) float64 array of distances, ``inf`` where nothing is hit within ``max_dist``.
    """
    n = angles.shape[0]
    out = np.empty(n, np.float64)
    for i in range(n):
        a = angles[i]
        out[i] = _cast_one(field, x0, y0, math.cos(a), math.sin(a), max_dist)
    return out


@njit(cache=True)
def cast_scan(field, x0, y0, heading, cos_rel, sin_rel, max_dist, out):
    """One scan: beam ``j`` points along ``heading + rel_j`` given ``cos/sin(rel_j)``.

    Writes distances (pixels, ``inf`` for no return) into ``out``. Avoids one
    ``cos``/``sin`` pair per beam by rotating precomputed beam directions.

    Parameters
    ----------
    field : float32 array
        From :func:`make_cast_grid`.
    x0, y0 : float
        Sensor position, pixels of the original grid.
    heading : float
        Sensor heading, pixel frame.
    cos_rel, sin_rel : float arrays
        Cosine and sine of the beams' angles relative to the heading.
    max_dist : float
        Longest range, pixels.
    out : float array
        Receives the distances.
    """
    ch = math.cos(heading)
    sh = math.sin(heading)
    for j in range(cos_rel.shape[0]):
        dx = ch * cos_rel[j] - sh * sin_rel[j]
        dy = sh * cos_rel[j] + ch * sin_rel[j]
        out[j] = _cast_one(field, x0, y0, dx, dy, max_dist)


@njit(cache=True)
def cast_rays_many(field, xs, ys, headings, rel_angles, max_dist):
    """Cast a whole scan from each of ``N`` poses: ``(N, B)`` distances in pixels.

    ``headings[k] + rel_angles[j]`` is the direction of beam ``j`` at pose ``k``
    (pixel frame). Used by benchmarks and batch simulation.

    Parameters
    ----------
    field : float32 array
        From :func:`make_cast_grid`.
    xs, ys, headings : (N,) float arrays
        Poses, pixel frame.
    rel_angles : (B,) float array
        Beam angles relative to the heading.
    max_dist : float
        Longest range, pixels.

    Returns
    -------
    (N, B) float array
    """
    n = xs.shape[0]
    b = rel_angles.shape[0]
    cr = np.cos(rel_angles)
    sr = np.sin(rel_angles)
    out = np.empty((n, b), np.float64)
    for k in range(n):
        cast_scan(field, xs[k], ys[k], headings[k], cr, sr, max_dist, out[k])
    return out
