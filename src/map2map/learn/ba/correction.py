"""What an auto-correction returns: the corrected map and its walls in world metres.

Its own module, light to import (numpy and the map type only): ``map2map autocorrect``
on a folder hands the maps to worker processes and only wraps their outputs, so the
calling process need not import the cleaning (scipy, numba) before the pool starts.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from ...core.grid import OccupancyMap

__all__ = ["Correction"]


@dataclass
class Correction:
    """An auto-corrected map and its wall segments (world metres: x0, y0, x1, y1).

    ``arcs`` are its curved walls, ``xc, yc, r, start, sweep`` (metres; degrees
    counter-clockwise), and ``arc_of`` says, per segment, which arc it is a chord of (-1:
    a straight wall); :meth:`save_dxf` writes both.
    """

    map: OccupancyMap
    segments: np.ndarray
    warnings: list[str]
    arcs: np.ndarray = field(default_factory=lambda: np.zeros((0, 5)))
    arc_of: np.ndarray | None = None

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
        segs = _world_segments(out, np.asarray(ac.get("segments_px", []), float))
        arcs_px = np.asarray(ac.get("arcs_px", []), float).reshape(-1, 5)
        if not len(arcs_px):
            return cls(out, segs, list(ac.get("warnings", [])))
        from ...maps.curves import arcs_to_world

        arcs = arcs_to_world(arcs_px, lambda x, y: out.pixel_to_world(y - 0.5, x - 0.5))
        return cls(out, segs, list(ac.get("warnings", [])), arcs,
                   np.asarray(ac["arc_of"], int))

    def save_dxf(self, path) -> None:
        """Write the walls as a DXF drawing in metres: straight walls as ``LINE`` entities,
        curved walls as ``ARC`` entities (:func:`map2map.maps.dxf.save_segments_dxf`).

        Examples
        --------
        >>> import tempfile, pathlib, ezdxf
        >>> m = OccupancyMap(np.full((20, 30), 255, np.uint8), 0.05)
        >>> m.meta["autocorrect"] = {"segments_px": [[0.5, 10.5, 20.5, 10.5]]}
        >>> p = pathlib.Path(tempfile.mkdtemp()) / "w.dxf"
        >>> Correction.of(m).save_dxf(p)
        >>> [e.dxftype() for e in ezdxf.readfile(p).modelspace()]
        ['LINE']
        """
        from ...maps.dxf import save_segments_dxf

        save_segments_dxf(self.segments, path, arcs=self.arcs, arc_of=self.arc_of)


def _world_segments(m: OccupancyMap, seg_px: np.ndarray) -> np.ndarray:
    """Segments in continuous input pixel coordinates (x = column) -> world metres."""
    seg_px = seg_px.reshape(-1, 4)
    if not len(seg_px):
        return np.zeros((0, 4))
    x0, y0 = m.pixel_to_world(seg_px[:, 1] - 0.5, seg_px[:, 0] - 0.5)
    x1, y1 = m.pixel_to_world(seg_px[:, 3] - 0.5, seg_px[:, 2] - 0.5)
    return np.stack([x0, y0, x1, y1], 1)
