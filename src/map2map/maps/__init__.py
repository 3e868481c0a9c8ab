"""Maps: the occupancy-grid model, file formats, floor plans and preprocessing."""

from .grid import FREE, OCCUPIED, UNKNOWN, OccupancyMap, ternarize

__all__ = ["FREE", "OCCUPIED", "UNKNOWN", "OccupancyMap", "ternarize"]
