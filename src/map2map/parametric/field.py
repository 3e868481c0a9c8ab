"""Displacement fields and the deformed map (thesis 3.2: "(d_x, d_y) used to deform the map").

Semantics (pinned down by the tests): the plan content at pixel ``p`` appears at
``p + d(p)`` in the output map, with ``x`` = columns (right) and ``y`` = rows (down), in
pixels. That is a *forward* warp.

How it is done, without holes. Splatting every plan pixel forward leaves holes where the
field stretches and collisions where it compresses. Instead the field is inverted: for
every output pixel ``q`` the source ``p`` with ``p + d(p) = q`` is found by the
fixed-point iteration ``p <- q - d(p)`` (``d`` sampled bilinearly with
:func:`cv2.remap`), which converges where the field is a contraction (``|grad d| < 1``,
true of smooth SLAM-like deformations), and the plan is sampled there with nearest
neighbour (:func:`cv2.remap`), so every output pixel gets exactly one of the three map
values. Nearest sampling can still drop a one-pixel wall where the field stretches, so
every observed occupied plan pixel is additionally splatted to ``round(p + d(p))``:
walls stay closed. Output pixels whose source was never observed stay unknown
(partial mapping, thesis Fig. 5.13).

Examples
--------
>>> import numpy as np
>>> plan = np.full((5, 7), 255, np.uint8); plan[2, 2] = 0
>>> f = DisplacementField(np.full((5, 7), 2.0, np.float32), np.zeros((5, 7), np.float32))
>>> out = warp_map(plan, f, np.ones((5, 7), bool))
>>> [int(c) for c in np.argwhere(out == 0)[0]]     # (row, col): moved 2 columns right
[2, 4]
"""

from __future__ import annotations

import os
from dataclasses import dataclass

import cv2
import numpy as np

from ..core._io import atomic_path
from ..core.errors import InputError
from ..core.geometry import invert_displacement
from ..core.grid import OCCUPIED, UNKNOWN

__all__ = ["DisplacementField", "invert_field", "warp_map"]


@dataclass
class DisplacementField:
    """Per-pixel displacement in pixels: ``dx`` (columns, right), ``dy`` (rows, down)."""

    dx: np.ndarray
    dy: np.ndarray

    def __post_init__(self) -> None:
        self.dx = np.ascontiguousarray(self.dx, np.float32)
        self.dy = np.ascontiguousarray(self.dy, np.float32)
        if self.dx.shape != self.dy.shape or self.dx.ndim != 2:
            raise ValueError("dx and dy must be 2-D arrays of the same shape")

    @classmethod
    def zeros(cls, shape: tuple[int, int]) -> DisplacementField:
        """A zero field of ``shape``.

        Parameters
        ----------
        shape : (H, W)

        Returns
        -------
        DisplacementField
        """
        return cls(np.zeros(shape, np.float32), np.zeros(shape, np.float32))

    @property
    def shape(self) -> tuple[int, int]:
        return self.dx.shape  # type: ignore[return-value]

    @property
    def magnitude(self) -> np.ndarray:
        """``|d|`` in pixels."""
        return np.hypot(self.dx, self.dy)

    def __add__(self, other: DisplacementField) -> DisplacementField:
        return DisplacementField(self.dx + other.dx, self.dy + other.dy)

    def masked(self, mask: np.ndarray) -> DisplacementField:
        """Zero outside ``mask``.

        Parameters
        ----------
        mask : (H, W) bool array

        Returns
        -------
        DisplacementField
        """
        return DisplacementField(np.where(mask, self.dx, 0), np.where(mask, self.dy, 0))

    def stats(self, mask: np.ndarray | None = None) -> dict[str, float]:
        """Mean and maximum ``|d|`` [px] (over ``mask`` if given).

        Parameters
        ----------
        mask : (H, W) bool array, optional

        Returns
        -------
        dict
            ``mean`` and ``max``.
        """
        mag = self.magnitude if mask is None else self.magnitude[mask]
        if mag.size == 0:
            return {"mean": 0.0, "max": 0.0}
        return {"mean": float(mag.mean()), "max": float(mag.max())}

    def save_npz(self, path: str | os.PathLike) -> None:
        """Write ``dx`` and ``dy`` (float32, pixels) to an ``.npz`` atomically.

        Parameters
        ----------
        path : path-like
        """
        with atomic_path(path) as tmp, open(tmp, "wb") as fh:
            np.savez(fh, dx=self.dx, dy=self.dy)

    @classmethod
    def load_npz(cls, path: str | os.PathLike) -> DisplacementField:
        """Read a field written by :meth:`save_npz` (:class:`InputError` if unreadable).

        Parameters
        ----------
        path : path-like

        Returns
        -------
        DisplacementField
        """
        try:
            with np.load(path) as z:
                return cls(z["dx"], z["dy"])
        except (OSError, KeyError, ValueError) as exc:
            raise InputError(path, f"not a displacement field ({exc})") from None


