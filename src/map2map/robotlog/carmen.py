"""CARMEN log files: write a simulated run, read classic Radish logs, replay them.

The format is the one of the CARMEN robot navigation toolkit logger, used by the
classic Radish SLAM data sets (http://carmen.sourceforge.net/logger_playback.html):
one message per line, ``NAME [fields] ipc_timestamp ipc_hostname logger_timestamp``.

Messages written by :func:`write_carmen` (one triple per scan):

* ``ODOM x y theta tv rv accel`` - integrated wheel odometry at the scan time;
* ``TRUEPOS true_x true_y true_theta odom_x odom_y odom_theta`` - ground truth,
  as the CARMEN simulator logs it;
* ``RAWLASER1 laser_type start_angle field_of_view angular_resolution
  maximum_range accuracy remission_mode num_readings [ranges] num_remissions
  [remissions]`` - the scan, any field of view. ``field_of_view`` is the span
  from the first to the last beam; no-return beams are written as
  ``maximum_range`` (the CARMEN convention) and read back as ``inf``.

:func:`read_carmen` also reads the old ``FLASER num_readings [ranges] x y theta
odom_x odom_y odom_theta`` (180 degrees starting at -90 degrees) and
``ROBOTLASER1`` messages, accepts gzip (``.gz``), keeps ``PARAM`` lines and
ignores the other documented message types (``SYNC``, ``RAWLASER2-4``, ``RLASER``,
GPS, ...). Unknown messages, corrupt lines, logs without odometry or scans and a
beam count that changes mid-log are bad input (:class:`~map2map.core.errors.InputError`
naming the line).

Numbers are written so that they read back bit-exactly (poses and times with
Python's shortest round-trip ``repr``, ranges in millimetres, which is the
scanner's own quantisation), so replaying a saved run rebuilds the same map.

Examples
--------
>>> import numpy as np, tempfile, pathlib
>>> from map2map.robotlog.base import LaserScan, OdometryReading
>>> scan = LaserScan(0.2, np.array([1.0, np.inf, 2.5], np.float32), -0.1, 0.1, 0.12, 3.5)
>>> odo = OdometryReading(0.2, 0.1, 0.0, 0.05)
>>> path = pathlib.Path(tempfile.mkdtemp()) / "run.log"
>>> write_carmen(path, [(odo, scan, (0.1, 0.0, 0.05))])
>>> log = read_carmen(path)
>>> len(log), log.scans[0].ranges.tolist(), log.odometry[0] == odo
(1, [1.0, inf, 2.5], True)
"""

from __future__ import annotations

import gzip
import math
import os
from collections.abc import Iterable, Iterator, Sequence
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from ..core._io import atomic_path
from ..core.errors import InputError
from .base import LaserScan, Mapper, OdometryReading

__all__ = ["CarmenLog", "write_carmen", "read_carmen", "replay"]

HEADER = """\
# CARMEN Logfile
# file format is one message per line
# message_name [message contents] ipc_timestamp ipc_hostname logger_timestamp
# message formats defined: PARAM SYNC ODOM RAWLASER1 RAWLASER2 RAWLASER3 RAWLASER4
#                          ROBOTLASER1 ROBOTLASER2
# old message formats defined: FLASER RLASER LASER3 LASER4
# PARAM param_name param_value
# SYNC tagname
# ODOM x y theta tv rv accel
# TRUEPOS true_x true_y true_theta odom_x odom_y odom_theta
# RAWLASER1 laser_type start_angle field_of_view angular_resolution
#   maximum_range accuracy remission_mode
#   num_readings [range_readings] num_remissions [remission values]
# FLASER num_readings [range_readings] x y theta odom_x odom_y odom_theta
# written by map2map (simulated TurtleBot3 run)
"""

#: CARMEN laser_type of a simulated laser.
SIMULATED_LASER = 3

#: Message names that are valid CARMEN but carry nothing a 2-D SLAM run needs.
_IGNORED = {
    "SYNC",
    "RAWLASER2",
    "RAWLASER3",
    "RAWLASER4",
    "ROBOTLASER2",
    "RLASER",
    "LASER3",
    "LASER4",
    "REAR_LASER",
    "NMEAGGA",
    "NMEARMC",
    "SONAR",
    "BUMPER",
    "SCANMARK",
    "POSITIONLASER",
    "VECTORMOVE",
    "ROBOTVELOCITY",
    "FOLLOWTRAJECTORY",
    "BASEVELOCITY",
    "ARM",
    "GPSNMEA",
    "IMU",
}


