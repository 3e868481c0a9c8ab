"""What an auto-correction returns: the corrected map and its walls in world metres.

Its own module, light to import (numpy and the map type only): ``map2map autocorrect``
on a folder hands the maps to worker processes and only wraps their outputs, so the
calling process need not import the cleaning (scipy, numba) before the pool starts.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ...core.grid import OccupancyMap

__all__ = ["Correction"]


@dataclass
class Correction:
    """An auto-corrected map and its wall segments (world metres: x0, y0, x1, y1)."""

    map: OccupancyMap
    segments: np.ndarray
    warnings: list[str]

    @classmethod
    def of(cls, out: OccupancyMap) -> Correction:
        """The correction an output map carries in ``meta["autocorrect"]`` (its wall
        segments in input pixels, its warnings): what every corrector of
        ``map2map autocorrect --model`` returns, as :func:`autocorrect_many` does.

        Examples
        --------
        >>> m = OccupancyMap(np.full((20, 30), 255, np.uint8), 0.05, (1.0, 2.0, 0.0))
        >>> m.meta["autocorrect"] = {"segments_px": [[0.5, 10.5, 20.5, 10.5]],
        ...                          "warnings": []}
        >>> Correction.of(m).segments.round(3).tolist()  # x0 y0 x1 y1, metres
        [[1.025, 2.475, 2.025, 2.475]]
        """
        ac = out.meta.get("autocorrect", {})
        return cls(out, _world_segments(out, np.asarray(ac.get("segments_px", []), float)),
                   list(ac.get("warnings", [])))


def _world_segments(m: OccupancyMap, seg_px: np.ndarray) -> np.ndarray:
    """Segments in continuous input pixel coordinates (x = column) -> world metres."""
    seg_px = seg_px.reshape(-1, 4)
    if not len(seg_px):
        return np.zeros((0, 4))
    x0, y0 = m.pixel_to_world(seg_px[:, 1] - 0.5, seg_px[:, 0] - 0.5)
    x1, y1 = m.pixel_to_world(seg_px[:, 3] - 0.5, seg_px[:, 2] - 0.5)
    return np.stack([x0, y0, x1, y1], 1)
