"""The input's straight wall runs kept inside the walls drawn for them
(:mod:`map2map.maps.cover`, and the plan drawer's ``cover``; issue #32: a wall the input
shows whole is never broken in the output)."""

from __future__ import annotations

import cv2
import numpy as np
import pytest

from map2map.evaluate.drawing import broken_runs
from map2map.maps.cover import keep_runs_inside, straight_runs
from map2map.maps.vectorize import DrawOptions, draw_plan, wall_points

RES = 0.05
FREE, UNK, OCC = 255, 127, 0


def test_a_stepped_run_is_one_run_and_short_ones_are_none():
    c = np.zeros((20, 80), bool)
    c[5, 0:40] = True
    c[7, 40:70] = True                       # a step of two across: still one run
    c[12, 10:25] = True                      # 15 px: shorter than 20
    lab, k = straight_runs(c, 20)
    assert k == 1
    assert (lab[5, 0:40] == 1).all() and (lab[7, 40:70] == 1).all()
    assert not lab[12].any()
    _, k0 = straight_runs(c, 20, slack=0)    # no step allowed: two runs
    assert k0 == 2


def _turned_run(deg: float, shape=(60, 200), v0=30.0, u=(20, 180)) -> np.ndarray:
    c = np.zeros(shape, bool)
    uu = np.arange(*u)
    c[np.round(v0 + np.tan(np.radians(deg)) * (uu - np.mean(u))).astype(int), uu] = True
    return c


def test_a_wall_across_a_turned_run_moves_to_keep_it_inside():
    c = _turned_run(3.0)                     # the run climbs about 8 px over 160
    lo, hi = np.array([20.5]), np.array([179.5])
    a0, a1 = np.array([30.5]), np.array([30.5])       # drawn straight through its middle
    b0, b1 = keep_runs_inside(lo, hi, a0, a1, c, 20, band=6.0, c=2.0)
    f = (np.arange(20, 180) + 0.5 - lo[0]) / (hi[0] - lo[0])
    line = b0[0] + (b1[0] - b0[0]) * f
    v = np.nonzero(c.T)[1] + 0.5
    assert np.max(np.abs(v - line)) <= 2.0 + 1e-9
    assert b0[0] < 30.5 - 1 and b1[0] > 30.5 + 1          # it leans with the run
    # the least move: still as near the original line as the tolerance allows
    assert np.max(np.abs(v - line)) > 1.5


def test_a_wall_that_already_holds_its_run_is_left_alone():
    c = _turned_run(1.0)                     # about 3 px over 160
    a0, a1 = np.array([30.5]), np.array([30.5])
    b0, b1 = keep_runs_inside(np.array([20.5]), np.array([179.5]), a0, a1, c, 20,
                              band=6.0, c=2.5)
    assert b0[0] == a0[0] and b1[0] == a1[0]


def test_a_run_beside_no_wall_moves_nothing():
    c = _turned_run(3.0, v0=45.0)            # 15 px away: another wall's, or clutter
    a0, a1 = np.array([30.5]), np.array([30.5])
    b0, b1 = keep_runs_inside(np.array([20.5]), np.array([179.5]), a0, a1, c, 20,
                              band=6.0, c=2.0)
    assert b0[0] == a0[0] and b1[0] == a1[0]


def test_each_run_goes_to_its_nearest_wall():
    c = _turned_run(0.0, v0=34.0) | _turned_run(0.0, v0=20.0)
    lo, hi = np.array([20.5, 20.5]), np.array([179.5, 179.5])
    a0 = np.array([30.0, 23.0])              # run at 34.5 is 4.5 from wall 0; 20.5 is 2.5 from 1
    b0, b1 = keep_runs_inside(lo, hi, a0, a0.copy(), c, 20, band=6.0, c=2.0)
    assert b0.tolist() == pytest.approx([32.5, 22.5])
    assert b1.tolist() == pytest.approx([32.5, 22.5])


