"""Map evaluation (issue 6): alignment, anchoring, nonrigid optimisation, error metric, CLI."""

from __future__ import annotations

import csv
import json
import math
import re

import cv2
import numpy as np
import pytest

from map2map.cli.main import main
from map2map.core.geometry import apply, decompose_similarity, similarity_matrix
from map2map.core.grid import FREE, OCCUPIED, UNKNOWN, OccupancyMap
from map2map.evaluate.align import AlignParams, align_maps, maximise_fitness
from map2map.evaluate.anchors import Anchors, anchor, auto_anchors
from map2map.evaluate.features import edge_points
from map2map.evaluate.fitness import fitness, fitness_map
from map2map.evaluate.icp import icp
from map2map.evaluate.metric import choose_chain, local_errors
from map2map.evaluate.nonrigid import PiecewiseAffine, SideFields, coherent_motion, warp_image
from map2map.evaluate.pipeline import evaluate_maps, register
from map2map.maps.synthetic import (
    deform,
    draw_walls,
    gaussian_field,
    office_walls,
    true_errors,
    wall_displacement,
)

W, H = 320, 240


@pytest.fixture(scope="module")
def plan() -> np.ndarray:
    return draw_walls((H, W), office_walls(W, H, thickness=4))


# --------------------------------------------------------------------------- eq. 8
def test_fitness_eq8_hand_computed():
    walls = np.zeros((21, 21), bool)
    walls[:, 10] = True
    Mf = fitness_map(walls, sigma=2.0)
    assert Mf[5, 10] == 1.0
    assert Mf[5, 13] == pytest.approx(math.exp(-9 / 8), rel=1e-6)
    pts = np.array([[10.5, 3.5], [13.5, 3.5], [7.5, 3.5], [99.0, 3.0]])  # last is off the plan
    expected = (1.0 + 2 * math.exp(-9 / 8) + 0.0) / 4
    assert fitness(Mf, pts) == pytest.approx(expected, rel=1e-6)


# ------------------------------------------------------------------------ eqs. 1-6
def test_anchoring_eqs_1_to_6_hand_computed():
    T_align = np.array([[1.0, 0, 5], [0, 1, 0], [0, 0, 1]])  # alignment off by 5 px in x
    Ps = np.array([[0.0, 0.0], [10.0, 0.0]])
    Pd = np.array([[0.0, 0.0], [0.0, 10.0]])
    # eq. 1: Psa = (5,0), (15,0); eq. 2: ET = rotation +90 deg, t = (0, -5); eq. 3: ET . T_align
    expected = np.array([[0.0, -1, 0], [1, 0, 0], [0, 0, 1]])
    np.testing.assert_allclose(anchor(T_align, Ps, Pd), expected, atol=1e-12)
    # rigid chain (eqs. 4-6) with inconsistent lengths: least squares splits the residual
    Pd2 = np.array([[0.0, 0.0], [12.0, 0.0]])
    T = anchor(np.eye(3), Ps, Pd2)
    np.testing.assert_allclose(apply(T, Ps), [[1.0, 0.0], [11.0, 0.0]], atol=1e-12)
    assert decompose_similarity(T)[0] == pytest.approx(1.0)  # Euclidean: no scale


# ------------------------------------------------------- recovery of a similarity
def _transform_map(data, T, shape):
    return cv2.warpAffine(
        data, T[:2], (shape[1], shape[0]), flags=cv2.INTER_NEAREST, borderValue=UNKNOWN
    )


