"""Small synthetic floor plans for the trajectory / parametric tests (built with numpy)."""

from __future__ import annotations

import numpy as np

from map2map.core.grid import FREE, OCCUPIED, UNKNOWN, OccupancyMap


def two_rooms(res: float = 0.05, door: bool = True) -> OccupancyMap:
    """4 m x 6 m: two rooms side by side, a 0.8 m door between them, a corridor below.

    Walls are 2 px thick; everything outside the outer wall is unknown.
    """
    h, w = 80, 120
    d = np.full((h + 4, w + 4), UNKNOWN, np.uint8)
    d[2 : h + 2, 2 : w + 2] = OCCUPIED
    d[4:h, 4:w] = FREE
    d[4:56, 60:62] = OCCUPIED  # wall between the rooms
    if door:
        d[20:36, 60:62] = FREE  # 0.8 m door
    d[56:58, 4:w] = OCCUPIED  # corridor wall
    d[56:58, 20:36] = FREE  # door to the corridor
    d[56:58, 84:100] = FREE
    if not door:
        d[56:58, 84:100] = OCCUPIED
    return OccupancyMap(d, res)


def centre(m: OccupancyMap, row: int, col: int) -> tuple[float, float]:
    """World (x, y) of pixel (row, col)."""
    x, y = m.pixel_to_world([row], [col])
    return float(x[0]), float(y[0])
