"""map2map: move robot maps between CAD floor plans and SLAM occupancy maps.

The public API re-exports the library functions behind every command line tool.
"""

from ._version import __version__
from .errors import InputError
from .maps import (
    FREE,
    OCCUPIED,
    UNKNOWN,
    OccupancyMap,
    crop_to_content,
    generate_floorplan,
    harmonise,
    load_map,
    preprocess,
    save_map,
    save_map_figure,
    square_resize,
    ternarize,
    thicken,
)

__all__ = [
    "__version__",
    "InputError",
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
