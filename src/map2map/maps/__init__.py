"""Maps: the occupancy-grid model, file formats, floor plans and preprocessing."""

from .formats import load_map, save_map
from .grid import FREE, OCCUPIED, UNKNOWN, OccupancyMap, ternarize
from .render import save_map_figure

__all__ = [
    "FREE",
    "OCCUPIED",
    "UNKNOWN",
    "OccupancyMap",
    "ternarize",
    "load_map",
    "save_map",
    "save_map_figure",
]