def invert_field(
    field: DisplacementField, iterations: int = 8, tol: float = 0.01, settled: float = 0.999
) -> tuple[np.ndarray, np.ndarray]:
    """Source coordinates ``(px, py)`` (float32 maps) with ``p + d(p) = q`` for every pixel ``q``.

    :func:`map2map.core.geometry.invert_displacement`: fixed-point iteration
    ``p <- q - d(p)`` started at ``p = q - d(q)``; stops after ``iterations`` or when a
    fraction ``settled`` of the pixels moved less than ``tol`` pixels in the last step.
    (Where the field jumps, e.g. at the edge of what a pose saw, or folds, there is no
    exact inverse and the iteration keeps oscillating there.)

    Parameters
    ----------
    field : DisplacementField
        Forward displacement.
    iterations : int
        Most fixed-point steps.
    tol : float
        Movement (pixels) below which a pixel counts as settled.
    settled : float
        Fraction of settled pixels that stops the iteration.

    Returns
    -------
    px, py : (H, W) float32 arrays

    Examples
    --------
    >>> f = DisplacementField(np.full((3, 4), 1.5, np.float32), np.zeros((3, 4), np.float32))
    >>> px, py = invert_field(f)
    >>> px[0].tolist()
    [-1.5, -0.5, 0.5, 1.5]
    """
    return invert_displacement(field.dx, field.dy, iterations, tol, settled)


def warp_map(plan: np.ndarray, field: DisplacementField, observed: np.ndarray) -> np.ndarray:
    """The deformed map: plan content at ``p`` moved to ``p + d(p)``; unobserved -> unknown.

    Parameters
    ----------
    plan : (H, W) uint8
        Plan cells (0 occupied, 255 free, 127 unknown).
    field : DisplacementField
        Displacement of every plan pixel.
    observed : (H, W) bool
        Plan pixels the LIDAR saw; only they appear in the output.

    Returns
    -------
    (H, W) uint8 array
    """
    plan = np.ascontiguousarray(plan, np.uint8)
    h, w = plan.shape
    px, py = invert_field(field)
    src = np.where(observed, plan, UNKNOWN).astype(np.uint8)
    out = cv2.remap(
        src, px, py, cv2.INTER_NEAREST, borderMode=cv2.BORDER_CONSTANT, borderValue=UNKNOWN
    )
    # keep every observed wall pixel: splat it forward to round(p + d(p))
    rows, cols = np.nonzero(observed & (plan == OCCUPIED))
    qc = np.floor(cols + field.dx[rows, cols] + 0.5).astype(np.int64)
    qr = np.floor(rows + field.dy[rows, cols] + 0.5).astype(np.int64)
    ok = (qr >= 0) & (qr < h) & (qc >= 0) & (qc < w)
    out[qr[ok], qc[ok]] = OCCUPIED
    return out
