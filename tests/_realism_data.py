"""A tiny simulated dataset for the realism tests: one 3.5 x 2.5 m room with a wall and a
door, simulated 8 s a pair at 32 px (test-only helper)."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from map2map.core.grid import OccupancyMap
from map2map.datasets.build import build_dataset
from map2map.datasets.pair import BuildParams
from map2map.maps.ros import save_ros_map


def room_dataset(plans: Path, ds: Path, count: int, seed: int) -> Path:
    """Write the room plan into folder ``plans`` and build ``count`` pairs of it in ``ds``."""
    d = np.full((50, 70), 127, np.uint8)
    d[2:-2, 2:-2] = 0
    d[4:-4, 4:-4] = 255
    d[4:-4, 35] = 0
    d[10:30, 35] = 255
    save_ros_map(OccupancyMap(d, 0.05), plans / "room.yaml")
    p = BuildParams(source="simulate", duration=8.0, size=32, fov=360.0)
    build_dataset(ds, str(plans), count, seed, p, workers=0, progress=False)
    return ds
