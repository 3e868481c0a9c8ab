"""Thesis 4.1 preprocessing: square/resize, harmonise, thicken, crop; metric frame kept."""

from __future__ import annotations

import numpy as np
import pytest
from scipy import ndimage

from map2map.core.errors import InputError
from map2map.core.grid import FREE, OCCUPIED, UNKNOWN, OccupancyMap
from map2map.maps.floorplan import generate_floorplan
from map2map.maps.preprocess import (
    crop_to_content,
    harmonise,
    preprocess,
    square_resize,
    thicken,
)


def room_map(h=80, w=200, res=0.05, origin=(1.0, -2.0, 0.0)) -> OccupancyMap:
    """A walled room with a 1-pixel interior wall (vertical) and unknown outside."""
    data = np.full((h, w), UNKNOWN, np.uint8)
    data[10 : h - 10, 20 : w - 20] = OCCUPIED
    data[14 : h - 14, 24 : w - 24] = FREE
    data[14 : h - 30, 101] = OCCUPIED  # 1-pixel thin wall
    data[30, 60] = OCCUPIED  # a lone marker pixel
    return OccupancyMap(data, res, origin)


def test_square_resize_keeps_aspect_and_values():
    m = room_map()
    s = square_resize(m, 64)
    assert s.shape == (64, 64)
    assert set(np.unique(s.data).tolist()) <= {OCCUPIED, UNKNOWN, FREE}
    assert s.resolution == pytest.approx(m.resolution * 200 / 64)
    # the known content keeps its aspect ratio (no stretching)
    r0, r1, c0, c1 = m.content_bbox()
    q0, q1, p0, p1 = s.content_bbox()
    assert (q1 - q0) / (p1 - p0) == pytest.approx((r1 - r0) / (c1 - c0), abs=0.08)
    # the content is centred vertically
    assert abs(q0 - (64 - q1)) <= 1


