"""The plan drawer (:mod:`map2map.maps.vectorize`) and the "drawn like a plan"
measurements (:mod:`map2map.evaluate.drawing`) on hand-made maps (issue #32)."""

from __future__ import annotations

import math

import cv2
import numpy as np
import pytest

from map2map.evaluate.drawing import (
    broken_runs,
    drawing_report,
    median_wall_thickness,
    wall_components,
)
from map2map.maps.vectorize import (
    DrawOptions,
    _residual_lines,
    draw_plan,
    save_plan_dxf,
    wall_points,
)

RES = 0.05
FREE, UNK, OCC = 255, 127, 0


def room(h=120, w=200, top=20, left=20, bottom=100, right=180, t=3) -> np.ndarray:
    """A free room with ``t`` px walls, unknown outside."""
    m = np.full((h, w), UNK, np.uint8)
    m[top:bottom, left:right] = FREE
    m[top:top + t, left:right] = OCC
    m[bottom - t:bottom, left:right] = OCC
    m[top:bottom, left:left + t] = OCC
    m[top:bottom, right - t:right] = OCC
    return m


def horizontal(segs, y=None, tol=2.0):
    s = segs[np.abs(segs[:, 1] - segs[:, 3]) < 1e-6]
    return s if y is None else s[np.abs(s[:, 1] - y) <= tol]


def vertical(segs, x=None, tol=2.0):
    s = segs[np.abs(segs[:, 0] - segs[:, 2]) < 1e-6]
    return s if x is None else s[np.abs(s[:, 0] - x) <= tol]


def test_a_dashed_wall_becomes_one_segment():
    m = room()
    for x0 in range(30, 170, 20):                 # gaps of unknown, none of free through
        m[20:23, x0:x0 + 4] = UNK
    m[20:23, 100:104] = FREE                      # free inside the wall, not through it
    m[19, 100:104] = UNK
    d = draw_plan(m == OCC, m, RES, 3)
    top = horizontal(d.segments, 21.5)
    assert len(top) == 1, d.segments
    assert top[0, 0] <= 22 and top[0, 2] >= 178
    assert (d.map[20:23, 22:178] == OCC).all()    # drawn through every gap
    assert wall_components(d.map) == 1


@pytest.mark.parametrize("pattern", ["x.", "xx..", "x...", "xxx...."])
def test_a_dotted_wall_is_one_wall(pattern):
    m = room()
    m[20:100, 99:102] = FREE
    dots = np.array([c == "x" for c in pattern * 80])[:80]
    m[20:100, 100][dots] = OCC                    # free between the dots: too narrow a door
    d = draw_plan(m == OCC, m, RES, 3)
    mid = vertical(d.segments, 100.5)
    assert len(mid) == 1 and mid[0, 1] <= 22 and mid[0, 3] >= 98, d.segments
    assert wall_components(d.map) == 1


def test_a_door_stays_open():
    m = room()
    m[20:100, 99:102] = OCC                       # a wall between two rooms
    m[50:64, 99:102] = FREE                       # a door: free through it
    d = draw_plan(m == OCC, m, RES, 3)
    mid = vertical(d.segments, 100.5)
    assert len(mid) == 2, d.segments
    ends = sorted([mid[0, 1], mid[0, 3], mid[1, 1], mid[1, 3]])
    assert ends[1] <= 51 and ends[2] >= 63         # the gap is the door
    assert (d.map[52:62, 99:102] == FREE).all()


@pytest.mark.parametrize(("jog", "jamb", "t"), [(0, 6, 3), (1, 6, 3), (0, 4, 6)])
def test_a_short_jamb_beside_a_door_stays_on_its_wall(jog, jamb, t):
    """A door 0.9 m wide leaves a jamb of 0.3 or 0.2 m (6 or 4 px, shorter than a wall
    piece; the 4 px one has both ends within the corner reach of the top wall) between
    itself and the top wall (``t`` px thick): the jamb is drawn (the door is not widened
    to the corner), on the line of the wall beyond the door even where SLAM saved it a
    pixel off."""
    m = room(t=t)
    m[20:100, 99:102] = OCC                       # a wall between two rooms
    face = 20 + t
    door = face + jamb
    m[face:door + 18, 99:102] = FREE              # the door
    m[face:door, 99 + jog:102 + jog] = OCC        # the jamb
    d = draw_plan(m == OCC, m, RES, 3)
    mid = vertical(d.segments, 100.5, tol=1.5)
    assert len(mid) == 2, d.segments
    assert np.allclose(mid[:, 0], mid[0, 0]) and np.allclose(mid[:, 2], mid[0, 0])
    ends = sorted([mid[0, 1], mid[0, 3], mid[1, 1], mid[1, 3]])
    top = horizontal(d.segments, 20 + t / 2)
    assert len(top) == 1 and ends[0] == pytest.approx(top[0, 1])
    assert door - 2 <= ends[1] <= door + 1 and door + 17 <= ends[2] <= door + 19
    assert (d.map[door + 2:door + 16, 99:102] == FREE).all()
    assert (d.map[face:door - 1, 99:102] == OCC).all()


