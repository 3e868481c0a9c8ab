"""Direction families of a map's walls (:mod:`map2map.maps.directions`) and the plan
drawer's use of them: a wing that SLAM turned by more than the drawer lets a wall lean is
drawn at its own angle (issue #32)."""

from __future__ import annotations

import cv2
import numpy as np
import pytest

from map2map.maps.directions import angle_families, orientation, sharp_angle, splat
from map2map.maps.vectorize import DrawOptions, dominant_angle, draw_plan, wall_points

RES = 0.05
FREE, UNK, OCC = 255, 127, 0


def _box(m: np.ndarray, cx: float, cy: float, w: float, h: float, deg: float, t: int = 3):
    b = np.round(cv2.boxPoints(((cx, cy), (w, h), deg))).astype(np.int32)
    cv2.fillPoly(m, [b], FREE)
    cv2.polylines(m, [b], True, OCC, t)


def two_wings(deg: float) -> np.ndarray:
    """A room along the grid and, beside it, one turned by ``deg`` degrees."""
    m = np.full((200, 320), UNK, np.uint8)
    _box(m, 80, 100, 120, 150, 0.0)
    _box(m, 225, 100, 140, 120, deg)
    return m


def _coverage(m: np.ndarray, drawn: np.ndarray, px: float = 2.0) -> float:
    """Share of the input's wall pixels within ``px`` of a drawn wall."""
    dist = cv2.distanceTransform((drawn != OCC).astype(np.uint8), cv2.DIST_L2, 3)
    return float((dist[m == OCC] <= px).mean())


def _angles(segs: np.ndarray) -> np.ndarray:
    return np.degrees(np.arctan2(segs[:, 3] - segs[:, 1], segs[:, 2] - segs[:, 0])) % 90


@pytest.mark.parametrize("deg", [8.0, 12.0])
def test_a_wing_turned_beyond_the_lean_is_drawn_at_its_own_angle(deg):
    m = two_wings(deg)
    d = draw_plan(m == OCC, m, RES, 3)
    assert len(d.info["angles"]) == 2
    assert sorted(d.info["angles"]) == pytest.approx([0.0, deg], abs=0.3)
    assert len(d.segments) == 8, d.segments
    ang = np.sort(_angles(d.segments))
    assert np.allclose(ang[:4], 0.0, atol=0.3) and np.allclose(ang[4:], deg, atol=0.5), ang
    assert _coverage(m, d.map) > 0.98
    # with one direction for the whole map the turned wing is drawn across its walls
    one = draw_plan(m == OCC, m, RES, 3, options=DrawOptions(families=1))
    assert one.info["angles"] == [one.angle]
    assert _coverage(m, one.map) < 0.9


@pytest.mark.parametrize("deg", [44.0, 45.0, 30.0])
def test_a_wing_at_45_degrees_is_a_family_of_its_own(deg):
    """Deviations are folded modulo 90 degrees: walls at +44 and -44 degrees are one
    direction, averaged around the circle (a linear average of a 45-degree wing's walls,
    some folded to +45 and some to -45, was 0, and the wing was drawn as dashes)."""
    m = two_wings(deg)
    d = draw_plan(m == OCC, m, RES, 3)
    assert len(d.info["angles"]) == 2
    got = sorted(a % 90 for a in d.info["angles"])
    assert got == pytest.approx(sorted([0.0, deg % 90]), abs=0.5)
    assert _coverage(m, d.map) > 0.97


