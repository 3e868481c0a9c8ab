"""The input's straight wall runs kept inside the walls drawn for them
(:mod:`map2map.maps.cover`, and the plan drawer's ``cover``; issue #32: a wall the input
shows whole is never broken in the output)."""

from __future__ import annotations

import warnings

import cv2
import numpy as np
import pytest

from map2map.evaluate.drawing import broken_runs
from map2map.maps.cover import bridge_gaps, keep_runs_inside, straight_runs
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
    off = draw_plan(corr, m, RES, 4, cover=m == OCC,
                    options=DrawOptions(cover_run=0.0, bridge_run=0.0))
    assert np.array_equal(none.segments, off.segments)
    # cover off, bridges on: the straight wall leaves the turned run at its left end
    # but runs beside it along most of the gap: a bridge would double the wall
    beside = draw_plan(corr, m, RES, 4, cover=m == OCC, options=DrawOptions(cover_run=0.0))
    assert beside.info["bridged"] == 0 and np.array_equal(beside.map, off.map)
    # nothing within one thickness (4 px) along a fifth of it: bridged when that is
    # enough and the wall beside counts as another wall (bridge_same 0); by default it
    # is the same wall (no free space between it and the run)
    kw = {"cover_run": 0.0, "bridge_share": 0.2, "bridge_beside": 1.0}
    half = draw_plan(corr, m, RES, 4, cover=m == OCC,
                     options=DrawOptions(**kw, bridge_same=0.0))
    assert half.info["bridged"] == 1 and broken_runs(m, half.map, RES) == (4, 0)
    same = draw_plan(corr, m, RES, 4, cover=m == OCC, options=DrawOptions(**kw))
    assert same.info["bridged"] == 0 and np.array_equal(same.map, off.map)


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


def _z_wall(jog: int = 14, door: bool = False) -> np.ndarray:
    """A walled room cut by an interior wall with a jog: down at x = 40 + ``jog`` to
    row 50, across to x = 40, down to the bottom (the drawer's pieces: two vertical
    walls and a jog too short beyond them to keep as a wall of its own). With ``door``,
    a 0.6 m door in the lower vertical wall."""
    m = np.full((100, 120), UNK, np.uint8)
    m[5:96, 5:115] = FREE
    m[5, 5:115] = m[95, 5:115] = OCC
    m[5:96, 5] = m[5:96, 114] = OCC
    x1 = 40 + jog
    m[10:51, x1] = OCC
    m[50, 40:x1 + 1] = OCC
    m[50:91, 40] = OCC
    if door:
        m[65:77, 40] = FREE
    return m


def test_a_jog_the_drawer_drops_is_bridged():
    """The jog is 0.7 m: bridged from ``bridge_run`` 0.5 m (the default, 1 m, leaves it)."""
    m = _z_wall()
    off = draw_plan(m == OCC, m, RES, 6, cover=m == OCC,
                    options=DrawOptions(bridge_run=0.0))
    assert np.array_equal(draw_plan(m == OCC, m, RES, 6, cover=m == OCC).map, off.map)
    on = draw_plan(m == OCC, m, RES, 6, cover=m == OCC, options=DrawOptions(bridge_run=0.5))
    # without bridges the jog (0.7 m) is dropped: the two rooms open into each other
    # where the input shows a continuous wall
    assert broken_runs(m, off.map, RES, min_run=0.5, opened=True) == (7, 1, 1)
    assert (off.map[50, 42:52] == FREE).all() and off.info["bridged"] == 0
    assert broken_runs(m, on.map, RES, min_run=0.5, opened=True) == (7, 0, 0)
    assert on.info["bridged"] == 1 and len(on.segments) == len(off.segments) + 1
    u0, v0, u1, v1 = on.segments[-1]                      # along the jog, end to end
    assert v0 == v1 == pytest.approx(50.5) and sorted([u0, u1]) == pytest.approx(
        [40.5, 54.5], abs=1.0)
    # as thin as the interior walls it joins
    assert on.thicknesses[-1] == pytest.approx(on.thicknesses[-2])
    same = np.ones(m.shape, bool)
    same[44:57, 36:60] = False                            # nothing else moved
    assert np.array_equal(on.map[same], off.map[same])


