"""The robot-log contract shared by the simulator and the SLAM backends.

* :mod:`~map2map.robotlog.base` -- :class:`LaserScan`, :class:`OdometryReading` and the
  :class:`Mapper` protocol (what a SLAM backend is fed: odometry and scans only);
* :mod:`~map2map.robotlog.mappers` -- the registry of mapping backends by name (filled
  by the package root, which registers the backends of sim and slam; each is imported
  only when used);
* :mod:`~map2map.robotlog.carmen` -- CARMEN log files (write, read, replay);
* :mod:`~map2map.robotlog.logs` -- every recorded-log format ``map2map slam`` reads.

:mod:`map2map.sim` and :mod:`map2map.slam` both import this package; it imports
neither.
"""

from .base import LaserScan, Mapper, OdometryReading

__all__ = ["LaserScan", "Mapper", "OdometryReading"]
