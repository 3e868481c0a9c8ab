"""ROS bags (:mod:`map2map.robotlog.rosbag`): round trips, ``map2map slam BAG``, refusals.

* A synthetic run whose values a bag holds exactly (times of whole nanoseconds, headings
  in [-pi, pi], float32 beam geometry) is written as a ROS 1 bag, a ROS 2 sqlite3 bag
  and a ROS 2 mcap bag; each reads back equal, field by field, and ``map2map slam`` on
  it writes byte for byte the map, trajectory and map.yaml it writes on the same run
  as a CARMEN log.
* The real Radish CARMEN log (aces, its first 100 scans; skipped without
  ``../shared/data``) converted to each kind of bag reads back with the same times,
  ranges and odometry; its geometry comes back float32, and with the log's geometry
  rounded to float32 both SLAM backends build the same map, bit for bit. (Against the
  unrounded log they need not: the backends are chaotic, and a 4.4e-8 rad change of
  ``angle_min`` can give the particle filter another map, as another seed would.)
* ``map2map simulate --bag`` writes the run's log as a bag holding what run.log holds.
* A bag without scans, without odometry, with two scan (or odometry) topics and no
  choice, a missing chosen topic, a corrupt bag and a missing rosbags each stop
  ``map2map slam`` with one line and exit status 2, writing nothing.
"""

from __future__ import annotations

import dataclasses
import math
import sys

import numpy as np
import pytest
from _slam_synth import room_plan, synthetic_run

from map2map.cli.main import main
from map2map.maps.ros import save_ros_map
from map2map.robotlog.base import OdometryReading
from map2map.robotlog.carmen import CarmenLog, read_carmen, write_carmen
from map2map.robotlog.logs import detect_format, load_log
from map2map.robotlog.rosbag import read_bag, write_bag
from map2map.sim.lidar import LidarConfig
from map2map.slam.offline import run_slam

FORMATS = ("ros1", "ros2", "mcap")


def _bag_path(d, fmt, stem="run"):
    return d / (f"{stem}.bag" if fmt == "ros1" else f"{stem}_{fmt}")


def _f32(v: float) -> float:
    return float(np.float32(v))


@pytest.fixture(scope="module")
def exact_log(tmp_path_factory) -> CarmenLog:
    """A synthetic run of values a bag holds exactly, as a CARMEN log reads it back; the
    laser 6.4 cm behind the centre, 1 cm left, turned 0.05 rad (TurtleBot3-like)."""
    lidar = LidarConfig(sensor_offset=(-0.064, 0.01, 0.05))
    wp = [(1.0, 1.0), (4.0, 1.0), (4.0, 4.0), (2.0, 4.0)]
    _, _, stream = synthetic_run(seed=5, waypoints=wp, lidar=lidar)
    records = []
    for k, (o, s) in enumerate(stream):
        t = k / 5  # the double nearest k/5: whole nanoseconds
        odo = OdometryReading(t, o.x, o.y, math.remainder(o.theta, 2 * math.pi))
        scan = dataclasses.replace(
            s, t=t, angle_min=_f32(s.angle_min), angle_increment=_f32(s.angle_increment)
        )
        records.append((odo, scan, None))
    path = tmp_path_factory.mktemp("exact") / "run.log"
    write_carmen(path, records)
    return read_carmen(path)  # range_min 0 (CARMEN has none), ranges >= range_max: inf


def _same_contents(a: CarmenLog, b: CarmenLog) -> None:
    assert len(a) == len(b)
    for (oa, sa), (ob, sb) in zip(a, b, strict=True):
        assert oa == ob  # t, x, y, theta bit for bit
        assert sa.t == sb.t
        assert np.array_equal(sa.ranges, sb.ranges, equal_nan=True)
        assert sb.ranges.dtype == np.float32
        geometry = ("angle_min", "angle_increment", "range_min", "range_max", "sensor_offset")
        assert [getattr(sa, g) for g in geometry] == [getattr(sb, g) for g in geometry]


# ----------------------------------------------------------------------------- round trips


