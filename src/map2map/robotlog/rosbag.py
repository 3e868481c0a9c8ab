"""ROS bags as robot logs: ROS 1 ``.bag`` and ROS 2 bags (sqlite3 or mcap), read and written.

Reading and writing use the pure-Python `rosbags <https://pypi.org/project/rosbags/>`_
package (no ROS installation), an optional dependency: ``pip install 'map2map[ros]'``.
Without it both functions refuse with one line saying so.

:func:`read_bag` turns a bag into the :class:`~map2map.robotlog.carmen.CarmenLog` every
other reader returns (one odometry reading per scan), so ``map2map slam BAG`` needs no
special path:

* **scans** are the ``sensor_msgs/LaserScan`` messages of one topic, found by type
  (``scan_topic`` chooses when there are several; several without a choice are refused,
  naming them). A reading that is NaN, ``-inf`` or below ``range_min`` is unusable
  (NaN, as a BreezySLAM 0 reading); ``+inf`` or at least ``range_max`` is a no-return
  (``inf``, as in a CARMEN log). Times are the header stamps (the bag's record times
  when the scans carry none: all stamps equal).
* **odometry** is a ``nav_msgs/Odometry`` topic, found by type (``odom_topic`` chooses),
  or, when the bag has none or ``odom_topic`` is ``/tf``, the ``odom -> base``
  transform on ``/tf`` (the parent frame's name ends in ``odom``, the child is the
  laser's robot frame). Each scan gets the odometry pose at its stamp: the message of
  that stamp when there is one, else linear interpolation between the two around it
  (the heading along the shorter arc). Scans outside the odometry's time span are
  dropped and counted in a note.
* the **laser mounting** (:attr:`~map2map.robotlog.base.LaserScan.sensor_offset`) is
  the chain of ``/tf_static`` transforms from the odometry's robot frame
  (``child_frame_id``) to the scan's ``frame_id``, projected on the floor (x, y, yaw);
  a transform missing from ``/tf_static`` is taken from ``/tf`` (its first value). A
  laser mounted upside down has its beam order reversed. No chain: the laser is taken
  to sit at the robot's centre, and a note says so.

:func:`write_bag` writes a log as a bag of the three kinds: ``/scan``
(``sensor_msgs/LaserScan``, frame ``base_scan``), ``/odom`` (``nav_msgs/Odometry``,
``odom -> base_footprint``), the same pose on ``/tf`` and the laser mounting on
``/tf_static``, all stamped with the scan times (the TurtleBot3's topic and frame
names). A ROS 2 bag also keeps the log's ``map2map_*`` ``PARAM`` values (a simulated
run's true start pose) in its ``custom_data``.

What comes back exactly and what does not: positions (float64) and ranges (float32, as
every reader keeps them) come back bit for bit; the heading too, wrapped to [-pi, pi]
(the writer picks, among the quaternions equal to the rotation within 1e-16, one that
:func:`read_bag` turns back into the same double). Times are integer nanoseconds: a
time read from text with at most 9 decimals (a CARMEN log's) comes back exactly, a float
sum such as ``0.15000000000000002`` as ``0.15``. The beam geometry (``angle_min``,
``angle_increment``, ``range_min``, ``range_max``) is float32 in
``sensor_msgs/LaserScan``: ``-pi/2`` comes back 4.4e-8 rad off. So a CARMEN log and its
bag map identically once the log's geometry is rounded to float32 (the SLAM backends
are chaotic: a 4e-8 rad change can give the particle filter another map, as another
seed would).

Examples
--------
>>> import numpy as np, tempfile, pathlib
>>> from map2map.robotlog.base import LaserScan, OdometryReading
>>> from map2map.robotlog.carmen import CarmenLog
>>> scans = [LaserScan(0.2 * k, np.array([1.0, np.inf, 2.5], np.float32), -0.5, 0.5,
...                    0.12, 3.5, (-0.064, 0.0, 0.0)) for k in range(3)]
>>> odom = [OdometryReading(0.2 * k, 0.1 * k, 0.0, 0.05 * k) for k in range(3)]
>>> bag = pathlib.Path(tempfile.mkdtemp()) / "run_bag"
>>> _ = write_bag(CarmenLog(odom, scans), bag, format="mcap")
>>> log = read_bag(bag)
>>> len(log), log.scans[1].ranges.tolist(), log.scans[0].sensor_offset
(3, [1.0, inf, 2.5], (-0.064, 0.0, 0.0))
>>> log.odometry[2].x == odom[2].x, abs(log.odometry[2].theta - 0.1) < 1e-15
(True, True)
"""