def test_a_run_along_the_grid_is_bridged_in_a_map_whose_walls_drift_turned():
    """The drawer's frames are its direction families' (here one, turned 5 degrees); a
    jog the input shows along the grid's columns, 1.25 m between two drawn walls, is a
    straight run in the grid's own frame only, and is closed there along its pixels."""
    from map2map.maps.vectorize import _bridges

    cover = np.zeros((80, 100), bool)
    cover[20, 10:51] = cover[45, 50:90] = True
    cover[20:46, 50] = True                                # the jog
    drawn = np.zeros_like(cover)
    drawn[18:23, 10:51] = drawn[43:48, 50:90] = True       # the walls, not the jog
    free = np.zeros_like(cover)
    free[23:70, 10:50] = True
    segs = np.array([[10.0, 20.5, 51.0, 20.5], [50.0, 45.5, 90.0, 45.5]])
    b, tk = _bridges(segs, np.array([5.0, 4.0]), drawn, cover, free, [-5.0], RES,
                     DrawOptions(), 5.0)
    assert b.tolist() == [[50.5, 22.5, 50.5, 43.5]] and tk.tolist() == [4.0]


def test_a_bridge_closes_no_door():
    m = _z_wall(door=True)
    d = draw_plan(m == OCC, m, RES, 6, cover=m == OCC, options=DrawOptions(bridge_run=0.5))
    assert d.info["doors"] >= 1
    assert (d.map[66:76, 38:43] == FREE).all()            # the door is open
    assert (d.map[50, 42:52] == OCC).all()                # the jog is closed


def test_bridge_gaps_leaves_short_gaps_uncovered_runs_and_walls_beside():
    canvas = np.zeros((30, 60), bool)
    canvas[10, 5:55] = True
    drawn = np.zeros((30, 60), bool)
    drawn[9:12, 5:30] = True
    drawn[9:12, 32:55] = True                             # a 2 px gap: left
    assert bridge_gaps(canvas, drawn, 20, near=2, open_=6).shape == (0, 4)
    drawn[9:12, 30:32] = True
    drawn[9:12, 20:40] = False                            # a 20 px gap: bridged
    assert bridge_gaps(canvas, drawn, 20, near=2, open_=6).tolist() == [
        [19.5, 10.5, 40.5, 10.5]]
    drawn[:] = False
    drawn[9:12, 5:20] = True                              # drawn on one side only
    assert bridge_gaps(canvas, drawn, 20, near=2, open_=6).shape == (0, 4)
    assert bridge_gaps(canvas, drawn, 51, near=2, open_=6).shape == (0, 4)  # too short


def test_a_corner_wall_ending_short_of_the_run_closes_its_end():
    """HELD25 000590's case: a 1.2 m outer wall run between two perpendicular walls; its
    own piece was dropped, the wall on the left ends 2 px short of the run (beyond
    ``near``) and the one on the right crosses it. Within ``end_near`` of the run's ends
    the corner counts as covered, so the gap between the corners is found."""
    canvas = np.zeros((40, 60), bool)
    canvas[20, 10:50] = True                              # the run
    drawn = np.zeros((40, 60), bool)
    drawn[:18, 8:13] = True                               # ends 2 px above the run
    drawn[10:30, 47:52] = True                            # crosses it
    kw = {"near": 1.5, "open_": 8}
    assert bridge_gaps(canvas, drawn, 20, **kw).shape == (0, 4)
    assert bridge_gaps(canvas, drawn, 20, **kw, end_near=4).tolist() == [
        [12.5, 20.5, 47.5, 20.5]]
    # not beyond the run's ends: the same wall 2 px short in the run's middle is no cover
    drawn[:] = False
    drawn[:18, 28:33] = True
    drawn[10:30, 47:52] = True
    canvas[20, 5:10] = True
    assert bridge_gaps(canvas, drawn, 20, **kw, end_near=4).shape == (0, 4)


def test_bridge_gaps_leaves_the_other_line_of_a_wall_saved_twice():
    """A run whose gap has a drawn wall 10 px beside it (beyond ``open_``): bridged
    when free space lies between the two (two walls), left when only the wall's
    unobserved inside does (one wall saved twice), unless ``same`` is 0."""
    canvas = np.zeros((40, 60), bool)
    canvas[10, 5:55] = True                               # the run
    drawn = np.zeros((40, 60), bool)
    drawn[9:12, 5:20] = drawn[9:12, 40:55] = True         # on it, with a 20 px gap
    drawn[20:23, 15:45] = True                            # a wall 10 px beside the gap
    free = np.zeros((40, 60), bool)
    free[:9] = True                                       # a room above the run
    kw = {"near": 2, "open_": 6, "same": 14}
    assert bridge_gaps(canvas, drawn, 20, free=free, **kw).shape == (0, 4)
    assert bridge_gaps(canvas, drawn, 20, free=free, **{**kw, "same": 0}).tolist() == [
        [19.5, 10.5, 40.5, 10.5]]
    free[12:20] = True                                    # a corridor between: two walls
    assert bridge_gaps(canvas, drawn, 20, free=free, **kw).tolist() == [
        [19.5, 10.5, 40.5, 10.5]]
    free[12:20] = False
    free[13, ::4] = True                                  # a few specks: still one wall
    assert bridge_gaps(canvas, drawn, 20, free=free, **kw).shape == (0, 4)
    assert bridge_gaps(canvas, drawn, 20, free=free, **{**kw, "same": 8}).tolist() == [
        [19.5, 10.5, 40.5, 10.5]]                         # 10 px apart: beyond same


