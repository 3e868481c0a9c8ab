"""Recorded runs for the SLAM backends: CARMEN logs, simulator runs, BreezySLAM logs, ROS bags.

:func:`load_log` reads any of them into a :class:`~map2map.robotlog.carmen.CarmenLog`
(one :class:`~map2map.robotlog.base.OdometryReading` per
:class:`~map2map.robotlog.base.LaserScan`, in time order):

* **CARMEN** logs (``ODOM``, ``FLASER``, ``RAWLASER1``, ``ROBOTLASER1`` lines; ``.gz``
  allowed) are parsed by :func:`map2map.robotlog.carmen.read_carmen`;
* a **simulator run** folder (``map2map simulate --out DIR``) is read from its
  ``run.log`` (CARMEN);
* **BreezySLAM raw logs** (the Mines ParisTech ``exp*.dat`` files) are parsed by
  :func:`read_breezyslam`;
* **ROS bags** (ROS 1 ``.bag``, ROS 2 bag folders with sqlite3 or mcap storage) are
  read by :func:`map2map.robotlog.rosbag.read_bag` (optional dependency ``rosbags``).

Every format problem is an :class:`~map2map.core.errors.InputError` naming the file and,
for a bad line, its line number.

Examples
--------
>>> import tempfile, pathlib
>>> d = pathlib.Path(tempfile.mkdtemp())
>>> row = "1000000 0 0 0 " + "0 " * 20 + " ".join(["1500"] * 682)
>>> _ = (d / "run.dat").write_text(row + "\\n" + row.replace("1000000", "1100000", 1) + "\\n")
>>> log = load_log(d / "run.dat")
>>> len(log), log.scans[0].n_beams, float(log.scans[0].ranges[0])
(2, 682, 1.5)
"""

from __future__ import annotations

import gzip
import math
import os
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from ..core.errors import InputError
from .base import LaserScan, OdometryReading
from .carmen import CarmenLog, read_carmen
from .rosbag import is_bag, read_bag

__all__ = ["BreezyRobot", "read_breezyslam", "load_log", "detect_format"]


@dataclass(frozen=True)
class BreezyRobot:
    """Geometry of the Mines ParisTech robot and its Hokuyo URG-04LX (BreezySLAM's values).

    Wheel encoders: 2000 ticks per revolution, wheel radius 77 mm, half axle
    165 mm. Laser: 682 beams over 240 degrees, about 10 Hz, 0 = no return, mounted
    145 mm ahead of the axle centre, readings up to 5.6 m.
    """

    ticks_per_rev: int = 2000
    wheel_radius: float = 0.077
    half_axle: float = 0.165
    n_beams: int = 682
    fov_deg: float = 240.0
    laser_offset: float = 0.145
    range_min: float = 0.02
    range_max: float = 5.6


def _open_lines(path: Path) -> list[str]:
    try:
        if path.suffix == ".gz":
            with gzip.open(path, "rt", encoding="ascii") as f:
                return f.read().splitlines()
        with open(path, encoding="ascii") as f:
            return f.read().splitlines()
    except (OSError, UnicodeDecodeError, EOFError) as exc:
        raise InputError(path, f"cannot read log ({exc})") from None


def read_breezyslam(path: str | os.PathLike, robot: BreezyRobot = BreezyRobot()) -> CarmenLog:
    """Read a BreezySLAM raw log: wheel ticks integrated to odometry, ranges to scans.

    Each line: column 0 the timestamp (microseconds), columns 2 and 3 the left and
    right cumulative encoder ticks, columns 24 to 24 + 682 the ranges in
    millimetres (extra trailing columns are ignored, as BreezySLAM does).
    Odometry integrates the differential-drive kinematics per line::

        dl, dr = 2 pi r * (ticks change) / ticks_per_rev
        ds = (dl + dr) / 2,  dtheta = (dr - dl) / (2 * half_axle)

    along an arc (midpoint heading). Beam ``i`` points at ``-120 + i * 240 / 681``
    degrees (counter-clockwise, 0 = ahead). A 0 reading (no echo or an error code)
    becomes NaN: unusable, it neither hits nor clears.

    Parameters
    ----------
    path : path-like
        The ``.dat`` log.
    robot : BreezyRobot
        Encoder and laser geometry.

    Returns
    -------
    CarmenLog
        Odometry (odometry frame starting at the origin) and scans, one per line.

    Raises
    ------
    InputError
        Empty file, a line that is not numeric or is too short (with its line
        number), or time running backwards.
    """
    path = Path(path)
    if not path.is_file():
        raise InputError(path, "log file not found")
    lines = _open_lines(path)
    need = 24 + robot.n_beams
    stamps, ticks, ranges = [], [], []
    for lineno, line in enumerate(lines, 1):
        toks = line.split()
        if not toks or toks[0].startswith("#"):
            continue
        if len(toks) < need:
            raise InputError(
                path,
                f"line {lineno}: {len(toks)} columns, a BreezySLAM scan line needs {need} "
                f"(timestamp, 23 odometry/status fields, {robot.n_beams} ranges)",
            )
        try:
            vals = np.array(toks[:need], dtype=np.float64)
        except ValueError:
            raise InputError(path, f"line {lineno}: corrupt line (not a number)") from None
        if not np.isfinite(vals).all():
            raise InputError(path, f"line {lineno}: corrupt line (non-finite value)")
        if stamps and vals[0] < stamps[-1][0]:
            raise InputError(path, f"line {lineno}: timestamp goes backwards")
        stamps.append((vals[0], lineno))
        ticks.append(vals[2:4])
        ranges.append(vals[24:need])
    if not stamps:
        raise InputError(path, "empty log: no scan lines")
    t = (np.array([s[0] for s in stamps]) - stamps[0][0]) * 1e-6
    tk = np.asarray(ticks)
    dphi = np.diff(tk, axis=0) * (2 * math.pi / robot.ticks_per_rev) * robot.wheel_radius
    ds = dphi.sum(axis=1) / 2
    dth = (dphi[:, 1] - dphi[:, 0]) / (2 * robot.half_axle)
    th = np.concatenate([[0.0], np.cumsum(dth)])
    mid = th[:-1] + dth / 2
    x = np.concatenate([[0.0], np.cumsum(ds * np.cos(mid))])
    y = np.concatenate([[0.0], np.cumsum(ds * np.sin(mid))])
    inc = math.radians(robot.fov_deg) / (robot.n_beams - 1)
    a0 = -math.radians(robot.fov_deg) / 2
    r = np.asarray(ranges) * 1e-3
    r[r <= 0] = np.nan  # the URG-04LX reports 0 for an error or no echo: unusable
    r = r.astype(np.float32)
    off = (robot.laser_offset, 0.0, 0.0)
    odometry = [
        OdometryReading(float(t[k]), float(x[k]), float(y[k]), float(th[k])) for k in range(len(t))
    ]
    scans = [
        LaserScan(float(t[k]), r[k], a0, inc, robot.range_min, robot.range_max, off)
        for k in range(len(t))
    ]
    return CarmenLog(odometry, scans, None, {"format": "breezyslam"})


