"""The SLAM-error statistics of issue #33 (:mod:`map2map.experiments.realism.slam_errors`),
each on hand-made maps: plans of square rooms with 2 px walls drawn with numpy, maps
made from them by hand (a wall saved twice, a room turned, free space cut off, rays)."""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy import ndimage
from skimage.draw import line, polygon

from map2map.core.grid import FREE, OCCUPIED, UNKNOWN
from map2map.experiments.realism.slam_errors import (
    SLAM_ERROR_STATS,
    doubled_walls,
    frontier,
    room_rotation,
    room_rotations,
    slam_error_stats,
    streak_components,
    streaks,
)


def _room(n=100, lo=10, hi=90, t=2) -> np.ndarray:
    """A square room: walls ``t`` px thick from ``lo`` to ``hi`` (exclusive), unknown
    outside. Default: walls at rows / columns 10-11 and 88-89, free 12..87."""
    p = np.full((n, n), UNKNOWN, np.uint8)
    p[lo:hi, lo:hi] = OCCUPIED
    p[lo + t:hi - t, lo + t:hi - t] = FREE
    return p


def _turned_room(out, centre, half, deg, t=2):
    """Draw a square room of outer half-size ``half`` turned by ``deg`` (positive: +x
    towards +y) about ``centre`` (row, col) into ``out``."""
    a = np.radians(deg)
    for h, v in ((half, OCCUPIED), (half - t, FREE)):
        x, y = np.array([-h, h, h, -h]), np.array([-h, -h, h, h])
        rr, cc = polygon(centre[0] + np.sin(a) * x + np.cos(a) * y,
                         centre[1] + np.cos(a) * x - np.sin(a) * y, out.shape)
        out[rr, cc] = v
    return out


def _two_rooms(deg_right=0.0) -> np.ndarray:
    out = np.full((100, 200), UNKNOWN, np.uint8)
    _turned_room(out, (50, 50), 36, 0.0)
    return _turned_room(out, (50, 150), 36, deg_right)


def test_equal_map_scores_no_error():
    plan = _room()
    s = slam_error_stats(plan, plan)
    assert list(s) == list(SLAM_ERROR_STATS)
    assert s["doubled"] == 0.0 and s["room_rot"] == 0.0
    assert s["frontier_open"] == 0.0 and s["streaks"] == 0.0
    assert math.isnan(s["frontier_rough"])                  # a closed room: no open edge
    with pytest.raises(ValueError):
        slam_error_stats(plan[:50], plan)


def test_doubled_wall_scores_its_share_and_a_thick_wall_none():
    plan = _room()
    twice = plan.copy()
    twice[15:17, 12:88] = OCCUPIED          # the top wall (rows 10-11) again, 4 px lower
    share, info = doubled_walls(twice, plan, profiles=True)
    top = np.isin(info["rows"], (10, 11))
    dbl = info["observed"] & (info["runs"] >= 2)
    assert dbl[top].all() and not dbl[~top].any()            # exactly the top wall's pixels
    assert share == pytest.approx(top.sum() / info["observed"].sum())
    assert share == pytest.approx(0.25, abs=0.02)            # one of four equal walls
    thick = plan.copy()
    thick[12:16, 12:88] = OCCUPIED                           # top wall 6 px thick
    assert doubled_walls(thick, plan) == 0.0
    far = plan.copy()
    far[22:24, 12:88] = OCCUPIED                             # 12 px off: outside the window
    assert doubled_walls(far, plan) == 0.0
    gap1 = plan.copy()
    gap1[13:15, 12:88] = OCCUPIED                            # 1 px gap: one ragged wall
    assert doubled_walls(gap1, plan) == 0.0


def test_doubled_counts_observed_walls_and_not_a_corridor():
    plan = _room()
    half = plan.copy()
    half[:, 50:] = np.where(half[:, 50:] == OCCUPIED, UNKNOWN, half[:, 50:])
    half[15:17, 12:50] = OCCUPIED                            # top wall doubled where seen
    share, info = doubled_walls(half, plan, profiles=True)
    assert info["observed"].sum() < 0.75 * len(info["observed"])   # unseen walls left out
    assert share > 0.25                                      # a larger share of fewer pixels
    blank = np.where(plan == OCCUPIED, UNKNOWN, plan).astype(np.uint8)
    assert math.isnan(doubled_walls(blank, plan))
    corridor = plan.copy()
    corridor[40:42, 12:88] = OCCUPIED
    corridor[47:49, 12:88] = OCCUPIED                        # two plan walls 5 px apart
    corridor[42:47, 12:88] = FREE
    assert doubled_walls(corridor, corridor) == 0.0


def test_room_rotation_of_one_turned_room():
    plan = _two_rooms()
    labels, angles, cells = room_rotations(plan, plan)
    assert len(labels) == 2 and np.all(angles == 0.0)
    turned = _two_rooms(5.0)
    labels, angles, cells = room_rotations(turned, plan)
    assert len(labels) == 2
    # the left room is the plan's own, the right one turned by +5 degrees
    by_room = dict(zip(labels.tolist(), angles.tolist(), strict=True))
    from map2map.learn.ab.room_drift import segment_rooms

    rooms = segment_rooms(plan, fill=False)
    lab_left, lab_right = int(rooms[50, 50]), int(rooms[50, 150])
    assert by_room[lab_left] == 0.0
    assert by_room[lab_right] == pytest.approx(5.0, abs=1.0)
    w = dict(zip(labels.tolist(), cells.tolist(), strict=True))
    expect = abs(by_room[lab_right]) * w[lab_right] / (w[lab_left] + w[lab_right])
    assert room_rotation(turned, plan) == pytest.approx(expect)
    assert 2.0 < room_rotation(turned, plan) < 3.0           # ~5 deg on about half the walls
    assert room_rotation(_two_rooms(-5.0), plan) == pytest.approx(room_rotation(turned, plan),
                                                                  abs=0.5)


