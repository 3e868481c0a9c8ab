"""The parametric model end to end: visibility, warp semantics, zero errors, determinism."""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import pytest
import yaml
from _parametric_plans import centre, two_rooms

from map2map.core.errors import InputError
from map2map.core.grid import FREE, OCCUPIED, UNKNOWN
from map2map.parametric import (
    DisplacementField,
    ParametricParams,
    deform,
    load_params,
    make_trajectory,
    save_params,
    warp_map,
)
from map2map.parametric.field import invert_field
from map2map.parametric.pipeline import keyframe_indices, trajectory_to_pixels
from map2map.parametric.visibility import visible_pixels


@pytest.fixture(scope="module")
def plan():
    return two_rooms()


@pytest.fixture(scope="module")
def traj(plan):
    wps = np.array([centre(plan, 10, 10), centre(plan, 45, 100), centre(plan, 70, 20)])
    t, _ = make_trajectory(plan, ParametricParams(), np.random.default_rng(0), waypoints=wps)
    return t


# ------------------------------------------------------------------------- visibility


def test_visibility_occlusion_range_and_fov():
    occ = np.zeros((41, 41), bool)
    occ[:, 30] = True
    pose = np.array([[20.0, 20.0, 0.0]])
    vis = visible_pixels(occ, pose, 2.0, 15.0)
    seen = vis.observed_mask()
    assert seen[20, 30] and not seen[20, 31:].any()  # wall seen, nothing behind it
    assert not seen[20, 20] and not seen[20, 21]  # closer than range_min
    assert seen[20, 34 - 30 + 5] and not seen[20, 4]  # left: 11 px in, 16 px out of range
    rr, cc = np.nonzero(seen)
    assert (np.hypot(rr - 20, cc - 20) <= 15.0 + 1.5).all()
    # every free pixel within range and line of sight is seen (no gaps between rays)
    yy, xx = np.mgrid[0:41, 0:41]
    dist = np.hypot(yy - 20, xx - 20)
    must = (dist >= 3) & (dist <= 14) & (xx < 30)
    assert seen[must].all()
    # 180 degree field of view facing +x (image frame): nothing behind the robot
    half = visible_pixels(occ, pose, 2.0, 15.0, math.pi).observed_mask()
    assert half[20, 28] and not half[20, 12] and not half[20, :18].any()
    # unknown pixels are neither seen nor blocking
    unk = np.zeros_like(occ)
    unk[20, 25] = True
    u = visible_pixels(occ, pose, 2.0, 15.0, unknown=unk).observed_mask()
    assert not u[20, 25] and u[20, 27]


def test_visibility_first_seen_and_counts():
    occ = np.zeros((21, 21), bool)
    vis = visible_pixels(occ, np.array([[5.0, 10.0, 0.0], [15.0, 10.0, 0.0]]), 0.0, 6.0)
    first = vis.first_seen()
    assert first[10, 3] == 0 and first[10, 18] == 1 and first[10, 10] == 0
    assert vis.counts()[10, 10] == 2 and vis.counts()[0, 0] == 0


# ---------------------------------------------------------------------- warp semantics


def test_warp_uniform_shift_moves_content_by_d():
    rng = np.random.default_rng(0)
    data = np.where(rng.random((30, 40)) < 0.3, OCCUPIED, FREE).astype(np.uint8)
    f = DisplacementField(np.full((30, 40), 3.0), np.full((30, 40), -2.0))
    out = warp_map(data, f, np.ones((30, 40), bool))
    # content at (row r, col c) appears at (r - 2, c + 3)
    assert np.array_equal(out[0:28, 3:40], data[2:30, 0:37])
    assert (out[:, :3] == UNKNOWN).all() and (out[28:, :] == UNKNOWN).all()


def test_invert_field_is_inverse_of_smooth_field():
    h, w = 50, 60
    yy, xx = np.mgrid[0:h, 0:w].astype(float)
    f = DisplacementField(2 * np.sin(yy / 9), 1.5 * np.cos(xx / 11))
    px, py = invert_field(f)
    # p + d(p) = q for every q (within the bilinear sampling error)
    dxp = f.dx[
        np.clip(np.rint(py).astype(int), 0, h - 1), np.clip(np.rint(px).astype(int), 0, w - 1)
    ]
    assert np.abs(px + dxp - xx)[5:-5, 5:-5].max() < 0.4
    # forward check on free pixels: plan value at p appears at round(p + d(p))
    data = np.full((h, w), FREE, np.uint8)
    data[::7, :] = OCCUPIED
    out = warp_map(data, f, np.ones((h, w), bool))
    q_r = np.rint(yy + f.dy).astype(int)
    q_c = np.rint(xx + f.dx).astype(int)
    inside = (q_r >= 0) & (q_r < h) & (q_c >= 0) & (q_c < w)
    free_src = (data == FREE) & inside
    agree = out[q_r[free_src], q_c[free_src]] == FREE
    assert agree.mean() > 0.9


