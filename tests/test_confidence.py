"""Warnings are earned: a good alignment of a cluttered map does not warn, a bad one does.

The "doubtful alignment" warning of :mod:`map2map.evaluate.confidence` rests on
``p_correct``, fitted on the synthetic sweep and the Halmstad pairs
(``map2map.experiments.alignment_confidence``); these tests pin both sides. It replaced
the ambiguity, poor-fit and free-space warnings: the tests that expected those now
expect a doubtful alignment naming the same cause.
"""

from __future__ import annotations

import cv2
import numpy as np
import pytest

from map2map.core.grid import UNKNOWN, OccupancyMap
from map2map.evaluate.align import AlignParams, align_maps
from map2map.evaluate.confidence import (
    alignment_notes,
    alignment_warnings,
    evaluation_notes,
    evaluation_warnings,
    p_correct,
)
from map2map.evaluate.pipeline import evaluate_maps
from map2map.maps.irregular import irregular_plan
from map2map.maps.synthetic import cluttered, draw_walls, office_walls

# figures measured on Halmstad pairs (map2map.experiments.alignment_confidence, 2026-11-27)
HIH_03_GOOD = {"fitness": 0.368, "fitness_source_to_target": 0.176,
               "fitness_target_to_source": 0.368, "free_agreement": 0.973,
               "runner_up_ratio": 0.533, "runner_up_rotation_deg": 89.8, "runner_up_scale": 0.646,
               "agreement_sigma_px": 6.4, "scale": 1.156, "metric_scale": None}  # fmt: skip
E5_01_GOOD = {"fitness": 0.41, "fitness_source_to_target": 0.41,
              "fitness_target_to_source": 0.257, "free_agreement": 0.962,
              "runner_up_ratio": 0.884, "runner_up_rotation_deg": -3.1, "runner_up_scale": 0.596,
              "scale": 0.83, "metric_scale": None}  # fmt: skip
E5_01_ON_HIH = {"fitness": 0.047, "fitness_source_to_target": 0.0,
                "fitness_target_to_source": 0.047, "free_agreement": 0.50,
                "runner_up_ratio": 0.961, "scale": 1.3, "metric_scale": None}  # fmt: skip
HIH_01_ON_E5 = {"fitness": 0.209, "fitness_source_to_target": 0.209,
                "fitness_target_to_source": 0.036, "free_agreement": 0.946,
                "runner_up_ratio": 0.899, "runner_up_rotation_deg": 0.3, "runner_up_scale": 1.375,
                "scale": 0.539, "metric_scale": None}  # fmt: skip


@pytest.fixture(scope="module")
def office():
    return draw_walls((240, 300), office_walls(300, 240))


def test_p_correct_on_measured_halmstad_figures():
    # a good real pair: walls differ (fitness 0.37), rooms agree: a note, no warning
    assert p_correct(HIH_03_GOOD) > 0.8
    assert alignment_warnings(HIH_03_GOOD) == []
    (note,) = alignment_notes(HIH_03_GOOD)
    assert "37% of the walls" in note and "97% of the free space" in note
    # sensor maps against the other building's layout: doubtful, every cause named
    for q in (E5_01_ON_HIH, HIH_01_ON_E5):
        assert p_correct(q) < 0.2
        (w,) = alignment_warnings(q)
        assert w.startswith("doubtful alignment: probability of being right")
        assert "as well in the search" in w and "of the walls of one map" in w
        assert "of the free space lands on walls" in w
    assert "50% of the free space" in alignment_warnings(E5_01_ON_HIH)[0]
    # a clean synthetic fit is sure, a coin flip between two placements is not
    clean = {"fitness": 0.99, "free_agreement": 1.0, "runner_up_ratio": 0.4}
    assert p_correct(clean) > 0.95 and alignment_warnings(clean) == []
    (w,) = alignment_warnings({**clean, "runner_up_ratio": 0.9})
    assert w.startswith("doubtful alignment: two placements fit (almost) equally well")
    assert "fits 90% as well" in w and p_correct({**clean, "runner_up_ratio": 0.9}) > 0.45
    # a p_correct already in q is the one used
    assert alignment_warnings({**clean, "p_correct": 0.2})[0].startswith("doubtful")


def test_an_ambiguity_at_another_scale_asks_for_the_resolutions():
    # E5_01: the runner-up lies at 0.6 x the scale and fits 88% as well: doubtful (it is
    # right, one of the 3 of 35 right Halmstad pairs warned)
    (w,) = alignment_warnings(E5_01_GOOD)
    assert w.startswith("doubtful alignment") and "--source-resolution" in w
    assert "fits 88% as well" in w
    # known scale, or a runner-up at the same scale (a building turned 180 deg): no hint
    assert "--source-resolution" not in alignment_warnings({**E5_01_GOOD, "metric_scale": 0.83})[0]
    q180 = {**E5_01_GOOD, "runner_up_rotation_deg": 180.0, "runner_up_scale": 1.0}
    assert "--source-resolution" not in alignment_warnings(q180)[0]