@pytest.mark.parametrize("fmt", FORMATS)
def test_bag_round_trip(tmp_path, exact_log, fmt):
    bag = write_bag(exact_log, _bag_path(tmp_path, fmt), format=fmt)
    assert detect_format(bag) == "rosbag"
    back = load_log(bag)
    _same_contents(exact_log, back)
    assert "laser mounting base_footprint -> base_scan from /tf_static" in back.notes[0]
    # the odometry from /tf instead of /odom: the same poses
    _same_contents(exact_log, load_log(bag, odom_topic="/tf"))


def test_odometry_only_on_tf_is_found(tmp_path, exact_log):
    bag = write_bag(exact_log, tmp_path / "tf_only", format="mcap", odom_topic=None)
    log = read_bag(bag)
    _same_contents(exact_log, log)
    assert "odometry /tf transform odom -> base_footprint" in log.notes[0]


def test_a_rewritten_bag_is_replaced_and_a_db3_file_names_its_folder(tmp_path, exact_log):
    bag = tmp_path / "b"
    write_bag(exact_log, bag, format="ros2")
    write_bag(CarmenLog(exact_log.odometry[:5], exact_log.scans[:5]), bag, format="ros2")
    assert sorted(p.name for p in bag.iterdir()) == ["b.db3", "metadata.yaml"]
    assert len(load_log(bag / "b.db3")) == 5
    (bag / "metadata.yaml").unlink()  # a bare storage file reads too
    assert len(load_log(bag / "b.db3")) == 5


@pytest.mark.parametrize(
    "fmt, backend", [("ros1", "rbpf"), ("ros2", "rbpf"), ("mcap", "rbpf"), ("mcap", "graph")]
)
def test_slam_on_a_bag_writes_what_it_writes_on_the_log(tmp_path, exact_log, fmt, backend):
    write_carmen(tmp_path / "run.log", [(o, s, None) for o, s in exact_log])
    bag = write_bag(exact_log, _bag_path(tmp_path, fmt), format=fmt)
    outs = []
    for src in (tmp_path / "run.log", bag):
        out = tmp_path / f"out_{src.name}"
        rc = main(["slam", str(src), "--out", str(out), "--backend", backend, "--quiet"])
        assert rc == 0
        outs.append(out)
    for name in ("map.pgm", "map.yaml", "trajectory.csv"):
        assert (outs[0] / name).read_bytes() == (outs[1] / name).read_bytes(), name


# ----------------------------------------------------------------------------- real data


def test_carmen_log_converted_to_a_bag_maps_the_same(tmp_path, shared_data):
    full = load_log(shared_data / "carmen" / "aces-corrected.log.gz")
    log = CarmenLog(full.odometry[:100], full.scans[:100])  # 100 of 440 scans: about 11 s
    backs = []
    for fmt in FORMATS:
        back = read_bag(write_bag(log, _bag_path(tmp_path, fmt, "aces"), format=fmt))
        assert len(back) == len(log)
        for (oa, sa), (ob, sb) in zip(log, back, strict=True):
            assert oa == ob and sa.t == sb.t
            assert np.array_equal(sa.ranges, sb.ranges)  # inf (no return) included
            assert (sb.angle_min, sb.angle_increment) == (
                _f32(sa.angle_min), _f32(sa.angle_increment))  # fmt: skip
            assert (sb.range_min, sb.range_max, sb.sensor_offset) == (
                sa.range_min, sa.range_max, sa.sensor_offset)  # fmt: skip
        backs.append(back)
    rounded = CarmenLog(log.odometry, [
        dataclasses.replace(s, angle_min=_f32(s.angle_min),
                            angle_increment=_f32(s.angle_increment))
        for s in log.scans
    ])  # fmt: skip
    for backend in ("rbpf", "graph"):
        a = run_slam(rounded, backend).map
        b = run_slam(backs[2], backend).map
        assert a.origin == b.origin and np.array_equal(a.data, b.data), backend


# ----------------------------------------------------------------------------- simulate