def test_the_input_walls_decide_the_families_where_the_evidence_lacks_a_wing():
    """A corrector's evidence may hold its walls in the main directions only, the input's
    turned walls at a low weight; the input's own wall pixels (``votes``, the drawer's
    ``cover``) still find the wing."""
    m = two_wings(30.0)
    walls = m == OCC
    pts = wall_points(walls)
    w = np.where(pts[:, 0] < 150, 1.0, 0.02)        # the turned room barely counts
    alone, _ = angle_families(pts, w, m.shape, 0.0, RES)
    assert alone == [0.0]
    angles, label = angle_families(pts, w, m.shape, 0.0, RES,
                                   votes=(pts, np.ones(len(pts))))
    assert len(angles) == 2 and abs(angles[1] % 90 - 30.0) < 0.5
    assert (label[pts[:, 0] > 170] == 1).all() and (label[pts[:, 0] < 130] == 0).all()


def test_a_slight_turn_stays_one_family():
    m = two_wings(3.0)                   # within what a leaning wall follows
    d = draw_plan(m == OCC, m, RES, 3)
    assert len(d.info["angles"]) == 1
    assert _coverage(m, d.map) > 0.95


@pytest.mark.parametrize("seed", range(3))
def test_ragged_walls_at_one_angle_are_one_family(seed):
    rng = np.random.default_rng(seed)
    m = np.full((220, 300), UNK, np.uint8)
    _box(m, 150, 110, 240, 170, 7.0)
    _box(m, 110, 110, 90, 100, 7.0)
    walls = np.argwhere(m == OCC)
    shift = rng.integers(-1, 2, size=walls.shape)              # each pixel moved by +-1
    m[tuple(walls.T)] = FREE
    moved = np.clip(walls + shift, 0, np.array(m.shape) - 1)
    m[tuple(moved.T)] = OCC
    pts = wall_points(m == OCC)
    a0 = dominant_angle(pts)
    angles, label = angle_families(pts, np.ones(len(pts)), m.shape, a0, RES)
    assert angles == [a0] and a0 == pytest.approx(7.0, abs=0.5)
    assert (label == 0).all()


def test_families_are_deterministic_and_labels_follow_the_wings():
    m = two_wings(10.0)
    pts = wall_points(m == OCC)
    w = np.ones(len(pts))
    a = angle_families(pts, w, m.shape, dominant_angle(pts), RES)
    b = angle_families(pts, w, m.shape, dominant_angle(pts), RES)
    assert a[0] == b[0] and np.array_equal(a[1], b[1])
    angles, label = a
    left = pts[:, 0] < 145
    k = int(np.argmin(np.abs(np.asarray(angles))))
    assert (label[left] == k).mean() > 0.95 and (label[~left] != k).mean() > 0.95
    one = angle_families(pts, w, m.shape, dominant_angle(pts), RES, max_families=1)
    assert len(one[0]) == 1 and (one[1] == 0).all()


def test_the_pieces():
    img = np.zeros((40, 40), np.float32)
    img[19:21, 4:36] = 1
    ang, coh = orientation(img)
    assert ang[20, 20] == pytest.approx(0.0, abs=1e-6) and coh[20, 20] > 0
    assert ang[0, 0] == 0.0 and coh[0, 0] == 0.0
    rr, cc = np.nonzero(img)
    pts = np.stack([cc + 0.5, rr + 0.5], 1)
    assert splat(pts, np.ones(len(pts)), img.shape).sum() == len(pts)
    t = np.radians(5.0)
    line = np.stack([np.arange(200.0), 30 + np.arange(200.0) * np.tan(t)], 1)
    assert sharp_angle(line, np.ones(200), 3.0) == pytest.approx(5.0, abs=0.15)


def test_sharpness_of_many_angles_is_each_angle_alone():
    """The angle search scores all candidates in one ``bincount``: bit for bit what each
    angle scored alone gives (the refined angle must not depend on the batching)."""
    from map2map.maps.directions import _sharpness

    rng = np.random.default_rng(3)
    pts = rng.random((700, 2)) * 200
    w = rng.random(700) + 0.1
    cand = 1.7 + np.arange(-3.0, 3.25, 0.5)
    many = _sharpness(pts, w, cand)
    assert many.tolist() == [float(_sharpness(pts, w, [a])[0]) for a in cand]
