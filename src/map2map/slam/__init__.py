"""SLAM: the mapper interface shared by the simulator and every backend."""

from ..robotlog.base import LaserScan, Mapper, OdometryReading

__all__ = ["LaserScan", "Mapper", "OdometryReading"]