from __future__ import annotations

import math
import os
import shutil
from collections.abc import Callable
from dataclasses import dataclass
from fractions import Fraction
from pathlib import Path

import numpy as np

from ..core._io import atomic_dir, atomic_path
from ..core.errors import InputError
from .base import LaserScan, OdometryReading
from .carmen import CarmenLog

__all__ = ["BAG_FORMATS", "is_bag", "read_bag", "write_bag", "bag_name", "check_bag_format"]

#: ``format`` names of :func:`write_bag`: a ROS 1 ``.bag`` file, a ROS 2 bag folder
#: with sqlite3 storage (ROS 2 Humble's default) or with mcap storage (Iron's onward).
BAG_FORMATS = ("ros1", "ros2", "mcap")

INSTALL_HINT = "pip install 'map2map[ros]' (or pip install rosbags)"

SCAN_TYPE = "sensor_msgs/msg/LaserScan"
ODOM_TYPE = "nav_msgs/msg/Odometry"
TF_TYPE = "tf2_msgs/msg/TFMessage"
TF_TOPIC, TF_STATIC_TOPIC = "/tf", "/tf_static"

#: ROS 1's tf2_msgs/TFMessage (not in rosbags' noetic store).
_TF_MSG_ROS1 = "geometry_msgs/TransformStamped[] transforms\n"


def _rosbags(path, doing: str):
    """Import rosbags' reader and writer modules, or refuse with the install hint."""
    try:
        import rosbags.highlevel
        import rosbags.rosbag1
        import rosbags.rosbag2
        import rosbags.serde
        import rosbags.typesys
    except ImportError as exc:
        raise InputError(
            path, f"{doing} a ROS bag needs the rosbags package: {INSTALL_HINT} ({exc})"
        ) from None
    return rosbags


def check_bag_format(format: str, source="bag") -> None:
    """Refuse, before any work, a ``format`` not in :data:`BAG_FORMATS` or a missing rosbags.

    Parameters
    ----------
    format : str
        The format to be written.
    source : str
        What the error names.

    Examples
    --------
    >>> check_bag_format("mcap")
    >>> check_bag_format("ros3")
    Traceback (most recent call last):
    ...
    map2map.core.errors.InputError: bag: unknown bag format 'ros3' (ros1, ros2, mcap)
    """
    if format not in BAG_FORMATS:
        raise InputError(source, f"unknown bag format '{format}' ({', '.join(BAG_FORMATS)})")
    _rosbags(source, "writing")


def bag_name(stem: str, format: str) -> str:
    """File or folder name of a bag: ``STEM.bag`` (ROS 1) or ``STEM_bag`` (a ROS 2 folder).

    >>> bag_name("run", "ros1"), bag_name("run", "mcap")
    ('run.bag', 'run_bag')
    """
    return f"{stem}.bag" if format == "ros1" else f"{stem}_bag"


def is_bag(path: str | os.PathLike) -> bool:
    """Whether ``path`` is a ROS bag: a ``.bag`` file (or one starting ``#ROSBAG``), a
    folder with ``metadata.yaml``, or a ROS 2 ``.db3`` / ``.mcap`` storage file.

    Parameters
    ----------
    path : path-like
        Anything ``map2map slam`` is given.

    Returns
    -------
    bool

    Examples
    --------
    >>> is_bag("run.bag"), is_bag("run.log")
    (True, False)
    """
    p = Path(path)
    if p.is_dir():
        return (p / "metadata.yaml").is_file()
    if p.suffix in (".bag", ".db3", ".mcap"):
        return True
    try:
        with open(p, "rb") as f:
            return f.read(8) == b"#ROSBAG "
    except OSError:
        return False


def _bag_path(path: Path) -> Path:
    """The path rosbags opens: the ``.bag`` file or the ROS 2 bag folder."""
    if not path.exists():
        raise InputError(path, "bag not found")
    if path.is_dir():
        if not (path / "metadata.yaml").is_file():
            raise InputError(path, "folder is not a ROS 2 bag (no metadata.yaml)")
        return path
    if path.suffix in (".db3", ".mcap"):  # its folder (metadata.yaml) if it has one
        return path.parent if (path.parent / "metadata.yaml").is_file() else path
    if path.suffix != ".bag":
        raise InputError(path, "a ROS 1 bag must be named *.bag")
    return path


