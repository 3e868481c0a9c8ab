"""Reachability check of a map's free space for a disc robot (step 7 of
:mod:`map2map.maps.floorplan`).

Examples
--------
>>> import numpy as np
>>> from map2map.core.grid import OccupancyMap
>>> data = np.zeros((40, 60), np.uint8)
>>> data[5:35, 5:55] = 255
>>> connectivity(OccupancyMap(data, 0.05)).ok
True
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import cv2
import numpy as np

from ...core.grid import FREE, OccupancyMap
from .layout import ROBOT_RADIUS

__all__ = ["Connectivity", "connectivity"]


@dataclass(frozen=True)
class Connectivity:
    """Reachability of a map's free space for a disc robot.

    Attributes
    ----------
    components : int
        Connected components (4-connected) of the robot's configuration space,
        i.e. free pixels whose distance to the nearest non-free pixel exceeds
        the robot radius.
    unreachable : (H, W) bool array
        Free pixels farther than ``robot_radius * sqrt(2)`` (+ half a pixel)
        from the largest component: no robot pose can sweep them.
    """

    components: int
    unreachable: np.ndarray

    @property
    def ok(self) -> bool:
        """One component and no unreachable free pixel."""
        return self.components == 1 and not bool(self.unreachable.any())


def connectivity(m: OccupancyMap, robot_radius: float = ROBOT_RADIUS) -> Connectivity:
    """Check that the free space is one connected component for a disc robot.

    The robot centre may stand on free pixels whose (exact Euclidean) distance
    to the nearest non-free pixel exceeds ``robot_radius``; these form the
    configuration space. A free pixel counts as reachable when it lies within
    ``robot_radius * sqrt(2)`` of the largest configuration-space component:
    the body of a disc robot cannot reach the corner pixel of a square room
    (it is ``r * sqrt(2)`` from the nearest centre), so a tolerance of exactly
    ``r`` would declare every rectangular room unreachable, while a pocket
    behind a gap narrower than the robot still fails.

    Parameters
    ----------
    m : OccupancyMap
        The map.
    robot_radius : float
        Disc radius, metres.

    Returns
    -------
    Connectivity
        Component count and the unreachable free pixels.

    Examples
    --------
    >>> data = np.zeros((40, 60), np.uint8)
    >>> data[5:35, 5:28] = data[5:35, 32:55] = 255      # two rooms, no door
    >>> connectivity(OccupancyMap(data, 0.05)).components
    2
    >>> data[15:31, 28:32] = 255                          # a 0.8 m door
    >>> connectivity(OccupancyMap(data, 0.05)).ok
    True
    """
    free = m.data == FREE
    if not free.any():
        return Connectivity(0, free)
    r_px = robot_radius / m.resolution
    dist = cv2.distanceTransform(free.astype(np.uint8), cv2.DIST_L2, cv2.DIST_MASK_PRECISE)
    core = dist > r_px
    n, labels, stats, _ = cv2.connectedComponentsWithStats(core.astype(np.uint8), connectivity=4)
    if n <= 1:
        return Connectivity(0, free)
    biggest = 1 + int(np.argmax(stats[1:, cv2.CC_STAT_AREA]))
    away = cv2.distanceTransform(
        (labels != biggest).astype(np.uint8), cv2.DIST_L2, cv2.DIST_MASK_PRECISE
    )
    unreachable = free & (away > r_px * math.sqrt(2.0) + 0.5)
    return Connectivity(n - 1, unreachable)
