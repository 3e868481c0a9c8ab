"""The thesis's hand-made features of a (CAD, SLAM) pair, for the cleaner (thesis sec. 4.1).

Thesis 4.1 tabulates "15 specific features" of each preprocessed image pair; its list
has sixteen, all computed here, in its order (black = occupied 0, grey = unknown 127,
white = free 255):

1-3.   black, grey and white pixel counts of the SLAM map;
4-6.   the same of the CAD map;
7-9.   their differences (SLAM - CAD);
10-12. differences (SLAM - CAD) of the black/white, grey/white and black/grey ratios
       (a zero denominator counts as 1);
13.    difference (SLAM - CAD) in the number of holes: enclosed non-white regions of the
       white area, found by boundary tracing (the thesis used MATLAB's Moore-neighbour
       tracing with Jacob's stopping criterion; here OpenCV's Suzuki-Abe border
       following, which gives the same count: one hole border per 4-connected non-white
       component enclosed by 8-connected white);
14-15. grey-white neighbour counts of the SLAM and CAD maps: horizontally or vertically
       adjacent pixel pairs with one grey and one white pixel (the length of the
       explored area's open border);
16.    their difference (SLAM - CAD).

Examples
--------
>>> a = np.full((8, 8), 255, np.uint8); a[[0, -1], :] = 0; a[:, [0, -1]] = 0
>>> b = a.copy(); b[1:7, 5:7] = 127
>>> f = dict(zip(FEATURE_NAMES, pair_features(a, b).tolist()))
>>> f["slam_grey"], f["diff_white"], f["slam_grey_white_nb"]
(12.0, -12.0, 6.0)
"""

from __future__ import annotations

import numpy as np

from ..core.grid import FREE, OCCUPIED, UNKNOWN

__all__ = ["FEATURE_NAMES", "pair_features", "count_holes", "grey_white_neighbours"]

FEATURE_NAMES = (
    "slam_black",
    "slam_grey",
    "slam_white",
    "cad_black",
    "cad_grey",
    "cad_white",
    "diff_black",
    "diff_grey",
    "diff_white",
    "diff_ratio_black_white",
    "diff_ratio_grey_white",
    "diff_ratio_black_grey",
    "diff_holes",
    "slam_grey_white_nb",
    "cad_grey_white_nb",
    "diff_grey_white_nb",
)


def count_holes(m: np.ndarray) -> int:
    """Holes of the white (free) area of a map: non-white regions it encloses.

    Examples
    --------
    >>> m = np.full((9, 9), 255, np.uint8)
    >>> m[2, 2] = 0; m[5:7, 5:7] = 127; m[0, 4] = 0      # the last touches the border
    >>> count_holes(m)
    2
    """
    import cv2

    white = (np.asarray(m) == FREE).astype(np.uint8)
    if not white.any():
        return 0
    _, hierarchy = cv2.findContours(white, cv2.RETR_CCOMP, cv2.CHAIN_APPROX_NONE)
    if hierarchy is None:
        return 0
    return int((hierarchy[0][:, 3] >= 0).sum())


def grey_white_neighbours(m: np.ndarray) -> int:
    """Horizontally or vertically adjacent (grey, white) pixel pairs.

    Examples
    --------
    >>> grey_white_neighbours(np.array([[127, 255, 127], [255, 0, 255]], np.uint8))
    4
    """
    m = np.asarray(m)
    g, w = m == UNKNOWN, m == FREE
    h = (g[:, :-1] & w[:, 1:]) | (w[:, :-1] & g[:, 1:])
    v = (g[:-1, :] & w[1:, :]) | (w[:-1, :] & g[1:, :])
    return int(h.sum() + v.sum())


def _counts(m: np.ndarray) -> tuple[float, float, float]:
    return float((m == OCCUPIED).sum()), float((m == UNKNOWN).sum()), float((m == FREE).sum())


def pair_features(cad: np.ndarray, slam: np.ndarray) -> np.ndarray:
    """The 16 features (:data:`FEATURE_NAMES` order) of one preprocessed pair.

    Parameters
    ----------
    cad, slam : (N, N) uint8
        The plan (A) and the SLAM map (B), values 0 / 127 / 255.

    Returns
    -------
    (16,) float64 array
    """
    cad, slam = np.asarray(cad), np.asarray(slam)
    sb, sg, sw = _counts(slam)
    cb, cg, cw = _counts(cad)

    def ratio(x: float, y: float) -> float:
        return x / max(y, 1.0)

    s_nb, c_nb = float(grey_white_neighbours(slam)), float(grey_white_neighbours(cad))
    return np.array([
        sb, sg, sw, cb, cg, cw,
        sb - cb, sg - cg, sw - cw,
        ratio(sb, sw) - ratio(cb, cw),
        ratio(sg, sw) - ratio(cg, cw),
        ratio(sb, sg) - ratio(cb, cg),
        float(count_holes(slam) - count_holes(cad)),
        s_nb, c_nb, s_nb - c_nb,
    ], float)  # fmt: skip
