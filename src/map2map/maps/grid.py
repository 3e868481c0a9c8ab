"""Moved to :mod:`map2map.core.grid`; ``map2map.maps.grid`` stays importable for existing code.

New code imports :mod:`map2map.core.grid` (or ``from map2map.maps import OccupancyMap``).

>>> import map2map.core.grid, map2map.maps.grid
>>> map2map.maps.grid.OccupancyMap is map2map.core.grid.OccupancyMap
True
"""

from ..core.grid import *  # noqa: F403
from ..core.grid import __all__  # noqa: F401
