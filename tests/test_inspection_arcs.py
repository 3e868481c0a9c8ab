"""Curved walls in the as-built inspection: an apse is one wall, judged on its curved face.

Hand-made at 0.05 m/px: a hall whose east side is a half circle of radius 3 m (its wall
leaves the straight walls tangentially, as drawn in CAD). Built right, the apse is
observed and within a pixel's noise; built bulging by 15 cm, it fails by about that.
"""

from __future__ import annotations

import csv

import cv2
import numpy as np
import pytest

from map2map.core.grid import FREE, OCCUPIED, UNKNOWN, OccupancyMap
from map2map.evaluate.pipeline import evaluate_maps
from map2map.evaluate.walls import inspect_walls, write_segments_csv
from map2map.maps.curves import circle_arcs

RES = 0.05
ORIGIN = (1.0, -2.0, 0.0)
#: the apse's centre (pixels, continuous) and centre-line radius
CX, CY, R = 180.0, 100.0, 60.0


def _hall(bulge_px: float = 0.0) -> np.ndarray:
    """The hall (walls 2 px): west wall at x 20, north/south at y 40/160, the apse
    beyond x = CX, a partition with a door at x 100; ``bulge_px`` widens the apse."""
    m = np.full((200, 280), UNKNOWN, np.uint8)
    yy, xx = np.mgrid[0:200, 0:280] + 0.5
    r = R + bulge_px
    d = np.hypot(xx - CX, yy - CY)
    inside = ((xx >= 20) & (xx <= CX) & (yy >= 40) & (yy <= 160)) | ((xx > CX) & (d <= r))
    m[inside] = FREE
    wall = (np.abs(d - r) <= 1.0) & (xx > CX)
    m[wall] = OCCUPIED
    # the straight walls meet the apse where it starts (tangentially, built or not)
    m[39:41, 19:int(CX) + 1] = OCCUPIED
    m[159:161, 19:int(CX) + 1] = OCCUPIED
    m[39:161, 19:21] = OCCUPIED
    m[39:85, 99:101] = OCCUPIED
    m[105:161, 99:101] = OCCUPIED
    if bulge_px:                         # the bulge's tangent joins, as built
        for y0, y1 in ((40, 40 - bulge_px), (160, 160 + bulge_px)):
            cv2.line(m, (int(CX) - 1, int(y0)), (int(CX), int(round(y1))), OCCUPIED, 2)
    return m


@pytest.fixture(scope="module")
def plan():
    return OccupancyMap(_hall(), RES, ORIGIN)


def _arc_walls(insp):
    return [s for s in insp.segments if s.shape == "arc"]


def test_circle_arcs_find_the_apse_and_drop_its_chords(plan):
    from map2map.evaluate.walls import _plan_segments

    segs = _plan_segments(plan, 0.4, 0.2)
    arcs, drop = circle_arcs(plan.data == OCCUPIED, RES, segs)
    assert len(arcs) == 1
    xc, yc, r, a0, span = arcs[0]
    assert abs(xc - CX) < 1.5 and abs(yc - CY) < 1.5 and abs(r - R) < 1.0
    assert 150 < np.degrees(span) <= 185
    assert drop.sum() >= 3                     # the chords a line detector cut it into
    assert circle_arcs(plan.data == OCCUPIED, RES, segs)[0].tolist() == arcs.tolist()


def test_an_apse_built_right_is_one_observed_wall_within_its_noise(plan, tmp_path):
    ev = evaluate_maps(OccupancyMap(_hall(), RES, ORIGIN), plan, resolution=RES)
    insp = inspect_walls(ev, plan, tolerance=0.05)
    (apse,) = _arc_walls(insp)
    assert apse.status != "not observed" and apse.coverage > 0.9
    assert apse.deviation_cm < 10.0 and apse.deviation_lo_cm <= 5.0   # not failed
    assert abs(apse.arc_m[2] - R * RES) < 0.05
    assert apse.length_m == pytest.approx(apse.arc_px[4] * apse.arc_px[2] * RES)
    # no straight wall is left along it, and nothing in the plan is unobserved
    assert insp.counts["not observed"] == 0 and insp.counts["fail"] == 0
    # the CSV says which walls are arcs, with their centre and radius
    rows = list(csv.DictReader(open(write_segments_csv(insp, tmp_path / "w.csv"))))
    arc_rows = [r for r in rows if r["shape"] == "arc"]
    assert len(arc_rows) == 1 and float(arc_rows[0]["radius_m"]) == pytest.approx(
        apse.arc_m[2], abs=1e-3)
    assert all(r["radius_m"] == "" for r in rows if r["shape"] == "line")


def test_an_apse_built_bulging_fails_by_its_bulge(plan):
    ev = evaluate_maps(OccupancyMap(_hall(bulge_px=3.0), RES, ORIGIN), plan, resolution=RES)
    (apse,) = _arc_walls(inspect_walls(ev, plan, tolerance=0.05))
    assert apse.status == "fail"
    assert 10.0 < apse.deviation_cm < 25.0          # 15 cm out, less what alignment takes
    assert apse.offset_cm > 5.0                      # outwards: + away from the centre
    loose = _arc_walls(inspect_walls(ev, plan, tolerance=0.30))[0]
    assert loose.status == "pass"


