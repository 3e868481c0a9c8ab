"""Vanilla point-to-point ICP, the baseline the appendix paper compares against (section 5.1).

Besl & McKay's iterative closest point: pair every source point with its nearest
target point (``scipy.spatial.cKDTree``), fit the Euclidean transform in the
least-squares sense, repeat until the mean distance stops improving. No outlier
rejection and no scale: that is the point of the baseline. Its error figures are
the nearest-neighbour distances at convergence, what an ICP-based metric reports.

Examples
--------
>>> import numpy as np
>>> t = np.linspace(0, 2 * np.pi, 200, endpoint=False)
>>> dst = np.column_stack([40 * np.cos(t) + 10 * np.cos(3 * t), 25 * np.sin(t)])
>>> c, s = np.cos(0.05), np.sin(0.05)
>>> src = (dst - [2.0, 1.0]) @ np.array([[c, s], [-s, c]])
>>> res = icp(src, dst)
>>> bool(res.mean_distance < 0.1)
True
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.spatial import cKDTree

from ..core.geometry import apply, fit_similarity

__all__ = ["ICPResult", "icp"]


@dataclass
class ICPResult:
    """Transform (3x3, source -> target), per-point distances at convergence, iterations."""

    T: np.ndarray
    distances: np.ndarray
    iterations: int

    @property
    def mean_distance(self) -> float:
        return float(self.distances.mean())

    @property
    def max_distance(self) -> float:
        return float(self.distances.max())


def icp(
    src: np.ndarray,
    dst: np.ndarray,
    T0: np.ndarray | None = None,
    *,
    scale: float = 1.0,
    iterations: int = 100,
    tolerance: float = 1e-6,
    tree: cKDTree | None = None,
) -> ICPResult:
    """Rigid ICP of ``src`` onto ``dst`` (both (N, 2)), from ``T0`` (identity by default).

    ``scale`` is held fixed (the maps' metric scale ratio, 1 for equal resolutions).
    """
    src = np.asarray(src, float)
    tree = tree or cKDTree(np.asarray(dst, float))
    T = np.eye(3) if T0 is None else np.asarray(T0, float).copy()
    prev = np.inf
    d = np.zeros(len(src))
    it = 0
    while it < iterations:
        it += 1
        d, j = tree.query(apply(T, src), workers=1)
        err = d.mean()
        if prev - err < tolerance:
            break
        prev = err
        T = fit_similarity(src, tree.data[j], scale=scale)
    d, _ = tree.query(apply(T, src), workers=1)
    return ICPResult(T, d, it)
