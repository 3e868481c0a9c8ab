"""The mapper interface: what the simulator (or a log replay) feeds a SLAM backend.

A mapper sees **only** odometry and laser scans, never the true pose. After each
scan the caller may ask for the current pose estimate and the current map.

Frames: poses are ``(x, y, theta)`` in metres/radians. Odometry poses live in the
odometry frame (integrated wheel odometry, drifting); a mapper's estimates live in
its map frame, which starts at the first odometry pose it was given.

Examples
--------
>>> import numpy as np
>>> scan = LaserScan(t=0.0, ranges=np.full(360, 2.0, np.float32),
...                  angle_min=0.0, angle_increment=np.deg2rad(1.0),
...                  range_min=0.12, range_max=3.5)
>>> scan.n_beams
360
>>> float(np.rad2deg(scan.angles[-1]))
359.0
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Protocol, runtime_checkable

import numpy as np

from ..core.grid import OccupancyMap

__all__ = ["LaserScan", "OdometryReading", "Mapper"]


@dataclass(frozen=True)
class OdometryReading:
    """An odometry pose (integrated wheel odometry) at time ``t`` (seconds)."""

    t: float
    x: float
    y: float
    theta: float

    @property
    def pose(self) -> np.ndarray:
        return np.array([self.x, self.y, self.theta])


@dataclass(frozen=True, eq=False)
class LaserScan:
    """One 2-D laser scan in the sensor frame (ROS ``sensor_msgs/LaserScan`` semantics).

    ``ranges[i]`` is measured along ``angle_min + i * angle_increment``. Readings
    outside ``[range_min, range_max]``, ``inf`` or ``nan`` mean "no return".
    ``sensor_offset`` is the sensor pose ``(x, y, theta)`` in the robot frame.
    """

    t: float
    ranges: np.ndarray
    angle_min: float
    angle_increment: float
    range_min: float
    range_max: float
    sensor_offset: tuple[float, float, float] = (0.0, 0.0, 0.0)

    @property
    def n_beams(self) -> int:
        return int(np.shape(self.ranges)[0])

    @property
    def angles(self) -> np.ndarray:
        return self.angle_min + self.angle_increment * np.arange(self.n_beams)

    @property
    def valid(self) -> np.ndarray:
        r = np.asarray(self.ranges, float)
        return np.isfinite(r) & (r >= self.range_min) & (r < self.range_max)


@runtime_checkable
class Mapper(Protocol):
    """What every mapping backend (oracle, particle filter, graph SLAM) provides."""

    name: str

    def update(self, odom: OdometryReading, scan: LaserScan) -> None:
        """Take one odometry reading and the scan taken at that time.

        Parameters
        ----------
        odom : OdometryReading
            Raw odometry at the scan's time.
        scan : LaserScan
            The scan.
        """
        ...

    def pose(self) -> np.ndarray:
        """Current pose estimate ``(x, y, theta)`` in the map frame.

        Returns
        -------
        (x, y, theta)
        """
        ...

    def get_map(self) -> OccupancyMap:
        """The current occupancy map (0 occupied, 255 free, 127 unknown).

        Returns
        -------
        OccupancyMap
        """
        ...