def test_a_widened_run_without_canvas_pixels_is_no_run():
    """Two short pieces one row apart widen (``slack``) into a long run on the row
    between, which holds none of the canvas's pixels: no run, and no 0 / 0 warning."""
    c = np.zeros((10, 30), bool)
    c[3, 0:10] = True
    c[5, 10:20] = True
    lab, k = straight_runs(c, 15)
    assert k == 0 and not lab.any()
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        a0, a1 = keep_runs_inside(np.array([0.5]), np.array([19.5]), np.array([4.5]),
                                  np.array([4.5]), c, 15, band=6, c=2)
    assert a0.tolist() == a1.tolist() == [4.5]


def _room_with_a_stub() -> tuple[np.ndarray, np.ndarray]:
    """A walled room with a 1.5 m interior wall hanging from its top wall at x = 60 (a
    wall the plan has), and a corrector's walls that lost it (the cleaning dropped it)."""
    m = np.full((100, 120), UNK, np.uint8)
    m[5:96, 5:115] = FREE
    m[5:7, 5:115] = m[94:96, 5:115] = OCC
    m[5:96, 5:7] = m[5:96, 113:115] = OCC
    corr = m == OCC
    m[7:37, 60:62] = OCC
    return m, corr


def test_a_wall_the_cleaning_dropped_is_drawn_along_the_input_run():
    m, corr = _room_with_a_stub()
    off = draw_plan(corr, m, RES, 4, cover=m == OCC, options=DrawOptions(bridge_ends=0.0))
    on = draw_plan(corr, m, RES, 4, cover=m == OCC)
    assert not (off.map[12:30, 58:64] == OCC).any()          # the stub is lost
    assert (on.map[12:30, 60:62] == OCC).all()               # drawn where the input has it
    assert on.info["bridged"] == 1 and len(on.segments) == len(off.segments) + 1
    _, _, short_off = broken_runs(m, off.map, RES, shortened=True)
    _, _, short_on = broken_runs(m, on.map, RES, shortened=True)
    assert (short_off, short_on) == (1, 0)
    same = np.ones(m.shape, bool)
    same[5:40, 55:67] = False                                 # nothing else moved
    assert np.array_equal(on.map[same], off.map[same])


def test_bridge_gaps_ends_close_an_open_end_or_a_lost_run_unless_a_wall_is_beside():
    canvas = np.zeros((30, 60), bool)
    canvas[10, 5:55] = True
    drawn = np.zeros((30, 60), bool)
    kw = {"near": 2, "open_": 6}
    assert bridge_gaps(canvas, drawn, 20, **kw).shape == (0, 4)
    assert bridge_gaps(canvas, drawn, 20, **kw, ends=5).tolist() == [
        [5.5, 10.5, 54.5, 10.5]]                              # lost: drawn whole, once
    drawn[9:12, 30:40] = True                                 # covered in its middle
    assert bridge_gaps(canvas, drawn, 20, **kw, ends=5).tolist() == [
        [5.5, 10.5, 30.5, 10.5], [39.5, 10.5, 54.5, 10.5]]
    assert bridge_gaps(canvas, drawn, 20, **kw, ends=20).tolist() == [
        [5.5, 10.5, 30.5, 10.5]]                              # the 15-column end: left
    drawn[14:17, 5:55] = True                                 # a wall drawn 4 px beside
    assert bridge_gaps(canvas, drawn, 20, **kw, ends=5).shape == (0, 4)


def test_bridge_gaps_draws_one_line_of_a_wall_saved_twice_that_no_drawn_wall_covers():
    """HELD27 000078: both lines of a wall SLAM saved twice, 8 px apart with unknown
    between, were left undrawn; ``ends`` drew both. Only the longer is drawn, unless
    free space lies between them (two walls)."""
    canvas = np.zeros((40, 60), bool)
    canvas[10, 5:55] = True
    canvas[18, 8:50] = True
    drawn = np.zeros((40, 60), bool)
    free = np.zeros((40, 60), bool)
    free[:10] = free[19:] = True                          # rooms above and below
    kw = {"near": 2, "open_": 6, "ends": 5, "free": free, "same": 14}
    assert bridge_gaps(canvas, drawn, 20, **kw).tolist() == [[5.5, 10.5, 54.5, 10.5]]
    free[12:17] = True                                    # a corridor between
    assert sorted(bridge_gaps(canvas, drawn, 20, **kw).tolist()) == [
        [5.5, 10.5, 54.5, 10.5], [8.5, 18.5, 49.5, 18.5]]