def _room_with_a_drifted_wall(deg: float = 4.0) -> tuple[np.ndarray, np.ndarray]:
    """A SLAM-like map whose bottom wall drift turned by ``deg`` degrees, and a
    corrector's walls (straight, the bottom one on the wall's mean line) for it."""
    m = np.full((140, 220), UNK, np.uint8)
    m[20:120, 20:200] = FREE
    m[20:22, 20:200] = OCC
    m[20:120, 20:22] = OCC
    m[20:120, 198:200] = OCC
    uu = np.arange(20, 200)
    rows = np.round(112 + np.tan(np.radians(deg)) * (uu - 110)).astype(int)
    below = np.arange(140)[:, None] > rows[None, :] + 1
    m[:, 20:200][below] = UNK
    for dr in (0, 1):
        m[rows + dr, uu] = OCC
    corr = np.zeros(m.shape, bool)
    corr[20:22, 20:200] = True
    corr[20:122, 20:22] = True
    corr[20:122, 198:200] = True
    corr[112:114, 20:200] = True
    return m, corr


def test_the_drawer_keeps_a_drifted_wall_whole():
    m, corr = _room_with_a_drifted_wall()
    p0, p1 = wall_points(corr), wall_points(m == OCC)
    ev = np.concatenate([p0, p1])
    w = np.concatenate([np.ones(len(p0)), np.full(len(p1), 0.1)])
    off = draw_plan(ev, m, RES, 4, weights=w, options=DrawOptions(cover_run=0.0),
                    cover=m == OCC)
    on = draw_plan(ev, m, RES, 4, weights=w, cover=m == OCC)
    # without cover the bottom wall is drawn along the corrector's straight line and
    # leaves the input's turned run at both ends (the measurement calls it broken);
    # with it, the run lies within the drawn wall plus cover_tol (0.15 m: 3 px)
    dist_off = cv2.distanceTransform((off.map != OCC).astype(np.uint8), cv2.DIST_L2, 3)
    dist_on = cv2.distanceTransform((on.map != OCC).astype(np.uint8), cv2.DIST_L2, 3)
    bottom = (m == OCC) & (np.arange(140)[:, None] > 100)
    assert dist_off[bottom].max() > 4.0
    assert dist_on[bottom].max() <= DrawOptions().cover_tol / RES
    assert broken_runs(m, off.map, RES) == (4, 1)
    assert broken_runs(m, on.map, RES) == (4, 0)
    assert len(on.segments) == len(off.segments) == 4


def test_cover_is_deterministic_and_off_means_off():
    m, corr = _room_with_a_drifted_wall()
    a = draw_plan(corr, m, RES, 4, cover=m == OCC)
    b = draw_plan(corr, m, RES, 4, cover=m == OCC)
    assert np.array_equal(a.segments, b.segments) and np.array_equal(a.map, b.map)
    none = draw_plan(corr, m, RES, 4)
    off = draw_plan(corr, m, RES, 4, cover=m == OCC, options=DrawOptions(cover_run=0.0))
    assert np.array_equal(none.segments, off.segments)


def test_a_cover_of_another_shape_is_refused():
    m, corr = _room_with_a_drifted_wall()
    with pytest.raises(ValueError, match="cover must be shaped like the map"):
        draw_plan(corr, m, RES, 4, cover=np.zeros((10, 10), bool))


def test_a_drifted_wall_follows_its_points_unless_lean_px_is_none():
    """A room whose bottom wall drift turned by 1.2 degrees (about 3.4 px over its
    length): drawn along its points by default (``lean_px`` 1.5); with ``lean_px``
    None parallel to the top wall, in the map's one direction."""
    m, _ = _room_with_a_drifted_wall(1.2)

    def rise(d, pick):                                     # along the wall's length
        s = d.segments[pick(np.minimum(d.segments[:, 1], d.segments[:, 3]))]
        return (s[3] - s[1]) / (s[2] - s[0])

    flat = draw_plan(m == OCC, m, RES, 4, cover=m == OCC, options=DrawOptions(lean_px=None))
    assert len(flat.info["angles"]) == 1              # one family (its angle: 0.4 deg)
    assert rise(flat, np.argmax) == pytest.approx(rise(flat, np.argmin), abs=1e-9)
    lean = draw_plan(m == OCC, m, RES, 4, cover=m == OCC)
    assert (rise(lean, np.argmax) - rise(lean, np.argmin)) * 180 > 2.0
