"""Wall lines by radiography: Radon-type projections along the dominant orientations.

Section 3.2.1 of the appendix paper, after Shahbandi & Magnusson: the occupied
cells are projected onto the axis perpendicular to each dominant orientation (one
column of the Radon transform at that angle); a wall parallel to the orientation is
a spike in that projection. Each spike is then read back along the wall direction
and cut into segments where the wall is interrupted by more than ``gap`` pixels
(shorter interruptions, such as doorways, are bridged so that rooms close).

Examples
--------
>>> import numpy as np
>>> img = np.full((60, 80), 255, np.uint8)
>>> img[20, 5:75] = 0                      # one horizontal wall
>>> segs = wall_lines(img, 0.0, min_length=10)
>>> [(round(x0), round(y0), round(x1), round(y1)) for x0, y0, x1, y1 in segs]
[(5, 20, 75, 20)]
"""

from __future__ import annotations

import numpy as np
from scipy.signal import find_peaks

from ..core.grid import OCCUPIED

__all__ = ["projection", "wall_lines"]


def projection(x: np.ndarray, y: np.ndarray, angle: float) -> tuple[np.ndarray, float]:
    """Radon projection of points for walls running along ``angle``.

    Returns the 1-px histogram of ``v = -x sin(angle) + y cos(angle)`` (the
    coordinate across such walls) and the ``v`` of bin 0.
    """
    v = -x * np.sin(angle) + y * np.cos(angle)
    v0 = float(np.floor(v.min())) if len(v) else 0.0
    return np.bincount(np.floor(v - v0).astype(np.int64)).astype(float), v0


def _runs(occupied_bins: np.ndarray, gap: int) -> list[tuple[int, int]]:
    """(start, stop) of runs of True, merging runs separated by at most ``gap`` False bins."""
    idx = np.flatnonzero(occupied_bins)
    if idx.size == 0:
        return []
    breaks = np.flatnonzero(np.diff(idx) > gap + 1)
    starts = np.concatenate([[idx[0]], idx[breaks + 1]])
    stops = np.concatenate([idx[breaks], [idx[-1]]]) + 1
    return list(zip(starts.tolist(), stops.tolist(), strict=True))


def wall_lines(
    data: np.ndarray,
    theta: float,
    *,
    min_length: float = 10.0,
    gap: int = 3,
    band: int = 1,
    min_separation: int = 2,
) -> list[tuple[float, float, float, float]]:
    """Wall segments ``(x0, y0, x1, y1)`` along ``theta`` and ``theta + pi/2``.

    Parameters
    ----------
    data : (H, W) uint8 occupancy map.
    theta : dominant orientation in radians (see :mod:`.orientation`).
    min_length : shortest wall segment kept, in pixels; a projection spike must
        also hold at least ``min_length / 2`` occupied cells.
    gap : longest interruption bridged inside one wall (doorways), in pixels.
    band : half-width in pixels of the strip read back around each spike.
    min_separation : spikes closer than this are one wall (its thickness).
    """
    r, c = np.nonzero(data == OCCUPIED)
    x, y = c.astype(float) + 0.5, r.astype(float) + 0.5
    segments: list[tuple[float, float, float, float]] = []
    if x.size == 0:
        return segments
    for angle in (theta, theta + np.pi / 2):
        ca, sa = np.cos(angle), np.sin(angle)
        hist, v0 = projection(x, y, angle)
        peaks, _ = find_peaks(
            np.concatenate([[0.0], hist, [0.0]]),
            height=max(min_length / 2.0, 2.0),
            distance=max(1, int(min_separation)),
        )
        if peaks.size == 0:
            continue
        v = -x * sa + y * ca
        t = x * ca + y * sa
        t0 = float(np.floor(t.min()))
        n_t = int(np.floor(t.max() - t0)) + 1
        for p in peaks - 1:
            vc = v0 + p + 0.5
            sel = np.abs(v - vc) <= band + 0.5
            bins = np.zeros(n_t, bool)
            bins[np.floor(t[sel] - t0).astype(np.int64)] = True
            for a, b in _runs(bins, gap):
                if b - a < min_length:
                    continue
                ta, tb = t0 + a, t0 + b
                segments.append(
                    (ta * ca - vc * sa, ta * sa + vc * ca, tb * ca - vc * sa, tb * sa + vc * ca)
                )
    return segments