@dataclass
class CarmenLog:
    """The contents of a CARMEN log: one odometry reading per scan, in order.

    Attributes
    ----------
    odometry : list of OdometryReading
        Odometry at each scan (from ``ROBOTLASER1``/``FLASER`` fields, else the
        latest preceding ``ODOM``).
    scans : list of LaserScan
    true_poses : (N, 3) array or None
        Ground truth per scan from ``TRUEPOS`` lines, when the log has them.
    params : dict
        ``PARAM`` name -> value strings.
    """

    odometry: list[OdometryReading]
    scans: list[LaserScan]
    true_poses: np.ndarray | None = None
    params: dict[str, str] = field(default_factory=dict)

    def __len__(self) -> int:
        return len(self.scans)

    def __iter__(self) -> Iterator[tuple[OdometryReading, LaserScan]]:
        return iter(zip(self.odometry, self.scans, strict=True))


def _num(v: float) -> str:
    v = float(v)
    return repr(v) if math.isfinite(v) else "0.0"


def _open_text(path: Path, mode: str):
    if path.suffix == ".gz":
        return gzip.open(path, mode + "t", encoding="ascii")
    return open(path, mode, encoding="ascii")


def write_carmen(
    path: str | os.PathLike,
    records: Iterable[tuple[OdometryReading, LaserScan, Sequence[float] | None]],
    *,
    params: dict[str, object] | None = None,
    velocities: Sequence[tuple[float, float]] | None = None,
    hostname: str = "map2map",
) -> None:
    """Write ``(odometry, scan, true_pose_or_None)`` records as a CARMEN log.

    Parameters
    ----------
    path : path
        Output file; gzip-compressed when it ends in ``.gz``. Written atomically.
    records : iterable
        One triple per scan; ``true_pose`` adds a ``TRUEPOS`` line.
    params : dict, optional
        Extra ``PARAM`` lines (the laser offset is always written).
    velocities : sequence of (tv, rv), optional
        Translational and rotational velocity per record for the ``ODOM`` lines.
    hostname : str
        The ``ipc_hostname`` field.
    """
    path = Path(path)
    records = list(records)
    with atomic_path(path) as tmp:
        opener = gzip.open(tmp, "wt", encoding="ascii") if path.suffix == ".gz" else None
        with opener or open(tmp, "w", encoding="ascii") as f:
            f.write(HEADER)
            all_params: dict[str, object] = {}
            if records:
                off = records[0][1].sensor_offset
                all_params.update(
                    robot_frontlaser_offset=off[0],
                    robot_frontlaser_side_offset=off[1],
                    robot_frontlaser_angular_offset=off[2],
                )
            all_params.update(params or {})
            for k, v in all_params.items():
                f.write(f"PARAM {k} {_num(v) if isinstance(v, float) else v} 0.0 {hostname} 0.0\n")
            fmts: dict[int, str] = {}  # "%.3f %.3f ..." per beam count: one % per scan
            for i, (odo, scan, truth) in enumerate(records):
                t = _num(scan.t)
                tail = f"{t} {hostname} {t}\n"
                tv, rv = velocities[i] if velocities is not None else (0.0, 0.0)
                ox, oy, oth = _num(odo.x), _num(odo.y), _num(odo.theta)
                f.write(f"ODOM {ox} {oy} {oth} {_num(tv)} {_num(rv)} 0.0 {tail}")
                if truth is not None:
                    tx, ty, tth = (_num(v) for v in truth)
                    f.write(f"TRUEPOS {tx} {ty} {tth} {ox} {oy} {oth} {tail}")
                r = np.asarray(scan.ranges, np.float64)
                r = np.where(np.isfinite(r), r, scan.range_max)
                n = r.shape[0]
                span = scan.angle_increment * (n - 1)
                fmt = fmts.get(n) or fmts.setdefault(n, " ".join(["%.3f"] * n))
                ranges = fmt % tuple(r.tolist())
                f.write(
                    f"RAWLASER1 {SIMULATED_LASER} {_num(scan.angle_min)} {_num(span)} "
                    f"{_num(scan.angle_increment)} {_num(scan.range_max)} 0.01 0 "
                    f"{n} {ranges} 0 {tail}"
                )


