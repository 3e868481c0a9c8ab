"""Loop closure after the particle filter (``map2map.slam.loops``, issue #35 item 3).

On the Radish fhw log the filter's best particle takes one wrong turn (0.3-0.7 rad in a
single step, measured against the corrected poses) where the robot comes back into a
corridor it has mapped, and lays the rest of the run down beside the first pass: the
map is doubled. The tests rebuild that failure on a generated ring corridor: the
front end's trajectory is the true one with such a turn injected, the odometry the
true one with drift; the map drawn from the front end's poses is doubled, the one
from the poses :func:`close_loops` returns is not.
"""

from __future__ import annotations

import numpy as np
import pytest
from _slam_synth import drive

from map2map.core.grid import FREE, OCCUPIED, OccupancyMap
from map2map.robotlog.base import LaserScan, OdometryReading
from map2map.robotlog.carmen import CarmenLog
from map2map.sim.lidar import Lidar, LidarConfig, Scene
from map2map.slam.graph import optimize_pose_graph
from map2map.slam.gridmap import CountGrid
from map2map.slam.loops import close_loops, gauss_newton_pose_graph, scan_points
from map2map.slam.offline import backend_options, run_slam
from map2map.slam.quality import ate_rmse, wall_distances
from map2map.slam.rbpf import absolute_difference, absolute_sum, prepare_scan

W, H, C = 20.0, 14.0, 2.5  # ring corridor: outer size and width (m)


def ring_plan(res: float = 0.05) -> OccupancyMap:
    """A corridor around a 15 x 9 m block, with pillars and niches so places differ."""
    d = np.full((int(H / res), int(W / res)), FREE, np.uint8)
    d[:2, :] = d[-2:, :] = OCCUPIED
    d[:, :2] = d[:, -2:] = OCCUPIED
    d[int(C / res) : int((H - C) / res), int(C / res) : int((W - C) / res)] = OCCUPIED
    for x, y, s in [(6.0, 0.6, 0.4), (13.0, 0.5, 0.6), (19.4, 5.0, 0.4), (16.0, 13.4, 0.5),
                    (7.5, 13.5, 0.4), (0.5, 9.0, 0.6), (0.6, 4.0, 0.4)]:  # fmt: skip
        a, b, k = int(y / res), int(x / res), int(s / res) // 2
        d[max(a - k, 0) : a + k, max(b - k, 0) : b + k] = OCCUPIED
    return OccupancyMap(d, res)


def ring_run(seed: int = 0, laps: float = 1.4):
    """True poses about 0.5 m apart around the ring and the simulator's LDS-01 scans."""
    c = C / 2
    corners = [(W - c, c), (W - c, H - c), (c, H - c), (c, c)]
    true = drive([(3.0, c)] + corners * 2, speed=0.5, dt=1.0)
    step = np.r_[0.0, np.hypot(*np.diff(true[:, :2], axis=0).T)]
    true = true[np.cumsum(step) <= laps * 2 * (W + H - 4 * c)]
    rng = np.random.default_rng(seed)
    lidar, scene = Lidar(LidarConfig()), Scene.from_map(ring_plan())
    scans = [lidar.scan(scene, p, float(k), rng) for k, p in enumerate(true)]
    return true, scans


def chain(start: np.ndarray, rel: np.ndarray) -> np.ndarray:
    out = [start]
    for r in rel:
        out.append(absolute_sum(out[-1], r))
    return np.array(out)


def draw(poses, scans) -> OccupancyMap:
    g = CountGrid.around(0.0, 0.0, 10.0, 0.05)
    for p, s in zip(poses, scans, strict=True):
        r, a = prepare_scan(s)
        g.register_scan(absolute_sum(p, np.asarray(s.sensor_offset)), r, a, 3.0, s.range_max, True)
    return g.to_occupancy_map()


@pytest.fixture(scope="module")
def wrong_turn():
    true, scans = ring_run()
    rel = absolute_difference(true[1:], true[:-1])
    rng = np.random.default_rng(1)
    # the front end: accurate steps but one wrong turn of 0.4 rad on the second lap,
    # where the robot is back in the first corridor
    front_rel = rel + rng.normal(0.0, [0.005, 0.005, 0.002], rel.shape)
    k = int(0.8 * len(rel))
    front_rel[k, 2] += 0.4
    # the odometry: 2 % heading drift per turn, 1 % scale, noise
    odo_rel = rel * [1.01, 1.01, 1.02] + rng.normal(0.0, [0.01, 0.01, 0.005], rel.shape)
    front = chain(true[0], front_rel)
    odo = chain(true[0], odo_rel)
    pts = [scan_points(*prepare_scan(s), s.sensor_offset, 3.0, 120) for s in scans]
    return true, scans, front, odo, pts