def test_unobserved_pixels_stay_unknown():
    data = np.full((10, 10), FREE, np.uint8)
    seen = np.zeros((10, 10), bool)
    seen[:, :5] = True
    out = warp_map(data, DisplacementField.zeros((10, 10)), seen)
    assert (out[:, :5] == FREE).all() and (out[:, 5:] == UNKNOWN).all()


# ------------------------------------------------------------------- model behaviour


@pytest.mark.parametrize("method", ["additive", "ekf"])
def test_zero_error_parameters_give_zero_field_and_the_plan(plan, traj, method):
    p = ParametricParams().zero_error()
    res = deform(plan, traj, method, p, np.random.default_rng(5))
    # exactly zero for the additive method; the EKF's metres -> pixels round trip leaves 1e-14
    assert np.abs(res.field.dx).max() < 1e-9 and np.abs(res.field.dy).max() < 1e-9
    obs = res.observed
    assert obs.sum() > 0.5 * plan.free.sum()
    assert np.array_equal(res.map.data[obs], plan.data[obs])
    assert (res.map.data[~obs] == UNKNOWN).all()
    assert res.map.resolution == plan.resolution and res.map.origin == plan.origin


@pytest.mark.parametrize("method", ["additive", "ekf"])
def test_observed_walls_land_on_walls_at_p_plus_d(plan, traj, method):
    # larger errors than the defaults, so that walls really move
    p = ParametricParams(alpha_eb_std_deg=1.5, beta_std_deg=3.0)
    res = deform(plan, traj, method, p, np.random.default_rng(2))
    f = res.field
    assert f.stats(res.observed)["max"] > 1.5
    rows, cols = np.nonzero(res.observed & plan.occupied)
    qr = np.rint(rows + f.dy[rows, cols]).astype(int)
    qc = np.rint(cols + f.dx[rows, cols]).astype(int)
    # content moved off the grid cannot appear; everything else must
    keep = (qr >= 0) & (qr < plan.height) & (qc >= 0) & (qc < plan.width)
    assert keep.mean() > 0.8
    rows, cols, qr, qc = rows[keep], cols[keep], qr[keep], qc[keep]
    occ = np.pad(res.map.data == OCCUPIED, 1)
    near = np.zeros(rows.size, bool)
    for dr in (-1, 0, 1):
        for dc in (-1, 0, 1):
            r, c = qr + 1 + dr, qc + 1 + dc
            ok = (r >= 0) & (r < occ.shape[0]) & (c >= 0) & (c < occ.shape[1])
            near[ok] |= occ[r[ok], c[ok]]
    assert near.all()
    # and the free content follows the same field (backward sampled part of the warp)
    fr, fc = np.nonzero(res.observed & plan.free)
    qr = np.clip(np.rint(fr + f.dy[fr, fc]).astype(int), 0, plan.height - 1)
    qc = np.clip(np.rint(fc + f.dx[fr, fc]).astype(int), 0, plan.width - 1)
    assert (res.map.data[qr, qc] == FREE).mean() > 0.85


def test_same_seed_same_bytes_different_seed_different_map(plan, traj):
    a = deform(plan, traj, "additive", ParametricParams(), np.random.default_rng(7))
    b = deform(plan, traj, "additive", ParametricParams(), np.random.default_rng(7))
    c = deform(plan, traj, "additive", ParametricParams(), np.random.default_rng(8))
    assert a.map.data.tobytes() == b.map.data.tobytes()
    assert a.field.dx.tobytes() == b.field.dx.tobytes()
    assert a.field.dy.tobytes() == b.field.dy.tobytes()
    assert not np.array_equal(a.field.dx, c.field.dx)
    assert not np.array_equal(a.map.data, c.map.data)


