"""Roadmap, shortest paths and timed trajectories (map2map.trajectory)."""

from __future__ import annotations

import numpy as np
import pytest
from _parametric_plans import centre, two_rooms

from map2map.core.errors import InputError
from map2map.trajectory import (
    build_roadmap,
    path_through,
    read_trajectory,
    read_waypoints,
    shortest_path,
    time_waypoints,
)
from map2map.trajectory.prm import segments_clear
from map2map.trajectory.timing import trajectory_from_poses, trapezoid


def _rm(plan, seed=0):
    return build_roadmap(plan, robot_radius=0.15, rng=np.random.default_rng(seed))


def test_roadmap_nodes_and_edges_keep_clearance():
    plan = two_rooms()
    rm = _rm(plan)
    assert rm.nodes.shape[0] > 20 and rm.edges.shape[0] > rm.nodes.shape[0]
    from scipy import ndimage

    clearance = ndimage.distance_transform_edt(plan.free) * plan.resolution
    r = np.floor(rm.nodes[:, 1] + 0.5).astype(int)
    c = np.floor(rm.nodes[:, 0] + 0.5).astype(int)
    assert (clearance[r, c] > 0.15 - plan.resolution).all()
    # every edge stays on free pixels of the plan
    assert segments_clear(plan.free, rm.nodes[rm.edges[:, 0]], rm.nodes[rm.edges[:, 1]]).all()


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_path_goes_through_the_door(seed):
    plan = two_rooms()
    rm = _rm(plan, seed)
    path = shortest_path(rm, np.array([30.0, 10.0]), np.array([90.0, 10.0]))  # (x, y) px
    assert np.allclose(path[0], (30, 10)) and np.allclose(path[-1], (90, 10))
    assert segments_clear(plan.free, path[:-1], path[1:]).all()
    # the only way across the wall at columns 60-61 is the door, rows 20-35
    cross = []
    for a, b in zip(path[:-1], path[1:], strict=True):
        if (a[0] - 60.5) * (b[0] - 60.5) < 0:
            t = (60.5 - a[0]) / (b[0] - a[0])
            cross.append(a[1] + t * (b[1] - a[1]))
    assert cross and all(20 <= y <= 36 for y in cross)


def test_not_connected_raises_naming_points():
    plan = two_rooms(door=False)
    rm = _rm(plan)
    with pytest.raises(InputError, match="not connected"):
        shortest_path(rm, np.array([30.0, 10.0]), np.array([90.0, 10.0]))
    with pytest.raises(InputError, match=r"A and B are not connected"):
        path_through(rm, np.array([[30.0, 10.0], [90.0, 10.0]]), ["A", "B"])


def test_path_through_waypoints_visits_them_in_order():
    plan = two_rooms()
    rm = _rm(plan)
    wps = np.array([[10.0, 10.0], [90.0, 30.0], [40.0, 70.0]])
    path = path_through(rm, wps)
    for wp in wps:
        assert np.min(np.hypot(*(path - wp).T)) < 1e-9


def test_trapezoid_profile_hand_computed():
    # 1 m at 0.5 m/s, 1 m/s^2: accelerate 0.5 s (0.125 m), cruise 1.5 s, decelerate 0.5 s
    s, v, total = trapezoid(np.array([0.25, 0.5, 1.0, 2.25, 2.5]), 1.0, 0.5, 1.0)
    assert total == pytest.approx(2.5)
    assert s == pytest.approx([0.03125, 0.125, 0.375, 0.96875, 1.0])
    assert v == pytest.approx([0.25, 0.5, 0.5, 0.25, 0.0])