def test_simulate_writes_its_log_as_a_bag(tmp_path):
    plan = tmp_path / "plan.yaml"
    save_ros_map(room_plan(), plan)
    out = tmp_path / "run"
    rc = main(["simulate", str(plan), "--out", str(out), "--duration", "20", "--seed", "1",
               "--mapper", "oracle", "--bag", "ros2", "--quiet"])  # fmt: skip
    assert rc == 0
    log, bag = load_log(out), load_log(out / "run_bag")
    assert len(bag) == len(log) > 50
    assert bag.plan_start_pose() == log.plan_start_pose() is not None
    for (oa, sa), (ob, sb) in zip(log, bag, strict=True):
        assert (oa.x, oa.y) == (ob.x, ob.y)
        assert math.remainder(oa.theta, 2 * math.pi) == ob.theta  # the bag's are wrapped
        assert abs(sa.t - sb.t) <= 5e-10  # whole nanoseconds
        assert sb.angle_increment == _f32(math.radians(1.0)) and sb.range_min == _f32(0.12)
        usable = sa.ranges >= 0.12  # the LDS-01's too-close 0.0 readings: NaN in the bag
        assert np.array_equal(sa.ranges[usable], sb.ranges[usable])
        assert np.isnan(sb.ranges[~usable & np.isfinite(sa.ranges)]).all()
    assert main(["slam", str(out / "run_bag"), "--out", str(tmp_path / "m"), "--quiet"]) == 0


# ----------------------------------------------------------------------------- bad bags


def _custom_bag(path, *, scans=("/scan",), odoms=("/odom",), n=12, stamped=True):
    """A ROS 2 mcap bag with the given LaserScan and Odometry topics (n messages each)."""
    from rosbags.rosbag2 import StoragePlugin, Writer
    from rosbags.typesys import Stores, get_typestore

    ts = get_typestore(Stores.ROS2_HUMBLE)
    T = ts.types
    vec = T["geometry_msgs/msg/Vector3"]

    def header(k, frame):
        return T["std_msgs/msg/Header"](
            stamp=T["builtin_interfaces/msg/Time"](sec=k if stamped else 0, nanosec=0),
            frame_id=frame,
        )

    with Writer(path, version=8, storage_plugin=StoragePlugin.MCAP) as w:
        conns = [w.add_connection(t, "sensor_msgs/msg/LaserScan", typestore=ts) for t in scans]
        conns += [w.add_connection(t, "nav_msgs/msg/Odometry", typestore=ts) for t in odoms]
        for k in range(n):
            for c in conns:
                if c.msgtype.endswith("LaserScan"):
                    msg = T["sensor_msgs/msg/LaserScan"](
                        header=header(k, "laser"), angle_min=-1.0, angle_max=1.0,
                        angle_increment=0.5, time_increment=0.0, scan_time=0.0,
                        range_min=0.1, range_max=5.0,
                        ranges=np.array([1.0, np.nan, -np.inf, 0.05, 7.0], np.float32),
                        intensities=np.zeros(0, np.float32),
                    )  # fmt: skip
                else:
                    pose = T["geometry_msgs/msg/Pose"](
                        position=T["geometry_msgs/msg/Point"](x=0.1 * k, y=0.0, z=0.0),
                        orientation=T["geometry_msgs/msg/Quaternion"](x=0.0, y=0.0, z=0.0,
                                                                       w=1.0),
                    )  # fmt: skip
                    msg = T["nav_msgs/msg/Odometry"](
                        header=header(k, "odom"), child_frame_id="base_link",
                        pose=T["geometry_msgs/msg/PoseWithCovariance"](
                            pose=pose, covariance=np.zeros(36)),
                        twist=T["geometry_msgs/msg/TwistWithCovariance"](
                            twist=T["geometry_msgs/msg/Twist"](linear=vec(x=0.0, y=0.0, z=0.0),
                                                               angular=vec(x=0.0, y=0.0, z=0.0)),
                            covariance=np.zeros(36)),
                    )  # fmt: skip
                w.write(c, k * 1_000_000_000, ts.serialize_cdr(msg, c.msgtype))
    return path