# ----------------------------------------------------------------------------- reading


@dataclass
class _Series:
    """Poses over time from an odometry topic or a /tf edge (stamps sorted)."""

    t: np.ndarray  # (N,) seconds
    pose: np.ndarray  # (N, 3) x, y, yaw

    @classmethod
    def build(cls, rows: list[tuple[float, float, float, float]]) -> _Series:
        a = np.asarray(rows, float).reshape(-1, 4)
        a = a[np.argsort(a[:, 0], kind="stable")]
        return cls(a[:, 0], a[:, 1:])

    def at(self, t: float) -> tuple[float, float, float] | None:
        """The pose at ``t``: the last sample of that stamp, else interpolated; None outside."""
        ts = self.t
        if len(ts) == 0 or t < ts[0] or t > ts[-1]:
            return None
        j = int(np.searchsorted(ts, t, side="right")) - 1
        if ts[j] == t:
            x, y, th = self.pose[j]
            return float(x), float(y), float(th)
        a, b = self.pose[j], self.pose[j + 1]
        f = (t - ts[j]) / (ts[j + 1] - ts[j])
        dth = math.remainder(b[2] - a[2], 2 * math.pi)
        th = math.remainder(a[2] + f * dth, 2 * math.pi)
        return float(a[0] + f * (b[0] - a[0])), float(a[1] + f * (b[1] - a[1])), th


def _stamp(stamp) -> float:
    """Seconds of a ROS time: the double nearest the exact nanosecond count."""
    return (int(stamp.sec) * 1_000_000_000 + int(stamp.nanosec)) / 1_000_000_000


def _frame(name: str) -> str:
    return name.lstrip("/")


def _yaw(q) -> float:
    """Heading of a quaternion; a pure rotation about z as ``2 atan2(z, w)`` in [-pi, pi]."""
    if q.x == 0 and q.y == 0:
        th = 2.0 * math.atan2(q.z, q.w)
        return th if -math.pi <= th <= math.pi else math.remainder(th, 2 * math.pi)
    return math.atan2(2.0 * (q.w * q.z + q.x * q.y), 1.0 - 2.0 * (q.y * q.y + q.z * q.z))


def _rotation(q) -> np.ndarray:
    x, y, z, w = q.x, q.y, q.z, q.w
    n = x * x + y * y + z * z + w * w
    s = 2.0 / n if n > 0 else 0.0
    return np.array(
        [
            [1 - s * (y * y + z * z), s * (x * y - z * w), s * (x * z + y * w)],
            [s * (x * y + z * w), 1 - s * (x * x + z * z), s * (y * z - x * w)],
            [s * (x * z - y * w), s * (y * z + x * w), 1 - s * (x * x + y * y)],
        ]
    )


def _transform(tr) -> tuple[np.ndarray, tuple[float, float, float] | None]:
    """4x4 matrix of a geometry_msgs/Transform, and ``(x, y, yaw)`` if it turns about z only."""
    m = np.eye(4)
    m[:3, :3] = _rotation(tr.rotation)
    m[:3, 3] = (tr.translation.x, tr.translation.y, tr.translation.z)
    q = tr.rotation
    planar = (tr.translation.x, tr.translation.y, _yaw(q)) if q.x == 0 and q.y == 0 else None
    return m, planar


def _choose(path, topics: dict[str, str], msgtype: str, what: str, param: str, chosen):
    """The one topic of ``msgtype`` (or the ``chosen`` one); refusals name the candidates."""
    found = sorted(t for t, ty in topics.items() if ty == msgtype)
    kind = msgtype.replace("/msg/", "/")
    if chosen is not None:
        if chosen not in topics:
            have = ", ".join(found) if found else "none"
            raise InputError(
                path, f"no topic `{param}={chosen}` in the bag ({kind} topics: {have})"
            )
        if topics[chosen] != msgtype:
            raise InputError(
                path, f"topic `{param}={chosen}` holds {topics[chosen]}, not {kind} {what}"
            )
        return chosen
    if len(found) > 1:
        raise InputError(
            path, f"bag has {len(found)} {kind} topics ({', '.join(found)}): choose one "
            f"with `{param}`",
        )
    return found[0] if found else None