def test_recovers_known_similarity_on_partial_noisy_map(plan):
    rng = np.random.default_rng(3)
    src = plan.copy()
    src[:, int(0.8 * W) :] = UNKNOWN  # partially explored
    free = src == FREE
    speckle = free & (rng.random(src.shape) < 0.004)  # clutter
    src[speckle] = OCCUPIED
    drop = (src == OCCUPIED) & (rng.random(src.shape) < 0.1)  # missing wall cells
    src[drop] = FREE
    # pixel-centre convention: continuous coordinates c + 0.5 (see transforms docstring)
    C = np.array([[1, 0, 0.5], [0, 1, 0.5], [0, 0, 1.0]])
    T_true = similarity_matrix(0.8, math.radians(33.0), 150.0, 20.0)
    warp = np.linalg.inv(C) @ T_true @ C
    source = _transform_map(src, warp, (360, 420))
    res = align_maps(source, plan)
    probe = np.array([[30.0, 30.0], [250.0, 40.0], [60.0, 200.0], [270.0, 210.0]])
    in_source = apply(T_true, probe)  # the warp maps plan -> source by T_true
    got = apply(res.similarity, in_source)
    assert np.abs(got - probe).max() < 2.0
    s, a, _, _ = decompose_similarity(res.similarity)
    assert s == pytest.approx(1 / 0.8, rel=0.01)
    assert math.degrees(a) == pytest.approx(-33.0, abs=0.5)
    assert res.hypotheses["passed"] and res.hypotheses["rejected"] > 0


def test_no_hypothesis_passes_warns_and_falls_back(plan):
    rng = np.random.default_rng(0)
    source = np.full((H, W), FREE, np.uint8)
    source[rng.random((H, W)) < 0.01] = OCCUPIED  # nothing like the plan
    res = align_maps(source, plan, params=AlignParams(auto_anchor=False, scale_range=(0.8, 1.25)))
    assert res.warnings and "no alignment hypothesis passed" in res.warnings[0]
    assert decompose_similarity(res.similarity)[0] == pytest.approx(1.0)  # rigid fallback
    assert np.all(np.isfinite(res.similarity))


def test_a_weak_hypothesis_is_kept_with_a_note_only_when_it_beats_the_rigid_fallback(plan):
    # a scaled copy: the search finds it, but demand a search score it cannot reach so
    # that it is "weak"; it fits far better than any scale-1 rigid fallback, so it is
    # kept (right scale) with a low-confidence note instead of replaced by a wrong rigid
    C = np.array([[1, 0, 0.5], [0, 1, 0.5], [0, 0, 1.0]])
    T_true = similarity_matrix(0.8, math.radians(10.0), 40.0, 30.0)
    source = _transform_map(plan, np.linalg.inv(C) @ T_true @ C, (H, W))
    weak = AlignParams(auto_anchor=False, min_score=0.99)
    res = align_maps(source, plan, params=weak)
    assert res.hypotheses["score_source_to_target"] < 0.99
    # a note since p_correct measures the doubt (it fired on 2 right Halmstad pairs)
    assert any("low-confidence alignment" in n for n in res.notes)
    assert decompose_similarity(res.similarity)[0] == pytest.approx(1 / 0.8, rel=0.02)
    # a margin no hypothesis can reach: back to the rigid fallback, with its warning
    res = align_maps(source, plan, params=AlignParams(auto_anchor=False, min_score=0.99,
                                                      weak_margin=1e9))  # fmt: skip
    assert "no alignment hypothesis passed" in res.warnings[0]
    assert decompose_similarity(res.similarity)[0] == pytest.approx(1.0)


def test_auto_anchors_find_distant_corners(plan):
    shifted = _transform_map(plan, similarity_matrix(1.0, 0.0, 3.0, -2.0), (H, W))
    found = auto_anchors(shifted, plan, np.array([[1.0, 0, -3], [0, 1, 2], [0, 0, 1]]))
    assert isinstance(found, Anchors)
    np.testing.assert_allclose(found.target - found.source, [[-3, 2], [-3, 2]], atol=1.01)
    assert np.hypot(*(found.source[0] - found.source[1])) > 100