def test_different_trajectories_give_different_maps(plan):
    p = ParametricParams()
    t1, _ = make_trajectory(plan, p, np.random.default_rng(1))
    t2, _ = make_trajectory(plan, p, np.random.default_rng(2))
    m1 = deform(plan, t1, "additive", p, np.random.default_rng(0)).map
    m2 = deform(plan, t2, "additive", p, np.random.default_rng(0)).map
    assert not np.array_equal(m1.data, m2.data)


def test_ekf_and_additive_fields_have_similar_magnitude(plan, traj):
    # thesis Fig. 5.13: both conversions give deformations of the same size
    p = ParametricParams()
    ratios = []
    for seed in range(4):
        add = deform(plan, traj, "additive", p, np.random.default_rng(seed))
        ekf = deform(plan, traj, "ekf", p, np.random.default_rng(seed))
        m_add = add.field.stats(add.observed)["mean"]
        m_ekf = ekf.field.stats(ekf.observed)["mean"]
        assert m_add > 0.1 and m_ekf > 0.1
        ratios.append(m_ekf / m_add)
        assert ekf.drawn["ekf_landmarks"] > 20
    assert 0.25 < float(np.median(ratios)) < 4.0


def test_ekf_reference_initial_is_the_filter_correction_only(plan, traj):
    p = ParametricParams(alpha_eb_std_deg=1.5, beta_std_deg=2.0)
    full = deform(plan, traj, "ekf", p, np.random.default_rng(4))
    corr = deform(
        plan, traj, "ekf", dataclasses.replace(p, ekf_reference="initial"), np.random.default_rng(4)
    )
    assert not np.array_equal(full.field.dx, corr.field.dx)
    zero = ParametricParams().zero_error()
    z = deform(
        plan,
        traj,
        "ekf",
        dataclasses.replace(zero, ekf_reference="initial"),
        np.random.default_rng(0),
    )
    assert np.abs(z.field.dx).max() < 1e-9


def test_geometry_mode_and_180_degree_fov(plan, traj):
    p = ParametricParams(lidar_geometry="geometry", fov_deg=180)
    res = deform(plan, traj, "additive", p, np.random.default_rng(0))
    full = deform(plan, traj, "additive", ParametricParams(), np.random.default_rng(0))
    assert res.observed.sum() < full.observed.sum()
    assert 0 < res.field.stats(res.observed)["mean"] < 20


def test_keyframes_and_pixel_poses(plan, traj):
    k = keyframe_indices(traj, 0.5, 0.5)
    assert k[0] == 0 and k[-1] == len(traj) - 1
    steps = np.hypot(np.diff(traj.x[k]), np.diff(traj.y[k]))
    assert steps[:-1].max() < 0.5 + 0.26 * 0.1 + 1e-9
    px = trajectory_to_pixels(plan, [centre(plan, 10, 20)[0]], [centre(plan, 10, 20)[1]], [0.3])
    assert px[0, :2] == pytest.approx([20.0, 10.0]) and px[0, 2] == pytest.approx(-0.3)