def read_bag(
    path: str | os.PathLike,
    *,
    scan_topic: str | None = None,
    odom_topic: str | None = None,
) -> CarmenLog:
    """Read a ROS 1 or ROS 2 bag (sqlite3 or mcap) into one odometry reading per scan.

    See the module docstring for how topics, odometry, mounting and ranges are read.

    Parameters
    ----------
    path : path-like
        A ROS 1 ``.bag`` file, a ROS 2 bag folder (with ``metadata.yaml``) or a ROS 2
        ``.db3`` / ``.mcap`` storage file (its folder is read when it has
        ``metadata.yaml``).
    scan_topic : str, optional
        The ``sensor_msgs/LaserScan`` topic; needed when the bag has several.
    odom_topic : str, optional
        The ``nav_msgs/Odometry`` topic, or ``/tf`` for the ``odom -> base``
        transform; needed when the bag has several odometry topics.

    Returns
    -------
    CarmenLog
        Scans and the odometry at each, ``params`` from a ROS 2 bag's
        ``custom_data`` (``map2map_*`` keys), notes on what was read.

    Raises
    ------
    InputError
        rosbags not installed, a missing or unreadable bag, no laser scans, no
        odometry, several candidate topics and no choice, a chosen topic that is
        missing or of another type, no scan within the odometry's time span, a beam
        count changing mid-bag.
    """
    path = Path(path)
    bag = _bag_path(path)
    rb = _rosbags(path, "reading")
    from rosbags.typesys import Stores, get_typestore

    errors = (
        rb.highlevel.AnyReaderError,
        rb.rosbag1.ReaderError,
        rb.rosbag2.ReaderError,
        rb.typesys.TypesysError,
        rb.serde.SerdeError,
        OSError,
        KeyError,
        ValueError,
    )
    default = get_typestore(Stores.ROS2_HUMBLE)
    try:
        with rb.highlevel.AnyReader([bag], default_typestore=default) as reader:
            return _read(path, reader, scan_topic, odom_topic)
    except InputError:
        raise
    except errors as exc:
        raise InputError(path, f"cannot read ROS bag ({type(exc).__name__}: {exc})") from None


