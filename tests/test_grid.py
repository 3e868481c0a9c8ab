import numpy as np
import pytest

from map2map.core.grid import FREE, OCCUPIED, UNKNOWN, OccupancyMap, ternarize


def make_map(h=10, w=14, res=0.1, origin=(1.0, -2.0, 0.0)):
    data = np.full((h, w), FREE, np.uint8)
    data[0, :] = OCCUPIED
    data[-1, 3] = UNKNOWN
    return OccupancyMap(data, res, origin)


def test_masks_partition():
    m = make_map()
    total = m.free.astype(int) + m.occupied + m.unknown
    assert (total == 1).all()
    assert m.occupied.sum() == 14 and m.unknown.sum() == 1


def test_rejects_bad_values_and_resolution():
    with pytest.raises(ValueError):
        OccupancyMap(np.full((3, 3), 10, np.uint8), 0.05)
    with pytest.raises(ValueError):
        OccupancyMap(np.full((3, 3), 255, np.uint8), 0.0)
    with pytest.raises(ValueError):
        OccupancyMap(np.full((3, 3), 255, np.float32), 0.05)


def test_lower_left_pixel_centre_is_origin_plus_half_cell():
    m = make_map()
    x, y = m.pixel_to_world(m.height - 1, 0)
    assert x == pytest.approx(1.0 + 0.05) and y == pytest.approx(-2.0 + 0.05)
    # top-right pixel
    x, y = m.pixel_to_world(0, m.width - 1)
    assert x == pytest.approx(1.0 + 1.4 - 0.05) and y == pytest.approx(-2.0 + 1.0 - 0.05)


@pytest.mark.parametrize("yaw", [0.0, 0.3, -1.2])
def test_world_pixel_round_trip(yaw):
    m = make_map(origin=(0.5, 0.7, yaw))
    rr, cc = np.meshgrid(np.arange(m.height), np.arange(m.width), indexing="ij")
    x, y = m.pixel_to_world(rr, cc)
    r2, c2 = m.world_to_pixel(x, y)
    assert (r2 == rr).all() and (c2 == cc).all()


@pytest.mark.parametrize("yaw", [0.0, 0.7])
def test_crop_and_pad_keep_world_positions(yaw):
    m = make_map(origin=(0.5, 0.7, yaw))
    c = m.crop(2, 7, 3, 11)
    assert np.allclose(c.pixel_to_world(0, 0), m.pixel_to_world(2, 3))
    assert np.allclose(c.pixel_to_world(4, 7), m.pixel_to_world(6, 10))
    assert (c.data == m.data[2:7, 3:11]).all()
    p = m.pad(top=2, bottom=3, left=4, right=1)
    assert p.shape == (m.height + 5, m.width + 5)
    assert np.allclose(p.pixel_to_world(2, 4), m.pixel_to_world(0, 0))
    assert (p.data[:2] == UNKNOWN).all()


def test_content_bbox_and_ternarize():
    data = np.full((8, 8), UNKNOWN, np.uint8)
    data[2:5, 3:7] = FREE
    m = OccupancyMap(data, 0.05)
    assert m.content_bbox() == (2, 5, 3, 7)
    assert ternarize(np.array([10, 127, 250], np.uint8)).tolist() == [OCCUPIED, UNKNOWN, FREE]