def detect_format(path: str | os.PathLike) -> str:
    """``"rosbag"``, ``"simrun"`` (a simulator output folder), ``"breezyslam"`` or ``"carmen"``.

    ROS bags are recognised by :func:`~map2map.robotlog.rosbag.is_bag` (a ``.bag``,
    ``.db3`` or ``.mcap`` file, a folder with ``metadata.yaml``); BreezySLAM logs by
    their first data line starting with a number; CARMEN lines start with a message
    name.

    Parameters
    ----------
    path : path-like
        A log file, or a folder written by ``map2map simulate``.

    Returns
    -------
    str
        The format name that :func:`load_log` takes.
    """
    path = Path(path)
    if path.exists() and is_bag(path):
        return "rosbag"
    if path.is_dir():
        return "simrun"
    if not path.is_file():
        raise InputError(path, "log file not found")
    try:
        opener = gzip.open if path.suffix == ".gz" else open
        with opener(path, "rt", encoding="ascii", errors="replace") as f:
            for line in f:
                toks = line.split()
                if not toks or toks[0].startswith("#"):
                    continue
                try:
                    float(toks[0])
                except ValueError:
                    return "carmen"
                return "breezyslam"
    except (OSError, EOFError) as exc:
        raise InputError(path, f"cannot read log ({exc})") from None
    raise InputError(path, "empty log: no lines")


def load_log(
    path: str | os.PathLike,
    fmt: str = "auto",
    *,
    scan_topic: str | None = None,
    odom_topic: str | None = None,
) -> CarmenLog:
    """Read a recorded run (see module docstring); ``fmt`` forces a format.

    Parameters
    ----------
    path : path-like
        A CARMEN log (``.log``, ``.log.gz``), a BreezySLAM ``.dat``, a simulator
        output folder (its ``run.log``) or a ROS bag (``.bag`` file, ROS 2 bag folder).
    fmt : {"auto", "carmen", "breezyslam", "simrun", "rosbag"}
        Format; ``"auto"`` asks :func:`detect_format`.
    scan_topic, odom_topic : str, optional
        A ROS bag's scan and odometry topics (see
        :func:`~map2map.robotlog.rosbag.read_bag`); refused for the other formats.

    Returns
    -------
    CarmenLog

    Raises
    ------
    InputError
        Unknown format, a folder without ``run.log``, or the reader's own refusals.
    """
    path = Path(path)
    kind = detect_format(path) if fmt == "auto" else fmt
    if kind == "rosbag":
        return read_bag(path, scan_topic=scan_topic, odom_topic=odom_topic)
    for name, value in (("scan_topic", scan_topic), ("odom_topic", odom_topic)):
        if value is not None:
            raise InputError(path, f"`{name}` is for ROS bags; this is a {kind} log")
    if kind == "simrun":
        run = path / "run.log"
        if not run.is_file():
            run = path / "run.log.gz"
        if not run.is_file():
            raise InputError(path, "folder holds no run.log (not a map2map simulate output)")
        return read_carmen(run)
    if kind == "carmen":
        return read_carmen(path)
    if kind == "breezyslam":
        return read_breezyslam(path)
    raise InputError(
        path, f"unknown log format '{fmt}' (auto, carmen, breezyslam, simrun, rosbag)"
    )