def _read(path: Path, reader, scan_topic, odom_topic) -> CarmenLog:
    topics = {c.topic: c.msgtype for c in reader.connections}
    scan_t = _choose(path, topics, SCAN_TYPE, "scans", "scan_topic", scan_topic)
    if scan_t is None:
        listed = ", ".join(sorted(topics)) or "none"
        raise InputError(path, f"bag has no sensor_msgs/LaserScan topic (topics: {listed})")
    use_tf = odom_topic is not None and odom_topic.strip("/") == TF_TOPIC.strip("/")
    odom_t = None
    if not use_tf:
        odom_t = _choose(path, topics, ODOM_TYPE, "odometry", "odom_topic", odom_topic)
    tf_topics = [t for t in (TF_TOPIC, TF_STATIC_TOPIC) if topics.get(t) == TF_TYPE]
    wanted = {scan_t, *tf_topics} | ({odom_t} if odom_t else set())
    conns = [c for c in reader.connections if c.topic in wanted]

    # header stamp and record time (s) of every message: (t, t_bag, ...)
    scans: list[tuple[float, float, str, object]] = []  # (t, t_bag, frame, msg)
    odom_rows: list[tuple[float, float, float, float, float]] = []  # (t, t_bag, x, y, yaw)
    odom_child: str | None = None
    static: dict[str, tuple] = {}  # child -> (parent, 4x4, planar (x, y, yaw) or None)
    tf_first: dict[str, tuple] = {}  # /tf child -> the same, of its first transform
    tf_rows: dict[tuple[str, str], list] = {}  # (parent, child) -> [(t, t_bag, x, y, yaw)]
    for conn, ns, raw in reader.messages(connections=conns):
        msg = reader.deserialize(raw, conn.msgtype)
        tb = ns / 1_000_000_000
        if conn.topic == scan_t:
            scans.append((_stamp(msg.header.stamp), tb, _frame(msg.header.frame_id), msg))
        elif conn.topic == odom_t:
            p = msg.pose.pose
            odom_rows.append(
                (_stamp(msg.header.stamp), tb, p.position.x, p.position.y, _yaw(p.orientation))
            )
            odom_child = odom_child or _frame(msg.child_frame_id)
        elif conn.topic == TF_STATIC_TOPIC:
            for tr in msg.transforms:
                static[_frame(tr.child_frame_id)] = (
                    _frame(tr.header.frame_id),
                    *_transform(tr.transform),
                )
        else:  # /tf
            for tr in msg.transforms:
                parent, child = _frame(tr.header.frame_id), _frame(tr.child_frame_id)
                tf_first.setdefault(child, (parent, *_transform(tr.transform)))
                tr_ = tr.transform.translation
                tf_rows.setdefault((parent, child), []).append(
                    (_stamp(tr.header.stamp), tb, tr_.x, tr_.y, _yaw(tr.transform.rotation))
                )
    if not scans:
        raise InputError(path, f"bag has no messages on the LaserScan topic {scan_t}")
    laser = scans[0][2]
    notes = []
    # scans without header stamps (all equal, e.g. 0): every time is the record time
    k = 1 if len(scans) > 1 and len({s[0] for s in scans}) == 1 else 0

    def clock(rows):
        return [(r[k], *r[2:]) for r in rows]

    if odom_t is not None:
        if not odom_rows:
            raise InputError(path, f"bag has no messages on the odometry topic {odom_t}")
        series, base = _Series.build(clock(odom_rows)), odom_child
        source = f"{odom_t} (nav_msgs/Odometry)"
    else:
        edge = _odom_edge(path, laser, static, tf_first, tf_rows, chosen=use_tf)
        series, base = _Series.build(clock(tf_rows[edge])), edge[1]
        source = f"{TF_TOPIC} transform {edge[0]} -> {edge[1]}"
    offset, mirrored, how = _mounting(laser, base, static, tf_first)
    notes.append(
        f"ROS {'2' if reader.is2 else '1'} bag: scans {scan_t} ({len(scans)}), odometry "
        f"{source}, laser mounting {how}"
    )

    out_scans: list[LaserScan] = []
    out_odom: list[OdometryReading] = []
    n_beams, dropped = None, 0
    if k:
        notes.append(
            f"the scans' header stamps are all {scans[0][0]:g} s: the bag's record times used"
        )
    for t, _, msg in sorted(clock(scans), key=lambda s: s[0]):
        pose = series.at(t)
        if pose is None:
            dropped += 1
            continue
        r = np.array(msg.ranges, np.float32)
        if n_beams is None:
            n_beams = r.shape[0]
        elif r.shape[0] != n_beams:
            raise InputError(
                path, f"scan at t={t:.9g} s has {r.shape[0]} beams, earlier scans {n_beams}"
            )
        rmin, rmax = float(msg.range_min), float(msg.range_max)
        r[np.isnan(r) | (r < msg.range_min)] = np.nan  # unusable (-inf: too close)
        r[r >= msg.range_max] = np.inf  # no return
        a0, inc = float(msg.angle_min), float(msg.angle_increment)
        if mirrored:  # upside down: beam i looks at yaw - angle_i; reverse the order
            r = r[::-1].copy()
            a0 = -(a0 + inc * (r.shape[0] - 1))
        out_scans.append(LaserScan(t, r, a0, inc, rmin, rmax, offset))
        out_odom.append(OdometryReading(t, *pose))
    if not out_scans:
        raise InputError(
            path, f"no scan of {scan_t} lies within the odometry's time span "
            f"({series.t[0]:.9g} to {series.t[-1]:.9g} s)",
        )
    if dropped:
        notes.append(f"{dropped} scans outside the odometry's time span dropped")
    params = {}
    for r in getattr(reader, "readers", []):  # a ROS 2 bag folder's metadata.yaml
        storage = getattr(r, "storage", r)
        custom = getattr(getattr(storage, "metadata", None), "custom", None) or {}
        params.update({k: str(v) for k, v in custom.items() if k.startswith("map2map_")})
    return CarmenLog(out_odom, out_scans, None, params, notes=notes)


def _ancestors(frame: str, static: dict, tf_first: dict) -> list[str]:
    """``frame`` and its parents through /tf_static, then /tf (loop-safe)."""
    chain = [frame]
    while True:
        edge = static.get(chain[-1]) or tf_first.get(chain[-1])
        if edge is None or edge[0] in chain:
            return chain
        chain.append(edge[0])


