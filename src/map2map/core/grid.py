"""The occupancy-map model: one grid convention for the whole package.

Convention (documented here once, used everywhere, converted only at the edges):

* ``data`` is a 2-D ``uint8`` array in **image order**: row 0 is the top row of the
  picture (the row a PGM file stores first), column 0 the left column.
* Values follow the thesis (section 4.1): ``OCCUPIED = 0``, ``FREE = 255``,
  ``UNKNOWN = 127``. Loaders map every other value onto one of these three
  (:func:`map2map.maps.ros.load_ros_map` does it exactly as ROS map_server).
* ``resolution`` is in metres per pixel.
* ``origin = (x, y, yaw)`` is the ROS origin: the world pose of the lower-left
  corner of the lower-left pixel (row ``H - 1``, column 0). ``yaw`` rotates the
  grid about that corner, counter-clockwise, in radians.
* Pixel coordinates used by the rest of the package: ``x`` = column (to the right),
  ``y`` = row (downwards), origin at the top-left corner of the image; the centre
  of pixel ``(row r, col c)`` is at ``(x, y) = (c + 0.5, r + 0.5)`` in *continuous*
  pixel coordinates, and integer indices ``(r, c)`` address it.

Examples
--------
>>> import numpy as np
>>> from map2map.core.grid import OccupancyMap, FREE
>>> m = OccupancyMap(np.full((4, 6), FREE, np.uint8), resolution=0.5)
>>> m.shape
(4, 6)
>>> m.pixel_to_world([3], [0])          # centre of row 3 (bottom), column 0
(array([0.25]), array([0.25]))
>>> m.world_to_pixel([0.25], [1.75])    # -> row 0, column 0
(array([0]), array([0]))
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field, replace
from typing import Any

import numpy as np

OCCUPIED: int = 0
UNKNOWN: int = 127
FREE: int = 255

__all__ = ["OCCUPIED", "UNKNOWN", "FREE", "OccupancyMap", "ternarize"]


def ternarize(values: np.ndarray, occupied_below: int = 64, free_above: int = 191) -> np.ndarray:
    """Snap arbitrary grey values onto the three map values.

    Values ``<= occupied_below`` become :data:`OCCUPIED`, values ``>= free_above``
    become :data:`FREE` and everything between becomes :data:`UNKNOWN`.

    Parameters
    ----------
    values : ndarray
        Grey values of any shape (any numeric dtype).
    occupied_below : int
        Values ``<=`` this are occupied.
    free_above : int
        Values ``>=`` this are free.

    Returns
    -------
    ndarray of uint8
        Same shape, values 0, 127 or 255 only.

    Examples
    --------
    >>> ternarize(np.array([0, 60, 127, 200, 255], np.uint8)).tolist()
    [0, 0, 127, 255, 255]
    """
    v = np.asarray(values)
    out = np.full(v.shape, UNKNOWN, np.uint8)
    out[v <= occupied_below] = OCCUPIED
    out[v >= free_above] = FREE
    return out


@dataclass(eq=False)
class OccupancyMap:
    """A 2-D occupancy grid with its metric frame.

    Parameters
    ----------
    data : (H, W) uint8 array
        Cell values: 0 occupied, 255 free, 127 unknown (see module docstring).
    resolution : float
        Metres per pixel, > 0.
    origin : (x, y, yaw)
        ROS origin of the lower-left pixel corner, metres and radians.
    meta : dict
        Free-form extras carried along (e.g. HouseExpo room categories).
    """

    data: np.ndarray
    resolution: float = 0.05
    origin: tuple[float, float, float] = (0.0, 0.0, 0.0)
    meta: dict[str, Any] = field(default_factory=dict)

    def __post_init__(self) -> None:
        data = np.asarray(self.data)
        if data.ndim != 2:
            raise ValueError(f"occupancy grid must be 2-D, got shape {data.shape}")
        if data.dtype != np.uint8:
            raise ValueError(f"occupancy grid must be uint8, got {data.dtype}")
        bad = (data != OCCUPIED) & (data != FREE) & (data != UNKNOWN)
        if bad.any():
            raise ValueError(
                "occupancy grid holds values other than 0/127/255; use ternarize() first"
            )
        res = float(self.resolution)
        if not math.isfinite(res) or res <= 0:
            raise ValueError(f"resolution must be a positive number, got {self.resolution!r}")
        origin = tuple(float(v) for v in self.origin)
        if len(origin) == 2:
            origin = (*origin, 0.0)
        if len(origin) != 3 or not all(math.isfinite(v) for v in origin):
            raise ValueError(f"origin must be (x, y, yaw), got {self.origin!r}")
        self.data = data
        self.resolution = res
        self.origin = origin  # type: ignore[assignment]

    # ------------------------------------------------------------------ basics
    @property
    def shape(self) -> tuple[int, int]:
        return self.data.shape  # type: ignore[return-value]

    @property
    def height(self) -> int:
        return self.data.shape[0]

    @property
    def width(self) -> int:
        return self.data.shape[1]

    @property
    def scale_known(self) -> bool:
        """Whether the resolution is the map's own (stored in its file or given), not the
        default a picture without one is read at (``meta["resolution_assumed"]``): only
        then are lengths on it metres (scale bars, errors in metres, the inspection).

        Examples
        --------
        >>> m = OccupancyMap(np.full((2, 2), 255, np.uint8), 0.05)
        >>> picture = OccupancyMap(m.data, 0.05, meta={"resolution_assumed": True})
        >>> m.scale_known, picture.scale_known
        (True, False)
        """
        return not self.meta.get("resolution_assumed", False)

    @property
    def size_m(self) -> tuple[float, float]:
        """(width, height) in metres."""
        return self.width * self.resolution, self.height * self.resolution

    def copy(self, data: np.ndarray | None = None, **changes: Any) -> OccupancyMap:
        """A copy, optionally with new data (same frame) or other fields changed.

        Parameters
        ----------
        data : (H, W) uint8 array, optional
            New cell values (same frame).
        **changes
            Other fields to replace (``resolution``, ``origin``, ``meta``).

        Returns
        -------
        OccupancyMap
        """
        new = replace(
            self,
            data=self.data.copy() if data is None else data,
            meta=dict(self.meta),
            **changes,
        )
        return new

    def __eq__(self, other: object) -> bool:
        if not isinstance(other, OccupancyMap):
            return NotImplemented
        return (
            self.shape == other.shape
            and bool(np.array_equal(self.data, other.data))
            and self.resolution == other.resolution
            and self.origin == other.origin
        )

    def __repr__(self) -> str:
        return (
            f"OccupancyMap(shape={self.shape}, resolution={self.resolution:g}, "
            f"origin={tuple(round(v, 6) for v in self.origin)}, "
            f"free={int(self.free.sum())}, occupied={int(self.occupied.sum())})"
        )

    # ------------------------------------------------------------------ masks
    @property
    def free(self) -> np.ndarray:
        """Boolean mask of free cells."""
        return self.data == FREE

    @property
    def occupied(self) -> np.ndarray:
        """Boolean mask of occupied cells."""
        return self.data == OCCUPIED

    @property
    def unknown(self) -> np.ndarray:
        """Boolean mask of unknown cells."""
        return self.data == UNKNOWN

    @classmethod
    def from_masks(
        cls,
        free: np.ndarray,
        occupied: np.ndarray,
        resolution: float = 0.05,
        origin: tuple[float, float, float] = (0.0, 0.0, 0.0),
        meta: dict[str, Any] | None = None,
    ) -> OccupancyMap:
        """Build a map from boolean masks; occupied wins where both are set, the rest is unknown.

        Parameters
        ----------
        free, occupied : (H, W) bool arrays
            Cell masks.
        resolution : float
            Metres per pixel.
        origin : (x, y, yaw)
            ROS origin.
        meta : dict, optional
            Copied into the map.

        Returns
        -------
        OccupancyMap
        """
        data = np.full(np.shape(free), UNKNOWN, np.uint8)
        data[np.asarray(free, bool)] = FREE
        data[np.asarray(occupied, bool)] = OCCUPIED
        return cls(data, resolution, origin, dict(meta or {}))

    # ------------------------------------------------------------ coordinates
    def pixel_to_world(self, rows, cols) -> tuple[np.ndarray, np.ndarray]:
        """World (x, y) in metres of pixel centres given integer or fractional (row, col).

        Integer indices give pixel centres; fractional indices are interpolated
        linearly (``row = r`` is the centre of row ``r``).

        Parameters
        ----------
        rows, cols : array-like
            Pixel indices (row 0 = top).

        Returns
        -------
        x, y : ndarray
            Metres.
        """
        r = np.asarray(rows, float)
        c = np.asarray(cols, float)
        lx = (c + 0.5) * self.resolution
        ly = (self.height - r - 0.5) * self.resolution
        ox, oy, yaw = self.origin
        if yaw == 0.0:
            return ox + lx, oy + ly
        cs, sn = math.cos(yaw), math.sin(yaw)
        return ox + cs * lx - sn * ly, oy + sn * lx + cs * ly

    def world_to_pixel_float(self, x, y) -> tuple[np.ndarray, np.ndarray]:
        """Fractional (row, col) of world points; the inverse of :meth:`pixel_to_world`.

        Parameters
        ----------
        x, y : array-like
            World points, metres.

        Returns
        -------
        rows, cols : ndarray of float
        """
        ox, oy, yaw = self.origin
        dx = np.asarray(x, float) - ox
        dy = np.asarray(y, float) - oy
        if yaw != 0.0:
            cs, sn = math.cos(yaw), math.sin(yaw)
            dx, dy = cs * dx + sn * dy, -sn * dx + cs * dy
        col = dx / self.resolution - 0.5
        row = self.height - dy / self.resolution - 0.5
        return row, col

    def world_to_pixel(self, x, y) -> tuple[np.ndarray, np.ndarray]:
        """Integer (row, col) of the pixels containing world points (may lie outside the grid).

        Parameters
        ----------
        x, y : array-like
            World points, metres.

        Returns
        -------
        rows, cols : ndarray of int64
        """
        row, col = self.world_to_pixel_float(x, y)
        return np.floor(row + 0.5).astype(np.int64), np.floor(col + 0.5).astype(np.int64)

    def contains(self, rows, cols) -> np.ndarray:
        """Whether integer pixel indices lie inside the grid.

        Parameters
        ----------
        rows, cols : array-like of int
            Pixel indices.

        Returns
        -------
        ndarray of bool
        """
        r = np.asarray(rows)
        c = np.asarray(cols)
        return (r >= 0) & (r < self.height) & (c >= 0) & (c < self.width)

    def _corner_shift(self, dcols: float, drows_up: float) -> tuple[float, float, float]:
        """Origin moved by ``dcols`` pixels right and ``drows_up`` pixels up in the grid frame."""
        ox, oy, yaw = self.origin
        lx, ly = dcols * self.resolution, drows_up * self.resolution
        cs, sn = math.cos(yaw), math.sin(yaw)
        return (ox + cs * lx - sn * ly, oy + sn * lx + cs * ly, yaw)

    # --------------------------------------------------------- crop and pad
    def crop(self, row0: int, row1: int, col0: int, col1: int) -> OccupancyMap:
        """Rows ``row0:row1`` and columns ``col0:col1``, origin kept on the same world point.

        Parameters
        ----------
        row0, row1, col0, col1 : int
            Half-open ranges of rows and columns.

        Returns
        -------
        OccupancyMap

        Examples
        --------
        >>> m = OccupancyMap(np.full((10, 10), 255, np.uint8), 0.1)
        >>> c = m.crop(2, 5, 3, 7)
        >>> np.allclose(c.pixel_to_world(0, 0), m.pixel_to_world(2, 3))
        True
        """
        h, w = self.shape
        row0, row1 = max(0, int(row0)), min(h, int(row1))
        col0, col1 = max(0, int(col0)), min(w, int(col1))
        if row1 <= row0 or col1 <= col0:
            raise ValueError("crop window is empty")
        origin = self._corner_shift(col0, h - row1)
        return self.copy(data=self.data[row0:row1, col0:col1].copy(), origin=origin)

    def pad(
        self, top: int = 0, bottom: int = 0, left: int = 0, right: int = 0, value: int = UNKNOWN
    ) -> OccupancyMap:
        """Pad with ``value`` (unknown by default), keeping every cell at its world position.

        Parameters
        ----------
        top, bottom, left, right : int
            Cells added on each side.
        value : int
            Value of the new cells.

        Returns
        -------
        OccupancyMap
        """
        if min(top, bottom, left, right) < 0:
            raise ValueError("padding must be non-negative")
        data = np.pad(
            self.data, ((top, bottom), (left, right)), mode="constant", constant_values=value
        )
        origin = self._corner_shift(-left, -bottom)
        return self.copy(data=data, origin=origin)

    def content_bbox(self) -> tuple[int, int, int, int] | None:
        """(row0, row1, col0, col1) of the known (non-unknown) cells, or None if all unknown.

        Returns
        -------
        (row0, row1, col0, col1) or None
            Half-open ranges.
        """
        known = ~self.unknown
        rows = np.flatnonzero(known.any(axis=1))
        if rows.size == 0:
            return None
        cols = np.flatnonzero(known.any(axis=0))
        return int(rows[0]), int(rows[-1]) + 1, int(cols[0]), int(cols[-1]) + 1
