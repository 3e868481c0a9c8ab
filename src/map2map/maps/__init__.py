"""Maps: the occupancy-grid model, file formats, floor plans and preprocessing."""

from ..core.grid import FREE, OCCUPIED, UNKNOWN, OccupancyMap, ternarize
from .floorplan import generate_floorplan
from .formats import load_map, save_map
from .preprocess import crop_to_content, harmonise, preprocess, square_resize, thicken
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
    "generate_floorplan",
    "square_resize",
    "harmonise",
    "thicken",
    "crop_to_content",
    "preprocess",
]