# ----------------------------------------------------------------------- nonrigid
def test_coherent_motion_is_a_gaussian_neighbourhood_average():
    rng = np.random.default_rng(0)
    pts = rng.uniform(0, 200, (400, 2))
    motion = rng.normal(size=(400, 2))
    w = rng.uniform(0.2, 1.0, 400)
    sigma = 30.0
    d2 = ((pts[:, None] - pts[None]) ** 2).sum(-1)
    g = np.exp(-d2 / (2 * sigma**2)) * w[None]
    exact = (g @ motion) / g.sum(1, keepdims=True)  # the O(N^2) definition
    fast = coherent_motion(pts, motion, w, sigma)
    assert np.abs(fast - exact).max() < 0.1 * np.abs(exact).max()


def test_piecewise_affine_warp_by_triangle_rasterisation():
    src = np.array([[0.0, 0], [100, 0], [0, 100], [100, 100], [50, 50]])
    pw = PiecewiseAffine(src, src + [[0, 0], [0, 0], [0, 0], [0, 0], [10, 0]])
    np.testing.assert_allclose(
        pw.forward(np.array([[50.0, 50.0], [150.0, 5.0]])), [[60, 50], [150, 5]]
    )
    img = np.full((101, 101), FREE, np.uint8)
    img[:, 50] = OCCUPIED
    out = warp_image(img, np.eye(3), img.shape, pw)
    assert out[50, 60] == OCCUPIED and out[50, 50] == FREE  # the middle moved 10 px right
    assert out[2, 50] == OCCUPIED  # the hull's edge did not move


def test_nonrigid_recovers_known_smooth_deformation(plan):
    field = gaussian_field(plan.shape, (0.6 * W, 0.6 * H), (6.0, -4.0), 45.0)
    slam, u = deform(plan, field)
    reg = register(OccupancyMap(slam, 0.05), OccupancyMap(plan, 0.05))
    r = np.floor(reg.X[:, 1]).astype(int)
    c = np.floor(reg.X[:, 0]).astype(int)
    truth = reg.X - u[r, c]  # where each SLAM wall point belongs on the plan
    moved = np.hypot(*u[r, c].T) > 3.0
    n = reg.normals[moved]
    err_affine = np.abs(((reg.X_affine[moved] - truth[moved]) * n).sum(1))
    err_opt = np.abs(((reg.X_optimised[moved] - truth[moved]) * n).sum(1))
    assert np.median(err_affine) > 2.0  # the affine alignment cannot follow the bend
    assert np.median(err_opt) < 1.0  # the wall-normal error is recovered
    sim, nonrigid = reg.map_points(reg.X[moved])
    assert np.median(np.hypot(*(nonrigid - truth[moved]).T)) < np.median(
        np.hypot(*(sim - truth[moved]).T)
    )


def test_maximise_fitness_polishes_a_nearly_right_similarity(plan):
    from map2map.evaluate.features import occupied_points

    pts = occupied_points(plan)
    Mf = fitness_map(plan == OCCUPIED, 4.0)
    T0 = similarity_matrix(1.02, math.radians(1.0), -2.0, 1.5)  # the truth is identity
    T = maximise_fitness(pts, Mf, T0)
    assert fitness(Mf, apply(T, pts)) > fitness(Mf, apply(T0, pts))
    assert np.abs(apply(T, pts) - pts).max() < 0.5 < np.abs(apply(T0, pts) - pts).max()


def test_maximise_fitness_rigid_holds_the_scale(plan):
    from map2map.evaluate.features import occupied_points

    pts = occupied_points(plan)
    Mf = fitness_map(plan == OCCUPIED, 4.0)
    T0 = similarity_matrix(1.02, math.radians(1.0), -2.0, 1.5)
    T = maximise_fitness(pts, Mf, T0, rigid=True)
    assert decompose_similarity(T)[0] == pytest.approx(1.02, abs=1e-12)
    assert fitness(Mf, apply(T, pts)) > fitness(Mf, apply(T0, pts))
    # the free similarity gets nearer the truth (identity), the rigid one cannot take
    # the 2 % of scale off
    Ts = maximise_fitness(pts, Mf, T0)
    assert fitness(Mf, apply(Ts, pts)) > fitness(Mf, apply(T, pts))


