"""Issue 11, items 1-2: alignment never silently wrong; the statistics describe walls."""

from __future__ import annotations

import json
import math

import cv2
import numpy as np
import pytest

from map2map.cli.main import main
from map2map.core.geometry import decompose_similarity, similarity_matrix
from map2map.core.grid import FREE, OCCUPIED, UNKNOWN, OccupancyMap
from map2map.evaluate.align import AlignParams, align_maps
from map2map.evaluate.metric import local_errors, summary_lines
from map2map.evaluate.nonrigid import SideFields
from map2map.evaluate.pipeline import evaluate_maps
from map2map.maps.irregular import irregular_plan
from map2map.maps.synthetic import draw_walls, office_walls


def transformed_copy(data: np.ndarray, scale: float, angle_deg: float) -> np.ndarray:
    """The map rotated and scaled onto a canvas that holds it (walls resampled unbroken)."""
    h, w = data.shape
    T = similarity_matrix(scale, math.radians(angle_deg), 0.0, 0.0)
    q = np.array([[0, 0], [w, 0], [0, h], [w, h]], float) @ T[:2, :2].T
    lo, hi = q.min(0) - 8, q.max(0) + 8
    T[:2, 2] = -lo
    C = np.array([[1, 0, 0.5], [0, 1, 0.5], [0, 0, 1.0]])
    M = (np.linalg.inv(C) @ T @ C)[:2]
    size = tuple(int(math.ceil(v)) for v in hi - lo)
    occ = cv2.warpAffine((data == OCCUPIED).astype(np.float32), M, size, flags=cv2.INTER_LINEAR)
    free = cv2.warpAffine((data == FREE).astype(np.float32), M, size, flags=cv2.INTER_LINEAR)
    out = np.full(occ.shape, UNKNOWN, np.uint8)
    out[free >= 0.5] = FREE
    out[occ >= 0.4] = OCCUPIED
    return out


# ------------------------------------------------------------------ item 1: alignment
def test_solid_block_plan_recovers_its_similarity_without_a_scale_prior():
    # HouseExpo-style: everything outside the rooms is solid occupied. Scoring occupied
    # cells let the copy's blocks lie on the plan's at scale 1.47x the truth, rotated
    # 180 deg, with no warning; wall surfaces and free-on-free scoring recover it.
    plan = irregular_plan(0)
    copy = transformed_copy(plan, 1.3, 23.0)
    res = align_maps(copy, plan, params=AlignParams(auto_anchor=False))
    s, a, _, _ = decompose_similarity(res.similarity)
    assert s * 1.3 == pytest.approx(1.0, abs=0.03)
    assert math.degrees(a) == pytest.approx(-23.0, abs=1.5)
    assert res.warnings == []
    q = res.hypotheses["quality"]
    assert q["fitness"] > 0.9 and q["runner_up_ratio"] < 0.8


def test_a_symmetric_plan_is_flagged_ambiguous():
    plan = np.full((120, 160), UNKNOWN, np.uint8)
    plan[10:110, 10:150] = OCCUPIED
    plan[16:104, 16:144] = FREE  # one rectangular room: 180 deg looks the same
    copy = transformed_copy(plan, 1.0, 37.0)
    res = align_maps(copy, plan, params=AlignParams(auto_anchor=False, metric_scale=1.0))
    # a coin flip between two placements: doubtful (was "ambiguous alignment")
    assert any(w.startswith("doubtful alignment") and "cannot tell which is right" in w
               for w in res.warnings)  # fmt: skip


def test_two_different_plans_carry_a_warning():
    res = align_maps(irregular_plan(0), irregular_plan(1), params=AlignParams(auto_anchor=False))
    assert res.warnings


def test_a_wrong_resolution_is_reported_as_a_scale_mismatch():
    plan = irregular_plan(2)
    copy = transformed_copy(plan, 1.3, -37.0)
    # the resolutions claim the copy is at scale 1.0, it is at 1.3
    res = align_maps(copy, plan, params=AlignParams(auto_anchor=False, metric_scale=1.0))
    assert any("scale" in w and "resolution" in w for w in res.warnings)
    # told the right metric scale, the alignment is exact and says nothing
    good = align_maps(copy, plan, params=AlignParams(auto_anchor=False, metric_scale=1 / 1.3))
    assert good.warnings == []
    assert decompose_similarity(good.similarity)[0] * 1.3 == pytest.approx(1.0, abs=0.01)


