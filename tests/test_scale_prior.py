"""Issue #34 item 1: the placement that fits both ways, and given resolutions as a constraint.

A one-way fitness rewards laying the larger map, shrunk, inside the explored part of
the smaller one (Halmstad HIH_01 against its layout: scale 1.71 where the annotations
give 1.17); where the one-way scores cannot tell two placements apart the two-way score
decides. With both resolutions given the scale never leaves 10 % of theirs, even where
another scale fits far better (then a warning says so).
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from test_trust import transformed_copy

from map2map.core.geometry import apply, decompose_similarity, similarity_matrix
from map2map.core.grid import UNKNOWN
from map2map.evaluate import align as A
from map2map.evaluate.align import AlignParams, align_maps
from map2map.maps.irregular import irregular_plan
from map2map.maps.synthetic import draw_walls, office_walls


@pytest.fixture(scope="module")
def office() -> np.ndarray:
    return draw_walls((240, 300), office_walls(300, 240))


def _in_band(scale: float, metric: float, tol: float = 0.1) -> bool:
    return metric / (1 + tol) - 1e-9 <= scale <= metric * (1 + tol) + 1e-9


def test_keep_scale_brings_a_similarity_into_the_band():
    T = similarity_matrix(1.3, 0.2, 5.0, -3.0)
    pts = np.array([[10.0, 20.0], [40.0, 25.0], [30.0, 60.0]])
    K = A._keep_scale(T, (0.9, 1.1), pts)
    s, a, _, _ = decompose_similarity(K)
    assert s == pytest.approx(1.1) and a == pytest.approx(0.2)
    # scaled about the mapped points' centroid: it stays where it was
    assert np.allclose(apply(K, pts).mean(0), apply(T, pts).mean(0))
    assert A._keep_scale(T, (1.0, 1.5), pts) is T  # inside the band: untouched


def test_a_wrong_scale_that_fits_far_better_stays_out_when_resolutions_are_given():
    """The resolutions claim scale 1; the copy is at 1.3 (scale 0.77 onto the plan),
    which fits far better: the alignment keeps within 10 % of 1 and says that another
    scale fits far better (until 2026-11-27 it took that other scale, leaving the
    resolutions' band)."""
    plan = irregular_plan(5)
    copy = transformed_copy(plan, 1.3, -37.0)
    res = align_maps(copy, plan, params=AlignParams(metric_scale=1.0, auto_anchor=False))
    assert _in_band(decompose_similarity(res.similarity)[0], 1.0)
    (w,) = [w for w in res.warnings if "fit far better at scale" in w]
    assert "0.770" in w and "check the resolutions" in w and "within 10%" in w
    # told the right scale, it is exact and says nothing about the scale
    res = align_maps(copy, plan, params=AlignParams(metric_scale=1 / 1.3, auto_anchor=False))
    assert decompose_similarity(res.similarity)[0] * 1.3 == pytest.approx(1.0, abs=0.01)
    assert res.warnings == []


def test_a_wrong_scale_fitting_well_does_not_leave_the_band(office):
    """A copy at 0.75 told 1: at 0.94 a placement turned 90 deg fits well enough for the
    search; the scale stays within 10 % of 1 and the result warns (scale mismatch, doubt)."""
    small = transformed_copy(office, 0.75, 0.0)
    res = align_maps(small, office, params=AlignParams(metric_scale=1.0, auto_anchor=False))
    assert _in_band(decompose_similarity(res.similarity)[0], 1.0)
    assert any("scale" in w and "resolution" in w for w in res.warnings)


@pytest.mark.parametrize("metric", [1.0 / 1.3, 1.0, 1.25])
def test_given_resolutions_bound_the_scale_whatever_they_say(metric):
    """Right or wrong, the resolutions bound the scale: within 10 % of theirs."""
    plan = irregular_plan(5)
    copy = transformed_copy(plan, 1.3, -37.0)
    res = align_maps(copy, plan, params=AlignParams(metric_scale=metric, auto_anchor=False))
    assert _in_band(decompose_similarity(res.similarity)[0], metric)


def _search_pair(office):
    """Both searches of a partial office (its left 150 columns) against the office."""
    part = np.full_like(office, UNKNOWN)
    part[:, :150] = office[:, :150]
    p = AlignParams(auto_anchor=False)
    crop = A._Crop.of(A.check_map(part, None), A.check_map(office, None))
    src, tgt = crop.cut(part, office)
    fwd = A._search(src, tgt, 3, 1, p)
    bwd = A._search(tgt, src, 3, 1, A._invert_similarity_range(p))
    # the right placement in the cropped frames, and a wrong one: the part shrunk to
    # 0.6 and laid in the middle of the office (both hand-made)
    right = np.eye(3)
    right[:2, 2] = (crop.s[2] - crop.t[2], crop.s[0] - crop.t[0])
    wrong = similarity_matrix(0.6, 0.0, 60.0, 40.0)
    return fwd, bwd, right, wrong


def test_two_way_score_breaks_a_one_way_tie(office):
    """A wrong placement scoring best one way, the right one within 85 % of it: the
    placement that fits both ways is kept; the wrong one is not a rival (it fits
    the other way far worse)."""
    fwd, bwd, right, wrong = _search_pair(office)
    fwd.refined = [(1.0, wrong), (0.9, right)]  # hand-made one-way scores: a near tie
    bwd.refined = []
    fwd, bwd, reverse = A._two_way(fwd, bwd, 0.85)
    assert not reverse
    assert np.allclose(fwd.T, right) and np.allclose(bwd.T, np.linalg.inv(right))
    assert fwd.stats["runner_up"]["ratio"] < 0.85
    assert fwd.stats["runner_up"]["one_way_ratio"] == pytest.approx(1 / 0.9)
    assert fwd.two_way > 0.3


def test_one_way_score_decides_outside_a_tie(office):
    """Clearly better one way, the one-way winner stays (the two-way score penalises a
    partial map for what it did not explore); and a solution the reverse search found
    is turned into a source -> target placement."""
    fwd, bwd, right, wrong = _search_pair(office)
    fwd.refined = [(1.0, wrong)]
    bwd.refined = [(0.5, np.linalg.inv(right))]
    fwd, bwd, reverse = A._two_way(fwd, bwd, 0.85)
    assert not reverse and np.allclose(fwd.T, wrong)
    fwd.refined, bwd.refined = [(0.5, wrong)], [(1.0, np.linalg.inv(right))]
    fwd, bwd, reverse = A._two_way(fwd, bwd, 0.85)
    assert reverse and np.allclose(fwd.T, right) and np.allclose(bwd.T, np.linalg.inv(right))


def test_halmstad_hih_01_as_the_cli_reads_it(shared_data):
    """Issue #34: `map2map align HIH_01.png HIH_layout.png` picked scale 1.71 (the
    annotations give 1.17), with or without `--source-resolution 0.05
    --target-resolution 0.05`."""
    from map2map.maps.formats import load_map
    from map2map.maps.halmstad import keypoint_residuals, map_path

    root = shared_data / "halmstad"
    src = load_map(map_path(root, "HIH_01"), resolution=0.05)
    tgt = load_map(map_path(root, "HIH_layout"), resolution=0.05)
    res = align_maps(src.data, tgt.data)
    s, a, _, _ = decompose_similarity(res.similarity)
    assert s == pytest.approx(1.17, rel=0.03) and math.degrees(a) == pytest.approx(-162.5, abs=2)

    def mapper(pts):
        q = apply(res.similarity, pts)
        return q, q

    floor, sim, _ = keypoint_residuals(root, "HIH_01", "HIH_layout", src, tgt, mapper)
    assert sim <= 1.5 * floor  # 11.9 against 8.3 px when measured
    # the user's guess, both maps at 0.05 m/px (their ratio is 1.17): the scale stays
    # within 10 % of 1, and a warning says that 1.17 fits far better
    told = align_maps(src.data, tgt.data, params=AlignParams(metric_scale=1.0, rigid_scale=1.0))
    assert _in_band(decompose_similarity(told.similarity)[0], 1.0)
    assert any("fit far better at scale 1.1" in w for w in told.warnings)