def test_a_fallback_against_a_line_drawn_plan_is_polished_like_a_passed_match():
    """No hypothesis passes (``min_score`` out of reach): the similarity is the rigid
    fallback polished on eq. 8 at ``direct_sigma`` with the scale held, as a passed
    similarity is against a line-drawn plan (Halmstad HIH_03 auto-corrected: keypoints
    8.2 -> 5.3 px, floor 4.4); the rigid variant, which carries the metric, is not."""
    from map2map.evaluate.features import occupied_points
    from map2map.evaluate.fitness import distance_map

    lines = draw_walls((H, W), office_walls(W, H, thickness=1))
    rng = np.random.default_rng(3)
    src = warp_image(draw_walls((H, W), office_walls(W, H, thickness=5)),
                     similarity_matrix(1.0, math.radians(0.5), 1.0, -1.5), (H, W))
    src[(src == OCCUPIED) & (rng.random(src.shape) < 0.3)] = FREE
    al = align_maps(src, lines, params=AlignParams(min_score=2.0))
    assert any("no alignment hypothesis passed" in w for w in al.warnings)
    assert decompose_similarity(al.similarity)[0] == pytest.approx(1.0, abs=1e-9)
    assert np.abs(al.similarity - al.rigid).max() > 1e-3
    # no less fit than the rigid in the polish's terms (the winning direction; the
    # polish scores a subsample bilinearly, hence the tolerance)
    a, b, S, R = src, lines, al.similarity, al.rigid
    if al.hypotheses["direction"] == "target->source":
        a, b, S, R = lines, src, np.linalg.inv(S), np.linalg.inv(R)
    pts = occupied_points(a)
    Mf = np.exp(-distance_map(b == OCCUPIED) ** 2 / (2 * 4.0**2)).astype(np.float32)
    assert fitness(Mf, apply(S, pts)) >= fitness(Mf, apply(R, pts)) - 1e-3
    off = align_maps(src, lines, params=AlignParams(min_score=2.0, direct_sigma=None))
    np.testing.assert_allclose(off.similarity, off.rigid)  # no polish: the fallback as it was
    np.testing.assert_allclose(off.rigid, al.rigid)


# ------------------------------------------------------------------- Algorithm 1
def test_error_is_measured_across_the_plan_wall_not_along_a_tilted_normal():
    plan = np.full((60, 60), FREE, np.uint8)
    plan[:, 20] = OCCUPIED
    fields = SideFields.from_map(plan, 0.0)
    # a wall built 6 px right of the plan's and bent by drift: its normal is 12 deg off
    a = np.radians(12.0)
    n = np.array([[-np.cos(a), np.sin(a)]] * 2)
    X_rigid = np.array([[26.5, 20.5], [26.5, 40.5]])
    X_opt = X_rigid + 6.0 / np.cos(a) * n  # the optimisation moved it onto the plan wall
    err = local_errors(X_rigid, X_opt, fields, n)
    np.testing.assert_allclose(err.distances, 6.0)  # not 6 cos(12 deg) = 5.87


def test_a_pixel_step_of_a_wall_is_matched_to_its_own_wall():
    plan = np.full((80, 60), FREE, np.uint8)
    plan[:, 20:24] = OCCUPIED  # a 4 px wall...
    plan[5:9, :] = OCCUPIED  # ...and a wall far above whose top faces up
    fields = SideFields.from_map(plan, 0.0)
    # a map's wall shifted by one pixel has a short face pointing up at the step
    n = np.array([[0.28, -0.96]])
    X = np.array([[23.5, 50.5]])
    err = local_errors(X, X, fields, n)
    assert not err.corner[0]
    assert err.distances[0] < 1.0  # not the 42 px to the far wall's top face


