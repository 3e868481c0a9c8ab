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


def _arc_points(e, n=200):
    """Points along a DXF ARC entity (world units)."""
    a0, a1 = e.dxf.start_angle, e.dxf.end_angle
    a = np.radians(a0 + np.linspace(0.0, np.mod(a1 - a0, 360.0), n))
    (x, y, _), r = e.dxf.center, e.dxf.radius
    return np.stack([x + r * np.cos(a), y + r * np.sin(a)], 1)


@pytest.mark.parametrize("origin", [(0.0, 0.0, 0.0), (1.5, -2.0, 0.7)])
def test_the_round_wall_is_in_the_dxf_as_arcs_on_the_raster_chords(tmp_path, origin):
    """Each arc is one DXF ARC, within the chords' tolerance of the chords the raster
    draws (in any map frame); the straight walls stay lines."""
    import ezdxf

    from map2map.core.geometry import point_segment_distances

    m = rotunda()
    d = draw_plan(m == OCC, m, RES, 4, cover=m == OCC)
    assert len(d.arcs) == 4 and set(d.arc_of[d.arc_of >= 0]) == {0, 1, 2, 3}
    world = save_plan_dxf(d, tmp_path / "w.dxf", RES, origin=origin)
    msp = ezdxf.readfile(tmp_path / "w.dxf").modelspace()
    assert len(msp.query("LINE")) == (d.arc_of < 0).sum()
    arcs = msp.query("ARC")
    assert len(arcs) == 4
    chords = world[d.arc_of >= 0]
    for e in arcs:
        dist, _ = point_segment_distances(_arc_points(e), chords)
        assert dist.min(axis=1).max() <= 0.25 * RES + 1e-6          # on the raster's chords
    # together the arcs hold every chord (none left out)
    pts = np.concatenate([_arc_points(e) for e in arcs])
    ends = np.concatenate([chords[:, :2], chords[:, 2:]])
    dist, _ = point_segment_distances(ends, np.concatenate([pts[:-1], pts[1:]], 1))
    assert dist.min(axis=1).max() < 1e-3 + RES


def test_arc_walls_with_a_width_bulge_along_the_circle_and_load_back(tmp_path):
    """With the thickness as width, an arc is a polyline whose bulges follow the circle;
    the DXF loader draws it back where the raster has the wall."""
    import ezdxf

    from map2map.maps.dxf import load_dxf

    m = rotunda()
    d = draw_plan(m == OCC, m, RES, 4, cover=m == OCC)
    save_plan_dxf(d, tmp_path / "w.dxf", RES, width=True)
    polys = ezdxf.readfile(tmp_path / "w.dxf").modelspace().query("LWPOLYLINE")
    bulged = [p for p in polys if any(abs(b) > 0 for *_, b in p.get_points("xyb"))]
    assert len(bulged) == 4
    back = load_dxf(tmp_path / "w.dxf", resolution=RES, wall_thickness=4 * RES)
    c = m.shape[0] / 2 * RES
    x0, y0 = back.pixel_to_world(*np.nonzero(back.data == OCC))
    r = np.hypot(x0 - c, y0 - c)
    ring = (r > 60 * RES) & (r < 75 * RES)
    # the round wall comes back around the drawn centre line (the face the room saw at
    # 70 px, grown outwards by the thickness)
    assert ring.sum() > 500
    assert np.abs(np.median(r[ring]) / RES - np.median(d.arcs[:, 2])) < 0.5
    assert ((r[ring] / RES > 69.5) & (r[ring] / RES < 74.5)).mean() > 0.9


def test_a_closed_circle_is_a_dxf_circle(tmp_path):
    import ezdxf

    from map2map.maps.dxf import save_segments_dxf

    save_segments_dxf(np.zeros((0, 4)), tmp_path / "c.dxf",
                      arcs=np.array([[1.0, 2.0, 3.0, 10.0, 360.0]]))
    (e,) = ezdxf.readfile(tmp_path / "c.dxf").modelspace()
    assert e.dxftype() == "CIRCLE" and e.dxf.radius == 3.0
    save_segments_dxf(np.zeros((0, 4)), tmp_path / "c.dxf", width=0.2,
                      arcs=np.array([[1.0, 2.0, 3.0, 10.0, 360.0]]))
    (e,) = ezdxf.readfile(tmp_path / "c.dxf").modelspace()
    assert e.dxftype() == "LWPOLYLINE" and e.closed and len(e) == 4


