"""``synthesize --model scans`` (issue #33): the robot's own scans mapped at the particle
filter's poses (the default) or at drawn ones."""

import json
import math
import subprocess
import sys
from dataclasses import replace

import numpy as np
import pytest

pytest.importorskip("torch")

from map2map.core.errors import InputError  # noqa: E402
from map2map.core.geometry import compose_pose, relative_pose  # noqa: E402
from map2map.learn.ab.room_drift import RoomDriftParams, room_drift_field  # noqa: E402
from map2map.learn.ab.scans import ScanMapParams, drifted_poses, scan_map  # noqa: E402
from map2map.learn.ab.synthesize import SCANS, synthesize  # noqa: E402
from map2map.maps.floorplan import generate_floorplan  # noqa: E402

STILL = dict(jitter_m=0.0, jitter_deg=0.0, global_deg=0.0, outlier_share=0.0)


@pytest.fixture(scope="module")
def plan():
    return generate_floorplan(3, size=(10, 8))


def test_a_scan_taken_in_a_drifted_room_maps_its_points_where_the_room_transform_puts_them(plan):
    """The pose error moves what a scan sees exactly as the room's rigid transform moves
    the plan's pixels (the sign of the rotation: pixel rows point down)."""
    d = room_drift_field(plan.data, np.random.default_rng(3), RoomDriftParams(rot_deg=4.0,
                                                                             lin=0.05))
    rot = np.degrees(np.arctan2(d.transforms[:, 1, 0], d.transforms[:, 0, 0]))
    assert np.abs(rot).max() > 0.5                       # some room really turns
    free = np.argwhere(plan.data == 255)
    rng = np.random.default_rng(0)
    pick = free[rng.choice(len(free), 40, replace=False)]
    x, y = plan.pixel_to_world(pick[:, 0].astype(float), pick[:, 1].astype(float))
    poses = np.column_stack([x, y, rng.uniform(-math.pi, math.pi, 40)])
    moved = drifted_poses(plan, poses, poses[0], d, np.random.default_rng(0),
                          ScanMapParams(**STILL))
    for p, q, (r, c) in zip(poses, moved, pick, strict=True):
        A = d.transforms[d.rooms[r, c] - 1]
        # a world point 0.8 m ahead and 0.3 m left of the robot
        w = compose_pose(tuple(p), (0.8, 0.3, 0.0))
        wr, wc = plan.world_to_pixel_float(np.array([w[0]]), np.array([w[1]]))
        want_c = A[0, 0] * wc[0] + A[0, 1] * wr[0] + A[0, 2]
        want_r = A[1, 0] * wc[0] + A[1, 1] * wr[0] + A[1, 2]
        got = compose_pose(tuple(q), relative_pose(tuple(p), w))
        gr, gc = plan.world_to_pixel_float(np.array([got[0]]), np.array([got[1]]))
        assert abs(gr[0] - want_r) < 1e-6 and abs(gc[0] - want_c) < 1e-6


def test_the_whole_run_turns_about_its_start_and_jitter_has_its_size(plan):
    d = room_drift_field(plan.data, np.random.default_rng(0), RoomDriftParams(scale=0.0))
    free = np.argwhere(plan.data == 255)[::50]
    x, y = plan.pixel_to_world(free[:, 0].astype(float), free[:, 1].astype(float))
    poses = np.column_stack([x, y, np.zeros(len(x))])
    turned = drifted_poses(plan, poses, poses[0], d, np.random.default_rng(1),
                           ScanMapParams(jitter_m=0.0, jitter_deg=0.0, global_deg=5.0,
                                         outlier_share=0.0))
    g = turned[:, 2]
    assert np.allclose(g, g[0]) and abs(g[0]) > 0
    assert np.allclose(turned[0, :2], poses[0, :2])     # the start does not move
    dist0 = np.hypot(*(poses[:, :2] - poses[0, :2]).T)
    dist1 = np.hypot(*(turned[:, :2] - turned[0, :2]).T)
    assert np.allclose(dist0, dist1)                     # rigid
    jit = drifted_poses(plan, np.repeat(poses[:1], 4000, 0), poses[0], d,
                        np.random.default_rng(2),
                        ScanMapParams(jitter_m=0.02, jitter_deg=0.5, global_deg=0.0,
                                      outlier_share=0.0))
    assert abs(np.std(jit[:, 0] - poses[0, 0]) - 0.02) < 0.002
    assert abs(np.degrees(np.std(jit[:, 2])) - 0.5) < 0.05