def test_a_hand_made_bag_reads_with_ros_semantics(tmp_path):
    log = read_bag(_custom_bag(tmp_path / "b"))
    assert len(log) == 12 and log.odometry[3].x == pytest.approx(0.3)
    # nan, -inf and below range_min: unusable (nan); beyond range_max: no return (inf)
    r = log.scans[0].ranges
    assert r[0] == 1.0 and np.isnan(r[1:4]).all() and r[4] == np.inf
    assert "unknown: no transform chain base_link -> laser" in log.notes[0]
    assert log.scans[0].sensor_offset == (0.0, 0.0, 0.0)
    # no header stamps: the record times
    log = read_bag(_custom_bag(tmp_path / "c", stamped=False))
    assert [s.t for s in log.scans] == list(range(12)) and log.odometry[3].x == 0.1 * 3
    assert "header stamps are all 0 s: the bag's record times used" in log.notes[1]


BAD_BAGS = {
    "no_scans": (dict(scans=()), [], "no sensor_msgs/LaserScan topic"),
    "no_odometry": (dict(odoms=()), [], "bag has no odometry"),
    "two_scan_topics": (
        dict(scans=("/scan", "/scan_rear")),
        [],
        "2 sensor_msgs/LaserScan topics (/scan, /scan_rear): choose one with --scan-topic",
    ),
    "two_odometry_topics": (
        dict(odoms=("/odom", "/odometry/filtered")),
        [],
        "choose one with --odom-topic",
    ),
    "missing_chosen_topic": ({}, ["--scan-topic", "/nope"], "no topic --scan-topic /nope"),
    "chosen_topic_of_another_type": (
        {}, ["--odom-topic", "/scan"], "topic --odom-topic /scan holds sensor_msgs/msg/LaserScan"
    ),
}


@pytest.mark.parametrize("case", sorted(BAD_BAGS))
def test_bad_bags_exit_2_with_one_line(tmp_path, capsys, case):
    kw, extra, needle = BAD_BAGS[case]
    bag = _custom_bag(tmp_path / "bag", **kw)
    out = tmp_path / "out"
    rc = main(["slam", str(bag), "--out", str(out), "--quiet", *extra])
    err = capsys.readouterr().err.strip().splitlines()
    assert rc == 2
    assert len(err) == 1 and err[0].startswith("map2map: error:"), err
    assert str(bag) in err[0] and needle in err[0], err[0]
    assert not out.exists()


def test_two_scan_topics_and_a_choice_read(tmp_path):
    bag = _custom_bag(tmp_path / "bag", scans=("/scan", "/scan_rear"))
    assert len(load_log(bag, scan_topic="/scan_rear")) == 12