def test_the_autocorrect_dxf_holds_the_arcs(tmp_path):
    """``map2map autocorrect --dxf`` writes the round room as arcs, in the map's frame."""
    import ezdxf

    from map2map.core.grid import OccupancyMap
    from map2map.jobs.autocorrect import AutocorrectSpec, autocorrect
    from map2map.maps.formats import save_map

    save_map(OccupancyMap(rotunda(), RES, (-3.0, 4.0, 0.0)), tmp_path / "r.yaml")
    run = autocorrect(AutocorrectSpec(tmp_path / "r.yaml", tmp_path / "o.yaml",
                                      dxf=tmp_path / "o.dxf"))
    r = run.corrections[0]
    assert len(r.arcs) == 4
    arcs = ezdxf.readfile(tmp_path / "o.dxf").modelspace().query("ARC")
    assert len(arcs) == 4
    cx, cy = -3.0 + 120 * RES, 4.0 + 120 * RES
    for e in arcs:
        assert math.hypot(e.dxf.center[0] - cx, e.dxf.center[1] - cy) < 3 * RES
        assert abs(e.dxf.radius - 72 * RES) < 3 * RES


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
    chords = curved_walls(m == OCC, m == FREE, RES, 4).chords
    assert len(chords) == 0
    m = rotunda(doors=((math.pi / 2, 1.4),), corridor=False)   # 200 degrees: an apse
    chords = curved_walls(m == OCC, m == FREE, RES, 4).chords
    assert len(chords) > 0


def test_a_dotted_round_wall_is_one_arc():
    """Gaps of a pixel are closed (wider ones are not: a real map's wavy walls, joined
    over wider gaps, make arcs of their own)."""
    m = rotunda(corridor=False, doors=())
    c = m.shape[0] / 2
    yy, xx = np.mgrid[0:m.shape[0], 0:m.shape[1]] + 0.5
    ang = np.degrees(np.arctan2(yy - c, xx - c))
    m[(m == OCC) & (np.mod(ang, 6) < 0.8)] = FREE            # gaps of 1 px every 7
    chords = curved_walls(m == OCC, m == FREE, RES, 4).chords
    mid = (chords[:, :2] + chords[:, 2:]) / 2
    a = np.sort(np.degrees(np.arctan2(mid[:, 1] - c, mid[:, 0] - c)))
    assert np.diff(a).max() < 10                               # no gap left open


def test_drawing_is_deterministic():
    m = rotunda()
    a = draw_plan(m == OCC, m, RES, 4, cover=m == OCC)
    b = draw_plan(m == OCC, m, RES, 4, cover=m == OCC)
    assert np.array_equal(a.segments, b.segments) and np.array_equal(a.map, b.map)
    assert cv2.countNonZero((a.map == OCC).astype(np.uint8)) > 0


def _bent_quarter(m, step=14.0, dent=3.0):
    """``m`` (a :func:`rotunda`) with its south-east arc redrawn as chords of ``step``
    degrees, every other one dented ``dent`` px inwards at its start: runs too short
    and straight to fit a circle alone, cut at corners (a stretch SLAM bent)."""
    c = m.shape[0] / 2
    yy, xx = np.mgrid[0:m.shape[0], 0:m.shape[1]] + 0.5
    ang = np.degrees(np.arctan2(yy - c, xx - c))
    d = np.hypot(xx - c, yy - c)
    q = (ang > 5) & (ang < 85) & (d > 60) & (d < 85)
    m[q & (m == OCC)] = UNK
    a = np.radians(np.arange(9, 82, step).tolist() + [81])
    pts = np.stack([c + 70 * np.cos(a), c + 70 * np.sin(a)], 1)
    for i in range(len(pts) - 1):
        p0 = pts[i] - (dent if i % 2 else 0) * (pts[i] - c) / 70
        cv2.line(m, tuple(np.round(p0 - 0.5).astype(int).tolist()),
                 tuple(np.round(pts[i + 1] - 0.5).astype(int).tolist()), OCC, 2)
    m[(d < 69) & q & (m == UNK)] = FREE
    return m


def test_a_round_rooms_bent_arc_is_completed_from_runs_too_short_alone():
    """The fourth arc of a round room, in runs no circle fits alone (short, straight,
    cut at dents' corners), is drawn along its own circle once the room is found; the
    corridors' straight walls beside the room are not made arcs (four in all)."""
    from map2map.maps import curves

    m = _bent_quarter(rotunda())
    cw = curved_walls(m == OCC, m == FREE, RES, 4)
    assert len(cw.arcs) == 4
    se = cw.arcs[np.argmin(np.abs(np.mod(cw.arcs[:, 3] + cw.arcs[:, 4] / 2, 2 * math.pi)
                                  - math.pi / 4))]
    assert np.degrees(se[4]) > 50                       # most of the quarter
    assert abs(se[2] - 72) < 3                          # the room's radius, grown outwards
    # without the completion the room has three arcs
    orig = curves._completed
    try:
        curves._completed = lambda *a, **k: []
        assert len(curved_walls(m == OCC, m == FREE, RES, 4).arcs) == 3
    finally:
        curves._completed = orig