def test_timed_trajectory_respects_turtlebot_limits():
    wps = np.array([[0.0, 0.0], [2.0, 0.0], [2.0, 1.5], [0.5, 0.5]])
    tr = time_waypoints(wps)
    assert tr.v.max() <= 0.26 + 1e-12 and np.abs(tr.omega).max() <= 1.82 + 1e-12
    # wheel speeds v +- omega b / 2 within the wheel limit 0.26 m/s (+1 % for 1.82 * 0.1435)
    wheel = np.abs(tr.v) + np.abs(tr.omega) * 0.287 / 2
    assert wheel.max() <= 0.262
    assert np.abs(tr.acceleration).max() <= 2.5 + 1e-6
    assert np.allclose([tr.x[-1], tr.y[-1]], wps[-1])
    times = tr.meta["waypoint_times"]
    assert len(times) == 4 and np.all(np.diff(times) > 0)
    for wp, t in zip(wps, times, strict=True):
        i = int(np.argmin(np.abs(tr.t - t)))
        assert np.hypot(tr.x[i] - wp[0], tr.y[i] - wp[1]) < 0.03
    # heading follows the segments; the path length is the polyline's
    assert tr.theta[5] == pytest.approx(0.0)
    assert tr.length == pytest.approx(2.0 + 1.5 + np.hypot(1.5, 1.0), rel=1e-6)


def test_trajectory_csv_round_trip(tmp_path):
    tr = time_waypoints(np.array([[0.0, 0.0], [1.0, 1.0]]))
    tr.to_csv(tmp_path / "t.csv")
    back = read_trajectory(tmp_path / "t.csv")
    for k in ("t", "x", "y", "theta", "v", "omega"):
        assert np.array_equal(getattr(back, k), getattr(tr, k)), k


def test_read_trajectory_three_and_four_columns(tmp_path):
    (tmp_path / "a.csv").write_text("0 0 0\n0.26 0 0\n0.26 0 1.82\n")
    a = read_trajectory(tmp_path / "a.csv")
    assert a.t == pytest.approx([0.0, 1.0, 2.0])  # times from the speed limits
    assert a.v[0] == pytest.approx(0.26) and a.omega[1] == pytest.approx(1.82)
    (tmp_path / "b.csv").write_text("t,x,y,theta\n0,0,0,0\n2,1,0,0\n")
    b = read_trajectory(tmp_path / "b.csv")
    assert b.v[0] == pytest.approx(0.5)
    (tmp_path / "c.csv").write_text("x,y\n0,0\n")
    with pytest.raises(InputError, match="x, y, theta"):
        read_trajectory(tmp_path / "c.csv")
    (tmp_path / "d.csv").write_text("2,0,0,0\n1,1,0,0\n")
    with pytest.raises(InputError, match="increase"):
        read_trajectory(tmp_path / "d.csv")


def test_read_waypoints(tmp_path):
    (tmp_path / "w.txt").write_text("# waypoints\nx,y\n1 2\n3,4  # comment\n")
    assert read_waypoints(tmp_path / "w.txt").tolist() == [[1.0, 2.0], [3.0, 4.0]]
    for bad, msg in [
        ("1 2\n3 four\n", "not numbers"),
        ("1 2 3\n4 5 6\n", "2 columns"),
        ("1 2\n", "two waypoints"),
        ("1 2\n3 nan\n", "non-finite"),
        ("1 2\n3\n", "columns"),
        ("", "empty"),
    ]:
        (tmp_path / "bad.txt").write_text(bad)
        with pytest.raises(InputError, match=msg):
            read_waypoints(tmp_path / "bad.txt")


def test_trajectory_from_poses_uses_given_times():
    tr = trajectory_from_poses([0, 1, 1], [0, 0, 1], [0, 0, np.pi / 2], t=[0, 4, 8])
    assert tr.v.tolist() == pytest.approx([0.25, 0.0, 0.0])
    assert tr.omega[1] == pytest.approx(np.pi / 8)


def test_centre_helper_matches_plan():
    plan = two_rooms()
    x, y = centre(plan, 30, 30)
    assert tuple(int(v[0]) for v in plan.world_to_pixel([x], [y])) == (30, 30)