def _odom_edge(path, laser, static, tf_first, tf_rows, chosen: bool) -> tuple[str, str]:
    """The /tf edge ``odom -> base`` whose child carries the laser (or the only one)."""
    odom = [e for e in tf_rows if e[0].rsplit("/", 1)[-1].endswith("odom")]
    chain = _ancestors(laser, static, tf_first)
    on_chain = [e for e in odom if e[1] in chain]
    if on_chain:
        return min(on_chain, key=lambda e: chain.index(e[1]))
    if len(odom) == 1:
        return odom[0]
    if len(odom) > 1:
        listed = ", ".join(f"{p} -> {c}" for p, c in sorted(odom))
        raise InputError(
            path, f"{TF_TOPIC} has several odometry transforms ({listed}) and none carries "
            f"the laser frame {laser}",
        )
    why = "" if chosen else "no nav_msgs/Odometry topic and "
    raise InputError(
        path, f"bag has no odometry: {why}no odom -> base transform on {TF_TOPIC} "
        "(choose a topic with `odom_topic`)",
    )


def _mounting(laser, base, static, tf_first) -> tuple[tuple[float, float, float], bool, str]:
    """The laser pose in the robot frame ``base`` (x, y, yaw), mirrored?, how it was found."""
    if base is None or base == laser:
        return (0.0, 0.0, 0.0), False, f"identity (scans in the robot frame {laser})"
    m, frame, used_tf = np.eye(4), laser, False
    seen, planar = {laser}, (0.0, 0.0, 0.0)
    while frame != base:
        edge = static.get(frame)
        if edge is None:
            edge = tf_first.get(frame)
            used_tf = edge is not None
        if edge is None or edge[0] in seen:
            return (
                (0.0, 0.0, 0.0),
                False,
                f"unknown: no transform chain {base} -> {laser} on /tf_static; the laser "
                "is taken to sit at the robot's centre, facing forward",
            )
        m = edge[1] @ m
        if planar is not None and edge[2] is not None:  # compose (x, y, yaw): exact for one
            ex, ey, eth = edge[2]
            px, py, pth = planar
            c, s_ = math.cos(eth), math.sin(eth)
            planar = (ex + (c * px - s_ * py), ey + (s_ * px + c * py), eth + pth)
        else:
            planar = None
        frame = edge[0]
        seen.add(frame)
    rot = m[:3, :3]
    mirrored = rot[2, 2] < 0  # the laser's z axis points down
    if planar is not None:
        x, y, yaw = (float(v) for v in planar)
        yaw = yaw if -math.pi <= yaw <= math.pi else math.remainder(yaw, 2 * math.pi)
    else:
        yaw = math.atan2(rot[1, 0], rot[0, 0])
        x, y = float(m[0, 3]), float(m[1, 3])
    src = "/tf_static" + (" and /tf" if used_tf else "")
    how = f"{base} -> {laser} from {src} (x {x:.4g} m, y {y:.4g} m, yaw {math.degrees(yaw):.4g} deg"
    if mirrored:
        how += ", upside down: beam order reversed"
    elif abs(rot[2, 2]) < math.cos(math.radians(5)):
        how += f", tilted {math.degrees(math.acos(min(1.0, rot[2, 2]))):.3g} deg: read as level"
    return (x, y, yaw), bool(mirrored), how + ")"


# ----------------------------------------------------------------------------- writing


def _heading_zw(theta: float) -> tuple[float, float]:
    """``(z, w)`` of the rotation by ``theta`` about z that :func:`_yaw` reads back exactly.

    ``sin``/``cos`` of the half angle, nudged by a few units in the last place where
    needed (a unit quaternion all the same, to 1e-16): the heading wrapped to
    [-pi, pi] survives the bag bit for bit.

    >>> th = 2.0 / 3
    >>> z, w = _heading_zw(th)
    >>> _yaw(_Q(z, w)) == th
    True
    """
    h = math.remainder(theta, 2 * math.pi)
    z0, w0 = math.sin(h / 2), math.cos(h / 2)
    for k in (0, 2, 8):
        for z in _ulps(z0, k):
            for w in _ulps(w0, k):
                if _yaw(_Q(z, w)) == h:
                    return z, w
    return z0, w0  # not met in practice (every heading of 10^5 tried takes at most 2 ulps)