def test_true_error_is_the_wall_face_displacement_not_the_copied_cell():
    plan = np.full((40, 60), FREE, np.uint8)
    plan[:, 20:24] = OCCUPIED
    # the wall's right face moves 2 px left, its left face stays: the wall is thinned
    xx = np.arange(60) + 0.5
    ux = np.broadcast_to(-np.clip((xx - 20) * 0.5, 0, 3.0), (40, 60))
    field = np.stack([ux, np.zeros_like(ux)], -1)
    slam, u = deform(plan, field)
    right = np.flatnonzero(slam[20] == OCCUPIED).max()  # the deformed wall's right face cell
    X = np.array([[right + 0.5, 20.5]])
    n = np.array([[1.0, 0.0]])
    drawn = true_errors(X, n, np.eye(3), plan, u)
    assert drawn[0] == pytest.approx(right + 1 - 24)  # the face as drawn, from the plan's
    # the cell it was copied from lies inside the plan wall: not the face's move
    assert u[20, right, 0] != pytest.approx(drawn[0])
    assert true_errors(X, n, np.eye(3), plan, u, field)[0] == pytest.approx(-2.0, abs=0.01)


def test_junction_points_are_left_out_of_the_statistics():
    plan = np.full((60, 60), FREE, np.uint8)
    plan[:, 20] = OCCUPIED
    fields = SideFields.from_map(plan, 0.0)
    X_rigid = np.array([[25.5, 10.5], [25.5, 25.5], [25.5, 40.5], [25.5, 55.5]])
    X_opt = X_rigid - [4.0, 0.0]  # the wall was built 4 px off
    # on axis, a slightly tilted wall, a ragged wall (24 deg), a diagonal normal
    ang = np.radians([0.0, 10.0, 24.0, 40.0])
    normals = np.column_stack([-np.cos(ang), np.sin(ang)])
    err = local_errors(X_rigid, X_opt, fields, normals)
    assert err.corner.tolist() == [False, False, False, True]
    summ = err.summary(0.05)
    assert summ["points"] == 3 and summ["corner_points_excluded"] == 1
    # the ragged point measures its 5 px across the wall, like the others
    np.testing.assert_allclose(err.distances[:3], 5.0, atol=0.05)
    assert summ["max_px"] == pytest.approx(err.distances[:3].max())


def _true_error(ev, plan, u, field=None):
    """True local error of the chosen chain's points: across the plan's wall, from the
    rigidly aligned wall face to the plan face it was made from."""
    reg = ev.registration
    t = true_errors(reg.X, reg.normals, reg.alignment.rigid, plan, u, field)
    return np.abs(t)[ev.errors[ev.chosen].valid]


@pytest.mark.parametrize(
    "corridor, partition",
    # (0, 4): junction points with tilted normals once set the max to +12%
    [((-6.0, 0.0), (7.0, -5.0)), ((0.0, 4.0), (0.0, 0.0))],
)
def test_metric_within_5_percent_on_walls_moved_by_known_amounts(plan, corridor, partition):
    walls = office_walls(W, H, thickness=4)
    built_walls = office_walls(
        W, H, thickness=4, corridor_shift=corridor, partition_shift=partition
    )
    built = draw_walls((H, W), built_walls)
    u = wall_displacement((H, W), walls, built_walls)
    ev = evaluate_maps(OccupancyMap(built, 0.05), OccupancyMap(plan, 0.05), resolution=0.05)
    assert ev.chosen == "rigid"
    true = _true_error(ev, plan, u)
    rep = ev.report["errors"]["rigid"]
    assert rep["mean_px"] == pytest.approx(true.mean(), rel=0.05)
    assert rep["max_px"] == pytest.approx(true.max(), rel=0.05)
    assert rep["mean_m"] == pytest.approx(true.mean() * 0.05, rel=0.05)
    assert ev.report["iou"]["rigid"]["free"] > 0.9