@pytest.mark.parametrize("t", [3, 6])
def test_a_door_is_drawn_as_wide_as_the_input_shows_it(t):
    """A wall's end at a door covers its last pixel and no more (every end is drawn
    extended by half the thickness so corners close; at a door that narrowed the door
    by the thickness), while its corners stay closed."""
    m = room()
    m[20:100, 99:102] = OCC
    m[50:64, 99:102] = FREE                       # the door: rows 50-63
    d = draw_plan(m == OCC, m, RES, t)
    col = d.map[:, 100]
    assert (col[50:64] == FREE).all() and col[49] == OCC and col[64] == OCC
    assert wall_components(d.map) == 1                       # corners and T closed
    assert (d.map[22:50, 99:102] == OCC).all()


def test_a_gap_with_free_space_into_a_speck_only_is_closed():
    m = room()
    m[17:20, 60:70] = FREE                        # a sliver of free space outside
    m[20:23, 60:70] = FREE                        # ... through a gap of the top wall
    d = draw_plan(m == OCC, m, RES, 3)
    assert len(horizontal(d.segments, 21.5)) == 1
    assert (d.map[17:20, 60:70] != FREE).all()    # the sliver is not a room: unknown


def test_a_t_junction_joins():
    m = room()
    m[23:95, 99:102] = OCC                        # stops 5 px short of the bottom wall
    d = draw_plan(m == OCC, m, RES, 3)
    mid = vertical(d.segments, 100.5)
    assert len(mid) == 1
    assert abs(max(mid[0, 1], mid[0, 3]) - 98.5) < 1e-6   # on the bottom wall's line
    assert (d.map[90:100, 99:102] == OCC).all()
    assert wall_components(d.map) == 1


def test_a_thick_wall_across_is_not_taken_into_the_wall_it_meets():
    """A wall at least ``L`` thick (a cleaned one-sided wall, grown outward) holds runs
    of ``L`` across its own direction: its pixels must not join the top wall's piece,
    whose line they would pull down into the room (dev map 000102: the top wall drawn
    8 px inside the room, then cut away as free space)."""
    m = room(t=3)
    m[20:100, 20:32] = OCC                        # the left wall, 12 px thick
    m[20:23, 20:180] = OCC
    d = draw_plan(m == OCC, m, RES, 3)
    top = horizontal(d.segments, 21.5, tol=1.0)
    assert len(top) == 1, d.segments
    assert top[0, 0] <= 32 and top[0, 2] >= 178
    assert len(horizontal(d.segments)) == 2       # top and bottom, nothing down the side
    assert (d.map[20:23, 40:170] == OCC).all()


def test_an_l_corner_closes():
    m = np.full((120, 200), FREE, np.uint8)
    m[20:23, 20:150] = OCC                        # horizontal, ends at x = 150
    m[27:100, 153:156] = OCC                      # vertical, starts 4 px below it
    d = draw_plan(m == OCC, m, RES, 3)
    h, v = horizontal(d.segments), vertical(d.segments)
    assert len(h) == 1 and len(v) == 1
    assert h[0, 2] == pytest.approx(v[0, 0]) and min(v[0, 1], v[0, 3]) == pytest.approx(h[0, 1])
    assert wall_components(d.map) == 1
    assert (d.map[20:23, 150:156] == OCC).all()   # the corner is filled


@pytest.mark.parametrize("over, top", [(8, 21.5), (10, 21.5), (16, 4.5)])
def test_an_end_poking_out_of_a_corner_is_cut_back_unless_it_is_a_wall(over, top):
    """Evidence running on past a corner (laser hits outside the building) by less than
    the shortest wall drawn plus its band is cut back to the corner (the demo's 0.37 m
    stub); a longer run stays a wall."""
    m = room()
    m[20 - over:20, 20:23] = OCC                  # the west wall runs on above the top wall
    d = draw_plan(m == OCC, m, RES, 3)
    v = vertical(d.segments, 21.5)
    assert len(v) == 1 and min(v[0, 1], v[0, 3]) == pytest.approx(top)
    poke = (d.map[:20, 15:30] == OCC).any()
    assert poke == (top < 20)


