"""A building with a wing at 45 degrees: two wall families in the evaluation.

Hand-made at 0.05 m/px: a hall on the axes (10 x 6 m) and a wing 4.5 x 9 m turned by
45 degrees, walls 3 px thick in the plan; the "SLAM map" is the same building in its
own frame (turned by 12 degrees and shifted), only the walls' inner faces. With one dominant
angle, one family's walls read as corners (their normals on the diagonal between the
axes) and were left out of the statistics (55 % of an oracle map's points), and the
alignment's search missed the rotation when the two maps' dominant angles named
different families.
"""

from __future__ import annotations

import math

import cv2
import numpy as np
import pytest
from shapely import affinity
from shapely.geometry import Polygon
from shapely.ops import unary_union

from map2map.core.grid import FREE, OCCUPIED, UNKNOWN, OccupancyMap
from map2map.evaluate.nonrigid import SideFields
from map2map.evaluate.orientation import dominant_orientation, wall_families
from map2map.evaluate.pipeline import evaluate_maps
from map2map.evaluate.walls import _oblique, inspect_walls

RES = 0.05


def _building(wing_deg: float = 45.0):
    hall = Polygon([(0, 0), (10, 0), (10, 6), (0, 6)])
    wing = affinity.rotate(Polygon([(0, 0), (4.5, 0), (4.5, 9), (0, 9)]), wing_deg,
                           origin=(0, 0))
    return unary_union([hall, affinity.translate(wing, 9.2, 4.2)])


def _raster(turn_deg: float, shift: tuple[float, float], faces_only: bool,
            wing_deg: float = 45.0) -> np.ndarray:
    """The building (its wing at ``wing_deg``) turned by ``turn_deg`` about its centre
    and shifted (metres), drawn with 3 px walls (only their inner faces with
    ``faces_only``), free inside, unknown outside."""
    b = affinity.translate(affinity.rotate(_building(wing_deg), turn_deg, origin="centroid"),
                           *shift)
    x0, y0 = -2.0, -2.0
    pts = np.array(b.exterior.coords)
    px = np.round(np.column_stack([(pts[:, 0] - x0) / RES, (pts[:, 1] - y0) / RES])).astype(
        np.int32)
    m = np.full((360, 360), UNKNOWN, np.uint8)
    cv2.fillPoly(m, [px], FREE)
    cv2.polylines(m, [px], True, OCCUPIED, 3)
    if faces_only:  # what a robot inside sees: the walls' inner faces
        free = (m == FREE).astype(np.uint8)
        seen = cv2.dilate(free, np.ones((3, 3), np.uint8)) > 0
        m[(m == OCCUPIED) & ~seen] = UNKNOWN
    return m


@pytest.fixture(scope="module")
def pair():
    plan = OccupancyMap(_raster(0.0, (0.0, 0.0), False), RES, (0.0, 0.0, 0.0))
    slam = OccupancyMap(_raster(12.0, (0.6, -0.4), True), RES, (0.0, 0.0, 0.0))
    return plan, slam


def test_wall_families_finds_the_wing_and_nothing_in_a_plain_building(pair):
    plan, slam = pair
    for m in (plan.data, slam.data):
        theta = dominant_orientation(m)[0]
        fams = wall_families(m, theta)
        assert len(fams) == 2 and fams[0] == theta
        assert 40 < math.degrees(abs(fams[1] - fams[0])) % 90 < 50
    box = np.full((200, 200), UNKNOWN, np.uint8)
    box[40:160, 30:170] = FREE
    cv2.rectangle(box, (30, 40), (170, 160), int(OCCUPIED), 2)
    cv2.line(box, (100, 40), (100, 160), int(OCCUPIED), 2)
    assert wall_families(box, dominant_orientation(box)[0]) == [dominant_orientation(box)[0]]


