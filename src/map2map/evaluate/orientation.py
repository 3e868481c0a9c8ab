"""Dominant orientations of a map (first step of the region decomposition, section 3.2.1).

Buildings are mostly rectilinear: the wall directions cluster around two
perpendicular angles. Following Shahbandi & Magnusson, the angle is read off a
histogram of wall orientations; here the histogram is of image-gradient angles of
the (smoothed) occupied mask, folded modulo 90 degrees and weighted by gradient
magnitude, so both wall families vote for the same bin.

Examples
--------
>>> import numpy as np, cv2
>>> img = np.full((200, 200), 255, np.uint8)
>>> box = cv2.boxPoints(((100, 100), (120, 60), 20.0)).astype(np.int32)
>>> _ = cv2.polylines(img, [box], True, 0, 3)
>>> theta, strength = dominant_orientation(img)
>>> round(float(np.degrees(theta)))
20

A building with a wing at 45 degrees has two families (:func:`wall_families`):

>>> img = np.full((300, 300), 255, np.uint8)
>>> _ = cv2.rectangle(img, (20, 150), (180, 280), 0, 3)              # a hall on the axes
>>> wing = cv2.boxPoints(((200, 90), (90, 160), 45.0)).astype(np.int32)
>>> _ = cv2.polylines(img, [wing], True, 0, 3)                      # a wing at 45 degrees
>>> sorted(round(float(np.degrees(a))) for a in wall_families(img, 0.0))
[0, 45]
"""

from __future__ import annotations

import cv2
import numpy as np

from ..core.grid import OCCUPIED
from ..maps.directions import angle_families

__all__ = ["dominant_orientation", "orientation_histogram", "projection_sharpness",
           "wall_families"]


def orientation_histogram(data: np.ndarray, bins: int = 180) -> np.ndarray:
    """Gradient-magnitude-weighted histogram of wall angles modulo 90 degrees (``bins`` bins)."""
    occ = (data == OCCUPIED).astype(np.float32)
    occ = cv2.GaussianBlur(occ, (0, 0), 1.0)
    gx = cv2.Sobel(occ, cv2.CV_32F, 1, 0, ksize=3)
    gy = cv2.Sobel(occ, cv2.CV_32F, 0, 1, ksize=3)
    mag = np.hypot(gx, gy)
    keep = mag > 0.05 * max(float(mag.max()), 1e-9)
    # a gradient at angle a is normal to a wall at a + 90 deg: the same bin modulo 90
    ang = np.mod(np.arctan2(gy[keep], gx[keep]), np.pi / 2)
    hist, _ = np.histogram(ang, bins=bins, range=(0.0, np.pi / 2), weights=mag[keep])
    return hist.astype(float)


def dominant_orientation(data: np.ndarray, bins: int = 180) -> tuple[float, float]:
    """The dominant wall angle ``theta`` in [0, pi/2) and its strength in [0, 1].

    The walls run along ``theta`` and ``theta + pi/2`` (radians, image x-axis
    towards image y-axis, i.e. clockwise on screen). ``strength`` is the share of
    the histogram within +-5 degrees of the peak: near 1 for a rectilinear
    building, near 1/9 for no preferred direction.
    """
    hist = orientation_histogram(data, bins)
    if hist.sum() <= 0:
        return 0.0, 0.0
    # circular smoothing (the histogram wraps at 90 degrees)
    k = np.exp(-0.5 * (np.arange(-5, 6) / 1.5) ** 2)
    smooth = np.real(
        np.fft.ifft(np.fft.fft(hist) * np.fft.fft(np.roll(np.pad(k, (0, bins - 11)), -5)))
    )
    i = int(np.argmax(smooth))
    l, c, r = smooth[(i - 1) % bins], smooth[i], smooth[(i + 1) % bins]
    den = l - 2 * c + r
    off = 0.5 * (l - r) / den if den < 0 else 0.0
    width = np.pi / 2 / bins
    theta = float(np.mod((i + 0.5 + off) * width, np.pi / 2))
    near = np.abs(((np.arange(bins) + 0.5) * width - theta + np.pi / 4) % (np.pi / 2) - np.pi / 4)
    strength = float(hist[near <= np.radians(5)].sum() / hist.sum())
    # the gradient histogram of pixelated walls is biased towards 0 and 45 degrees:
    # refine by the sharpest Radon projection (see :mod:`.radiography`) around the peak
    r, c = np.nonzero(data == OCCUPIED)
    if len(r) >= 10:
        cand = theta + np.radians(np.arange(-4.0, 4.01, 0.1))
        sharp = [projection_sharpness(c, r, a) for a in cand]
        theta = float(np.mod(cand[int(np.argmax(sharp))], np.pi / 2))
    return theta, strength


def projection_sharpness(x: np.ndarray, y: np.ndarray, theta: float) -> float:
    """Sum of squared 1-px projection bins of points along ``theta`` and ``theta + pi/2``.

    The Radon projection of a wall parallel to the projection direction is a spike;
    the sum of squares is largest when the walls are exactly aligned with it.
    """
    c, s = np.cos(theta), np.sin(theta)
    total = 0.0
    for u in (x * c + y * s, -x * s + y * c):
        h = np.bincount(np.floor(u - u.min()).astype(np.int64))
        total += float((h.astype(float) ** 2).sum())
    return total


def wall_families(data: np.ndarray, theta: float, resolution: float = 0.05,
                  min_dev_deg: float = 20.0) -> list[float]:
    """Direction families of a map's walls: ``theta`` first, then any further one.

    A building whose wing runs at 45 degrees to the rest has two families of
    perpendicular walls; one dominant angle (:func:`dominant_orientation`) names only
    one of them, and the other's walls would then read as corners (their normals on
    the diagonal between the axes) and their rotation would be missing from the
    alignment's hypotheses. The further families are those of
    :func:`map2map.maps.directions.angle_families` on the occupied cells: at least
    ``min_dev_deg`` off every other (a building's own second direction, not a wing
    that SLAM drift turned by a few degrees), 15 % of the walls and 4 m of wall.

    Parameters
    ----------
    data : (H, W) uint8
        The map (occupied 0, free 255, unknown 127).
    theta : float
        The dominant wall angle (radians, as :func:`dominant_orientation` returns it).
    resolution : float
        Metres per pixel (the 4 m and the 1 m neighbourhood of ``angle_families``).
    min_dev_deg : float

    Returns
    -------
    list of float
        Angles in [0, pi/2) (radians), ``theta`` first; one element for a building
        whose walls all run along ``theta`` and ``theta + pi/2``.
    """
    r, c = np.nonzero(data == OCCUPIED)
    if len(r) < 3:
        return [float(theta)]
    deg = (np.degrees(theta) + 45.0) % 90.0 - 45.0
    pts = np.column_stack([c + 0.5, r + 0.5])
    angles, _ = angle_families(pts, np.ones(len(pts)), data.shape, deg, resolution,
                               min_dev=min_dev_deg, max_families=3)
    return [float(theta)] + [float(np.mod(np.radians(a), np.pi / 2)) for a in angles[1:]]