@pytest.mark.parametrize(
    "centre, amplitude, sigma",
    # a bent wing; a bend at the outer wall (corner points once set the max to +7%)
    [((0.8, 0.8), (0.0, 8.0), 60.0), ((0.95, 0.5), (8.0, 0.0), 70.0)],
)
def test_metric_within_5_percent_on_smooth_field(plan, centre, amplitude, sigma):
    field = gaussian_field(plan.shape, (centre[0] * W, centre[1] * H), amplitude, sigma)
    slam, u = deform(plan, field)
    ev = evaluate_maps(OccupancyMap(slam, 0.05), OccupancyMap(plan, 0.05), resolution=0.05)
    true = _true_error(ev, plan, u)
    rep = ev.report["errors"][ev.chosen]
    assert rep["mean_px"] == pytest.approx(true.mean(), rel=0.05)
    assert rep["max_px"] == pytest.approx(true.max(), rel=0.05)


def test_metric_within_5_percent_on_a_parametric_model_field(plan):
    import cv2

    from map2map.parametric import deform as parametric_deform
    from map2map.parametric import make_trajectory
    from map2map.parametric.params import ParametricParams

    pm = OccupancyMap(plan, 0.05)
    rng = np.random.default_rng(2)
    traj, _ = make_trajectory(pm, ParametricParams(), rng, tour=5)
    res = parametric_deform(pm, traj, params=ParametricParams(), rng=rng)
    # smoothed, the model's field moves each wall with the space around it; this one
    # jogs a partition by a pixel part-way along, and the jog's short face, matched to
    # a far wall facing the same way, once set the max to 49 px
    field = np.stack([cv2.GaussianBlur(a, (0, 0), 5.0) for a in (res.field.dx, res.field.dy)], -1)
    slam, u = deform(plan, field)
    ev = evaluate_maps(OccupancyMap(slam, 0.05), OccupancyMap(plan, 0.05), resolution=0.05)
    true = _true_error(ev, plan, u)
    rep = ev.report["errors"][ev.chosen]
    assert rep["mean_px"] == pytest.approx(true.mean(), rel=0.05)
    assert rep["max_px"] == pytest.approx(true.max(), rel=0.05)


def test_chain_rule_scale_or_shear_means_nonrigid():
    sim = similarity_matrix(1.0, 0.3, 5, 5)
    assert choose_chain(sim, sim)[0] == "rigid"
    assert choose_chain(similarity_matrix(1.1, 0.3, 5, 5), sim)[0] == "nonrigid"
    sheared = sim.copy()
    sheared[0, 1] += 0.1
    assert choose_chain(sim, sheared)[0] == "nonrigid"


# --------------------------------------------------------------------------- ICP
def test_vanilla_icp_small_offset_converges_large_offset_fails(plan):
    pts, _ = edge_points(plan)
    c, s = math.cos(0.02), math.sin(0.02)
    R = np.array([[c, -s], [s, c]])
    src = (pts - 150) @ R.T + 150 + [2.0, -1.5]
    assert icp(src, pts).mean_distance < 0.2
    far = (pts - 150) @ np.array([[0.0, -1], [1, 0]]).T + 150  # rotated 90 degrees
    assert icp(far, pts).mean_distance > 2.0  # the paper's point: ICP needs a good start


# --------------------------------------------------------------------------- CLI
def _save(path, data, resolution=0.05):
    from map2map.maps.formats import save_map

    save_map(OccupancyMap(data, resolution), path)
    return str(path)