def test_jitter_correlated_in_time_keeps_its_size_and_makes_neighbours_alike(plan):
    """``jitter_s`` > 0: the per-scan error is a Gauss-Markov process along the run (the
    scans' times give its step), the same size as the independent jitter of ``jitter_s=0``."""
    d = room_drift_field(plan.data, np.random.default_rng(0), RoomDriftParams(scale=0.0))
    pose = np.array([[3.0, 2.0, 0.0]])
    poses, times = np.repeat(pose, 6000, 0), np.arange(6000) * 0.2
    lag1 = {}
    for tau in (0.0, 5.0):
        sp = ScanMapParams(jitter_m=0.02, jitter_deg=0.5, global_deg=0.0, outlier_share=0.0,
                           jitter_s=tau)
        e = drifted_poses(plan, poses, pose[0], d, np.random.default_rng(4), sp, times)[:, 0] - 3.0
        assert abs(e.std() - 0.02) < 0.004
        lag1[tau] = np.corrcoef(e[1:], e[:-1])[0, 1]
    assert abs(lag1[0.0]) < 0.05 and lag1[5.0] > 0.9            # exp(-0.2 / 5) = 0.96
    with pytest.raises(InputError, match="jitter_s"):
        ScanMapParams(jitter_s=-1.0)


def test_scan_maps_are_seeded_and_differ_between_hypotheses(plan):
    sp = ScanMapParams(duration=40.0, pose_error="drawn")
    a, b = scan_map(plan, 5, 0, sp), scan_map(plan, 5, 0, sp)
    c = scan_map(plan, 5, 1, sp)
    assert np.array_equal(a.map.data, b.map.data)
    assert not np.array_equal(a.map.data, c.map.data)
    assert a.map.shape == plan.shape and a.map.resolution == plan.resolution
    assert a.info["scans"] > 10 and a.info["pose_error_m"]["max"] > 0
    # without pose error the scans' walls are the plan's: occupied cells within 1 px of a
    # plan wall; the drift moves them off
    from scipy import ndimage
    near = ndimage.distance_transform_edt(plan.data != 0) <= 1
    exact = scan_map(plan, 5, 0, ScanMapParams(duration=40.0, **STILL, pose_error="drawn",
                                               rooms=RoomDriftParams(parametric=False,
                                                                     scale=0.0)))
    assert exact.info["pose_error_m"]["max"] == 0.0
    assert near[exact.map.occupied].mean() > 0.97
    assert near[a.map.occupied].mean() < near[exact.map.occupied].mean() - 0.05


def test_synthesize_scans_gives_k_hypotheses_and_refuses_network_options(plan):
    res = synthesize(plan, SCANS, samples=2, seed=0, scans=ScanMapParams(duration=30.0))
    assert len(res.maps) == 2 and res.model == SCANS and 0.0 < res.diversity < 1.0
    meta = res.maps[1].meta["synthesize"]
    assert meta["model"] == SCANS and meta["scans"]["duration"] == 30.0
    for kw in ({"render": "plain"}, {"drift": "none"}, {"coverage": "rays"},
               {"traces": "none"}, {"drift_scale": 2.0}):
        with pytest.raises(InputError) as e:
            synthesize(plan, SCANS, samples=1, **kw)
        assert e.value.source == next(iter(kw))
    with pytest.raises(InputError, match="model 'scans' only"):
        synthesize(plan, "pretrained", samples=1, scans=ScanMapParams())


def test_cli_synthesize_scans_writes_maps_and_its_summary(tmp_path, plan):
    from map2map.maps.formats import save_map

    src = tmp_path / "apt.yaml"
    save_map(plan, src)
    out = tmp_path / "hyp"
    cmd = [sys.executable, "-m", "map2map", "synthesize", str(src), "--out", str(out),
           "--model", "scans", "--samples", "2", "--no-figure"]
    r = subprocess.run(cmd, capture_output=True, text=True, timeout=600)
    assert r.returncode == 0, r.stderr
    summary = json.loads((out / "apt_synthesize.json").read_text())
    assert summary["model"] == "scans" and len(summary["hypotheses"]) == 2
    assert summary["scans"]["pose_error"] == "filter"                    # the default
    assert (out / "apt_hyp01.pgm").is_file()
    bad = subprocess.run(cmd[:-1] + ["--render", "plain", "--out", str(tmp_path / "x")],
                         capture_output=True, text=True, timeout=600)
    assert bad.returncode == 2 and "render" in bad.stderr and "Traceback" not in bad.stderr
    assert not (tmp_path / "x").exists()
    grid = subprocess.run(cmd + ["--explore-map", "grid", "--out", str(tmp_path / "g")],
                          capture_output=True, text=True, timeout=600)
    assert grid.returncode == 0, grid.stderr
    summary = json.loads((tmp_path / "g" / "apt_synthesize.json").read_text())
    assert summary["scans"]["explore_map"] == "grid"
    net = subprocess.run(cmd[:5] + ["--model", "pretrained", "--explore-map", "grid",
                                    "--out", str(tmp_path / "n")],
                         capture_output=True, text=True, timeout=600)
    assert net.returncode == 2 and "--explore-map" in net.stderr and "Traceback" not in net.stderr
    assert not (tmp_path / "n").exists()
    drawn = subprocess.run(cmd + ["--pose-error", "drawn", "--out", str(tmp_path / "f")],
                           capture_output=True, text=True, timeout=600)
    assert drawn.returncode == 0, drawn.stderr
    summary = json.loads((tmp_path / "f" / "apt_synthesize.json").read_text())
    assert summary["scans"]["pose_error"] == "drawn"
    bad = subprocess.run(cmd + ["--pose-error", "filter", "--explore-map", "grid",
                                "--out", str(tmp_path / "fg")], capture_output=True, text=True,
                         timeout=600)
    assert bad.returncode == 2 and "explore_map" in bad.stderr and "Traceback" not in bad.stderr
    assert not (tmp_path / "fg").exists()