def test_corrupt_bag_and_missing_rosbags_say_one_line(tmp_path, capsys, monkeypatch):
    bad = tmp_path / "broken.bag"
    bad.write_bytes(b"#ROSBAG V2.0\n" + b"\x00" * 100)
    assert main(["slam", str(bad), "--out", str(tmp_path / "o"), "--quiet"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "broken.bag: cannot read ROS bag" in err[0], err
    monkeypatch.setitem(sys.modules, "rosbags.highlevel", None)  # import fails
    assert main(["slam", str(bad), "--out", str(tmp_path / "o"), "--quiet"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "needs the rosbags package: pip install 'map2map[ros]'" in err[0]
    plan = tmp_path / "plan.yaml"
    save_ros_map(room_plan(), plan)
    assert main(["simulate", str(plan), "--out", str(tmp_path / "s"), "--bag", "mcap"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "--bag: writing a ROS bag needs the rosbags package" in err[0], err


def test_topics_are_refused_for_other_logs(tmp_path, exact_log, capsys):
    write_carmen(tmp_path / "run.log", [(o, s, None) for o, s in exact_log][:5])
    rc = main(["slam", str(tmp_path / "run.log"), "--out", str(tmp_path / "o"),
               "--scan-topic", "/scan"])  # fmt: skip
    assert rc == 2
    assert "--scan-topic is for ROS bags; this is a carmen log" in capsys.readouterr().err


def test_mounting_chain_upside_down_laser_and_interpolated_odometry(tmp_path):
    """Odometry at other stamps than the scans is interpolated; a two-edge /tf_static
    chain with an upside-down laser reverses the beams and negates their angles."""
    from rosbags.rosbag1 import Writer
    from rosbags.typesys import Stores, get_types_from_msg, get_typestore

    ts = get_typestore(Stores.ROS1_NOETIC)
    ts.register(get_types_from_msg("geometry_msgs/TransformStamped[] transforms\n",
                                   "tf2_msgs/msg/TFMessage"))  # fmt: skip
    T = ts.types

    def stamp(t):
        ns = round(t * 1e9)
        return T["builtin_interfaces/msg/Time"](sec=ns // 10**9, nanosec=ns % 10**9)

    def tfs(t, parent, child, xyz, q):
        return T["geometry_msgs/msg/TransformStamped"](
            header=T["std_msgs/msg/Header"](seq=0, stamp=stamp(t), frame_id=parent),
            child_frame_id=child,
            transform=T["geometry_msgs/msg/Transform"](
                translation=T["geometry_msgs/msg/Vector3"](x=xyz[0], y=xyz[1], z=xyz[2]),
                rotation=T["geometry_msgs/msg/Quaternion"](x=q[0], y=q[1], z=q[2], w=q[3])),
        )  # fmt: skip

    path = tmp_path / "mount.bag"
    s = math.sqrt(0.5)
    with Writer(path) as w:
        c_static = w.add_connection("/tf_static", "tf2_msgs/msg/TFMessage", typestore=ts)
        c_tf = w.add_connection("/tf", "tf2_msgs/msg/TFMessage", typestore=ts)
        c_scan = w.add_connection("/base_scan", "sensor_msgs/msg/LaserScan", typestore=ts)
        static = [tfs(0, "base_footprint", "base_link", (0.0, 0.0, 0.1), (0, 0, 0, 1)),
                  # 0.2 m ahead, turned +90 deg about z, then upside down (180 deg about x)
                  tfs(0, "base_link", "laser", (0.2, 0.0, 0.2), (s, s, 0.0, 0.0))]  # fmt: skip
        msg = T["tf2_msgs/msg/TFMessage"](transforms=static)
        w.write(c_static, 0, ts.serialize_ros1(msg, "tf2_msgs/msg/TFMessage"))
        for k in range(11):  # odometry at 0, 0.1, ... 1.0 s: x = t, heading = t
            t = k / 10
            q = (0.0, 0.0, math.sin(t / 2), math.cos(t / 2))
            msg = T["tf2_msgs/msg/TFMessage"](transforms=[tfs(t, "odom", "base_footprint",
                                                              (t, 0.0, 0.0), q)])  # fmt: skip
            w.write(c_tf, round(t * 1e9), ts.serialize_ros1(msg, "tf2_msgs/msg/TFMessage"))
        for t in (0.25, 0.55, 1.5):  # the last is after the odometry: dropped
            msg = T["sensor_msgs/msg/LaserScan"](
                header=T["std_msgs/msg/Header"](seq=0, stamp=stamp(t), frame_id="/laser"),
                angle_min=-0.5, angle_max=0.5, angle_increment=0.5, time_increment=0.0,
                scan_time=0.0, range_min=0.1, range_max=5.0,
                ranges=np.array([1.0, 2.0, 3.0], np.float32), intensities=np.zeros(0, np.float32),
            )  # fmt: skip
            w.write(c_scan, round(t * 1e9), ts.serialize_ros1(msg, "sensor_msgs/msg/LaserScan"))
    log = read_bag(path)
    assert len(log) == 2 and "1 scans outside the odometry's time span dropped" in log.notes
    o = log.odometry[1]
    assert (o.t, o.x, o.theta) == pytest.approx((0.55, 0.55, 0.55))
    sc = log.scans[0]
    assert sc.sensor_offset == pytest.approx((0.2, 0.0, math.pi / 2))
    assert sc.ranges.tolist() == [3.0, 2.0, 1.0]  # reversed
    assert sc.angle_min == pytest.approx(-0.5) and sc.angle_increment == pytest.approx(0.5)
    assert "upside down" in log.notes[0] and "odometry /tf transform odom -> base_footprint" in (
        log.notes[0])  # fmt: skip