def _floats(path, lineno, fields, name):
    try:
        return [float(v) for v in fields]
    except ValueError:
        raise InputError(path, f"line {lineno}: corrupt {name} message (not a number)") from None


def _take(path, lineno, toks, k, name):
    if len(toks) < k:
        raise InputError(path, f"line {lineno}: truncated {name} message")
    return toks[:k], toks[k:]


def read_carmen(path: str | os.PathLike, *, range_min: float = 0.0) -> CarmenLog:
    """Read a CARMEN log (``.gz`` allowed) into one odometry reading per scan.

    Parameters
    ----------
    path : path
        The log file.
    range_min : float
        Minimum valid range stored in the scans (CARMEN logs do not record it).

    Raises
    ------
    InputError
        Missing file, unknown or corrupt lines (with the line number), no odometry,
        no scans, an empty log, or a beam count changing mid-log.
    """
    path = Path(path)
    if not path.is_file():
        raise InputError(path, "log file not found")
    params: dict[str, str] = {}
    odometry: list[OdometryReading] = []
    scans: list[LaserScan] = []
    truths: list[tuple[float, float, float] | None] = []
    last_odom: OdometryReading | None = None
    last_true: tuple[float, float, float] | None = None
    pending: list[int] = []  # scans waiting for a first ODOM
    n_beams: int | None = None
    any_odom = False
    try:
        f = _open_text(path, "r")
        lines = f.read().splitlines()
        f.close()
    except (OSError, UnicodeDecodeError, EOFError) as exc:
        raise InputError(path, f"cannot read log ({exc})") from None

    def offset() -> tuple[float, float, float]:
        try:
            return (
                float(params.get("robot_frontlaser_offset", 0.0)),
                float(params.get("robot_frontlaser_side_offset", 0.0)),
                float(params.get("robot_frontlaser_angular_offset", 0.0)),
            )
        except ValueError:
            raise InputError(path, "PARAM robot_frontlaser_* is not a number") from None

    def add_scan(lineno, t, ranges, a0, inc, rmax, odo):
        nonlocal n_beams
        if n_beams is None:
            n_beams = len(ranges)
        elif len(ranges) != n_beams:
            raise InputError(
                path, f"line {lineno}: scan has {len(ranges)} beams, earlier scans {n_beams}"
            )
        r = np.asarray(ranges, np.float32)
        r = np.where(r >= np.float32(rmax), np.float32(np.inf), r)
        scans.append(LaserScan(t, r, a0, inc, range_min, rmax, offset()))
        if odo is None:
            if last_odom is None:
                pending.append(len(odometry))
                odometry.append(OdometryReading(t, 0.0, 0.0, 0.0))
            else:
                odometry.append(OdometryReading(t, last_odom.x, last_odom.y, last_odom.theta))
        else:
            odometry.append(odo)
        truths.append(last_true)

    for lineno, line in enumerate(lines, 1):
        toks = line.split()
        if not toks or toks[0].startswith("#"):
            continue
        name, rest = toks[0], toks[1:]
        if name == "PARAM":
            if len(rest) >= 2:
                params[rest[0]] = rest[1]
            continue
        if name in _IGNORED:
            continue
        if name == "ODOM":
            vals, tail = _take(path, lineno, rest, 6, name)
            x, y, th = _floats(path, lineno, vals[:3], name)[:3]
            t = _stamp(path, lineno, tail, name)
            last_odom = OdometryReading(t, x, y, th)
            any_odom = True
            for k in pending:
                odometry[k] = OdometryReading(odometry[k].t, x, y, th)
            pending.clear()
        elif name == "TRUEPOS":
            vals, tail = _take(path, lineno, rest, 6, name)
            v = _floats(path, lineno, vals, name)
            last_true = (v[0], v[1], v[2])
        elif name == "RAWLASER1":
            h, ranges, tail = _laser_block(path, lineno, rest, name)
            t = _stamp(path, lineno, tail, name)
            add_scan(lineno, t, ranges, h[1], h[3], h[4], None)
        elif name == "FLASER":
            head, rest2 = _take(path, lineno, rest, 1, name)
            n = _count(path, lineno, _floats(path, lineno, head, name)[0], name)
            vals, tail = _take(path, lineno, rest2, n + 6, name)
            v = _floats(path, lineno, vals, name)
            t = _stamp(path, lineno, tail, name)
            inc = math.pi / (n - 1) if n % 2 == 1 else math.pi / max(n, 1)
            rmax = float(params.get("robot_front_laser_max", 81.9))
            odo = OdometryReading(t, v[n + 3], v[n + 4], v[n + 5])
            any_odom = True
            add_scan(lineno, t, v[:n], -math.pi / 2, inc, rmax, odo)
        elif name == "ROBOTLASER1":
            h, ranges, rest4 = _laser_block(path, lineno, rest, name)
            vals, tail = _take(path, lineno, rest4, 11, name)
            v = _floats(path, lineno, vals, name)
            t = _stamp(path, lineno, tail, name)
            any_odom = True
            add_scan(lineno, t, ranges, h[1], h[3], h[4], OdometryReading(t, v[3], v[4], v[5]))
        else:
            raise InputError(path, f"line {lineno}: unknown CARMEN message '{name[:40]}'")

    if not scans and not any_odom:
        raise InputError(path, "empty log: no ODOM or laser messages")
    if not scans:
        raise InputError(path, "log has no laser scans (RAWLASER1, FLASER or ROBOTLASER1)")
    if not any_odom:
        raise InputError(path, "log has no odometry (ODOM, FLASER or ROBOTLASER1)")
    true_poses = None
    if all(tp is not None for tp in truths):
        true_poses = np.array(truths, float)
    return CarmenLog(odometry, scans, true_poses, params)