def test_cli_align_and_evaluate_outputs(plan, tmp_path, capsys):
    slam = draw_walls((H, W), office_walls(W, H, thickness=4, partition_shift=(5.0, 0.0)))
    src = _save(tmp_path / "slam.png", np.ascontiguousarray(np.rot90(slam)))
    tgt = _save(tmp_path / "plan.png", plan)
    pts = tmp_path / "pts.csv"
    pts.write_text("x,y\n20.5,30.5\n100.5,200.5\n")
    out = tmp_path / "al"
    assert main(["align", src, tgt, "--out", str(out), "--points", str(pts)]) == 0
    doc = json.loads((out / "alignment.json").read_text())
    for k in ("similarity", "affine", "rigid"):
        assert np.array(doc[k]).shape == (3, 3)
    assert 0.45 < doc["p_correct"] <= 1.0  # a clean, right alignment: not doubtful
    T = np.array(doc["similarity"])  # np.rot90: source (x, y) = plan (y, W - x)
    np.testing.assert_allclose(apply(T, [[30.5, W - 20.5]]), [[20.5, 30.5]], atol=1.5)
    rows = list(csv.DictReader((out / "points_aligned.csv").open()))
    assert list(rows[0]) == ["x_similarity", "y_similarity", "x_nonrigid", "y_nonrigid"]
    assert len(rows) == 2
    assert (out / "overlay.png").stat().st_size > 0

    ev_out = tmp_path / "ev"
    assert main(["evaluate", src, tgt, "--out", str(ev_out)]) == 0
    rep = json.loads((ev_out / "report.json").read_text())
    assert rep["chosen_chain"] == "rigid"
    assert rep["p_correct"] == rep["alignment"]["p_correct"] == pytest.approx(doc["p_correct"])
    assert rep["chosen_errors"]["max_m"] == pytest.approx(0.25, rel=0.1)
    assert {"rigid", "nonrigid"} <= set(rep["errors"]) and "from_identity" in rep["icp"]
    assert (ev_out / "overlay.png").exists() and (ev_out / "error_map.png").exists()

    pairs = tmp_path / "pairs.csv"
    pairs.write_text("slam,plan\nslam.png,plan.png\nplan.png,plan.png\n")
    assert main(["evaluate", "--pairs", str(pairs), "--out", str(tmp_path / "b"), "--quiet"]) == 0
    table = list(csv.DictReader((tmp_path / "b" / "pairs.csv").open()))
    assert len(table) == 2 and float(table[1]["max_px"]) < 1.0
    assert float(table[1]["p_correct"]) > 0.9  # the plan on itself
    assert (tmp_path / "b" / "errors_boxplot.png").exists()
    capsys.readouterr()


def _bad(args, capsys, out, expect):
    assert main(args) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and err[0].startswith("map2map: error:") and expect in err[0], err
    assert not out.exists()


def test_cli_bad_inputs(plan, tmp_path, capsys):
    tgt = _save(tmp_path / "plan.png", plan)
    out = tmp_path / "out"
    empty = _save(tmp_path / "empty.png", np.full((H, W), FREE, np.uint8))
    _bad(["evaluate", empty, tgt, "--out", str(out)], capsys, out, "no occupied pixels")
    tiny = np.full((H, W), UNKNOWN, np.uint8)
    tiny[10:18, 10:18] = OCCUPIED
    tiny_p = _save(tmp_path / "tiny.png", tiny)
    _bad(["align", tiny_p, tgt, "--out", str(out)], capsys, out, "too small to decompose")
    cases = {
        "x,y\n1,2\n": "header",
        "x_source,y_source,x_target,y_target\n1,2,3\n": "expected 4 values",
        "x_source,y_source,x_target,y_target\n1,2,3,4\n": "at least two anchor pairs",
        "x_source,y_source,x_target,y_target\n1,2,3,x\n5,6,7,8\n": "must be numbers",
        "x_source,y_source,x_target,y_target\n10,10,10,10\n9999,10,50,50\n": "outside",
        "x_source,y_source,x_target,y_target\n10,10,10,10\n10,10,50,50\n": "identical",
    }
    for text, expect in cases.items():
        a = tmp_path / "anchors.csv"
        a.write_text(text)
        _bad(["evaluate", tgt, tgt, "--out", str(out), "--anchors", str(a)], capsys, out, expect)
    no_res = tmp_path / "nores.png"
    cv2.imwrite(str(no_res), plan)  # a plain picture: no resolution stored
    _bad(["evaluate", str(no_res), str(no_res), "--out", str(out), "--units", "m"], capsys,
         out, "--resolution")
    _bad(["evaluate", str(no_res), str(no_res), "--out", str(out), "--report", "r.html"],
         capsys, out, "--resolution")
    pts = tmp_path / "pts.csv"
    pts.write_text("x,y\n1,oops\n")
    _bad(["align", tgt, tgt, "--out", str(out), "--points", str(pts)], capsys, out, "line 2")