def test_room_rotation_needs_observed_walls():
    plan = _two_rooms()
    only_left = plan.copy()
    only_left[:, 100:] = UNKNOWN
    only_left[14, 120:150] = OCCUPIED         # 30 cells of its top wall: too few for a room
    labels, _, cells = room_rotations(only_left, plan)
    assert len(labels) == 1 and cells[0] >= 40
    nothing = np.where(plan == OCCUPIED, UNKNOWN, plan).astype(np.uint8)
    assert math.isnan(room_rotation(nothing, plan))


def test_room_rotation_compares_only_the_walls_the_map_saw():
    """A plan room with a slanted wall (25 deg) the map never saw: the plan's orientation
    is taken from the walls near the map's (-4.2 deg off with all the plan's walls)."""
    plan = np.full((100, 100), UNKNOWN, np.uint8)
    rr, cc = polygon([12, 12, 39, 87, 87], [12, 30, 87, 87, 12], plan.shape)
    free = np.zeros(plan.shape, bool)
    free[rr, cc] = True
    plan[ndimage.binary_dilation(free, iterations=2)] = OCCUPIED
    plan[free] = FREE
    seen = plan.copy()
    rows, cols = np.indices(plan.shape)
    seen[(seen == OCCUPIED) & (rows < 42) & (cols > 28)] = UNKNOWN   # the slanted wall
    assert room_rotation(plan, plan) == 0.0
    assert abs(room_rotation(seen, plan)) < 0.5


def test_frontier_of_a_straight_cut():
    plan = _room()
    cut = plan.copy()
    cut[:, 60:] = UNKNOWN          # free 12..87 x 12..59, its right edge in the open
    op, rough = frontier(cut)
    # border: 2 x 48 (rows 12, 87) + 2 x 74 (columns 12, 59) = 244 px; open: column 59,
    # rows 14..85 (rows 12-13 and 86-87 are within 2 px of the walls' ends)
    assert op == pytest.approx(72 / 244)
    assert rough == 1.0
    rr, cc = np.mgrid[:100, :100]
    slanted = plan.copy()
    slanted[(cc - 60) * np.cos(0.5) + (rr - 50) * np.sin(0.5) >= 0] = UNKNOWN
    op2, rough2 = frontier(slanted)
    assert 0.2 < op2 < 0.4 and rough2 == pytest.approx(1.0, abs=0.05)


def test_frontier_of_a_ragged_cut():
    plan = _room()
    rng = np.random.default_rng(0)
    ragged = plan.copy()
    ends = 60 + rng.integers(-3, 4, 76)                      # each row ends +-3 px about 60
    cols = np.arange(100)[None]
    ragged[12:88][cols >= ends[:, None]] = UNKNOWN
    ragged[10:12, 64:] = ragged[88:90, 64:] = UNKNOWN
    op, rough = frontier(ragged)
    assert rough > 1.3
    straight = plan.copy()
    straight[:, 60:] = UNKNOWN
    assert op > frontier(straight)[0]                        # a ragged edge is longer


def test_streaks_count_drawn_rays():
    plan = _room()
    cut = plan.copy()
    cut[:, 60:] = UNKNOWN
    assert streaks(cut) == 0.0
    rays = cut.copy()
    for r in (20, 35, 50, 65):                               # four 1 px rays, 16 px long
        rays[r, 60:76] = FREE
    rr, cc = line(80, 59, 70, 75)                            # a fifth, slanted
    rays[rr, cc] = FREE
    rays[40:44, 60:64] = FREE                                # a short stub: no streak
    lab, streak = streak_components(rays)
    assert int(streak.sum()) == 5
    assert streaks(rays) == pytest.approx(5 * 1e4 / np.count_nonzero(rays == FREE))
    fat = cut.copy()
    fat[20:27, 60:80] = FREE                                 # 7 px wide: survives the opening
    assert streaks(fat) == 0.0


def test_streaks_through_a_closed_wall():
    plan = _room()
    m = plan.copy()
    for r in (30, 50, 70):                                   # rays through gaps in the wall
        m[r, 88:98] = FREE
    lab, streak = streak_components(m)
    assert int(streak.sum()) == 3
    fo, _ = frontier(m)
    assert fo > 0.0                                          # the rays are open frontier


def test_empty_maps_give_nan_not_errors():
    unknown = np.full((40, 40), UNKNOWN, np.uint8)
    free = np.full((40, 40), FREE, np.uint8)
    s = slam_error_stats(unknown, free)                      # nothing mapped, no plan wall
    assert all(math.isnan(v) for v in s.values())
    s = slam_error_stats(free, free)     # all free: the square's edge borders the unknown
    assert math.isnan(s["doubled"]) and math.isnan(s["room_rot"])
    assert s["frontier_open"] == 1.0 and s["frontier_rough"] == 1.0 and s["streaks"] == 0.0
