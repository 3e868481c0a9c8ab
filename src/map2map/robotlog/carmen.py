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
odom_x odom_y odom_theta`` and ``ROBOTLASER1`` messages, accepts gzip (``.gz``) and
keeps ``PARAM`` lines. The format is open-ended (``SYNC``, ``NEFF``, ``GPS``,
``RLASER``, ``RAWLASER2-4``, vendors' own messages...): every message type it does
not use is skipped and counted (:attr:`CarmenLog.skipped`, said once in
:attr:`CarmenLog.notes`). A corrupt line of a type it uses, a log without odometry or
scans and a beam count that changes mid-log are bad input
(:class:`~map2map.core.errors.InputError` naming the line).

``FLASER`` geometry follows CARMEN's own reader (``readlog.c``,
``carmen_laser_guess_fov`` / ``carmen_laser_guess_angle_increment``): the first
beam at -90 degrees, 1 degree apart for 180 or 181 readings, 0.5 degree for 360 or
361, 0.25 degree for 400 or 401, else 180 degrees over ``n - 1`` steps; ranges in
metres. The maximum range is the ``robot_front_laser_max`` (or
``laser_front_laser_max_range``) ``PARAM``, else 50 m: GMapping's CARMEN reader
uses 50 m, and the Radish logs write no-returns as 50.0-51.1 m (``ranges >=`` the
maximum read as ``inf``).

**Corrected logs.** Radish's ``*-corrected.log`` / ``*.gfs.log`` files are written
by GMapping's log tools: the pose fields of each laser line are the SLAM-corrected
pose, and right after each scan an ``ODOM`` line with that corrected pose and
timestamp 0 re-anchors the odometry stream, whose later lines continue from it by
the wheel-odometry increments. Feeding those poses to a SLAM backend would hand it
the answer. So when the ``ODOM`` stream re-anchors (a timestamp running
backwards), the odometry of each scan is rebuilt from the ``ODOM`` increments with
the re-anchoring jumps left out (the raw wheel odometry, in its own frame), and the
laser lines' poses are kept in :attr:`CarmenLog.logged_poses` (a reference, never
shown to a backend). Otherwise the laser line's odometry fields are the odometry,
as CARMEN defines them.

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

__all__ = ["CarmenLog", "write_carmen", "read_carmen", "replay", "flaser_angle_increment"]

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

#: Message names read; every other well-formed message name is skipped and counted.
USED_MESSAGES = ("PARAM", "ODOM", "TRUEPOS", "RAWLASER1", "FLASER", "ROBOTLASER1")

#: FLASER maximum range when the log names none (GMapping's CARMEN reader; the
#: Radish logs write no-returns as 50.0-51.1 m).
FLASER_DEFAULT_MAX_RANGE = 50.0

