"""Curved walls in the plan drawer (:mod:`map2map.maps.curves`): a round room's wall is
drawn along its circle; straight walls, drift-bent ones and a single wobble are not."""

from __future__ import annotations

import math

import cv2
import numpy as np
import pytest

from map2map.maps.curves import arc_chords, curved_walls
from map2map.maps.vectorize import DrawOptions, draw_plan, save_plan_dxf

RES = 0.05
FREE, UNK, OCC = 255, 127, 0


def rotunda(size=240, r=70, doors=None, t=2, corridor=True, w=10):
    """A round room of radius ``r`` px (its wall ``t`` px outside it); with
    ``corridor``, corridors ``2 w`` px wide leave it to the four sides between straight
    walls. ``doors``: (angle, half angle) of the wall's gaps (default: the corridors')."""
    m = np.full((size, size), UNK, np.uint8)
    c, ci = size / 2, size // 2
    yy, xx = np.mgrid[0:size, 0:size] + 0.5
    d = np.hypot(xx - c, yy - c)
    ang = np.arctan2(yy - c, xx - c)
    if doors is None:
        half = math.asin(w / r)
        doors = [(a, half) for a in (0.0, math.pi / 2, math.pi, -math.pi / 2)]
    wall = (d >= r) & (d < r + t)
    for a, half in doors:
        wall &= np.abs(np.mod(ang - a + math.pi, 2 * math.pi) - math.pi) > half
    m[d < r] = FREE
    m[wall] = OCC
    if corridor:
        out = d >= r + t
        for lo, hi in ((ci - w - 2, ci - w), (ci + w, ci + w + 2)):
            m[ci - w:ci + w, :][out[ci - w:ci + w, :]] = FREE
            m[:, ci - w:ci + w][out[:, ci - w:ci + w]] = FREE
            m[lo:hi, :][out[lo:hi, :]] = OCC
            m[:, lo:hi][out[:, lo:hi]] = OCC
    return m


def test_arc_chords_stay_within_their_tolerance_of_the_circle():
    ch = arc_chords((50.0, 40.0), 30.0, 0.3, 2.0, sag_tol=0.25)
    mid = (ch[:, :2] + ch[:, 2:]) / 2
    assert np.all(30.0 - np.hypot(mid[:, 0] - 50, mid[:, 1] - 40) <= 0.25 + 1e-9)
    ends = np.concatenate([ch[:, :2], ch[-1:, 2:]])
    assert np.allclose(np.hypot(ends[:, 0] - 50, ends[:, 1] - 40), 30.0)
    assert np.allclose(ch[1:, :2], ch[:-1, 2:])                  # one chain


def test_a_round_room_is_drawn_along_its_circle_and_its_doors_stay_open():
    m = rotunda()
    d = draw_plan(m == OCC, m, RES, 4, cover=m == OCC)
    assert d.info["curved"] > 0
    c = m.shape[0] / 2
    yy, xx = np.mgrid[0:m.shape[0], 0:m.shape[1]] + 0.5
    dist = np.hypot(xx - c, yy - c)
    # every pixel of the input's round wall lies under the drawn wall
    arc = (m == OCC) & (dist < 75)
    assert (d.map[arc] == OCC).mean() > 0.95
    # the drawn round wall keeps the face the room saw: nothing drawn inside it (the
    # corridor walls' ends reach a pixel or two into it where they meet the arcs)
    assert not (d.map[dist < 67] == OCC).any()
    assert (d.map[(dist >= 67) & (dist < 69.5)] == OCC).mean() < 0.02
    # the corridors through the doors stay free
    for y, x in ((c, c + 72), (c + 72, c), (c, c - 72), (c - 72, c)):
        assert d.map[int(y), int(x)] == FREE


def test_the_round_wall_is_in_the_dxf_as_the_raster_draws_it(tmp_path):
    import ezdxf

    m = rotunda()
    d = draw_plan(m == OCC, m, RES, 4, cover=m == OCC)
    world = save_plan_dxf(d, tmp_path / "w.dxf", RES)
    lines = ezdxf.readfile(tmp_path / "w.dxf").modelspace().query("LINE")
    assert len(lines) == len(d.segments) == len(world)
    c = m.shape[0] / 2 * RES
    r_world = np.hypot(world[:, 0] - c, world[:, 1] - c)
    assert ((r_world > 70 * RES) & (r_world < 76 * RES)).sum() > 20   # the chords


def test_off_draws_no_arc():
    m = rotunda()
    d = draw_plan(m == OCC, m, RES, 4, cover=m == OCC, options=DrawOptions(curve_min=0))
    assert d.info["curved"] == 0


@pytest.mark.parametrize("bend", [0.0, 3.0])
def test_straight_and_drift_bent_walls_get_no_arc(bend):
    """A 6 m wall bent by up to 3 px (a particle filter's slow heading drift) stays
    straight."""
    m = np.full((120, 200), UNK, np.uint8)
    m[20:100, 20:180] = FREE
    x = np.arange(20, 180)
    y = np.round(20 + bend * (1 - ((x - 100) / 80.0) ** 2)).astype(int)
    for k in range(2):
        m[y + k, x] = OCC
    m[98:100, 20:180] = OCC
    m[20:100, 20:22] = OCC
    m[20:100, 178:180] = OCC
    d = draw_plan(m == OCC, m, RES, 4, cover=m == OCC)
    assert d.info["curved"] == 0


def test_one_wobble_is_not_a_round_room():
    """A single arc turning 60 degrees (a real map's wavy wall) is not drawn as one."""
    m = rotunda(doors=((math.pi / 2, 2.6),), corridor=False)   # 62 degrees of wall
    chords, _ = curved_walls(m == OCC, m == FREE, RES, 4)
    assert len(chords) == 0
    m = rotunda(doors=((math.pi / 2, 1.4),), corridor=False)   # 200 degrees: an apse
    chords, _ = curved_walls(m == OCC, m == FREE, RES, 4)
    assert len(chords) > 0


def test_a_dotted_round_wall_is_one_arc():
    """Gaps of a pixel are closed (wider ones are not: a real map's wavy walls, joined
    over wider gaps, make arcs of their own)."""
    m = rotunda(corridor=False, doors=())
    c = m.shape[0] / 2
    yy, xx = np.mgrid[0:m.shape[0], 0:m.shape[1]] + 0.5
    ang = np.degrees(np.arctan2(yy - c, xx - c))
    m[(m == OCC) & (np.mod(ang, 6) < 0.8)] = FREE            # gaps of 1 px every 7
    chords, _ = curved_walls(m == OCC, m == FREE, RES, 4)
    mid = (chords[:, :2] + chords[:, 2:]) / 2
    a = np.sort(np.degrees(np.arctan2(mid[:, 1] - c, mid[:, 0] - c)))
    assert np.diff(a).max() < 10                               # no gap left open


def test_drawing_is_deterministic():
    m = rotunda()
    a = draw_plan(m == OCC, m, RES, 4, cover=m == OCC)
    b = draw_plan(m == OCC, m, RES, 4, cover=m == OCC)
    assert np.array_equal(a.segments, b.segments) and np.array_equal(a.map, b.map)
    assert cv2.countNonZero((a.map == OCC).astype(np.uint8)) > 0