def test_cli_resolution_per_input_and_strict(tmp_path, capsys):
    plan = irregular_plan(3)
    copy = transformed_copy(plan, 1.3, 90.0)
    cv2.imwrite(str(tmp_path / "plan.png"), plan)
    cv2.imwrite(str(tmp_path / "copy.png"), copy)
    cv2.imwrite(str(tmp_path / "other.png"), irregular_plan(1))
    out = tmp_path / "al"
    args = ["align", str(tmp_path / "copy.png"), str(tmp_path / "plan.png"), "--out", str(out)]
    rc = main([*args, "--source-resolution", str(0.05 / 1.3), "--target-resolution", "0.05"])
    doc = json.loads((out / "alignment.json").read_text())
    assert rc == 0 and doc["warnings"] == []
    assert doc["scale"] * 1.3 == pytest.approx(1.0, abs=0.01)
    assert doc["hypotheses"]["scale_range"][0] > 0.65  # the prior narrowed the search
    # two different plans: a warning on stderr, exit 0; with --strict exit 3
    bad = [str(tmp_path / "other.png"), str(tmp_path / "plan.png"), "--resolution", "0.05"]
    capsys.readouterr()
    assert main(["evaluate", *bad, "--out", str(tmp_path / "ev")]) == 0
    assert "warning" in capsys.readouterr().err
    assert main(["evaluate", *bad, "--out", str(tmp_path / "ev2"), "--strict"]) == 3
    assert json.loads((tmp_path / "ev2" / "report.json").read_text())["warnings"]
    assert main([*args, "--source-resolution", "-1"]) == 2


# --------------------------------------------------------- item 2: wall statistics
def test_a_point_facing_away_from_the_wall_beside_it_matches_no_wall():
    plan = np.full((80, 80), FREE, np.uint8)
    plan[:, 30:33] = OCCUPIED  # a vertical wall
    plan[60:63, :] = OCCUPIED  # a horizontal wall whose top faces up, 27 px below
    fields = SideFields.from_map(plan, 0.0)
    # 3.6 px right of the vertical wall, but its normal faces up (a ragged SLAM wall)
    X = np.array([[36.6, 33.5], [32.5, 20.5]])
    n = np.array([[0.0, -1.0], [1.0, 0.0]])
    err = local_errors(X, X, fields, n, match_px=6.0)
    assert err.unmatched.tolist() == [True, False]
    s = err.summary(0.05)
    assert s["points"] == 1 and s["unmatched_points"] == 1
    assert s["max_px"] < 1.0 and s["max_all_px"] > 20  # the wrong wall stays out


W, H = 320, 240


def _with_clutter(data: np.ndarray, seed: int) -> np.ndarray:
    """Furniture-like blobs inside the rooms and stray points outside the building.

    The blobs stand more than ``match_px`` (0.3 m) off the walls: nearer, a cabinet's
    face is indistinguishable from the wall behind it built that much off.
    """
    rng = np.random.default_rng(seed)
    out = data.copy()
    free = np.argwhere(cv2.erode((data == FREE).astype(np.uint8), np.ones((41, 41))) > 0)
    for r, c in free[rng.choice(len(free), 6, replace=False)]:
        hw, hh = rng.integers(3, 7, 2)
        out[r - hh : r + hh, c - hw : c + hw] = OCCUPIED  # a table, a cabinet
    for _ in range(8):  # stray points outside the building (reflections, glass)
        r, c = rng.integers(1, 5), rng.integers(20, W - 20)  # >= 0.45 m outside
        out[r : r + 2, c : c + 2] = OCCUPIED
        out[r + 2 : r + 4, c : c + 2] = FREE
    return out


def test_clutter_does_not_move_the_wall_statistics():
    plan = draw_walls((H, W), office_walls(W, H, thickness=4))
    built = draw_walls((H, W), office_walls(W, H, thickness=4, partition_shift=(4.0, 0.0)))
    clean = evaluate_maps(OccupancyMap(built, 0.05), OccupancyMap(plan, 0.05), resolution=0.05)
    messy = evaluate_maps(
        OccupancyMap(_with_clutter(built, 0), 0.05), OccupancyMap(plan, 0.05), resolution=0.05
    )
    a, b = clean.report["chosen_errors"], messy.report["chosen_errors"]
    assert clean.chosen == messy.chosen == "rigid"
    assert b["mean_px"] == pytest.approx(a["mean_px"], rel=0.05, abs=0.05)
    assert b["max_px"] == pytest.approx(a["max_px"], rel=0.05)
    assert b["max_px"] == pytest.approx(4.0, abs=0.3)  # the partition built 20 cm off
    assert b["unmatched_points"] >= 6 * 8  # the blobs' and strays' points, counted
    assert b["max_all_px"] > 2 * b["max_px"]  # and in the all-points figures
    lines = summary_lines(messy.report)
    assert "unmatched points" in lines[2]


def test_summary_labels_every_number_with_its_unit():
    e = {
        "mean_px": 0.68, "max_px": 4.1, "p95_px": 2.0, "mean_m": 0.034, "max_m": 0.205,
        "p95_m": 0.1, "points": 900, "unmatched_points": 12, "unmatched_share": 0.013,
        "corner_points_excluded": 30, "points_all": 942, "mean_all_px": 1.0,
        "max_all_px": 50.19, "mean_all_m": 0.05, "max_all_m": 2.51,
    }  # fmt: skip
    rep = {"errors": {"rigid": e, "nonrigid": e}, "chosen_chain": "rigid", "chosen_reason": "x"}
    text = "\n".join(summary_lines(rep))
    assert "mean 0.68 px (0.034 m)" in text and "max 4.10 px (0.205 m)" in text
    assert "max 50.19 px (2.510 m)" in text  # the all-points max, labelled as such
    assert "= 0.034 m" not in text