def test_thin_wall_survives_4x_downscale():
    m = room_map()
    m2 = m.copy()
    s = square_resize(m2, 50)  # 200 -> 50: 4x
    # the 1-px wall is at world x of column 101; it must still be a wall in the output
    x, y = m.pixel_to_world(np.arange(16, 50), np.full(34, 101))
    rows, cols = s.world_to_pixel(x, y)
    assert (s.data[rows, cols] == OCCUPIED).all()
    # and it is not smeared: at most 2 output pixels wide along a row
    row = int(rows[len(rows) // 2])
    interior = s.data[row, 10:40]
    assert 1 <= (interior == OCCUPIED).sum() <= 2


def test_square_resize_world_points_keep_content():
    m = generate_floorplan(3, "apartment", size=(12.0, 7.0))
    s = square_resize(m, 128)
    rng = np.random.default_rng(0)
    # sample world points deep inside uniform regions of the original: same class after resize
    rr = rng.integers(0, m.height, 4000)
    cc = rng.integers(0, m.width, 4000)
    k = 2 * int(np.ceil(s.resolution / m.resolution)) + 1
    same = ndimage.maximum_filter(m.data, k) == ndimage.minimum_filter(m.data, k)
    uniform = same[rr, cc]
    x, y = m.pixel_to_world(rr[uniform], cc[uniform])
    r2, c2 = s.world_to_pixel(x, y)
    assert uniform.sum() > 1000
    assert (s.data[r2, c2] == m.data[rr[uniform], cc[uniform]]).mean() > 0.995
    # room metadata in world coordinates stays valid
    assert s.meta["rooms"] == m.meta["rooms"]


def test_upscale_is_nearest():
    a = np.array([[0, 255], [127, 255]], np.uint8)
    assert square_resize(a, 4).tolist() == [
        [0, 0, 255, 255],
        [0, 0, 255, 255],
        [127, 127, 255, 255],
        [127, 127, 255, 255],
    ]


def test_harmonise_houseexpo_and_ros_values():
    img = np.array([[0, 10, 128, 127, 205, 250, 255, 100]], np.uint8)
    assert harmonise(img).tolist() == [[0, 0, 127, 127, 127, 255, 255, 127]]
    rgba = np.zeros((1, 3, 4), np.uint8)
    rgba[0, 0] = (255, 255, 255, 255)
    rgba[0, 1] = (0, 0, 0, 255)
    rgba[0, 2] = (255, 255, 255, 0)  # transparent
    assert harmonise(rgba).tolist() == [[255, 0, 127]]
    m = room_map()
    assert harmonise(m) == m


def test_thicken_widens_walls_by_k():
    m = room_map()
    for k in (1, 2, 3):
        t = thicken(m, k)
        row = t.data[40]
        # the thin wall (col 101) becomes 1 + 2k wide
        assert (row[90:110] == OCCUPIED).sum() == 1 + 2 * k
        # outer walls grow into free space only: the unknown outside is untouched
        assert np.array_equal(t.unknown, m.unknown)
        assert (t.data[40, 20 : 24 + k] == OCCUPIED).all() and t.data[40, 24 + k] == FREE
    grown = thicken(m, 2, into_unknown=True)
    assert grown.unknown.sum() < m.unknown.sum()
    assert thicken(m, 0) == m


def test_crop_to_content_keeps_world_frame():
    m = room_map()
    c = crop_to_content(m, 3)
    assert c.shape == (80 - 20 + 6, 200 - 40 + 6)
    assert np.allclose(c.pixel_to_world(3, 3), m.pixel_to_world(10, 20))
    # a margin larger than the border pads with unknown
    big = crop_to_content(m, 15)
    assert big.shape == (60 + 30, 160 + 30)
    assert np.allclose(big.pixel_to_world(15, 15), m.pixel_to_world(10, 20))
    assert big.unknown[:15].all()
    empty = OccupancyMap(np.full((5, 5), UNKNOWN, np.uint8), 0.1)
    assert crop_to_content(empty, 2) == empty


def test_preprocess_chain():
    m = generate_floorplan(2, "office", size=(20.0, 10.0))
    p = preprocess(m, size=256, thicken=1, crop=True, margin=4)
    assert p.shape == (256, 256)
    assert set(np.unique(p.data).tolist()) == {OCCUPIED, UNKNOWN, FREE}
    # after cropping, the building spans the full width minus the margin
    r0, r1, c0, c1 = p.content_bbox()
    assert c1 - c0 >= 256 - 2 * 5
    # the centre of the building stays where it was
    bx0, by0, bx1, by1 = m.meta["building_bbox"]
    r, c = p.world_to_pixel((bx0 + bx1) / 2, (by0 + by1) / 2)
    assert abs(r - 128) <= 2 and abs(c - 128) <= 2
    arr = preprocess(m.data, size=64)
    assert arr.shape == (64, 64) and arr.dtype == np.uint8


@pytest.mark.parametrize(
    ("call", "message"),
    [
        (lambda m: square_resize(m, 0), "size"),
        (lambda m: preprocess(m, size=-3), "size"),
        (lambda m: thicken(m, -1), "thicken"),
        (lambda m: crop_to_content(m, 1.5), "margin"),
        (lambda m: square_resize(np.zeros((3, 3, 3), np.uint8)), "2-D"),
    ],
)
def test_bad_arguments(call, message):
    with pytest.raises(InputError, match=message):
        call(room_map())


@pytest.mark.parametrize("size", [37, 64, 77, 100])
def test_thin_walls_survive_any_reduction_factor(size):
    rng = np.random.default_rng(size)
    data = np.full((200, 300), FREE, np.uint8)
    cols = rng.choice(np.arange(5, 295), 6, replace=False)
    rows = rng.choice(np.arange(55, 245 - 50), 4, replace=False) - 50
    data[:, cols] = OCCUPIED
    data[rows, :] = OCCUPIED
    m = OccupancyMap(data, 0.02)
    s = square_resize(m, size)
    f = int(np.ceil(300 / size))  # input pixels per output pixel; wall ends may shrink by that
    along_r = np.arange(f, 200 - f, 3)
    along_c = np.arange(f, 300 - f, 3)
    for c in cols:  # every vertical wall is still there, at its world position, along its length
        x, y = m.pixel_to_world(along_r, np.full(along_r.size, c))
        r, cc = s.world_to_pixel(x, y)
        near = np.stack([s.data[r, np.clip(cc + d, 0, size - 1)] for d in (-1, 0, 1)])
        assert (near == OCCUPIED).any(axis=0).all(), (size, c)
    for r0 in rows:
        x, y = m.pixel_to_world(np.full(along_c.size, r0), along_c)
        rr, c = s.world_to_pixel(x, y)
        near = np.stack([s.data[np.clip(rr + d, 0, size - 1), c] for d in (-1, 0, 1)])
        assert (near == OCCUPIED).any(axis=0).all(), (size, r0)
    # and walls do not smear over the free space: free area keeps most of its share
    assert s.free.mean() > 0.5 * m.free.mean() * (200 / 300)