_NAME_CHARS = frozenset("ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789_-")


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
    logged_poses : (N, 3) array or None
        The pose fields ``x y theta`` of each ``FLASER``/``ROBOTLASER1`` line when
        the log is a corrected one (see the module docstring): the SLAM-corrected
        laser poses, a reference map's poses. Never given to a backend.
    skipped : dict
        Message name -> number of lines skipped as not used (``NEFF``, ``SYNC``...).
    notes : list of str
        What a user should be told once about how the log was read (skipped
        messages, the odometry source, assumed laser geometry).
    """

    odometry: list[OdometryReading]
    scans: list[LaserScan]
    true_poses: np.ndarray | None = None
    params: dict[str, str] = field(default_factory=dict)
    logged_poses: np.ndarray | None = None
    skipped: dict[str, int] = field(default_factory=dict)
    notes: list[str] = field(default_factory=list)

    def __len__(self) -> int:
        return len(self.scans)

    def __iter__(self) -> Iterator[tuple[OdometryReading, LaserScan]]:
        return iter(zip(self.odometry, self.scans, strict=True))

    def plan_start_pose(self) -> tuple[float, float, float] | None:
        """Pose of the odometry (and SLAM map) frame in the plan frame, or None.

        ``map2map simulate`` writes the robot's true start pose as ``PARAM
        map2map_start_x``, ``_y``, ``_theta``: a map built from the log (whose frame
        is the first pose) is placed on the plan by it. A recorded log has none.

        Examples
        --------
        >>> CarmenLog([], [], params={"map2map_start_x": "1.5", "map2map_start_y": "2",
        ...                           "map2map_start_theta": "0.25"}).plan_start_pose()
        (1.5, 2.0, 0.25)
        >>> CarmenLog([], []).plan_start_pose() is None
        True
        """
        keys = ("map2map_start_x", "map2map_start_y", "map2map_start_theta")
        try:
            pose = tuple(float(self.params[k]) for k in keys)
        except (KeyError, ValueError):
            return None
        return pose if all(math.isfinite(v) for v in pose) else None


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

    Returns
    -------
    CarmenLog
        Scans, odometry, ``PARAM`` values; for corrected logs the logged poses;
        counts of the skipped message types and notes to show the user.

    Raises
    ------
    InputError
        Missing file, a corrupt line of a message type it reads or a line that is
        not a message at all (with the line number), no odometry, no scans, an
        empty log, or a beam count changing mid-log.
    """
    path = Path(path)
    if not path.is_file():
        raise InputError(path, "log file not found")
    params: dict[str, str] = {}
    skipped: dict[str, int] = {}
    # scans and, per scan: its laser-line odometry (or None), the laser-line pose,
    # the number of ODOM lines before it, the latest TRUEPOS
    scans: list[LaserScan] = []
    line_odo: list[OdometryReading | None] = []
    line_pose: list[tuple[float, float, float] | None] = []
    n_odom_before: list[int] = []
    truths: list[tuple[float, float, float] | None] = []
    # ODOM stream: (t, x, y, theta) as logged, and whether the line re-anchors
    odoms: list[tuple[float, float, float, float]] = []
    anchors: list[bool] = []
    last_true: tuple[float, float, float] | None = None
    n_beams: int | None = None
    flaser_geometry: tuple[int, float, float, float] | None = None
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

    def add_scan(lineno, t, ranges, a0, inc, rmax, odo, pose):
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
        line_odo.append(odo)
        line_pose.append(pose)
        n_odom_before.append(len(odoms))
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
        if name == "ODOM":
            vals, tail = _take(path, lineno, rest, 6, name)
            x, y, th = _floats(path, lineno, vals[:3], name)[:3]
            t = _stamp(path, lineno, tail, name)
            # a corrected log re-anchors the stream with timestamp-0 lines
            anchors.append(bool(odoms) and t < odoms[-1][0])
            odoms.append((t, x, y, th))
        elif name == "TRUEPOS":
            vals, tail = _take(path, lineno, rest, 6, name)
            v = _floats(path, lineno, vals, name)
            last_true = (v[0], v[1], v[2])
        elif name == "RAWLASER1":
            h, ranges, tail = _laser_block(path, lineno, rest, name)
            t = _stamp(path, lineno, tail, name)
            add_scan(lineno, t, ranges, h[1], h[3], h[4], None, None)
        elif name == "FLASER":
            head, rest2 = _take(path, lineno, rest, 1, name)
            n = _count(path, lineno, _floats(path, lineno, head, name)[0], name)
            vals, tail = _take(path, lineno, rest2, n + 6, name)
            v = _floats(path, lineno, vals, name)
            t = _stamp(path, lineno, tail, name)
            inc = flaser_angle_increment(n)
            rmax = _flaser_max_range(path, params)
            flaser_geometry = (n, inc, rmax, inc * (n - 1))
            odo = OdometryReading(t, v[n + 3], v[n + 4], v[n + 5])
            add_scan(lineno, t, v[:n], -math.pi / 2, inc, rmax, odo, (v[n], v[n + 1], v[n + 2]))
        elif name == "ROBOTLASER1":
            h, ranges, rest4 = _laser_block(path, lineno, rest, name)
            vals, tail = _take(path, lineno, rest4, 11, name)
            v = _floats(path, lineno, vals, name)
            t = _stamp(path, lineno, tail, name)
            odo = OdometryReading(t, v[3], v[4], v[5])
            add_scan(lineno, t, ranges, h[1], h[3], h[4], odo, (v[0], v[1], v[2]))
        elif set(name) <= _NAME_CHARS:
            skipped[name] = skipped.get(name, 0) + 1
        else:
            raise InputError(
                path, f"line {lineno}: not a CARMEN message (starts with {name[:20]!r})"
            )

    if not scans and not odoms:
        raise InputError(path, "empty log: no ODOM or laser messages")
    if not scans:
        raise InputError(path, "log has no laser scans (RAWLASER1, FLASER or ROBOTLASER1)")
    notes: list[str] = []
    if skipped:
        listed = ", ".join(f"{n} {k}" for k, n in sorted(skipped.items(), key=lambda kv: -kv[1]))
        notes.append(f"skipped message types not used: {listed}")
    corrected = any(anchors)
    logged_poses = None
    if corrected:
        odometry = _odometry_from_stream(odoms, anchors, scans, n_odom_before)
        logged_poses = np.array([p if p is not None else (np.nan,) * 3 for p in line_pose], float)
        notes.append(
            f"corrected log: {sum(anchors)} ODOM lines re-anchor the odometry at corrected "
            "poses (timestamp running backwards); odometry rebuilt from the ODOM increments "
            "without those jumps, the laser lines' corrected poses kept only as a reference"
        )
    else:
        odometry = []
        for k, odo in enumerate(line_odo):
            if odo is None:  # RAWLASER1: the latest ODOM before it (else the first after)
                if not odoms:
                    raise InputError(path, "log has no odometry (ODOM, FLASER or ROBOTLASER1)")
                j = max(n_odom_before[k] - 1, 0)
                _, x, y, th = odoms[j]
                odo = OdometryReading(scans[k].t, x, y, th)
            odometry.append(odo)
    if flaser_geometry is not None:
        n, inc, rmax, span = flaser_geometry
        how = "PARAM" if _max_range_param(params) is not None else "default"
        notes.append(
            f"FLASER: {n} beams from -90 deg, {math.degrees(inc):.3g} deg apart "
            f"(field of view {math.degrees(span):.4g} deg), maximum range {rmax:g} m ({how}); "
            "readings at or beyond it are no-returns"
        )
    true_poses = None
    if all(tp is not None for tp in truths):
        true_poses = np.array(truths, float)
    return CarmenLog(odometry, scans, true_poses, params, logged_poses, skipped, notes)