@dataclass(frozen=True)
class _Q:
    z: float
    w: float
    x: float = 0.0
    y: float = 0.0


def _ulps(v: float, k: int) -> list[float]:
    """``v`` and its ``k`` neighbours on each side."""
    out, lo, hi = [v], v, v
    for _ in range(k):
        lo, hi = math.nextafter(lo, -math.inf), math.nextafter(hi, math.inf)
        out += [lo, hi]
    return out


def _ns(t: float) -> int:
    """Nanoseconds nearest ``t`` seconds, exactly (no float product)."""
    return round(Fraction(t) * 1_000_000_000)


def write_bag(
    log: CarmenLog,
    path: str | os.PathLike,
    *,
    format: str = "ros2",
    scan_topic: str = "/scan",
    odom_topic: str | None = "/odom",
    tf: bool = True,
    odom_frame: str = "odom",
    base_frame: str = "base_footprint",
    laser_frame: str = "base_scan",
) -> Path:
    """Write ``log`` (scans and the odometry at each) as a ROS bag.

    Per scan, all stamped with the scan time: the ``nav_msgs/Odometry`` on
    ``odom_topic`` (``odom_frame -> base_frame``), the same pose on ``/tf``, the
    ``sensor_msgs/LaserScan`` on ``scan_topic`` (no-returns as ``+inf``, unusable
    readings as NaN); once, the laser mounting ``base_frame -> laser_frame`` (the first
    scan's ``sensor_offset``) on ``/tf_static``. A ROS 2 bag keeps the log's
    ``map2map_*`` params in its metadata ``custom_data``. Written to a temporary
    name and renamed; an existing bag at ``path`` is replaced.

    Parameters
    ----------
    log : CarmenLog
        The run (:func:`~map2map.robotlog.logs.load_log` reads any recorded log).
    path : path-like
        ``format="ros1"``: the ``.bag`` file; otherwise the bag folder.
    format : {"ros1", "ros2", "mcap"}
        ROS 1 bag, ROS 2 bag with sqlite3 storage, ROS 2 bag with mcap storage.
    scan_topic : str
        The LaserScan topic.
    odom_topic : str or None
        The Odometry topic; None writes none (the odometry is then on ``/tf`` only).
    tf : bool
        Write the odometry as the ``odom_frame -> base_frame`` transform on ``/tf``.
    odom_frame, base_frame, laser_frame : str
        Frame names (TurtleBot3's by default).

    Returns
    -------
    pathlib.Path
        ``path``.

    Raises
    ------
    InputError
        rosbags not installed, an unknown ``format``, a ROS 1 path not ending in
        ``.bag``, an empty log, an unwritable path.
    """
    path = Path(path)
    if format not in BAG_FORMATS:
        raise InputError(path, f"unknown `format={format}` ({', '.join(BAG_FORMATS)})")
    if format == "ros1" and path.suffix != ".bag":
        raise InputError(path, "a ROS 1 bag must be named *.bag")
    if len(log) == 0:
        raise InputError(path, "log has no scans: nothing to write")
    rb = _rosbags(path, "writing")

    if format == "ros1":
        with atomic_path(path) as tmp:
            tmp.unlink()
            _write(rb, log, tmp, format, scan_topic, odom_topic, tf, odom_frame, base_frame,
                   laser_frame)  # fmt: skip
    else:
        with atomic_dir(path) as tmp:
            inner = tmp / path.name  # rosbags names the storage file after the folder
            _write(rb, log, inner, format, scan_topic, odom_topic, tf, odom_frame, base_frame,
                   laser_frame)  # fmt: skip
            for f in list(inner.iterdir()):
                shutil.move(str(f), str(tmp / f.name))
            inner.rmdir()
    return path