def test_a_jamb_beside_a_junction_stays():
    """A wall running 10 px on past a junction, rooms on both sides (a door's jamb), is
    not cut back as an end poking out of a corner is."""
    m = room()
    m[59:62, 20:110] = OCC                        # ends 8.5 px past the stem's far face
    m[60:100, 99:102] = OCC
    d = draw_plan(m == OCC, m, RES, 3)
    bar = horizontal(d.segments, 60.5)
    assert len(bar) == 1 and max(bar[0, 0], bar[0, 2]) == pytest.approx(109.5)


def _rotated_room(angle_deg: float, t: int = 3) -> np.ndarray:
    m = np.full((240, 240), UNK, np.uint8)
    c, a = np.array([120.0, 120.0]), math.radians(angle_deg)
    u, n = np.array([math.cos(a), math.sin(a)]), np.array([-math.sin(a), math.cos(a)])
    corners = [c + sx * 70 * u + sy * 45 * n for sx, sy in ((-1, -1), (1, -1), (1, 1), (-1, 1))]
    poly = np.round(np.array(corners) * 16).astype(np.int32)
    cv2.fillPoly(m, [poly], FREE, cv2.LINE_8, shift=4)
    cv2.polylines(m, [poly], True, OCC, t, cv2.LINE_8, shift=4)
    return m


def test_a_room_turned_20_degrees_keeps_its_angle():
    m = _rotated_room(20.0)
    d = draw_plan(m == OCC, m, RES, 3)
    assert d.angle == pytest.approx(20.0, abs=0.5)
    s = d.segments
    ang = np.degrees(np.arctan2(s[:, 3] - s[:, 1], s[:, 2] - s[:, 0])) % 90
    assert len(s) == 4, s
    assert np.allclose(ang, 20.0, atol=0.8), ang
    assert wall_components(d.map) == 1
    assert median_wall_thickness(d.map) == pytest.approx(3.0, abs=0.5)


def test_sub_pixel_points_with_weights():
    rng = np.random.default_rng(0)
    x = np.linspace(20, 180, 400)
    pts = np.concatenate([np.stack([x, 30.3 + rng.normal(0, 0.3, x.size)], 1),
                          np.stack([x, 90.7 + rng.normal(0, 0.3, x.size)], 1),
                          np.stack([20.4 + rng.normal(0, 0.3, 150), np.linspace(30, 91, 150)], 1),
                          np.stack([179.6 + rng.normal(0, 0.3, 150),
                                    np.linspace(30, 91, 150)], 1)])
    w = np.ones(len(pts))
    junk = np.array([[100.0, 60.0], [101.0, 60.5]])       # weight 0: ignored
    pts, w = np.concatenate([pts, junk]), np.concatenate([w, [0.0, 0.0]])
    occ = np.full((120, 200), UNK, np.uint8)
    occ[31:90, 21:179] = FREE
    d = draw_plan(pts, occ, RES, 2, weights=w, options=DrawOptions(keep_faces=False))
    h = horizontal(d.segments)
    assert sorted(np.round(h[:, 1], 1).tolist()) == pytest.approx([30.3, 90.7], abs=0.15)
    assert len(vertical(d.segments)) == 2
    with pytest.raises(ValueError, match="weights"):
        draw_plan(pts, occ, RES, 2, weights=w[:-1])


@pytest.mark.parametrize("t", [2, 3, 5])
def test_walls_are_drawn_at_the_requested_thickness(t):
    m = room(t=4)
    d = draw_plan(m == OCC, m, RES, t)
    assert d.thickness == t
    assert (d.map[:, 100] == OCC).sum() == 2 * t           # top and bottom walls
    assert (d.map[60] == OCC).sum() == 2 * t               # left and right walls
    assert median_wall_thickness(d.map) == t


@pytest.mark.parametrize("res, t, t0", [(0.1, 4, 2), (0.05, 6, 4), (0.03, 9, 7)])
def test_outer_walls_are_drawn_at_the_plans_convention_by_default(res, t, t0):
    # a room seen from inside only: its walls at 0.20 m plus a pixel on each side (the
    # dataset's plans at that resolution), not 0.30 m (3, 6 and 10 px)
    m = room(t=3)
    d = draw_plan(m == OCC, m, res)
    assert d.thickness == t
    assert median_wall_thickness(d.map) == t
    assert (d.map[:, 100] == OCC).sum() == 2 * t
    # grown by 0: 0.20 m alone
    d0 = draw_plan(m == OCC, m, res, options=DrawOptions(grow_px=0.0))
    assert d0.thickness == t0