def test_cli_anchors_are_used(plan, tmp_path, capsys):
    tgt = _save(tmp_path / "plan.png", plan)
    a = tmp_path / "anchors.csv"
    a.write_text(
        "x_source,y_source,x_target,y_target\n20.5,20.5,20.5,20.5\n300.5,220.5,300.5,220.5\n"
    )
    out = tmp_path / "al"
    assert main(["align", tgt, tgt, "--out", str(out), "--anchors", str(a)]) == 0
    doc = json.loads((out / "alignment.json").read_text())
    assert doc["anchored"] == "manual"
    np.testing.assert_allclose(doc["rigid"], np.eye(3), atol=1e-3)
    capsys.readouterr()


# ----------------------------------------------------------------------- Halmstad
def test_halmstad_pair_within_floor(shared_data):
    from map2map.maps.halmstad import keypoint_residuals, load_halmstad

    root = shared_data / "halmstad"
    src, tgt = load_halmstad(root, "E5_05"), load_halmstad(root, "E5_layout")
    reg = register(src, tgt)
    floor, sim, nonrigid = keypoint_residuals(root, "E5_05", "E5_layout", src, tgt, reg.map_points)
    assert sim <= 1.5 * floor
    assert nonrigid <= 1.5 * floor


def test_demo_stage_evaluates_a_known_bend(tmp_path, capsys):
    from map2map.demo import STAGES, DemoContext, stage_evaluate

    assert STAGES[-1][1] is stage_evaluate
    ctx = DemoContext(out=tmp_path, seed=0)
    ctx.plan = OccupancyMap(draw_walls((H, W), office_walls(W, H, thickness=4)), 0.05)
    stage_evaluate(ctx)
    line = capsys.readouterr().out
    assert "true: mean" in line
    names = {p.name for _, p in ctx.written}
    reports = {"inspection.html", "inspection.md", "inspection.csv"}
    assert {"report.json", "overlay.png", "error_map.png", "points.csv"} | reports <= names
    figures = {p for _, p in ctx.written if p.parent.name == "inspection_files"}
    assert names == {"report.json", "overlay.png", "error_map.png", "points.csv"} | reports | {
        p.name for p in figures
    } and len(figures) >= 3  # the inspection report's own figures, written beside it
    assert re.search(r"inspect known_bend: plan walls \d+ pass, \d+ uncertain, \d+ fail", line)
    e = ctx.evaluation["known_bend"]
    assert 0.0 < e["mean_m"] < e["max_m"]


def test_one_rule_for_a_picture_without_a_resolution(plan, tmp_path, capsys):
    """A picture with no stored resolution is read at 0.05 m/px and has no metric scale:
    evaluate reports pixels with a note (metres only with --resolution), no scale bar."""
    import json

    no_res = tmp_path / "nores.png"
    cv2.imwrite(str(no_res), plan)
    out = tmp_path / "ev"
    assert main(["evaluate", str(no_res), str(no_res), "--out", str(out), "--quiet"]) == 0
    got = capsys.readouterr()
    assert "errors in pixels: the plan has no metric scale" in got.out + got.err
    assert "--resolution" in got.out + got.err                     # the way to metres
    report = json.loads((out / "report.json").read_text())
    assert report["errors"][report["chosen_chain"]]["mean_m"] is None
    assert main(["evaluate", str(no_res), str(no_res), "--out", str(tmp_path / "ev_m"),
                 "--resolution", "0.05", "--quiet"]) == 0
    metric = json.loads((tmp_path / "ev_m" / "report.json").read_text())
    assert metric["errors"][metric["chosen_chain"]]["mean_m"] is not None
    assert "errors in pixels" not in "".join(metric.get("notes", []))
