"""Robot, odometry, oracle mapping and CARMEN logs."""

import gzip
import math

import numpy as np
import pytest

from map2map.core.errors import InputError
from map2map.core.geometry import compose_pose as compose
from map2map.core.geometry import relative_pose as relative
from map2map.core.grid import OccupancyMap
from map2map.robotlog.base import LaserScan, Mapper, OdometryReading
from map2map.robotlog.carmen import read_carmen, replay, write_carmen
from map2map.robotlog.mappers import make_mapper
from map2map.sim.lidar import Lidar, LidarConfig
from map2map.sim.mapping import OracleMapper
from map2map.sim.odometry import OdometryErrors, WheelOdometry
from map2map.sim.robot import DiffDriveRobot, RobotParams
from map2map.sim.world import World


def box_plan(h=80, w=120, res=0.05):
    data = np.full((h, w), 255, np.uint8)
    data[[0, -1], :] = 0
    data[:, [0, -1]] = 0
    data[:, w // 2] = 0  # a dividing wall with a door
    data[h // 2 - 8 : h // 2 + 8, w // 2] = 255
    return OccupancyMap(data, res, (1.0, -1.0, 0.0))


def drive(robot, odo, cmds, dt=0.1):
    true = [robot.pose]
    est = [odo.pose]
    for v, w in cmds:
        res = robot.step(v, w, dt)
        odo.step(res.ds, res.dth)
        true.append(robot.pose)
        est.append(odo.pose)
    return np.array(true), np.array(est)


def wrap(a):
    return (a + np.pi) % (2 * np.pi) - np.pi


def test_zero_error_odometry_reproduces_true_path():
    world = World.build(box_plan(), start=(2.0, 1.0, 0.0), rng=np.random.default_rng(0))
    robot = DiffDriveRobot(RobotParams(), (2.0, 1.0, 0.0), world)
    odo = WheelOdometry(
        OdometryErrors.none(ticks_per_rev=0), rng=np.random.default_rng(0), pose=robot.pose
    )
    rng = np.random.default_rng(3)
    cmds = np.column_stack([rng.uniform(-0.1, 0.26, 300), rng.uniform(-1.8, 1.8, 300)])
    true, est = drive(robot, odo, cmds)
    np.testing.assert_allclose(est[:, :2], true[:, :2], atol=1e-9)
    np.testing.assert_allclose(wrap(est[:, 2] - true[:, 2]), 0, atol=1e-9)
    # encoder quantisation alone stays below a millimetre
    robot = DiffDriveRobot(RobotParams(), (2.0, 1.0, 0.0), world)
    odo = WheelOdometry(OdometryErrors.none(), rng=np.random.default_rng(0), pose=robot.pose)
    true, est = drive(robot, odo, cmds)
    assert np.abs(est[:, :2] - true[:, :2]).max() < 1e-3


def test_systematic_errors_bend_a_straight_line_and_turns():
    world = World.build(box_plan(200, 200), start=(2.0, 1.0, 0.0), rng=np.random.default_rng(0))
    robot = DiffDriveRobot(RobotParams(), (2.0, 1.0, 0.0), world)
    err = OdometryErrors(wheel_diameter_ratio=1.01, wheelbase_ratio=1.0, slip_sigma=0.0)
    odo = WheelOdometry(err, rng=np.random.default_rng(0), pose=robot.pose)
    true, est = drive(robot, odo, [(0.2, 0.0)] * 100)
    assert abs(true[-1, 2]) < 1e-12 and abs(est[-1, 2]) > 0.01  # right wheel bigger
    robot = DiffDriveRobot(RobotParams(), (5.0, 5.0, 0.0), world)
    err = OdometryErrors(wheel_diameter_ratio=1.0, wheelbase_ratio=1.05, slip_sigma=0.0)
    odo = WheelOdometry(err, rng=np.random.default_rng(0), pose=robot.pose)
    true, est = drive(robot, odo, [(0.0, 1.0)] * 30)
    turned_true = true[-1, 2] - true[0, 2]
    turned_odo = est[-1, 2] - est[0, 2]
    assert turned_odo == pytest.approx(turned_true * 1.05, rel=2e-3)


def test_collision_stops_robot_never_tunnels():
    plan = box_plan()
    world = World.build(plan, start=(2.0, 1.0, 0.0), rng=np.random.default_rng(0))
    robot = DiffDriveRobot(RobotParams(), (2.0, 1.0, 0.0), world)
    collided = False
    for _ in range(400):  # drive west into the outer wall at full speed
        r = robot.step(0.26, 0.0, 0.5)
        collided |= r.collided
        if r.collided:
            assert robot.v == 0.0
    assert collided
    x_wall = plan.origin[0] + plan.width * plan.resolution
    assert robot.pose[0] < x_wall
    assert world.clearance_at([robot.pose[0]], [robot.pose[1]])[0] >= 0.2
    # the dividing wall (col 60) with the robot in the left room, away from the door
    robot = DiffDriveRobot(RobotParams(), (2.0, 2.0, 0.0), world)
    wall_x = float(plan.pixel_to_world([0], [60])[0][0])
    for _ in range(100):
        robot.step(0.26, 0.0, 1.0)  # big steps must not jump the 5 cm wall
    assert robot.pose[0] < wall_x - 0.2


def test_pose_algebra():
    a = (1.0, 2.0, 0.5)
    b = (0.3, -0.2, 1.0)
    np.testing.assert_allclose(relative(a, compose(a, b)), b, atol=1e-12)


def make_scans(plan, poses, seed=0, **lidar_options):
    world = World.build(plan, start=poses[0], rng=np.random.default_rng(0))
    lidar = Lidar(LidarConfig(**lidar_options))
    rng = np.random.default_rng(seed)
    return [lidar.scan(world.scene, p, 0.2 * i, rng) for i, p in enumerate(poses)]


def test_oracle_maps_the_room_in_the_start_frame():
    plan = box_plan()
    poses = [(2.0, 1.0, 0.3), (2.5, 1.2, 0.5), (3.0, 0.8, 1.0)]
    scans = make_scans(plan, poses, p_short=0, p_max=0, p_rand=0)
    m = OracleMapper(0.05)
    assert isinstance(m, Mapper)
    for p, s in zip(poses, scans, strict=True):
        m.observe_truth(p)
        m.update(OdometryReading(s.t, 0.0, 0.0, 0.0), s)
        np.testing.assert_allclose(m.pose(), relative(poses[0], p), atol=1e-12)
    g = m.get_map()
    # west wall of the plan at x = 1.0 m lies 1.0 m behind the start along -x(world)
    occ_r, occ_c = np.nonzero(g.occupied)
    wx, wy = g.pixel_to_world(occ_r, occ_c)
    # bring wall pixels into the plan frame and check they sit on plan walls
    c, s = math.cos(0.3), math.sin(0.3)
    px, py = 2.0 + c * wx - s * wy, 1.0 + s * wx + c * wy
    rr, cc = plan.world_to_pixel(px, py)
    inside = plan.contains(rr, cc)
    near_wall = np.zeros(len(rr), bool)
    for dr in (-1, 0, 1):
        for dc in (-1, 0, 1):
            r2, c2 = np.clip(rr + dr, 0, plan.height - 1), np.clip(cc + dc, 0, plan.width - 1)
            near_wall |= plan.occupied[r2, c2]
    assert inside.all() and near_wall.mean() > 0.97


def test_carmen_round_trip_gzip_and_replay_same_map(tmp_path):
    plan = box_plan()
    poses = [(2.0, 1.0, 0.3), (2.5, 1.2, 0.5), (3.0, 0.8, 1.0), (3.1, 0.9, 1.2)]
    scans = make_scans(plan, poses)
    odo = [OdometryReading(s.t, 0.01 * i, -0.02 * i, 0.1 * i) for i, s in enumerate(scans)]
    live = OracleMapper(0.05)
    for p, o, s in zip(poses, odo, scans, strict=True):
        live.observe_truth(p)
        live.update(o, s)
    for name in ("run.log", "run.log.gz"):
        path = tmp_path / name
        write_carmen(path, zip(odo, scans, poses, strict=True))
        log = read_carmen(path)
        assert len(log) == 4 and log.odometry == odo
        np.testing.assert_array_equal(log.true_poses, np.array(poses))
        for a, b in zip(log.scans, scans, strict=True):
            assert np.array_equal(a.ranges, b.ranges)
            assert a.angle_min == b.angle_min and a.angle_increment == b.angle_increment
        again = replay(log, make_mapper("oracle"))
        assert again.get_map() == live.get_map()
    with gzip.open(tmp_path / "run.log.gz", "rt") as f:
        assert any(line.startswith("RAWLASER1 ") for line in f)


def test_carmen_reads_classic_flaser(tmp_path):
    ranges = " ".join(["1.5"] * 181)
    text = (
        "# a Radish-style log\nPARAM robot_front_laser_max 50.0 0 host 0\n"
        "ODOM 0.0 0.0 0.0 0 0 0 1.0 host 1.0\n"
        f"FLASER 181 {ranges} 0.1 0.2 0.3 0.1 0.2 0.3 1.1 host 1.1\n"
        "SYNC tag 1.2 host 1.2\n"
        f"FLASER 181 {ranges} 0.2 0.2 0.3 0.2 0.2 0.3 1.3 host 1.3\n"
    )
    (tmp_path / "a.log").write_text(text)
    log = read_carmen(tmp_path / "a.log")
    assert len(log) == 2 and log.true_poses is None
    s = log.scans[1]
    assert s.n_beams == 181 and s.angle_min == pytest.approx(-np.pi / 2)
    assert s.angles[-1] == pytest.approx(np.pi / 2) and s.range_max == 50.0
    assert log.odometry[1] == OdometryReading(1.3, 0.2, 0.2, 0.3)


@pytest.mark.parametrize(
    ("text", "message"),
    [
        ("", "empty log"),
        ("ODOM 0 0 0 0 0 0 1 h 1\n", "no laser scans"),
        ("RAWLASER1 3 0 1 1 3.5 0.01 0 2 1.0 1.0 0 1 h 1\n", "no odometry"),
        ("ODOM 0 0 0 0 0 0 1 h 1\n3.5 1 2 3\n", "line 2: not a CARMEN message"),
        ("ODOM 0 0 0 0 0 0 1 h 1\nFLASER 3 1.0 1.0 0 0 0 0 0 0 1 h 1\n", "line 2: corrupt FLASER"),
        (
            "PARAM robot_front_laser_max abc 0 h 0\nODOM 0 0 0 0 0 0 1 h 1\n"
            "FLASER 2 1.0 1.0 0 0 0 0 0 0 1 h 1\n",
            "robot_front_laser_max",
        ),
        ("ODOM 0 0 x 0 0 0 1 h 1\n", "line 1: corrupt ODOM"),
        ("ODOM 0 0 0 0 0 0 1 h 1\nRAWLASER1 3 0 1 1 3.5 0.01 0 2 1.0\n", "line 2: truncated"),
        (
            "ODOM 0 0 0 0 0 0 1 h 1\nRAWLASER1 3 0 1 1 3.5 0.01 0 2 1.0 1.0 0 1 h 1\n"
            "RAWLASER1 3 0 1 1 3.5 0.01 0 3 1.0 1.0 1.0 0 2 h 2\n",
            "line 3: scan has 3 beams, earlier scans 2",
        ),
    ],
)
def test_carmen_bad_input(tmp_path, text, message):
    p = tmp_path / "bad.log"
    p.write_text(text)
    with pytest.raises(InputError, match=message):
        read_carmen(p)


def test_write_rejects_nothing_half_written(tmp_path):
    scan = LaserScan(0.0, np.ones(3, np.float32), 0.0, 0.1, 0.1, 3.5)
    path = tmp_path / "x.log"

    def records():
        yield OdometryReading(0.0, 0, 0, 0), scan, None
        raise RuntimeError("boom")

    with pytest.raises(RuntimeError):
        write_carmen(path, records())
    assert not path.exists() and not list(tmp_path.iterdir())


def _flaser(pose, t, ranges="1.5 2.0 2.5"):
    x, y, th = pose
    return f"FLASER 3 {ranges} {x} {y} {th} {x} {y} {th} {t} pippo {t}"


def test_carmen_skips_unused_messages_and_counts_them(tmp_path):
    text = "\n".join(
        [
            "# CARMEN Logfile",
            "PARAM robot_frontlaser_offset 0.0 nohost 0",
            "NEFF 30",
            "ODOM 0 0 0 0 0 0 1.0 h 1.0",
            "SYNC tag 1.1 h 1.1",
            "GPSNMEA garbage fields here",
            _flaser((0.1, 0.0, 0.0), 1.2),
            "NEFF 29.5",
            "MYVENDOR_MSG 1 2 3",
            _flaser((0.2, 0.0, 0.0), 1.4),
        ]
    )
    (tmp_path / "a.log").write_text(text + "\n")
    log = read_carmen(tmp_path / "a.log")
    assert len(log) == 2
    assert log.skipped == {"NEFF": 2, "SYNC": 1, "GPSNMEA": 1, "MYVENDOR_MSG": 1}
    assert log.notes[0].startswith("skipped message types not used: 2 NEFF")
    assert log.logged_poses is None  # not a corrected log: FLASER odometry is the odometry
    assert log.odometry[1] == OdometryReading(1.4, 0.2, 0.0, 0.0)
    s = log.scans[0]  # CARMEN's FLASER geometry: 3 beams over 180 degrees, 50 m default
    assert s.angle_min == pytest.approx(-np.pi / 2) and s.angles[-1] == pytest.approx(np.pi / 2)
    assert s.range_max == 50.0


def test_carmen_corrected_log_odometry_from_odom_increments(tmp_path):
    """A corrected log (GMapping's tools): FLASER poses are corrected, and an ODOM line with
    the corrected pose and timestamp 0 re-anchors the odometry after every scan. The
    odometry must be the wheel increments, never the corrected poses."""
    lines = ["ODOM 0 0 0 0 0 0 1.0 pippo 1.0", "ODOM 1.0 0 0 0 0 0 2.0 pippo 2.0"]
    lines += [_flaser((0.9, 0.1, 0.05), 2.0), "NEFF 30", "ODOM 0.9 0.1 0.05 0 0 0 0 pippo 0"]
    # the wheels then move 1 m straight ahead, from the re-anchored pose
    c, s = np.cos(0.05), np.sin(0.05)
    lines += [f"ODOM {0.9 + c} {0.1 + s} 0.05 0 0 0 3.0 pippo 3.0"]
    lines += [_flaser((2.0, 0.3, 0.1), 3.0), "NEFF 29", "ODOM 2.0 0.3 0.1 0 0 0 0 pippo 0"]
    (tmp_path / "c.log").write_text("\n".join(lines) + "\n")
    log = read_carmen(tmp_path / "c.log")
    odo = np.array([(o.x, o.y, o.theta) for o in log.odometry])
    np.testing.assert_allclose(odo, [[1.0, 0.0, 0.0], [2.0, 0.0, 0.0]], atol=1e-12)
    np.testing.assert_array_equal(log.logged_poses, [[0.9, 0.1, 0.05], [2.0, 0.3, 0.1]])
    assert any("corrected log: 2 ODOM lines re-anchor" in n for n in log.notes)


def test_real_carmen_logs_load(shared_data):
    for name in ("aces", "fhw"):
        log = read_carmen(shared_data / "carmen" / f"{name}-corrected.log.gz")
        assert len(log) > 400 and log.skipped == {"NEFF": len(log)}
        assert log.logged_poses.shape == (len(log), 3)
        o = np.array([(r.x, r.y, r.theta) for r in log.odometry])
        # wheel odometry, not the corrected poses: it drifts away from them
        assert np.abs(o[:, :2] - log.logged_poses[:, :2]).max() > 1.0
