"""What the LIDAR sees from each pose: visible pixels with occlusion (thesis 3.2, Fig. 5.13).

An LDS-01 scanner sees from ``range_min`` 0.12 m to ``range_max`` 3.5 m over 360 degrees
(or the 180 degrees of the thesis experiments, centred on the heading). From each key
pose, rays are cast through the grid with an exact cell traversal (Amanatides & Woo) so
that every pixel a ray crosses within range is seen; a ray stops at the first occupied
pixel, which is seen too. Rays are spaced so that neighbouring rays are at most
0.9 px apart at full range (a pixel's width seen along any direction is at
least 1 px), so no pixel of the visible region is skipped. Unknown plan pixels
(outside the building) neither stop rays nor are marked seen.

The result is a compressed sparse row structure: the pixels seen from pose ``k`` are
``pixels[indptr[k]:indptr[k + 1]]`` (flat indices ``row * W + col``, each once per pose).
This is the per-pose field-of-view *mask* of thesis eqs. 3.83-3.90, in a form that costs
memory proportional to what is seen rather than ``K * H * W``.

Examples
--------
>>> import numpy as np
>>> occ = np.zeros((21, 21), bool); occ[:, 15] = True          # a wall at column 15
>>> vis = visible_pixels(occ, np.array([[5.0, 10.0, 0.0]]), 0.0, 30.0)
>>> seen = vis.observed_mask()
>>> bool(seen[10, 15]), bool(seen[10, 16])                       # wall seen, behind it not
(True, False)
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numba
import numpy as np

__all__ = ["Visibility", "visible_pixels"]


@dataclass
class Visibility:
    """Pixels seen from each pose (CSR layout) on a grid of ``shape``."""

    indptr: np.ndarray  # (K + 1,) int64
    pixels: np.ndarray  # (nnz,) int32 flat indices
    shape: tuple[int, int]

    @property
    def n_poses(self) -> int:
        return self.indptr.size - 1

    def seen_from(self, k: int) -> np.ndarray:
        """Flat indices of the pixels seen from pose ``k``.

        Parameters
        ----------
        k : int

        Returns
        -------
        int32 array
        """
        return self.pixels[self.indptr[k] : self.indptr[k + 1]]

    def observed_mask(self) -> np.ndarray:
        """Pixels seen from at least one pose.

        Returns
        -------
        (H, W) bool array
        """
        m = np.zeros(self.shape[0] * self.shape[1], bool)
        m[self.pixels] = True
        return m.reshape(self.shape)

    def first_seen(self) -> np.ndarray:
        """(H, W) int32: index of the first pose that saw each pixel, -1 if never seen.

        Returns
        -------
        (H, W) int32 array
        """
        first = np.full(self.shape[0] * self.shape[1], -1, np.int32)
        pose = np.repeat(np.arange(self.n_poses, dtype=np.int32), np.diff(self.indptr))
        # reversed assignment keeps the earliest pose for duplicated indices
        first[self.pixels[::-1]] = pose[::-1]
        return first.reshape(self.shape)

    def counts(self) -> np.ndarray:
        """(H, W) int32: how many poses saw each pixel.

        Returns
        -------
        (H, W) int32 array
        """
        c = np.bincount(self.pixels, minlength=self.shape[0] * self.shape[1])
        return c.astype(np.int32).reshape(self.shape)


@numba.njit(cache=True)
def _cast_pose(
    occ, stamp, mark, x0, y0, heading, rmin, rmax, fov, n_beams, buf
):  # pragma: no cover
    """Cells seen from one pose into ``buf``; returns how many (each once, via ``stamp``)."""
    h, w = occ.shape
    full = fov >= 2.0 * math.pi - 1e-9
    n = 0
    # shift so that the cell containing (x, y) is (floor(y), floor(x))
    x0 += 0.5
    y0 += 0.5
    for b in range(n_beams):
        if full:
            ang = heading + 2.0 * math.pi * b / n_beams
        else:
            ang = heading - 0.5 * fov + fov * b / (n_beams - 1)
        dx = math.cos(ang)
        dy = math.sin(ang)
        cx = int(math.floor(x0))
        cy = int(math.floor(y0))
        step_x = 1 if dx > 0 else -1
        step_y = 1 if dy > 0 else -1
        if dx != 0.0:
            t_dx = abs(1.0 / dx)
            t_mx = ((cx + 1 - x0) if dx > 0 else (x0 - cx)) * t_dx
        else:
            t_dx = 1e30
            t_mx = 1e30
        if dy != 0.0:
            t_dy = abs(1.0 / dy)
            t_my = ((cy + 1 - y0) if dy > 0 else (y0 - cy)) * t_dy
        else:
            t_dy = 1e30
            t_my = 1e30
        t_in = 0.0
        while t_in <= rmax:
            if cx < 0 or cy < 0 or cx >= w or cy >= h:
                break
            cell = occ[cy, cx]
            if cell != 2 and min(t_mx, t_my) >= rmin:
                idx = cy * w + cx
                if stamp[idx] != mark:
                    stamp[idx] = mark
                    buf[n] = idx
                    n += 1
            if cell == 1:
                break
            if t_mx < t_my:
                cx += step_x
                t_in = t_mx
                t_mx += t_dx
            else:
                cy += step_y
                t_in = t_my
                t_my += t_dy
    return n


@numba.njit(cache=True)
def _cast(occ, poses, rmin, rmax, fov, n_beams):  # pragma: no cover - compiled
    h, w = occ.shape
    k_poses = poses.shape[0]
    stamp = np.zeros(h * w, np.uint8)  # small, so it stays in cache; reset every 255 poses
    buf = np.empty(h * w, np.int32)
    indptr = np.zeros(k_poses + 1, np.int64)
    cap = max(1024, k_poses * 64)
    out = np.empty(cap, np.int32)
    n = 0
    for k in range(k_poses):
        mark = np.uint8(k % 255 + 1)
        if mark == 1 and k > 0:
            stamp[:] = 0
        m = _cast_pose(
            occ, stamp, mark, poses[k, 0], poses[k, 1], poses[k, 2], rmin, rmax, fov, n_beams, buf
        )
        if n + m > cap:
            cap = max(2 * cap, n + m)
            bigger = np.empty(cap, np.int32)
            bigger[:n] = out[:n]
            out = bigger
        out[n : n + m] = buf[:m]
        n += m
        indptr[k + 1] = n
    return indptr, out[:n].copy()


def visible_pixels(
    occupancy: np.ndarray,
    poses_px: np.ndarray,
    range_min_px: float,
    range_max_px: float,
    fov: float = 2 * math.pi,
    *,
    unknown: np.ndarray | None = None,
    beam_spacing_px: float = 0.9,
) -> Visibility:
    """Pixels seen from each pose, with occlusion.

    Parameters
    ----------
    occupancy : (H, W) bool array
        Cells that stop a ray (walls).
    poses_px : (K, 3) float array
        Sensor poses in pixel coordinates ``(x = column, y = row, angle)``; the angle is
        measured in the image (x right, y down), i.e. clockwise on screen.
    range_min_px, range_max_px : float
        Sensing range in pixels.
    fov : float
        Field of view [rad], centred on the pose angle (2 pi = all around).
    unknown : (H, W) bool array, optional
        Cells that neither stop rays nor are marked seen.
    beam_spacing_px : float
        Largest gap between neighbouring rays at full range.

    Returns
    -------
    Visibility

    Examples
    --------
    >>> occ = np.zeros((20, 20), bool); occ[:, 12] = True
    >>> vis = visible_pixels(occ, np.array([[5.0, 10.0, 0.0]]), 0.0, 30.0)
    >>> bool((vis.seen_from(0) % 20 > 12).any())
    False
    """
    occ = np.ascontiguousarray(occupancy, dtype=np.uint8)
    if unknown is not None:
        occ = occ.copy()
        occ[np.asarray(unknown, bool) & (occ == 0)] = 2
    poses = np.ascontiguousarray(poses_px, dtype=np.float64).reshape(-1, 3)
    n_beams = max(360, int(math.ceil(fov * range_max_px / beam_spacing_px)))
    indptr, pixels = _cast(
        occ, poses, float(range_min_px), float(range_max_px), float(fov), n_beams
    )
    return Visibility(indptr=indptr, pixels=pixels, shape=occ.shape)