def _write(rb, log, path, format, scan_topic, odom_topic, tf, odom_frame, base_frame, laser_frame):
    from rosbags.typesys import Stores, get_types_from_msg, get_typestore

    ros1 = format == "ros1"
    if ros1:
        ts = get_typestore(Stores.ROS1_NOETIC)
        ts.register(get_types_from_msg(_TF_MSG_ROS1, TF_TYPE))
        writer = rb.rosbag1.Writer(path)
        serialize: Callable = ts.serialize_ros1
    else:
        ts = get_typestore(Stores.ROS2_HUMBLE)
        plugins = rb.rosbag2.StoragePlugin
        plugin = plugins.MCAP if format == "mcap" else plugins.SQLITE3
        writer = rb.rosbag2.Writer(path, version=8, storage_plugin=plugin)
        for k, v in log.params.items():
            if k.startswith("map2map_"):
                writer.set_custom_data(k, str(v))
        serialize = ts.serialize_cdr
    T = ts.types
    Time, Header = T["builtin_interfaces/msg/Time"], T["std_msgs/msg/Header"]
    Vec, Quat = T["geometry_msgs/msg/Vector3"], T["geometry_msgs/msg/Quaternion"]
    Point, Pose = T["geometry_msgs/msg/Point"], T["geometry_msgs/msg/Pose"]
    Tf, TfStamped = T["geometry_msgs/msg/Transform"], T["geometry_msgs/msg/TransformStamped"]
    seq = [0]

    def header(t: float, frame: str):
        ns = _ns(t)
        stamp = Time(sec=ns // 1_000_000_000, nanosec=ns % 1_000_000_000)
        if ros1:
            seq[0] += 1
            return Header(seq=seq[0], stamp=stamp, frame_id=frame), ns
        return Header(stamp=stamp, frame_id=frame), ns

    def quat(th: float):
        z, w = _heading_zw(float(th))
        return Quat(x=0.0, y=0.0, z=z, w=w)

    def tf_msg(t, parent, child, x, y, th):
        h, ns = header(t, parent)
        tr = Tf(translation=Vec(x=float(x), y=float(y), z=0.0), rotation=quat(th))
        return T[TF_TYPE](transforms=[TfStamped(header=h, child_frame_id=child, transform=tr)]), ns

    zeros36 = np.zeros(36, np.float64)
    Twist = T["geometry_msgs/msg/Twist"]
    no_twist = T["geometry_msgs/msg/TwistWithCovariance"](
        twist=Twist(linear=Vec(x=0.0, y=0.0, z=0.0), angular=Vec(x=0.0, y=0.0, z=0.0)),
        covariance=zeros36,
    )
    with writer:
        c_static = writer.add_connection(TF_STATIC_TOPIC, TF_TYPE, typestore=ts)
        c_tf = writer.add_connection(TF_TOPIC, TF_TYPE, typestore=ts) if tf else None
        c_odom = writer.add_connection(odom_topic, ODOM_TYPE, typestore=ts) if odom_topic else None
        c_scan = writer.add_connection(scan_topic, SCAN_TYPE, typestore=ts)
        first = log.scans[0]
        msg, ns = tf_msg(first.t, base_frame, laser_frame, *first.sensor_offset)
        writer.write(c_static, ns, serialize(msg, TF_TYPE))
        for odo, scan in log:
            h, ns = header(scan.t, odom_frame)
            pose = T["geometry_msgs/msg/PoseWithCovariance"](
                pose=Pose(position=Point(x=float(odo.x), y=float(odo.y), z=0.0),
                          orientation=quat(odo.theta)),
                covariance=zeros36,
            )  # fmt: skip
            m = T[ODOM_TYPE](header=h, child_frame_id=base_frame, pose=pose, twist=no_twist)
            if c_odom is not None:
                writer.write(c_odom, ns, serialize(m, ODOM_TYPE))
            if c_tf is not None:
                msg, _ = tf_msg(scan.t, odom_frame, base_frame, odo.x, odo.y, odo.theta)
                writer.write(c_tf, ns, serialize(msg, TF_TYPE))
            r = np.asarray(scan.ranges, np.float32)
            n = r.shape[0]
            h, _ = header(scan.t, laser_frame)
            m = T[SCAN_TYPE](
                header=h,
                angle_min=float(scan.angle_min),
                angle_max=float(scan.angle_min + scan.angle_increment * (n - 1)),
                angle_increment=float(scan.angle_increment),
                time_increment=0.0,
                scan_time=0.0,
                range_min=float(scan.range_min),
                range_max=float(scan.range_max),
                ranges=r,
                intensities=np.zeros(0, np.float32),
            )
            writer.write(c_scan, ns, serialize(m, SCAN_TYPE))