def _count(path, lineno, v, name, zero_ok=False) -> int:
    if not (float(v).is_integer() and (0 if zero_ok else 1) <= v < 100_000):
        raise InputError(path, f"line {lineno}: corrupt {name} message (bad reading count)")
    return int(v)


def _laser_block(path, lineno, rest, name):
    """The laser part shared by RAWLASER and ROBOTLASER lines.

    Eight header numbers (type, start angle, field of view, angular resolution,
    maximum range, accuracy, remission mode, beam count), the ranges, then the
    remission count and values. Returns (header, ranges, what follows).
    """
    head, rest2 = _take(path, lineno, rest, 8, name)
    h = _floats(path, lineno, head, name)
    n = _count(path, lineno, h[7], name)
    rng, rest3 = _take(path, lineno, rest2, n + 1, name)
    ranges = _floats(path, lineno, rng[:n], name)
    nrem = _count(path, lineno, _floats(path, lineno, rng[n:], name)[0], name, True)
    _, after = _take(path, lineno, rest3, nrem, name)
    return h, ranges, after


def _stamp(path, lineno, tail, name) -> float:
    # ipc_timestamp ipc_hostname logger_timestamp
    if len(tail) != 3:
        raise InputError(path, f"line {lineno}: corrupt {name} message (wrong field count)")
    return _floats(path, lineno, tail[:1], name)[0]


def replay(log: CarmenLog, mapper: Mapper, *, use_truth: bool = True, progress: bool = False):
    """Feed every (odometry, scan) of ``log`` to ``mapper``; returns the mapper.

    Mappers that take ground truth (the oracle, which has ``observe_truth``) get
    the log's ``TRUEPOS`` poses when ``use_truth`` is set; SLAM backends never see
    them.
    """
    from tqdm.auto import tqdm

    truth = log.true_poses if use_truth and hasattr(mapper, "observe_truth") else None
    if hasattr(mapper, "observe_truth") and truth is None:
        raise InputError(None, f"mapper '{mapper.name}' needs true poses; the log has no TRUEPOS")
    for i, (odo, scan) in enumerate(
        tqdm(log, total=len(log), desc="replay", unit="scan", disable=not progress)
    ):
        if truth is not None:
            mapper.observe_truth(truth[i])
        mapper.update(odo, scan)
    return mapper