def flaser_angle_increment(n: int) -> float:
    """Beam spacing of an old-format ``FLASER`` line of ``n`` readings (CARMEN's guess).

    Parameters
    ----------
    n : int
        Number of readings on the line.

    Returns
    -------
    float
        Angle between beams in radians: 180 and 181 beams span 180 degrees at 1
        degree, 361 at 0.5, 401 at 0.25; any other count spans 180 degrees evenly.

    Examples
    --------
    >>> [round(math.degrees(flaser_angle_increment(n)), 3) for n in (180, 181, 361, 401, 90)]
    [1.0, 1.0, 0.5, 0.25, 2.022]
    """
    if n in (180, 181):
        return math.pi / 180
    if n in (360, 361):
        return math.pi / 360
    if n in (400, 401):
        return math.pi / 720
    return math.pi / max(n - 1, 1)


def _max_range_param(params: dict[str, str]) -> str | None:
    for key in ("robot_front_laser_max", "laser_front_laser_max_range"):
        if key in params:
            return key
    return None


def _flaser_max_range(path, params: dict[str, str]) -> float:
    key = _max_range_param(params)
    if key is None:
        return FLASER_DEFAULT_MAX_RANGE
    try:
        v = float(params[key])
    except ValueError:
        v = float("nan")
    if not (math.isfinite(v) and v > 0):
        raise InputError(path, f"PARAM {key} {params[key]!r} is not a positive number")
    return v


def _odometry_from_stream(odoms, anchors, scans, n_odom_before) -> list[OdometryReading]:
    """Raw wheel odometry at each scan from an ODOM stream with re-anchoring lines.

    The chain starts at the first ODOM pose; each later non-anchor line adds its
    increment over the line before it (in that line's frame); an anchor line adds
    nothing and becomes the new reference for the increments that follow. The
    odometry of a scan is the chain at the latest ODOM line before it.
    """
    raw = np.asarray([o[1:] for o in odoms], float)
    prev = raw[:-1]
    dx, dy = raw[1:, 0] - prev[:, 0], raw[1:, 1] - prev[:, 1]
    c, s_ = np.cos(prev[:, 2]), np.sin(prev[:, 2])
    keep = ~np.asarray(anchors[1:], bool)
    fwd = np.where(keep, c * dx + s_ * dy, 0.0)  # increments in the previous line's frame
    side = np.where(keep, -s_ * dx + c * dy, 0.0)
    dth = np.where(keep, np.angle(np.exp(1j * (raw[1:, 2] - prev[:, 2]))), 0.0)
    th = raw[0, 2] + np.concatenate([[0.0], np.cumsum(dth)])
    ct, st = np.cos(th[:-1]), np.sin(th[:-1])
    x = raw[0, 0] + np.concatenate([[0.0], np.cumsum(ct * fwd - st * side)])
    y = raw[0, 1] + np.concatenate([[0.0], np.cumsum(st * fwd + ct * side)])
    chain = np.column_stack([x, y, np.angle(np.exp(1j * th))])
    out = []
    for k, scan in enumerate(scans):
        j = max(n_odom_before[k] - 1, 0)
        x, y, th = chain[j]
        out.append(OdometryReading(scan.t, float(x), float(y), float(th)))
    return out


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

    Parameters
    ----------
    log : CarmenLog
        The recorded run.
    mapper : Mapper
        The backend to feed (its state is updated in place).
    use_truth : bool
        Give ``TRUEPOS`` poses to mappers that observe truth.
    progress : bool
        Show a tqdm progress bar.

    Returns
    -------
    Mapper
        ``mapper`` after the last scan.

    Raises
    ------
    InputError
        The mapper needs true poses and the log has none.

    Examples
    --------
    >>> from map2map.robotlog.base import LaserScan, OdometryReading
    >>> from map2map.robotlog.mappers import make_mapper
    >>> scan = LaserScan(0.0, np.full(5, 2.0), -1.0, 0.5, 0.1, 3.5)
    >>> log = CarmenLog(odometry=[OdometryReading(0.0, 0.0, 0.0, 0.0)], scans=[scan],
    ...                 true_poses=np.zeros((1, 3)))
    >>> bool(replay(log, make_mapper("oracle")).get_map().occupied.any())
    True
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
