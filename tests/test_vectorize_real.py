"""The plan drawer (:mod:`map2map.maps.vectorize`) on what real sensor maps show and
simulated ones rarely do (issue #32: the drawn default was worse than its input on the
Halmstad maps): walls seen as two faces with clutter between them, lines joined across
free space, wall pixels only the input (not the corrector) shows, free space bounded by
unknown along most of its outline. Hand-made maps."""

from __future__ import annotations

import numpy as np

from map2map.maps.vectorize import draw_plan, render_plan, wall_points

RES = 0.05
FREE, UNK, OCC = 255, 127, 0


def two_faced(beyond: int) -> np.ndarray:
    """A closed room split by a wall seen from both sides as two faces (rows 50-51 and
    58-59, unknown between) with clutter across the band at three places, running on
    ``beyond`` px past both faces into the free space."""
    m = np.full((120, 220), UNK, np.uint8)
    m[10:110, 10:210] = FREE
    m[52:58, 10:210] = UNK
    m[50:52, 10:210] = OCC
    m[58:60, 10:210] = OCC
    for x in (60, 110, 160):
        m[50 - beyond:60 + beyond, x:x + 3] = OCC
    m[10:12, 10:210] = OCC
    m[108:110, 10:210] = OCC
    m[10:110, 10:12] = OCC
    m[10:110, 208:210] = OCC
    return m


def verticals_inside(segs: np.ndarray) -> np.ndarray:
    v = segs[np.abs(segs[:, 0] - segs[:, 2]) < 1e-6]
    return v[(v[:, 0] > 20) & (v[:, 0] < 200)]


def test_a_tick_across_a_wall_seen_as_two_faces_goes():
    m = two_faced(beyond=8)                       # 0.4 m past each face: under min_len
    d = draw_plan(m == OCC, m, RES, 6)
    assert len(verticals_inside(d.segments)) == 0, d.segments
    h = d.segments[np.abs(d.segments[:, 1] - d.segments[:, 3]) < 1e-6]
    mid = h[(h[:, 1] > 45) & (h[:, 1] < 65)]
    assert len(mid) >= 1 and (mid[:, 2] - mid[:, 0]).max() > 190   # the wall is drawn
    assert (d.map[50:60, 20:200] == OCC).all()    # over both faces, one band
    assert (d.map[30:45, 58:66] == FREE).all()    # no tick into the rooms
    assert (d.map[66:80, 58:66] == FREE).all()


def test_a_wall_running_on_past_two_faces_stays():
    m = two_faced(beyond=25)                      # 1.25 m into the room above and below
    d = draw_plan(m == OCC, m, RES, 6)
    assert len(verticals_inside(d.segments)) == 3


def open_hall() -> np.ndarray:
    """A wide hall bounded by unknown (no outer walls: on neither side of the wall line
    is the free space a room by its outline, so the passage is no door), one wall line
    x = 250-252 broken by a passage 40 px wide (rows 45-85) through which the free space
    runs."""
    m = np.full((130, 500), UNK, np.uint8)
    m[5:125, 10:490] = FREE
    m[5:45, 250:253] = OCC
    m[85:125, 250:253] = OCC
    return m


def test_a_wall_is_not_drawn_across_free_space_it_does_not_show():
    m = open_hall()
    d = draw_plan(m == OCC, m, RES, 4)
    assert (d.map[50:80, 249:254] != OCC).all(), d.segments   # the passage stays open
    assert (d.map[10:40, 250:253] == OCC).all()               # both pieces stay
    assert (d.map[90:120, 250:253] == OCC).all()
    assert d.info["cut"] >= 1


def test_a_hole_with_unknown_in_it_is_still_closed():
    m = open_hall()
    m[45:85, 240:262] = UNK                        # nothing seen in the gap: a hole
    d = draw_plan(m == OCC, m, RES, 4)
    assert (d.map[45:85, 250:253] == OCC).all(), d.segments
    assert d.info["cut"] == 0


def test_walls_only_the_input_shows_are_not_drawn():
    """Evidence at two weights (the corrector's walls 1, the input's own pixels 0.1, as
    :class:`~map2map.learn.ba.correctors.DrawnCorrector` hands it over): a run of input
    pixels the corrector dropped as clutter, on no line of the corrector's walls, is
    not drawn; input pixels that continue a corrector's wall still join it."""
    m = np.full((120, 200), FREE, np.uint8)
    main = np.zeros(m.shape, bool)
    main[20:23, 20:120] = True                     # the corrector's wall
    inp = main.copy()
    inp[20:23, 120:180] = True                     # ... the input shows it on to 180
    inp[70:72, 40:140] = True                      # clutter the corrector dropped
    m[inp] = OCC
    p0, p1 = wall_points(main), wall_points(inp)
    pts = np.concatenate([p0, p1])
    w = np.concatenate([np.ones(len(p0)), np.full(len(p1), 0.1)])
    d = draw_plan(pts, m, RES, 3, weights=w)
    h = d.segments[np.abs(d.segments[:, 1] - d.segments[:, 3]) < 1e-6]
    assert len(h) == 1, d.segments
    assert abs(h[0, 1] - 21.5) < 1 and h[0, 0] < 22 and h[0, 2] > 178
    assert (d.map[69:73, 40:140] != OCC).all()
    # the same pixels at one weight (a raster: all of it is the corrector's) are drawn
    d1 = draw_plan(inp, m, RES, 3)
    assert (d1.map[70:72, 45:135] == OCC).all()


def test_the_largest_free_region_stays_free_however_ragged_its_outline():
    """A building's free space on a real map is bounded by unknown along most of its
    outline: it is not a ray fan, and stays free; a small region outside does not."""
    m = np.full((200, 200), UNK, np.uint8)
    m[20:180, 20:180] = FREE
    m[20:100, 20:23] = OCC                         # one wall along 1/8 of the outline
    m[5:15, 100:150] = FREE                        # a fan outside, bounded by unknown
    segs = np.array([[21.5, 20.0, 21.5, 100.0]])
    out = render_plan(segs, m, 3, RES)
    assert (out[30:170, 40:170] == FREE).all()
    assert (out[5:15, 100:150] == UNK).all()