def test_unmatched_walls_are_a_note_until_the_maps_share_none():
    # good Halmstad pairs: 41-83% unmatched; wrong maps up to 97%
    assert evaluation_warnings(0.93, 0.75) == []
    assert "describe 25%" in evaluation_notes(0.75)[0]
    assert evaluation_notes(0.3) == [] and evaluation_notes(0.97) == []
    (w,) = evaluation_warnings(0.93, 0.97)
    assert "share almost no walls" in w and "only 3%" in w
    assert evaluation_warnings(0.3, 0.2)[0].startswith("aligned maps disagree")


def test_a_good_alignment_of_a_cluttered_map_does_not_warn(office):
    ev = evaluate_maps(OccupancyMap(cluttered(office), 0.05), OccupancyMap(office, 0.05),
                       resolution=0.05)  # fmt: skip
    T = ev.registration.alignment.similarity
    assert np.allclose(T[:2, :2], np.eye(2), atol=0.01) and np.abs(T[:2, 2]).max() < 1.0
    assert ev.report["warnings"] == []
    assert ev.report["chosen_errors"]["unmatched_share"] > 0.3  # the clutter is there


def test_an_unrelated_map_warns(office):
    res = align_maps(irregular_plan(1), office)
    assert res.p_correct < 0.45
    assert any(w.startswith("doubtful alignment") for w in res.warnings)
    res = align_maps(irregular_plan(2), office)
    (w,) = [w for w in res.warnings if w.startswith("doubtful alignment")]
    assert "of the free space lands on walls" in w


def test_a_wrong_scale_warns(office):
    from test_trust import transformed_copy

    # the resolutions claim the same scale; the map is at 0.75
    small = transformed_copy(office, 0.75, 0.0)
    res = align_maps(small, office, params=AlignParams(metric_scale=1.0))
    assert any("scale" in w and "resolution" in w for w in res.warnings)
    # forced to the claimed scale, the placement is wrong (rotated 90 deg): it must say so
    small = cv2.resize(office, None, fx=0.75, fy=0.75, interpolation=cv2.INTER_NEAREST)
    res = align_maps(small, office, params=AlignParams(metric_scale=1.0))
    assert any(w.startswith("doubtful alignment") for w in res.warnings)


def test_a_tiny_overlap_warns(office):
    part = np.full_like(office, UNKNOWN)
    part[:, :45] = office[:, :45]  # 15% of a floor of repeated offices
    res = align_maps(part, office)
    # a placement one office over fits 89% as well (>= ambiguity 0.85): doubtful
    (w,) = [w for w in res.warnings if w.startswith("doubtful alignment")]
    assert "cannot tell which is right" in w


def test_halmstad_good_pair_has_notes_not_warnings_and_a_wrong_map_warns(shared_data):
    from map2map.maps.halmstad import keypoint_residuals, load_halmstad

    root = shared_data / "halmstad"
    src, tgt = load_halmstad(root, "HIH_03"), load_halmstad(root, "HIH_layout")
    ev = evaluate_maps(src, tgt, names=("HIH_03", "HIH_layout"))
    floor, sim, _ = keypoint_residuals(root, "HIH_03", "HIH_layout", src, tgt,
                                       ev.registration.map_points)  # fmt: skip
    assert sim <= 1.5 * floor  # at the floor (4.9 vs 4.4 px when measured)
    assert ev.report["warnings"] == [] and ev.report["p_correct"] > 0.8
    assert ev.report["alignment"]["p_correct"] == ev.report["p_correct"]
    assert any(n.startswith("the maps differ") for n in ev.report["notes"])
    wrong = evaluate_maps(load_halmstad(root, "HIH_03"), load_halmstad(root, "E5_layout"))
    assert wrong.report["p_correct"] < 0.45
    assert any(w.startswith("doubtful alignment") for w in wrong.report["warnings"])


def test_halmstad_ambiguity_goes_once_the_scale_is_known(shared_data):
    from map2map.maps.halmstad import load_halmstad

    root = shared_data / "halmstad"
    src, tgt = load_halmstad(root, "E5_04").data, load_halmstad(root, "E5_layout").data
    res = align_maps(src, tgt)
    assert any("--source-resolution" in w for w in res.warnings)  # runner-up at 0.61 x
    # the E5 sensor maps are at 0.83 x the layout's scale: told so, no doubt is left
    assert align_maps(src, tgt, params=AlignParams(metric_scale=0.83)).warnings == []


def test_notes_are_printed_and_never_make_strict_fail(capsys):
    from map2map.cli.align import report_warnings

    assert report_warnings([], True, ["the maps differ: 41% ..."]) == 0
    assert "map2map: note: the maps differ" in capsys.readouterr().err
    assert report_warnings(["doubtful alignment: ..."], True, ["x"]) == 3


def test_the_inspection_report_shows_notes_apart_from_the_warnings():
    from test_inspection import _maps

    from map2map.reports.inspection import inspection_report

    slam, plan = _maps()
    ev = evaluate_maps(slam, plan, resolution=0.05)
    assert ev.report["warnings"] == [] and ev.report["notes"] == []
    ev.report["notes"] = evaluation_notes(0.75)
    r = inspection_report(ev, plan)
    assert r.warnings == []  # a fact, not a doubt: no "alignment is doubtful" box
    md, _ = r.to_markdown()
    assert "Note: the wall error figures describe 25%" in md