@pytest.mark.parametrize("t", [2, 3, 6])
def test_walls_turned_by_half_a_degree_keep_the_thickness(t):
    m = _rotated_room(0.6)
    d = draw_plan(m == OCC, m, RES, t)
    assert d.angle == pytest.approx(0.6, abs=0.2)
    assert median_wall_thickness(d.map) == t
    cols = (d.map[:, 60:180] == OCC).sum(axis=0)          # top and bottom walls only
    assert set(cols.tolist()) == {2 * t}


def _two_rooms(t_in: int, wall_top: int = 58) -> np.ndarray:
    """A room with 3 px outer walls cut in two by a horizontal interior wall ``t_in`` px
    thick (rows ``wall_top`` to ``wall_top + t_in - 1``), free on both sides."""
    m = room(t=3)
    m[wall_top:wall_top + t_in, 20:180] = OCC
    return m


@pytest.mark.parametrize("t_in", [1, 2, 3, 4])
def test_a_wall_seen_from_both_sides_is_drawn_between_its_faces_grown_by_a_pixel(t_in):
    m = _two_rooms(t_in)
    d = draw_plan(m == OCC, m, RES, 7)
    col = d.map[:, 100] == OCC
    rows = np.flatnonzero(col[30:90]) + 30                 # the interior wall only
    assert rows.tolist() == list(range(57, 58 + t_in + 1))   # one pixel beyond each face
    assert d.info["two_sided"] == 1
    i = np.argmin(np.abs(d.segments[:, 1] - (58 + t_in / 2)) + np.abs(
        d.segments[:, 1] - d.segments[:, 3]))
    assert d.thicknesses[i] == t_in + 2
    # the outer walls, seen from one side, keep the drawing's thickness behind their face
    assert (col[:30]).sum() == 7 and (col[90:]).sum() == 7
    assert (d.map[21:58, 100] == FREE).sum() >= 58 - 21 - 3
    # off: every wall at one thickness
    d0 = draw_plan(m == OCC, m, RES, 7, options=DrawOptions(two_sided=False))
    assert (d0.map[30:90, 100] == OCC).sum() == 7 and d0.info["two_sided"] == 0
    # grown by 0: between the faces the input saw (at least 2 px)
    d1 = draw_plan(m == OCC, m, RES, 7, options=DrawOptions(grow_px=0.0))
    assert (d1.map[30:90, 100] == OCC).sum() == max(2, t_in)


def test_a_wall_saved_twice_is_not_taken_for_a_thin_wall_seen_from_both_sides():
    m = _two_rooms(1)
    m[60, 20:180] = OCC                     # the same wall saved again 2 px lower
    d = draw_plan(m == OCC, m, RES, 7)
    assert len(d.segments) == 5
    # its faces are the rooms' (rows 58 and 60 are its outer lines), not the free row
    # between the lines: both lines are inside, grown by a pixel
    rows = np.flatnonzero(d.map[30:90, 100] == OCC) + 30
    assert rows.tolist() == [57, 58, 59, 60, 61]


def test_an_outer_wall_with_laser_rays_beyond_it_keeps_its_seen_face():
    m = room(t=1)                           # 1 px walls: the top one is row 20
    for x in range(25, 175, 4):             # rays through it, into the unknown outside
        m[8:20, x] = FREE
    d = draw_plan(m == OCC, m, RES, 7)
    rows = np.flatnonzero(d.map[:40, 102] == OCC)
    assert rows.tolist() == list(range(14, 21))       # grown outward, not into the room
    assert (d.map[21:99, 102] == FREE).all()


def test_a_wall_thicker_than_the_drawing_keeps_the_drawing_thickness():
    m = _two_rooms(6)
    d = draw_plan(m == OCC, m, RES, 5)
    assert (d.map[30:90, 100] == OCC).sum() == 5
    assert d.info["two_sided"] == 0


def test_render_plan_takes_one_thickness_per_segment():
    from map2map.maps.vectorize import render_plan

    m = np.full((40, 60), FREE, np.uint8)
    segs = np.array([[5.0, 10.5, 55.0, 10.5], [5.0, 30.5, 55.0, 30.5]])
    out = render_plan(segs, m, np.array([3.0, 5.0]), RES, min_room=0.01)
    assert (out[:, 30] == OCC).sum() == 8
    assert np.flatnonzero(out[:, 30] == OCC).tolist() == [9, 10, 11, 28, 29, 30, 31, 32]
    assert np.array_equal(render_plan(segs, m, 4.0, RES, min_room=0.01),
                          render_plan(segs, m, np.array([4.0, 4.0]), RES, min_room=0.01))