def test_loop_closure_undoes_a_wrong_turn(wrong_turn):
    true, scans, front, odo, pts = wrong_turn
    plan = ring_plan()
    est, closures = close_loops(front, pts, odometry=odo)
    assert len(closures) >= 3
    # the maps are drawn in the plan's frame (the poses start at the true start)
    before = wall_distances(draw(front, scans), plan, (0.0, 0.0, 0.0))
    after = wall_distances(draw(est, scans), plan, (0.0, 0.0, 0.0))
    oracle = wall_distances(draw(true, scans), plan, (0.0, 0.0, 0.0))
    # the front end's map is doubled: 18 % of its walls stand 20 cm or more off the plan's
    assert np.mean(before > 0.2) > 0.1 and ate_rmse(front, true) > 1.0
    # closed: as good as the map drawn at the true poses (no wall 20 cm off, 2.4 cm mean)
    assert np.mean(after > 0.2) < 0.005 and np.mean(after) < np.mean(oracle) + 0.01
    assert ate_rmse(est, true) < 0.1
    again, _ = close_loops(front, pts, odometry=odo)
    np.testing.assert_array_equal(again, est)  # no random step


def test_without_odometry_the_wrong_turn_stays(wrong_turn):
    """The odometry check is what catches the wrong turn: loop closures alone do not."""
    true, scans, front, _, pts = wrong_turn
    est, _ = close_loops(front, pts)
    assert ate_rmse(est, true) > 0.5  # measured 1.2 m


def test_gauss_newton_agrees_with_the_trust_region_solver():
    rng = np.random.default_rng(0)
    rel = np.tile([1.0, 0.0, 2 * np.pi / 20], (39, 1))
    true = chain(np.zeros(3), rel)
    edges = [(k, k + 1, rel[k] + rng.normal(0, [0.02, 0.02, 0.01]), np.diag([50.0, 50, 100]))
             for k in range(39)]  # fmt: skip
    edges += [(k, k + 20, np.zeros(3), np.diag([50.0, 50, 100])) for k in range(0, 20, 4)]
    init = true + rng.normal(0, 0.2, true.shape)
    init[0] = true[0]
    gn = gauss_newton_pose_graph(init, edges)
    tr = optimize_pose_graph(init, edges)
    np.testing.assert_allclose(gn[:, :2], tr[:, :2], atol=0.02)
    assert ate_rmse(gn, true, align=False) < 0.1


def test_close_loops_is_the_default_for_a_recorded_log_only():
    ang = np.pi / 179
    scans = [LaserScan(float(k), np.full(180, 2.0), -np.pi / 2, ang, 0.1, 50.0) for k in range(3)]
    odo = [OdometryReading(float(k), 0.1 * k, 0.0, 0.0) for k in range(3)]
    start = {"map2map_start_x": "0", "map2map_start_y": "0", "map2map_start_theta": "0"}
    recorded = CarmenLog(odometry=odo, scans=scans)
    simulated = CarmenLog(odometry=odo, scans=scans, params=start)
    assert backend_options(recorded)["close_loops"] is True
    assert backend_options(simulated)["close_loops"] is False  # simulate, datasets: unchanged
    assert backend_options(recorded, close_loops=False)["close_loops"] is False
    assert "close_loops" not in backend_options(recorded, "graph")
    res = run_slam(recorded)
    assert res.mapper.params.close_loops and len(res.trajectory) >= 1
    assert not run_slam(simulated).mapper.params.close_loops


def test_slam_help_describes_loop_closure(capsys):
    from map2map.cli.main import main

    with pytest.raises(SystemExit):
        main(["slam", "--help"])
    text = " ".join(capsys.readouterr().out.split())
    assert "--close-loops, --no-close-loops" in text
    assert "on for a recorded log, off for a 'map2map simulate' run" in text


def test_scans_without_returns_in_range_are_skipped(wrong_turn):
    """A stretch of empty scans (no reading within range) neither matches nor fails."""
    true, _, front, odo, pts = wrong_turn
    pts = list(pts)
    for k in range(100, 115):  # across the wrong turn and the chains before it
        pts[k] = np.zeros((0, 2))
    for k in range(30, 45):
        pts[k] = np.zeros((0, 2))
    est, _ = close_loops(front, pts, odometry=odo)
    assert np.isfinite(est).all() and est.shape == front.shape
