"""Exploration, routes and whole runs (small plans, short budgets)."""

import numpy as np
import pytest

from map2map.core.grid import OccupancyMap
from map2map.jobs.simulate import save_run
from map2map.robotlog.carmen import read_carmen, replay
from map2map.robotlog.mappers import make_mapper
from map2map.sim.explore import dijkstra, find_frontiers, make_costmap
from map2map.sim.runner import simulate


def two_rooms(res=0.05):
    """4 x 3 m: two rooms joined by a 0.8 m door, walls one pixel thick."""
    h, w = int(3 / res), int(4 / res)
    data = np.full((h + 2, w + 2), 127, np.uint8)
    data[1:-1, 1:-1] = 255
    data[[1, -2], 1:-1] = 0
    data[1:-1, [1, -2]] = 0
    mid = w // 2
    data[1:-1, mid] = 0
    door = int(0.8 / res)
    data[h // 2 - door // 2 : h // 2 + door // 2, mid] = 255
    return OccupancyMap(data, res, (-1.0, 0.5, 0.0))


def test_frontiers_ignore_beam_gaps_and_small_groups():
    data = np.full((50, 50), 127, np.uint8)
    data[10:40, 10:40] = 255
    data[20, 20] = 127  # a one-cell hole between beams
    m = OccupancyMap(data, 0.05)
    fr = find_frontiers(m, min_size_cells=5)
    assert len(fr.sizes) == 1 and fr.labels[20, 20] == 0 and fr.labels[19, 20] == 0
    assert fr.sizes[0] == 4 * 30 - 4


def test_costmap_and_dijkstra_keep_out_of_walls():
    m = two_rooms()
    cm = make_costmap(m, robot_radius=0.2)
    assert np.isinf(cm.cost[m.occupied]).all() and np.isinf(cm.cost[m.unknown]).all()
    # cells closer than radius + safety to a wall are lethal
    assert np.isinf(cm.cost[5, 10]) and np.isfinite(cm.cost[30, 20])
    dist, _ = dijkstra(cm.cost, 30, 20)
    assert np.isfinite(dist[30, 60])  # the other room, through the door
    assert dist[30, 60] > 40


def test_exploration_covers_two_rooms_without_collisions():
    m = two_rooms()
    res = simulate(m, mapper="oracle", seed=3, duration=120, progress=False)
    assert res.stop_reason == "explored"
    assert res.coverage > 0.95
    assert res.collisions == 0
    assert res.sim_seconds < 120
    # the oracle's estimate is the truth
    np.testing.assert_allclose(res.estimated_poses[:, :2], res.true_poses[:, :2], atol=1e-9)


def test_same_seed_identical_outputs_and_log_replays_to_same_map(tmp_path):
    m = two_rooms()
    kw = dict(seed=5, duration=25, obstacles=2, people=1, progress=False)
    a, b = simulate(m, mapper="oracle", **kw), simulate(m, mapper="oracle", **kw)
    pa, pb = save_run(a, tmp_path / "a"), save_run(b, tmp_path / "b")
    for key in ("slam_map", "trajectory_true", "trajectory_estimated", "log"):
        assert pa[key].read_bytes() == pb[key].read_bytes(), key
    assert pa["slam_map"].with_suffix(".pgm").read_bytes() == (
        pb["slam_map"].with_suffix(".pgm").read_bytes()
    )
    c = simulate(m, mapper="oracle", **{**kw, "seed": 6})
    assert not np.array_equal(c.true_poses[-1], a.true_poses[-1])
    log = read_carmen(pa["log"])
    assert len(log) == len(a.scans)
    again = replay(log, make_mapper("oracle"))
    assert again.get_map() == a.slam_map


def test_route_following_reaches_the_end():
    m = two_rooms()
    route = [(-0.3, 2.0), (0.7, 2.0), (1.5, 2.0), (2.3, 2.0)]
    res = simulate(m, mapper="oracle", seed=0, duration=60, route=route, progress=False)
    assert res.stop_reason == "route done"
    assert np.hypot(*(res.true_poses[-1, :2] - route[-1])) < 0.2
    assert res.collisions == 0


def test_narrow_fov_and_odometry_drift_recorded():
    m = two_rooms()
    res = simulate(m, mapper="oracle", seed=1, duration=30, fov=180, progress=False)
    assert res.scans[0].n_beams == 181
    drift = np.hypot(*(res.odometry_poses[-1, :2] - res.true_poses[-1, :2]))
    assert 0 < drift < 0.5


def test_bad_inputs_raise_input_error():
    from map2map.core.errors import InputError

    m = two_rooms()
    with pytest.raises(InputError, match="duration"):
        simulate(m, mapper="oracle", duration=0)
    with pytest.raises(InputError, match="no free space"):
        simulate(OccupancyMap(np.zeros((20, 20), np.uint8), 0.05), mapper="oracle", duration=5)
    with pytest.raises(InputError, match="wall"):
        simulate(m, mapper="oracle", start=(-0.95, 0.56, 0.0), duration=5, progress=False)
    with pytest.raises(InputError, match="outside"):
        simulate(m, mapper="oracle", start=(50.0, 0.0, 0.0), duration=5, progress=False)
    with pytest.raises(InputError, match="through a wall"):
        simulate(m, mapper="oracle", route=[(-0.3, 1.0), (2.3, 1.0)], duration=5, progress=False)
    tiny = np.zeros((12, 12), np.uint8)
    tiny[2:10, 2:10] = 255
    with pytest.raises(InputError, match="too small"):
        simulate(OccupancyMap(tiny, 0.05), mapper="oracle", duration=5, progress=False)


def test_demo_stage_writes_its_outputs(tmp_path):
    from map2map.demo import DemoContext, stage_simulate

    ctx = DemoContext(out=tmp_path, seed=0)
    ctx.plan = two_rooms()
    stage_simulate(ctx)
    written = {p.name for _, p in ctx.written}
    assert {"slam_map.yaml", "run.log", "report.json", "figure.png", "exploration.gif"} <= written
    assert all(p.exists() for _, p in ctx.written)
    assert ctx.sim.coverage > 0.9


class OdometryOnlyMapper:
    """A mapper that trusts odometry: exercises the plain Mapper protocol (no truth)."""

    name = "odometry"

    def __init__(self):
        from map2map.sim.mapping import LogOddsGrid

        self.grid = LogOddsGrid(0.05)
        self._pose = np.zeros(3)

    def update(self, odom, scan):
        self._pose = odom.pose
        self.grid.integrate(self._pose, scan)

    def pose(self):
        return self._pose

    def get_map(self):
        return self.grid.to_map()


def test_any_mapper_instance_drives_the_explorer(monkeypatch):
    from map2map.robotlog import mappers
    from map2map.sim.odometry import OdometryErrors

    monkeypatch.setattr(mappers, "MAPPERS", dict(mappers.MAPPERS))

    m = two_rooms()
    res = simulate(
        m,
        seed=2,
        duration=40,
        mapper=OdometryOnlyMapper(),
        odometry=OdometryErrors(),
        progress=False,
    )
    # the estimate is the odometry (in the plan frame), which drifts from the truth
    np.testing.assert_allclose(res.estimated_poses, res.odometry_poses, atol=1e-9)
    assert res.info["mapper"] == "odometry" and res.coverage > 0.5
    mappers.register_mapper("odometry-test", lambda resolution, seed: OdometryOnlyMapper())
    again = simulate(m, seed=2, duration=40, mapper="odometry-test", progress=False)
    np.testing.assert_array_equal(again.true_poses, res.true_poses)


def test_config_value_runs_like_the_keywords():
    from map2map.sim.runner import SimConfig

    m = two_rooms()
    kw = dict(mapper="oracle", seed=4, duration=8, progress=False)
    a = simulate(m, **kw)
    b = simulate(m, config=SimConfig(**kw))
    assert np.array_equal(a.true_poses, b.true_poses) and a.slam_map == b.slam_map
    # a keyword other than its default overrides the config; a default one does not
    c = simulate(m, seed=5, config=SimConfig(**kw))
    d = simulate(m, seed=0, config=SimConfig(**kw))
    assert (c.info["seed"], d.info["seed"]) == (5, 4)


def test_a_route_that_turns_back_is_driven_to_its_end():
    """Pure pursuit over a route that turns back aimed alternately before and after the
    turn (both within its lookahead) and spun there; the follower drives it leg by leg."""
    m = two_rooms()
    route = [(-0.3, 2.0), (2.3, 2.0), (-0.3, 2.15)]
    res = simulate(m, mapper="oracle", seed=0, duration=90, route=route, progress=False)
    assert res.stop_reason == "route done"
    assert np.hypot(*(res.true_poses[-1, :2] - route[-1])) < 0.2
    assert res.collisions == 0
    assert res.info["route_driven_m"] == pytest.approx(res.info["route_length_m"])


def test_an_unfinished_route_is_warned_about():
    from map2map.core.errors import MapWarning

    m = two_rooms()
    route = [(-0.3, 2.0), (2.3, 2.0), (-0.3, 2.15)]
    with pytest.warns(MapWarning, match=r"not completed within the time budget "
                      r"\(`duration` 8 s\): the robot got 1\.\d m along its 5\.2 m"):
        res = simulate(m, mapper="oracle", seed=0, duration=8, route=route, progress=False)
    assert res.stop_reason == "time budget"


def test_a_run_replays_its_own_true_path(tmp_path):
    """simulate --trajectory run/trajectory_true.csv stalled in a door frame after a
    quarter of this run's path (steered by the drifting SLAM estimate) and spun at its
    turns on the spot; now it drives the whole path within the same time budget."""
    import warnings

    from map2map.jobs.simulate import SimulateSpec
    from map2map.jobs.simulate import simulate as simulate_job
    from map2map.maps.floorplan import generate_floorplan

    plan = generate_floorplan(4, kind="apartment")
    first = simulate_job(SimulateSpec(plan=plan, plan_name="p", out=tmp_path / "run",
                                      progress=False, figures=False))  # fmt: skip
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        again = simulate_job(SimulateSpec(
            plan=plan, plan_name="p", out=tmp_path / "run2", progress=False, figures=False,
            trajectory=tmp_path / "run" / "trajectory_true.csv"))  # fmt: skip
    assert again.result.stop_reason == "route done"
    assert again.result.collisions == 0
    assert again.result.coverage > first.result.coverage - 0.05