def test_raster_and_dxf_agree(tmp_path):
    ezdxf = pytest.importorskip("ezdxf")
    m = room()
    m[20:100, 99:102] = OCC
    m[50:64, 99:102] = FREE
    d = draw_plan(m == OCC, m, RES, 3)
    world = save_plan_dxf(d, tmp_path / "w.dxf", RES, origin=(1.0, 2.0, 0.0))
    lines = ezdxf.readfile(tmp_path / "w.dxf").modelspace().query("LINE")
    got = np.array([[e.dxf.start.x, e.dxf.start.y, e.dxf.end.x, e.dxf.end.y] for e in lines])
    assert np.allclose(got, world)
    # back to pixels: every line's points lie on drawn wall pixels
    H = m.shape[0]
    for x0, y0, x1, y1 in got:
        for f in np.linspace(0, 1, 9):
            x = (x0 + f * (x1 - x0) - 1.0) / RES
            y = H - (y0 + f * (y1 - y0) - 2.0) / RES
            assert d.map[int(math.floor(y)), int(math.floor(x))] == OCC


def test_the_map_form_and_the_dxf_give_the_same_world_segments(tmp_path):
    from map2map.core.grid import OccupancyMap
    from map2map.maps.vectorize import draw_plan_map

    m = OccupancyMap(_rotated_room(12.0), resolution=RES, origin=(-3.0, 4.0, 0.3))
    out, world = draw_plan_map(m)
    d = draw_plan(m.occupied, m.data, RES)
    assert np.array_equal(out.data, d.map) and out.origin == m.origin
    assert out.meta["plan_drawer"]["segments_px"] == d.segments.tolist()
    w2 = save_plan_dxf(d, tmp_path / "w.dxf", RES, origin=m.origin)
    assert np.allclose(world, w2)


def test_specks_and_ray_ends_are_removed():
    m = room()
    for r, c in ((50, 60), (70, 140), (40, 100)):          # furniture legs in the room
        m[r:r + 2, c:c + 2] = OCC
    m[5:8, 60:63] = OCC                                     # ray ends outside
    m[23:27, 130] = OCC                                     # a tick on the top wall
    d = draw_plan(m == OCC, m, RES, 3)
    assert len(d.segments) == 4
    assert wall_components(d.map) == 1
    assert (d.map[50:52, 60:62] == FREE).all()
    assert (d.map[5:8, 60:63] == UNK).all()


def test_no_unknown_sliver_is_left_between_a_moved_wall_and_its_room():
    """A stretch of the top wall saved 3 px low (shorter than a run the drawer keeps
    inside its wall) is drawn on the wall's line: the input's wall pixels and the
    unknown beyond them, now inside the room, become free; a corner of the room the
    robot never saw (an unknown pocket 12 px deep) stays unknown."""
    m = room()
    m[20:26, 120:135] = UNK
    m[23:26, 120:135] = OCC
    m[26:38, 40:60] = UNK
    d = draw_plan(m == OCC, m, RES, 3)
    top = horizontal(d.segments, 21.5)
    assert len(top) == 1 and top[0, 1] == pytest.approx(21.5, abs=0.2)
    assert (d.map[20:23, 22:178] == OCC).all()
    assert (d.map[23:26, 110:145] == FREE).all()
    assert (d.map[26:38, 40:60] == UNK).all()


def test_lines_off_the_families_are_found_where_they_are_and_nowhere_else():
    """Walls off both directions (ragged, as SLAM draws them) in two corners of a map:
    the lines found in each do not depend on what lies in the other (the Hough
    transform draws its points at random; run on the whole map, one pixel anywhere
    moved every line)."""
    rng = np.random.default_rng(3)

    def ragged(img, p0, p1):
        t = np.linspace(0, 1, 2 * int(np.hypot(p1[0] - p0[0], p1[1] - p0[1])))[:, None]
        pts = np.array(p0) + t * np.subtract(p1, p0) + rng.normal(0, 0.3, (len(t), 2))
        img[np.round(pts[:, 1]).astype(int), np.round(pts[:, 0]).astype(int)] = 1

    a, b = np.zeros((200, 300), np.uint8), np.zeros((200, 300), np.uint8)
    ragged(a, (10, 20), (120, 70))
    ragged(a, (30, 150), (110, 110))
    ragged(b, (180, 30), (280, 150))
    ragged(b, (200, 170), (260, 120))
    none = np.zeros(a.shape, bool)
    apart = np.concatenate([_residual_lines(a, none, 20), _residual_lines(b, none, 20)])
    both = _residual_lines(a | b, none, 20)
    assert len(apart) >= 4
    assert sorted(map(tuple, apart.round(6))) == sorted(map(tuple, both.round(6)))


