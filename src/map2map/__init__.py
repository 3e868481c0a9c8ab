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
    load_map,
    save_map,
    save_map_figure,
    ternarize,
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
]