def test_side_fields_of_two_families_match_a_wing_wall_to_its_own_face(pair):
    plan, _ = pair
    fams = wall_families(plan.data, 0.0)
    one = SideFields.from_map(plan.data, 0.0)
    two = SideFields.from_map(plan.data, 0.0, families=fams)
    assert one.n_sides == 4 and two.n_sides == 8 and len(two.sides) == 8
    d = np.array([[math.cos(math.radians(a)), math.sin(math.radians(a))]
                  for a in (0.0, 45.0, 22.5, 10.0)])
    # one family: a normal at 45 degrees is a corner; two: only near the bisector 22.5
    assert one.corners(d, math.radians(10.0)).tolist() == [False, True, False, False]
    assert two.corners(d, math.radians(10.0)).tolist() == [False, False, True, False]
    assert two.side_groups(d[:2]).tolist() == [0, 4]
    # a point 2 px inside the wing from its long wall u = 4.5 (wing frame), facing into
    # the wing: matched across to that wall's face, not along to a staircase cell
    h = math.sqrt(0.5)
    m_wall = np.array([[9.2 + 4.5 * h - 4.5 * h, 4.2 + 4.5 * h + 4.5 * h]])  # u = 4.5, v = 4.5
    c = (m_wall[0, 0] + 2.0) / RES
    r = (m_wall[0, 1] + 2.0) / RES
    n = np.array([[-math.sqrt(0.5), -math.sqrt(0.5)]])
    p = np.array([[c, r]]) + 2.0 * n
    near, dist, _ = two.nearest(p, n)
    along = float(((near - p) * n).sum())
    assert dist[0] < 4.0 and abs(abs(along) - dist[0]) < 1.0   # across the wall, not along


@pytest.mark.parametrize("wing_deg", [45.0, 30.0])
def test_a_wing_is_aligned_measured_whole_and_not_failed(wing_deg):
    plan = OccupancyMap(_raster(0.0, (0.0, 0.0), False, wing_deg), RES, (0.0, 0.0, 0.0))
    slam = OccupancyMap(_raster(12.0, (0.6, -0.4), True, wing_deg), RES, (0.0, 0.0, 0.0))
    ev = evaluate_maps(slam, plan, resolution=RES)
    r = ev.report
    al = r["alignment"]
    assert al["hypotheses"]["passed"] and not al["warnings"]
    off = [(a - al["families_deg"]["target"][0]) % 90 for a in al["families_deg"]["target"]]
    assert len(off) == 2 and min(abs(off[1] - wing_deg % 90), abs(off[1] - 90 + wing_deg)) < 1
    assert abs(al["rotation_deg"] + 12.0) < 0.5
    e = r["errors"]["rigid"]
    # the wing's walls are measured, not left out as corners (one family: about half)
    assert e["corner_points_excluded"] < 0.2 * e["points_all"]
    assert e["mean_px"] < 1.0 and e["p95_px"] < 2.0
    # built right: no wall fails; a wall off the pixel grid is a staircase in both maps,
    # its interval widened by a whole pixel (5 cm) beyond its own rank interval
    insp = inspect_walls(ev, plan, tolerance=0.05)
    assert not [w for w in insp.segments if w.status == "fail"]
    assert sum(w.status == "not observed" for w in insp.segments) <= 3
    # one segment per wall line: the outline's 8-9 sides (the line detector's pieces of a
    # staircase, 13 and 15 segments with cuts of 0.2-0.4 m, are merged)
    assert len(insp.segments) <= 11
    stair = [w for w in insp.segments if w.status != "not observed" and w.length_m > 1.0
             and 10 < math.degrees(math.atan2(abs(w.y1_m - w.y0_m), abs(w.x1_m - w.x0_m))) < 80]
    assert len(stair) >= 4
    assert all(w.deviation_hi_cm - w.deviation_cm >= 5.0 - 1e-6 for w in stair)


def test_a_wing_at_30_degrees_faces_one_side_per_cell():
    """Rounded to the eight neighbours, the sides at 60 and 150 degrees look below and
    to the left, and a staircase at 30 degrees shows free cells both ways: every face
    of the wing was in two sides, and the plan-corner rule called its points corners."""
    from map2map.evaluate.nonrigid import _family_masks

    plan = _raster(0.0, (0.0, 0.0), False, 30.0)
    fams = wall_families(plan, dominant_orientation(plan)[0])
    masks = _family_masks(plan, fams)
    count = np.sum(masks, axis=0)
    assert count.max() == 1                 # no cell faces two ways (3 px walls)
    surface = (plan == OCCUPIED) & (cv2.dilate((plan == FREE).astype(np.uint8),
                                               np.ones((3, 3), np.uint8)) > 0)
    assert (count[surface] == 1).mean() > 0.95


def test_oblique_walls_are_those_off_every_family():
    segs = np.array([[0.0, 0.0, 40.0, 40.0], [0.0, 0.0, 40.0, 0.0], [0.0, 0.0, 40.0, 20.0]])
    assert _oblique(segs, (0.0,), 10.0).tolist() == [True, False, True]
    assert _oblique(segs, (0.0, math.pi / 4), 10.0).tolist() == [False, False, True]