def test_determinism():
    m = _rotated_room(7.0)
    m[60:64, 100:104] = OCC
    a = draw_plan(m == OCC, m, RES)
    b = draw_plan(m.copy() == OCC, m.copy(), RES)
    assert np.array_equal(a.segments, b.segments)
    assert a.map.tobytes() == b.map.tobytes()


def test_bad_evidence_is_refused():
    m = room()
    with pytest.raises(ValueError, match="boolean raster"):
        draw_plan(np.zeros((5, 3)), m, RES)
    with pytest.raises(ValueError, match="weights"):
        draw_plan(m == OCC, m, RES, weights=np.ones(3))


def test_wall_points_round_trip():
    m = room() == OCC
    p = wall_points(m)
    back = np.zeros_like(m)
    back[np.floor(p[:, 1]).astype(int), np.floor(p[:, 0]).astype(int)] = True
    assert np.array_equal(back, m)


# ------------------------------------------------------------ the measurements
def test_a_broken_run_is_detected_and_a_continuous_one_is_not():
    m = room()                                   # walls 160 px = 8 m long
    runs, broken = broken_runs(m, m, RES)
    assert runs == 4 and broken == 0
    out = m.copy()
    out[20:23, 90:94] = UNK                      # a 4 px gap in the top wall
    assert broken_runs(m, out, RES) == (4, 1)
    out = m.copy()
    out[20:23, 90:92] = UNK                      # 2 px: within the tolerance
    assert broken_runs(m, out, RES) == (4, 0)
    out = np.roll(m, 2, axis=0)                  # moved by 2 px across: still there
    assert broken_runs(m, out, RES)[1] == 0
    w = np.full((60, 200), FREE, np.uint8)
    w[30:33, 20:180] = OCC
    out = w.copy()
    out[30:33, 160:180] = FREE                   # a wall cut back at its free end
    assert broken_runs(w, out, RES, shortened=True) == (1, 0, 1)
    out = m.copy()
    out[20:23, 150:180] = UNK                    # up to the corner: the right wall is
    assert broken_runs(m, out, RES)[1] == 1      # still there, so the top one is broken


def test_short_runs_are_not_counted():
    m = np.full((60, 60), FREE, np.uint8)
    m[30:32, 10:28] = OCC                        # 18 px = 0.9 m < 1 m
    assert broken_runs(m, np.full_like(m, FREE), RES) == (0, 0)


def test_report_on_the_drawer_output():
    plan = room(t=4)
    slam = room(t=2)
    for x0 in range(30, 170, 15):
        slam[20:22, x0:x0 + 3] = UNK             # a dashed SLAM wall
    d = draw_plan(slam == OCC, slam, RES, 4)
    r = drawing_report(d.map, slam, plan, RES, d.segments)
    assert r["components"] == 1 < r["components_input"]
    assert r["thickness_px"] == r["thickness_plan_px"] == 4
    assert r["segments"] == 4 and r["plan_walls"] == 4
    assert r["broken"] == 0 and r["targets_met"]
    assert r["ok_opened"] and r["targets_met_opened"]
    r_in = drawing_report(slam, slam, plan, RES)
    assert not r_in["ok_thickness"]


def test_report_tells_a_wall_drawn_beside_its_run_from_an_opened_one():
    """A wall drawn 5 px beside the input's run breaks the run (no output wall within
    3 px) but opens nothing; a gap in the drawn wall opens it."""
    plan = room(t=4)
    slam = room(t=2)
    out = slam.copy()
    out[20:22, 60:120] = FREE                    # the top wall's middle, moved 5 px down
    out[25:27, 60:120] = OCC
    r = drawing_report(out, slam, plan, RES)
    assert r["broken"] == 1 and not r["ok_broken"] and not r["targets_met"]
    assert r["opened"] == 0 and r["ok_opened"]
    out[25:27, 80:100] = FREE                    # and a hole in it: opened
    r = drawing_report(out, slam, plan, RES)
    assert r["opened"] == 1 and not r["ok_opened"] and not r["targets_met_opened"]


