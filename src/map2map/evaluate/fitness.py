"""The Gaussian fitness map of a plan and the fitness score of aligned points, eq. 8.

Section 3.2.3 of the appendix paper: the plan ``M_o`` becomes a distance map
``M_d = DT(M_o)`` (distance of every cell to the nearest occupied cell), normalised
by a Gaussian ``M_f = exp(-M_d^2 / (2 sigma_f^2))``: 1 on the walls, falling to 0
away from them. The fitness of source points ``X`` mapped into the plan is the mean
of ``M_f`` at them, eq. 8; points falling outside the plan score 0.

Examples
--------
>>> import numpy as np
>>> plan = np.full((11, 11), 255, np.uint8); plan[:, 5] = 0
>>> Mf = fitness_map(plan == 0, sigma=2.0)
>>> float(Mf[0, 5]), round(float(Mf[0, 7]), 4)       # on the wall, 2 px away
(1.0, 0.6065)
>>> fitness(Mf, np.array([[5.5, 3.5], [7.5, 3.5], [50.5, 3.5]])).round(4)
np.float64(0.5355)
"""

from __future__ import annotations

import numpy as np
from scipy import ndimage

from ..core.geometry import apply

__all__ = ["distance_map", "fitness_map", "fitness", "transformed_fitness", "lookup"]


def distance_map(walls: np.ndarray, *, return_indices: bool = False):
    """Euclidean distance of every cell to the nearest ``walls`` cell, ``M_d = DT(M_o)``.

    With ``return_indices`` also the (2, H, W) row/col indices of that nearest cell
    (the *labels* of Algorithm 1). A map without walls gives infinite distances.
    """
    walls = np.asarray(walls, bool)
    if not walls.any():
        d = np.full(walls.shape, np.inf)
        if return_indices:
            return d, np.zeros((2, *walls.shape), np.int32)
        return d
    d = np.empty(walls.shape, np.float64)
    if return_indices:  # preallocated int32 indices: no conversion copies
        idx = np.empty((2, *walls.shape), np.int32)
        ndimage.distance_transform_edt(~walls, return_indices=True, distances=d, indices=idx)
        return d, idx
    ndimage.distance_transform_edt(~walls, distances=d)
    return d


def fitness_map(walls: np.ndarray, sigma: float) -> np.ndarray:
    """``M_f = exp(-M_d^2 / (2 sigma^2))`` of a wall mask (``sigma`` in pixels)."""
    d = distance_map(walls)
    return np.exp(-(d.astype(np.float64) ** 2) / (2.0 * sigma**2)).astype(np.float32)


def lookup(grid: np.ndarray, pts: np.ndarray, outside: float = 0.0) -> np.ndarray:
    """Values of ``grid`` at the cells containing points (x, y); ``outside`` off the grid."""
    pts = np.asarray(pts, float).reshape(-1, 2)
    c = np.floor(pts[:, 0]).astype(np.int64)
    r = np.floor(pts[:, 1]).astype(np.int64)
    h, w = grid.shape[:2]
    ok = (r >= 0) & (r < h) & (c >= 0) & (c < w)
    out = np.full(len(pts), outside, dtype=np.float64)
    out[ok] = grid[r[ok], c[ok]]
    return out


def fitness(Mf: np.ndarray, pts: np.ndarray) -> float:
    """Eq. 8: mean of ``M_f`` over the points (x, y) in plan pixels (0 outside the plan).

    Points are continuous pixel coordinates: pixel ``(r, c)`` covers
    ``[c, c + 1) x [r, r + 1)`` (its centre is ``(c + 0.5, r + 0.5)``).
    """
    if len(pts) == 0:
        return 0.0
    return lookup(Mf, pts).mean()


def transformed_fitness(Mf: np.ndarray, pts: np.ndarray, T: np.ndarray) -> float:
    """Eq. 8 of source points (continuous pixel coordinates) mapped by the 3x3 ``T``."""
    return fitness(Mf, apply(T, pts))