def test_a_given_start_is_where_every_hypothesis_starts(plan):
    free = np.argwhere(plan.data == 255)
    r, c = free[len(free) // 2]
    x, y = plan.pixel_to_world(np.array([float(r)]), np.array([float(c)]))
    start = (float(x[0]), float(y[0]), 0.7)
    p = ScanMapParams(duration=20.0)
    for k in (0, 1):
        h = scan_map(plan, 0, k, p, start=start)
        assert np.allclose(h.true_poses[0], start)
    own = [scan_map(plan, 0, k, p).true_poses[0] for k in (0, 1)]
    assert not np.allclose(own[0], own[1])          # by default each draws its own
    res = synthesize(plan, SCANS, samples=2, scans=p, start=start)
    assert len(res.maps) == 2 and 0.0 < res.diversity < 1.0
    with pytest.raises(InputError, match="model 'scans' only") as e:
        synthesize(plan, "pretrained", samples=1, start=start)
    assert e.value.source == "start"


def test_cli_synthesize_start_is_recorded_and_a_start_outside_names_the_plan(tmp_path, plan):
    from map2map.maps.formats import save_map

    src = tmp_path / "apt.yaml"
    save_map(plan, src)
    free = np.argwhere(plan.data == 255)
    r, c = free[len(free) // 2]
    x, y = plan.pixel_to_world(np.array([float(r)]), np.array([float(c)]))
    base = [sys.executable, "-m", "map2map", "synthesize", str(src), "--model", "scans",
            "--samples", "1", "--no-figure", "--start"]
    ok = subprocess.run(base + [f"{x[0]}", f"{y[0]}", "0.5", "--out", str(tmp_path / "s")],
                        capture_output=True, text=True, timeout=600)
    assert ok.returncode == 0, ok.stderr
    summary = json.loads((tmp_path / "s" / "apt_synthesize.json").read_text())
    assert np.allclose(summary["start"], [x[0], y[0], 0.5])
    bad = subprocess.run(base + ["-50", "-50", "0", "--out", str(tmp_path / "x")],
                         capture_output=True, text=True, timeout=600)
    assert bad.returncode == 2 and str(src) in bad.stderr and "start" in bad.stderr
    assert "Traceback" not in bad.stderr and not (tmp_path / "x").exists()



def test_the_drift_follows_the_route_the_start_room_unmoved(plan):
    """``room_order="visits"`` (the default): the room the robot starts in keeps its true
    poses (only the whole-run turn and the jitter move them, here off), rooms it entered
    later are moved; ``"random"`` chains the rooms from a random room instead."""
    sp = ScanMapParams(duration=60.0, explore_map="grid", **STILL)   # a route with 3 rooms
    h = scan_map(plan, 0, 1, sp)
    rows, cols = plan.world_to_pixel(h.true_poses[:, 0], h.true_poses[:, 1])
    room = h.drift.rooms[rows, cols]
    first = room == room[0]
    assert int(h.drift.order[0]) == int(room[0])
    assert np.allclose(h.poses[first], h.true_poses[first])
    assert (~first).any() and not np.allclose(h.poses[~first], h.true_poses[~first])
    r = scan_map(plan, 0, 1, replace(sp, room_order="random"))
    assert not np.array_equal(r.poses, h.poses)
    with pytest.raises(InputError, match="room_order"):
        ScanMapParams(room_order="time")


def test_the_robot_explores_on_the_grid_that_is_drawn(plan):
    """``explore_map="grid"``: without pose error the hypothesis is exactly
    the map the robot planned on (:class:`GridOracle`, GMapping's update rule);
    ``"oracle"`` explores on the simulator's log-odds map and maps one scan every 0.5 s."""
    from map2map.learn.ab.coverage import explore_rng
    from map2map.learn.ab.scans import GridOracle
    from map2map.sim.mapping import resample_to_frame
    from map2map.sim.runner import simulate

    still = dict(STILL, duration=40.0, rooms=RoomDriftParams(parametric=False, scale=0.0))
    assert ScanMapParams(**still, explore_map="grid").pose_error == "drawn"
    h = scan_map(plan, 3, 0, ScanMapParams(**still, explore_map="grid"))
    m = GridOracle(plan.resolution)
    res = simulate(plan, seed=int(explore_rng(3, 0).integers(1 << 32)), duration=40.0,
                   fov=180.0, mapper=m, progress=False)
    assert np.allclose(h.true_poses, res.true_poses)
    assert m.processed[0] == 0 and 10 < len(m.processed) < len(res.scans)
    assert np.array_equal(h.map.data, resample_to_frame(m.get_map(), res.start, plan).data)
    o = scan_map(plan, 3, 0, ScanMapParams(**still, explore_map="oracle"))
    assert not np.array_equal(o.map.data, h.map.data)
    with pytest.raises(InputError, match="explore_map"):
        ScanMapParams(explore_map="gmapping")


def test_the_robot_may_explore_on_its_particle_filters_map(plan):
    """``explore_map="rbpf"`` (the default): the robot drives as a run's robot does (on the best
    particle's map, steered by its pose estimate); the scans the filter processed are the
    ones mapped, at the hypothesis's own poses (here the true ones)."""
    from map2map.learn.ab.coverage import explore_rng
    from map2map.learn.ab.scans import map_scans
    from map2map.robotlog.mappers import make_mapper
    from map2map.sim.runner import simulate

    still = dict(STILL, duration=40.0, rooms=RoomDriftParams(parametric=False, scale=0.0),
                 pose_error="drawn")
    h = scan_map(plan, 3, 0, ScanMapParams(**still, explore_map="rbpf"))
    seed = int(explore_rng(3, 0).integers(1 << 32))
    m = make_mapper("rbpf", resolution=plan.resolution, seed=seed)
    res = simulate(plan, seed=seed, duration=40.0, fov=180.0, mapper=m, progress=False)
    assert np.array_equal(h.true_poses, res.true_poses)
    keep = np.searchsorted(res.times, m.trajectory()[:, 0])
    assert len(keep) == m.n_updates and 10 < len(keep) < len(res.scans)
    assert np.array_equal(res.times[keep], m.trajectory()[:, 0])
    ref = map_scans(res.scans, res.times, res.true_poses, res.start, plan, keep)
    assert np.array_equal(h.map.data, ref.data)
    assert np.array_equal(scan_map(plan, 3, 0, ScanMapParams(**still)).map.data, h.map.data)
    # the filter's own map is not the one drawn: its poses err, the hypothesis's do not
    assert not np.array_equal(h.map.data, res.slam_map_plan.data)


def test_with_the_filters_own_poses_a_hypothesis_is_a_simulated_runs_map(plan):
    """``pose_error="filter"``: the scans the exploring particle filter processed, mapped at
    its best particle's trajectory, are its own map: exactly the map of a simulated
    ``rbpf`` run with that seed (what the datasets' pairs hold)."""
    from map2map.learn.ab.coverage import explore_rng
    from map2map.robotlog.mappers import make_mapper
    from map2map.sim.runner import simulate

    sp = ScanMapParams(duration=40.0, pose_error="filter")
    assert ScanMapParams(duration=40.0) == sp                 # the default since session 31
    h = scan_map(plan, 3, 0, sp)
    seed = int(explore_rng(3, 0).integers(1 << 32))
    m = make_mapper("rbpf", resolution=plan.resolution, seed=seed)
    res = simulate(plan, seed=seed, duration=40.0, fov=180.0, mapper=m, progress=False)
    assert np.array_equal(h.map.data, res.slam_map_plan.data)
    assert h.drift is None and h.info["pose_error"] == "filter"
    assert 0 < h.info["pose_error_m"]["mean"] < 0.5          # the filter's own error
    drawn = scan_map(plan, 3, 0, replace(sp, pose_error="drawn"))
    assert np.array_equal(drawn.true_poses, h.true_poses)    # the same exploration
    assert not np.array_equal(drawn.map.data, h.map.data)
    with pytest.raises(InputError, match="explore_map"):
        ScanMapParams(pose_error="filter", explore_map="grid")
    with pytest.raises(InputError, match="pose_error"):
        ScanMapParams(pose_error="odometry")