def _random_apartment(seed: int) -> np.ndarray:
    """Rooms on a grid of walls (2-4 px), doors cut with free space through them, walls
    wobbling by a pixel, pieces of walls missing (unknown), specks in the rooms."""
    rng = np.random.default_rng(seed)
    H, W = 200, 260
    m = np.full((H, W), UNK, np.uint8)
    y0, y1, x0, x1 = 20, 180, 20, 240
    m[y0:y1, x0:x1] = FREE
    ys = [y0] + sorted(rng.choice(np.arange(60, 150, 10), 1, replace=False).tolist()) + [y1 - 3]
    xs = [x0] + sorted(rng.choice(np.arange(60, 200, 10), 2, replace=False).tolist()) + [x1 - 3]
    for y in ys:
        t = int(rng.integers(2, 5))
        for a in range(x0, x1, 20):               # wobble: each 20 px, up to a pixel
            dy = int(rng.integers(-1, 2)) if y not in (y0, y1 - 3) else 0
            m[y + dy:y + dy + t, a:min(a + 20, x1)] = OCC
    for x in xs:
        t = int(rng.integers(2, 5))
        m[y0:y1, x:x + t] = OCC
    for y in ys[1:-1]:                             # a door in every interior wall line
        a = int(rng.integers(x0 + 10, x1 - 30))
        m[y - 2:y + 6, a:a + 14] = FREE
    for x in xs[1:-1]:
        a = int(rng.integers(y0 + 10, y1 - 30))
        m[a:a + 14, x - 2:x + 6] = FREE
    for _ in range(8):                             # holes in walls: unknown, not through
        r, c = int(rng.integers(y0, y1)), int(rng.integers(x0, x1))
        hole = m[r:r + 3, c:c + 3]
        hole[hole == OCC] = UNK
    for _ in range(10):                            # specks
        r, c = int(rng.integers(y0 + 5, y1 - 5)), int(rng.integers(x0 + 5, x1 - 5))
        if (m[r - 3:r + 5, c - 3:c + 5] == FREE).all():
            m[r:r + 2, c:c + 2] = OCC
    return m


@pytest.mark.parametrize("seed", range(6))
def test_continuous_walls_are_never_broken(seed):
    m = _random_apartment(seed)
    d = draw_plan(m == OCC, m, RES, 3)
    runs, broken = broken_runs(m, d.map, RES)
    assert runs > 0 and broken == 0
    assert wall_components(d.map) <= wall_components(m)
    assert median_wall_thickness(d.map) == 3


def test_many_maps_are_drawn_alike_in_worker_processes_and_in_this_one():
    from map2map.core.grid import OccupancyMap
    from map2map.maps.vectorize import draw_plan_maps

    maps = [OccupancyMap(_two_rooms(t), RES) for t in (1, 2, 3, 4)]
    maps.append(OccupancyMap(room(t=2), RES))
    one = draw_plan_maps(maps, wall_thickness=[7, 7, 5, 6, None], workers=1)
    two = draw_plan_maps(maps, wall_thickness=[7, 7, 5, 6, None], workers=2, min_maps=2)
    for (m1, w1), (m2, w2) in zip(one, two, strict=True):
        assert np.array_equal(m1.data, m2.data) and np.array_equal(w1, w2)
        assert m1.meta["plan_drawer"] == m2.meta["plan_drawer"]
    # one per map, as draw_plan_map draws it
    d = draw_plan(maps[2].occupied, maps[2].data, RES, 5)
    assert np.array_equal(one[2][0].data, d.map)
    with pytest.raises(ValueError, match="one entry per map"):
        draw_plan_maps(maps, wall_thickness=[7, 7])


def test_a_maps_interior_walls_are_drawn_at_one_thickness():
    """Two interior walls seen 2 px thick and one SLAM blurred to 6 px: all three are
    drawn at the median of the sharp ones (2 px plus a pixel each side), the blurred one
    centred between its faces; without ``one_interior`` it keeps the drawing's 7 px."""
    m = room(t=3)
    m[40:42, 20:180] = OCC
    m[60:62, 20:180] = OCC
    m[78:84, 20:180] = OCC                                  # blurred: rows 78-83
    col = lambda d: np.flatnonzero(d.map[30:95, 100] == OCC) + 30   # noqa: E731
    d = draw_plan(m == OCC, m, RES, 7)
    assert col(d).tolist() == [*range(39, 43), *range(59, 63), *range(79, 83)]
    assert sorted(d.thicknesses.tolist()).count(4.0) == 3
    d0 = draw_plan(m == OCC, m, RES, 7, options=DrawOptions(one_interior=False))
    rows = col(d0).tolist()
    assert rows[:8] == [*range(39, 43), *range(59, 63)] and len(rows) == 8 + 7
    # one interior wall alone keeps its own thickness (nothing to take a median of)
    m1 = _two_rooms(4)
    assert (draw_plan(m1 == OCC, m1, RES, 7).map[30:90, 100] == OCC).sum() == 6