def test_a_dxf_plan_with_an_arc_is_inspected_from_the_command_line(tmp_path):
    """The whole path a user takes: a CAD drawing with an ARC, converted, and
    ``map2map evaluate --report``: the CSV holds the apse as one arc of its radius."""
    import ezdxf

    from map2map.cli.main import main
    from map2map.maps.formats import load_map, save_map

    doc = ezdxf.new(units=6)
    msp = doc.modelspace()
    for a, b in (((0, 0), (8, 0)), ((0, 0), (0, 6)), ((0, 6), (8, 6))):
        msp.add_line(a, b)
    msp.add_arc((8, 3), 3, -90, 90)                    # the apse, radius 3 m
    doc.saveas(tmp_path / "hall.dxf")
    assert main(["convert", str(tmp_path / "hall.dxf"), str(tmp_path / "plan.yaml"),
                 "--resolution", "0.05"]) == 0
    plan = load_map(tmp_path / "plan.yaml")
    save_map(plan.copy(plan.data.copy()), tmp_path / "built.yaml")   # built as drawn
    assert main(["evaluate", str(tmp_path / "built.yaml"), str(tmp_path / "plan.yaml"),
                 "--out", str(tmp_path / "ev"), "--report", "insp.html"]) == 0
    rows = list(csv.DictReader(open(tmp_path / "ev" / "insp.csv")))
    arcs = [r for r in rows if r["shape"] == "arc"]
    assert len(arcs) == 1 and arcs[0]["status"] != "not observed"
    assert float(arcs[0]["radius_m"]) == pytest.approx(3.0, abs=0.05)
    assert float(arcs[0]["centre_x_m"]) == pytest.approx(8.0, abs=0.05)
    assert not any(r["status"] in ("fail", "not observed") for r in rows)
    # the report says the key numbers leave the curve's points out (the metric's corners)
    page = (tmp_path / "ev" / "insp.md").read_text()
    assert "curved or more than 10 degrees off the plan's axes: 1." in page


def _chamfered(shift_px: float = 0.0) -> np.ndarray:
    """A room (walls 2 px) whose north-east corner is cut by a wall at 45 degrees,
    ``shift_px`` further out (perpendicular) as built."""
    m = np.full((200, 260), UNKNOWN, np.uint8)
    d = shift_px * np.sqrt(0.5)
    p0 = (150 + d, 30 - d)          # the chamfer from the north wall ...
    p1 = (230 + d, 110 - d)         # ... to the east wall (x y, continuous)
    poly = np.array([(30, 30), p0, p1, (230, 170), (30, 170)])
    cv2.fillPoly(m, [np.round(poly * 16).astype(np.int32)], FREE, shift=4)
    cv2.polylines(m, [np.round(poly * 16).astype(np.int32)], True, OCCUPIED, 2, shift=4)
    return m


def test_a_wall_at_45_degrees_is_observed_and_judged_on_its_own_face():
    """The metric calls every point of a diagonal wall a corner (its surfaces are
    axis-wise): the wall was "not observed". It takes its evidence by geometry now."""
    plan = OccupancyMap(_chamfered(), RES, ORIGIN)
    right = inspect_walls(evaluate_maps(OccupancyMap(_chamfered(), RES, ORIGIN), plan,
                                        resolution=RES), plan)
    diag = [s for s in right.segments if abs(abs(s.x1_m - s.x0_m) - abs(s.y1_m - s.y0_m))
            < 0.1 and s.length_m > 3]
    assert len(diag) == 1 and diag[0].oblique
    assert sum(s.oblique for s in right.segments) == 1
    assert diag[0].status != "not observed" and diag[0].coverage > 0.9
    assert diag[0].deviation_lo_cm <= 5.0                        # not failed
    assert right.counts["not observed"] == 0 and right.counts["fail"] == 0
    off = inspect_walls(evaluate_maps(OccupancyMap(_chamfered(3.0), RES, ORIGIN), plan,
                                      resolution=RES), plan)
    (moved,) = [s for s in off.segments if s.id == diag[0].id]
    assert moved.status == "fail" and 10.0 < moved.deviation_cm < 25.0
    assert abs(moved.offset_cm) > 8.0


def test_a_solid_block_is_judged_by_its_faces_not_its_medial_axis():
    """A plan whose space between rooms is drawn as solid wall (as HouseExpo plans are
    converted): the segments run along the block's faces, where the map sees walls, not
    diagonally through the block along its skeleton."""
    m = np.full((200, 260), UNKNOWN, np.uint8)
    m[30:170, 30:230] = FREE
    cv2.rectangle(m, (29, 29), (230, 170), OCCUPIED, 2)
    m[100:171, 150:231] = OCCUPIED                    # a 4 x 3.5 m solid block
    plan = OccupancyMap(m, RES, ORIGIN)
    ev = evaluate_maps(OccupancyMap(m.copy(), RES, ORIGIN), plan, resolution=RES)
    insp = inspect_walls(ev, plan)
    slanted = [s for s in insp.segments
               if min(abs(s.x1_m - s.x0_m), abs(s.y1_m - s.y0_m)) > 0.1]
    assert not slanted                                 # no medial-axis diagonals
    x_face = ORIGIN[0] + 150 * RES                    # the block's west face
    faces = [s for s in insp.segments if abs(s.x0_m - x_face) < 0.1
             and abs(s.x1_m - x_face) < 0.1]
    assert faces and all(s.status != "not observed" for s in faces)
    assert insp.counts["fail"] == 0
