"""Appendix Table 2's synthetic maps: known errors, and the metric finds them."""

from __future__ import annotations

import numpy as np

from map2map.core.grid import UNKNOWN
from map2map.evaluate.validation import TABLE2, Table2Spec, table2_cases
from map2map.maps.synthetic import affine_field, bump_field, deform, draw_walls, office_walls


def _plan() -> np.ndarray:
    return np.pad(draw_walls((160, 220), office_walls(220, 160, thickness=4)), 24,
                  constant_values=UNKNOWN)  # fmt: skip


def test_affine_field_is_the_affine_map():
    u = affine_field((50, 80), rotation_deg=90.0, centre=(40.0, 25.0))
    # the cell centre (50.5, 25.5) is 10.5 px right of the centre; rotated by 90 degrees
    # (x right, y down) it goes 10.5 px down: (40 - 0.5, 25 + 10.5)
    x, y = 50.5, 25.5
    assert np.allclose([x, y] + u[25, 50], [39.5, 35.5])


def test_bump_field_is_seeded():
    a = bump_field((40, 40), 3.0, 8.0, 3, np.random.default_rng(5))
    b = bump_field((40, 40), 3.0, 8.0, 3, np.random.default_rng(5))
    assert np.array_equal(a, b) and np.abs(a).max() > 0.5


def test_rigid_motion_alone_has_no_true_error():
    plan = _plan()
    spec = Table2Spec(".0", "rotation, translation", 3.0, (5.0, -4.0), local=0.0)
    [(_, name, slam, case)] = table2_cases({"Map 9": plan}, 0, specs=(spec,))
    assert name == "Map 9.0" and (slam != plan).any()
    # the alignment undoes the motion: what is left is whole-pixel drawing, under a pixel
    assert case.true["rigid"]["mean_px"] < 0.5
    assert case.reported["rigid"]["mean_px"] < 0.8
    assert abs(case.rotation_deg + 3.0) < 0.5  # the inverse rotation was found


def test_metric_finds_the_known_local_shear():
    plan = _plan()
    fwd = affine_field(plan.shape, rotation_deg=-2.0, translation=(3.0, 2.0))
    fwd = fwd + bump_field(plan.shape, 5.0, 30.0, 3, np.random.default_rng(1))
    slam, carried = deform(plan, fwd)
    from map2map.evaluate.validation import known_error_case

    case = known_error_case("bent", plan, slam, carried, fwd)
    t, r = case.true[case.chosen], case.reported[case.chosen]
    assert t["max_px"] > 2.0  # a real error to find
    assert abs(r["max_px"] - t["max_px"]) < 1.0
    assert abs(r["mean_px"] - t["mean_px"]) < 0.3


def test_table2_specs_follow_the_paper():
    kinds = [s.what for s in TABLE2]
    assert [s.name for s in TABLE2] == [".1", ".2", ".3"]
    assert TABLE2[1].local > TABLE2[0].local  # high vs low local shear
    assert TABLE2[2].scale != (1.0, 1.0) and TABLE2[2].shear != 0  # global scale and shear
    assert "scale" in kinds[2]