def test_a_run_is_opened_only_where_no_output_wall_lies_near_it():
    """A wall drawn 5 px beside part of an input run breaks it by the 3 px measure but
    opens nothing; a hole in the wall opens it."""
    m = np.full((60, 120), FREE, np.uint8)
    m[30:32, 10:110] = OCC                                   # a 5 m run
    beside = m.copy()
    beside[30:32, 50:70] = FREE
    beside[35:37, 48:72] = OCC                               # that part drawn 5 px off
    assert broken_runs(m, beside, RES, opened=True) == (1, 1, 0)
    hole = m.copy()
    hole[30:32, 50:70] = FREE                                # a 1 m opening
    assert broken_runs(m, hole, RES, opened=True) == (1, 1, 1)
    assert broken_runs(m, hole, RES, shortened=True, opened=True) == (1, 1, 0, 1)


def test_wall_raster_is_what_render_plan_occupies():
    """``draw_plan`` hands the bridges ``wall_raster`` instead of a rendered map: its walls
    must be exactly ``render_plan``'s occupied pixels (axis-aligned, near-axis and
    slanted walls, one thickness each)."""
    from map2map.maps.vectorize import render_plan, wall_raster

    rng = np.random.default_rng(5)
    occ = rng.choice(np.array([0, 127, 255], np.uint8), (90, 120), p=[0.1, 0.3, 0.6])
    segs = np.array([[5.0, 10.0, 100.0, 10.0], [30.0, 5.0, 30.0, 80.0],
                     [10.0, 40.0, 110.0, 45.0], [60.0, 20.0, 90.0, 85.0]])
    tk = np.array([5.0, 3.0, 4.0, 6.0])
    out = render_plan(segs, occ, tk, 0.05)
    assert np.array_equal(wall_raster(segs, tk, occ.shape) > 0, out == 0)


def test_an_unknown_stripe_between_a_drawn_wall_and_its_room_becomes_free():
    """A wall drawn a few pixels off the input's face leaves the input's wall pixels and
    the unknown beyond them between itself and the room: up to ``sliver`` wall
    thicknesses across it becomes free (a plan has no unknown stripe along its walls);
    wider, or open to the map's border, it stays unknown."""
    from map2map.maps.vectorize import _render

    occ = np.full((60, 100), 127, np.uint8)
    occ[5:40, 5:95] = 255                          # the room; rows 40-43: a 4 px stripe
    wall = np.zeros(occ.shape, np.uint8)
    wall[44:50, 2:98] = 1                          # the drawn wall below the stripe
    wall[2:50, 2:5] = wall[2:50, 95:98] = wall[2:5, 2:98] = 1
    t = 6.0
    stripe = (slice(40, 44), slice(5, 95))
    assert (_render(wall, occ, 0.05, 0.5, 0.2, 1.5)[stripe] == 127).all()    # 3 px only
    assert (_render(wall, occ, 0.05, 0.5, 0.2, max(1.5, 1.0 * t / 2))[stripe] == 255).all()
    occ[5:44, 50:52] = 127                         # ... not when it is open to the border
    wall[44:50, 50:52] = 0
    out = _render(wall, occ, 0.05, 0.5, 0.2, t / 2)
    assert (out[stripe] == 127).sum() > 0


def test_draw_option_sliver_is_read_from_the_command_line():
    """``--draw-option sliver=0`` turns the wide stripes off (3 pixels only, as before)."""
    from map2map.jobs.autocorrect import parse_draw_options

    assert parse_draw_options(["sliver=0"]).sliver == 0.0
    assert parse_draw_options(None) is None or parse_draw_options(None).sliver == 1.0


@pytest.mark.parametrize("door", [False, True])
def test_an_unseen_corner_is_closed_and_a_seen_opening_is_not(door):
    """A room whose corner the robot never saw (free space cut diagonally by unknown,
    0.6-0.75 m from the corner along both walls): the two walls are drawn on to their
    corner (``corner_reach``). Where the input's free space runs out through the gap (the
    robot saw through it: a door), it stays open."""
    from map2map.maps.vectorize import DrawOptions, draw_plan

    m = np.full((80, 100), 127, np.uint8)
    m[10:70, 10:90] = 255
    m[9, 9:91] = 0; m[9:71, 9] = 0; m[70, 9:91] = 0; m[9:71, 90] = 0   # noqa: E702
    for k in range(12):                                    # the corner never seen
        m[70 - k:71, 78 + k:91] = 127
    if door:
        m[66:75, 78:95] = 255; m[75:80, 70:99] = 255       # noqa: E702
    closed = draw_plan(m == 0, m, 0.05, cover=m == 0)
    off = draw_plan(m == 0, m, 0.05, options=DrawOptions(corner_reach=0), cover=m == 0)
    assert int(off.map[70, 89]) != 0                       # open without the rule
    assert (int(closed.map[70, 89]) == 0) == (not door)