def test_stair_step_heading_jitter_does_not_make_key_poses():
    # a diagonal grid path: 1 cm steps, heading alternating 0 / pi/4 every 5 steps
    n = 400
    th = np.where((np.arange(n) // 5) % 2 == 0, 0.0, np.pi / 4)
    step = np.stack([np.cos(th), np.sin(th)], 1) * 0.01
    xy = np.cumsum(step, axis=0)
    from map2map.trajectory.timing import trajectory_from_poses

    tr = trajectory_from_poses(xy[:, 0], xy[:, 1], th)
    k = keyframe_indices(tr, 1.0, 0.5)
    assert len(k) <= 6  # ~3.7 m of travel: a key pose per metre, none for the jitter
    # a real turn still makes one
    turn = trajectory_from_poses([0, 0.1, 0.1, 0.1], [0, 0, 0, 0.1], [0, 0, 1.5, 1.5])
    assert 2 in keyframe_indices(turn, 1.0, 0.5, smooth=1)
    # ... also through the filter, once the new heading lasts
    x = np.r_[np.linspace(0, 0.3, 30), np.full(30, 0.3)]
    y = np.r_[np.zeros(30), np.linspace(0, 0.3, 30)]
    th = np.r_[np.zeros(30), np.full(30, np.pi / 2)]
    k = keyframe_indices(trajectory_from_poses(x, y, th), 1.0, 0.5)
    # first, last, and one key pose per 0.5 rad of the 1.57 rad turn, all around the turn
    assert len(k) == 5 and all(25 < i < 45 for i in k[1:-1])


def test_real_houseexpo_plan_with_recorded_trajectory(shared_data):
    from map2map.maps.houseexpo import houseexpo_to_world, load_houseexpo
    from map2map.trajectory import read_trajectory
    from map2map.trajectory.timing import trajectory_from_poses

    d = shared_data / "houseexpo" / "json"
    plan = load_houseexpo(d / "0a1b29dba355df2ab02630133187bfab.json", resolution=0.05)
    rec = read_trajectory(d / "0a1b29dba355df2ab02630133187bfab_trajectory.csv")
    traj = trajectory_from_poses(*houseexpo_to_world(rec.x, rec.y, rec.theta))
    res = deform(plan, traj, "additive", ParametricParams(), np.random.default_rng(0))
    st = res.field.stats(res.observed)
    assert res.observed.sum() > 0.8 * plan.free.sum()  # the recorded run explores the flat
    assert 0.3 < st["mean"] < 10 and st["max"] < 40  # centimetres to decimetres at 5 cm/px
    assert (res.map.data[res.observed] != 127).mean() > 0.99


def test_rotated_map_frame(plan):
    # a plan whose grid is rotated in the world (origin yaw): the trajectory still runs
    # through its free space and the output keeps the frame
    rot = plan.copy(origin=(2.0, -1.0, 0.4))
    s, g = centre(rot, 10, 10), centre(rot, 70, 100)
    traj, _ = make_trajectory(rot, ParametricParams(), np.random.default_rng(0), start=s, goal=g)
    r, c = rot.world_to_pixel(traj.x, traj.y)
    assert (rot.data[r, c] == FREE).all()
    res = deform(rot, traj, "additive", ParametricParams().zero_error(), np.random.default_rng(0))
    assert res.map.origin == rot.origin
    assert np.array_equal(res.map.data[res.observed], rot.data[res.observed])
    # while driving straight, the image angle of a pose is the direction of motion in pixels
    i = int(np.flatnonzero(traj.v > 0)[0]) + 1
    px = trajectory_to_pixels(
        rot, traj.x[i : i + 6 : 5], traj.y[i : i + 6 : 5], traj.theta[i : i + 6 : 5]
    )
    motion = np.arctan2(px[1, 1] - px[0, 1], px[1, 0] - px[0, 0])
    assert abs((px[0, 2] - motion + np.pi) % (2 * np.pi) - np.pi) < 1e-6


def test_start_goal_errors(plan):
    p = ParametricParams()
    rng = np.random.default_rng(0)
    with pytest.raises(InputError, match="outside the map"):
        make_trajectory(plan, p, rng, start=(-1.0, 1.0), goal=centre(plan, 10, 10))
    with pytest.raises(InputError, match="in a wall"):
        make_trajectory(plan, p, rng, start=centre(plan, 3, 30), goal=centre(plan, 10, 10))
    closed = two_rooms(door=False)
    with pytest.raises(InputError, match=r"start \(.*\) m and goal \(.*\) m are not connected"):
        make_trajectory(closed, p, rng, start=centre(closed, 30, 30), goal=centre(closed, 30, 90))


# ------------------------------------------------------------------------- parameters


def test_params_yaml_round_trip_and_rejections(tmp_path):
    p = dataclasses.replace(ParametricParams(), eta=0.02, fov_deg=180.0, z_weights=(1, 0, 0, 0))
    save_params(p, tmp_path / "p.yaml", run={"seed": 3}, drawn={"E_b": 1.0})
    assert load_params(tmp_path / "p.yaml") == p
    (tmp_path / "flat.yaml").write_text("eta: 0.05\nmedian_size: 3\n")
    assert load_params(tmp_path / "flat.yaml").median_size == 3
    for text, msg in [
        ("etaa: 0.05\n", "unknown parameter"),
        ("eta: .nan\n", "finite"),
        ("z_weights: [0.4, .nan, 0.2, 0.1]\n", "non-finite"),
        ("eta: -1\n", ">= 0"),
        ("fov_deg: 90\n", "180 or 360"),
        ("lidar_geometry: magic\n", "lidar_geometry"),
        ("[1, 2]\n", "mapping"),
        ("eta: [\n", "YAML"),
    ]:
        (tmp_path / "bad.yaml").write_text(text)
        with pytest.raises(InputError, match=msg):
            load_params(tmp_path / "bad.yaml")
    doc = yaml.safe_load((tmp_path / "p.yaml").read_text())
    assert set(doc) == {"run", "parameters", "drawn"}
