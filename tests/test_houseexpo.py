"""HouseExpo plans: thin walls survive at 5 cm, doors stay open, rooms, frame, bad input."""

import json

import numpy as np
import pytest
from scipy import ndimage as ndi
from skimage.graph import MCP_Geometric

from map2map.core.errors import InputError
from map2map.maps.houseexpo import (
    houseexpo_to_world,
    load_houseexpo,
    rasterise_houseexpo,
    room_labels,
)


def geodesic(m, rc):
    """Shortest free-space path lengths (metres) from pixel ``rc`` to every pixel."""
    costs = np.where(m.free, 1.0, np.inf)
    d, _ = MCP_Geometric(costs, fully_connected=True).find_costs([tuple(int(v) for v in rc)])
    return d * m.resolution


def plan_pixel(m, x, y):
    """Pixel of plan coordinates (x, y)."""
    wx, wy = houseexpo_to_world(x, y)
    r, c = m.world_to_pixel(wx, wy)
    return int(r), int(c)


def path_length(m, a, b):
    return float(geodesic(m, plan_pixel(m, *a))[plan_pixel(m, *b)])


def plan(verts):
    v = np.asarray(verts, float)
    return {"verts": v.tolist(), "bbox": {"min": v.min(0).tolist(), "max": v.max(0).tolist()}}


# A 4 x 3 m flat split by a 1 cm thick wall from y = 0 up to y = 2 (a 1 m opening above it).
SLIT = plan([[0, 0], [2.0, 0], [2.0, 2.0], [2.01, 2.0], [2.01, 0], [4, 0], [4, 3], [0, 3]])
# A 5 x 4 m flat with a 1 cm slanted wall from (2, 0) to (3, 2).
SLANTED = plan([[0, 0], [2.0, 0], [3.0, 2.0], [3.01, 2.0], [2.01, 0], [5, 0], [5, 4], [0, 4]])
# The same flat as SLIT with a wall of zero width (the polygon touches itself: invalid).
ZERO = plan([[0, 0], [2.0, 0], [2.0, 2.0], [2.0, 0], [4, 0], [4, 3], [0, 3]])


@pytest.mark.parametrize(
    "doc, a, b, detour",
    [
        (SLIT, (1.0, 1.0), (3.0, 1.0), 2.0 * np.hypot(1.0, 1.0)),
        (SLANTED, (1.0, 0.5), (4.5, 0.5), np.hypot(2.0, 1.5) + np.hypot(1.5, 1.5)),
        (ZERO, (1.0, 1.0), (3.0, 1.0), 2.0 * np.hypot(1.0, 1.0)),
    ],
    ids=["1cm-slit", "1cm-slanted-slit", "zero-width-slit"],
)
def test_wall_thinner_than_a_pixel_survives(doc, a, b, detour):
    fine = rasterise_houseexpo(doc, resolution=0.005)
    coarse = rasterise_houseexpo(doc, resolution=0.05)
    # at 5 mm the path goes round the end of the wall ...
    assert path_length(fine, a, b) > 0.97 * detour
    # ... and at 5 cm too: the wall has no hole (8-connected paths included)
    assert path_length(coarse, a, b) > 0.97 * detour
    assert path_length(coarse, a, b) < 1.1 * detour + 0.2  # the opening stays open
    # plain centre sampling loses the wall: the test above would catch it
    if doc is not ZERO:
        plain = rasterise_houseexpo(doc, resolution=0.05, thin_walls=False)
        assert path_length(plain, a, b) < 0.9 * detour


def test_rooms_stay_free_and_walls_keep_true_width():
    # a 20 cm wall between x = 2 and 2.2 at 5 cm is four pixels, not thickened
    doc = plan([[0, 0], [2, 0], [2, 2], [2.2, 2], [2.2, 0], [4, 0], [4, 3], [0, 3]])
    m = rasterise_houseexpo(doc, resolution=0.05, margin=0.0)
    r = plan_pixel(m, 1.0, 1.0)[0]
    row = m.data[r]
    walls = np.flatnonzero(row == 0)
    inner = walls[(walls > 2) & (walls < m.width - 3)]
    assert len(inner) == 4
    assert int(m.free.sum()) == round((4 * 3 - 0.2 * 2) / 0.05**2)


def test_free_space_never_touches_unknown():
    doc = plan([[0, 0], [3, 0], [3, 2], [0, 2]])  # the polygon IS the bounding box
    m = rasterise_houseexpo(doc, resolution=0.05)
    near_free = ndi.binary_dilation(m.free, np.ones((3, 3), bool))
    assert not (near_free & m.unknown).any()
    assert m.free.sum() == 60 * 40


def test_frame_matches_houseexpo_renders_and_world():
    doc = plan([[1, 1], [3, 1], [3, 2], [1, 2]])
    m = rasterise_houseexpo(doc, resolution=0.1, margin=0.2)
    # rows grow with plan y (like HouseExpo's renders): plan (1.05, 1.05) is the first
    # free pixel after the 2-pixel margin
    assert plan_pixel(m, 1.05, 1.05) == (2, 2) and m.free[2, 2] and not m.free[1, 2]
    x, y = m.pixel_to_world(2, 2)
    assert np.allclose(houseexpo_to_world(x, y), (1.05, 1.05))
    assert houseexpo_to_world(1.0, 2.0, 0.3) == (1.0, -2.0, -0.3)


def test_room_labels_prefer_the_smaller_box_and_survive_crop():
    doc = plan([[0, 0], [4, 0], [4, 3], [0, 3]])
    doc["room_category"] = {"Living_Room": [[-0.5, -0.5, 4.5, 3.5]], "Kitchen": [[3, 2, 4, 3]]}
    doc["id"], doc["room_num"] = "abc", 2
    m = rasterise_houseexpo(doc, resolution=0.1)
    assert m.meta["houseexpo_id"] == "abc" and m.meta["room_num"] == 2
    labels, names = room_labels(m)
    assert names == ["Living_Room", "Kitchen"]
    assert (labels[m.free] > 0).all() and (labels[~m.free] == 0).all()
    assert labels[plan_pixel(m, 3.5, 2.5)] == 2 and labels[plan_pixel(m, 1, 1)] == 1
    assert (labels == 2).sum() == 100
    cropped = m.crop(5, m.height, 5, m.width)
    lc, _ = room_labels(cropped)
    assert np.array_equal(lc, labels[5:, 5:])


def test_load_from_file(tmp_path):
    path = tmp_path / "p.json"
    path.write_text(json.dumps(SLIT))
    m = load_houseexpo(path, resolution=0.1)
    assert m.resolution == 0.1 and m.meta["source"] == str(path)


@pytest.mark.parametrize(
    "content, message",
    [
        ("{not json", "not valid JSON"),
        ('{"bbox": {"min": [0, 0], "max": [1, 1]}}', "no 'verts'"),
        ('{"verts": [[0, 0], [1, 0]]}', "at least 3 distinct vertices"),
        ('{"verts": [[0, 0], [1, 0], [0, 0]]}', "at least 3 distinct vertices"),
        ('{"verts": [[0, 0], [1, 0], [2, 0]]}', "encloses no area"),
        ('{"verts": "abc"}', "list of [x, y] pairs"),
        ("[1, 2, 3]", "expected a JSON object"),
    ],
)
def test_bad_plans(tmp_path, content, message):
    path = tmp_path / "bad.json"
    path.write_text(content)
    with pytest.raises(InputError) as err:
        load_houseexpo(path)
    assert message in str(err.value) and str(path) in str(err.value)


def test_missing_file_and_bad_resolution(tmp_path):
    with pytest.raises(InputError, match="file not found"):
        load_houseexpo(tmp_path / "nothing.json")
    with pytest.raises(InputError, match="resolution must be > 0"):
        rasterise_houseexpo(SLIT, resolution=0)


# ------------------------------------------------------------------ real HouseExpo plans
def test_real_plans_keep_every_wall_at_5cm(shared_data):
    """1 cm vs 5 cm rasterisation of every shipped HouseExpo plan.

    (a) every 1 cm wall pixel bordering free space lies within one 5 cm pixel of a 5 cm
    wall pixel; (b) free space has the same number of components; (c) geodesic distances
    agree: no shortcut through a wall (would mean a hole), no detour (a closed door).
    """
    files = sorted((shared_data / "houseexpo" / "json").glob("*.json"))
    assert files
    for path in files:
        fine = load_houseexpo(path, resolution=0.01)
        coarse = load_houseexpo(path, resolution=0.05)
        # (a) wall presence
        wall_edge = fine.occupied & ndi.binary_dilation(fine.free, np.ones((3, 3), bool))
        rr, cc = np.nonzero(wall_edge)
        x, y = fine.pixel_to_world(rr, cc)
        r5, c5 = coarse.world_to_pixel(x, y)
        near_wall = ndi.binary_dilation(coarse.occupied, np.ones((3, 3), bool))
        assert near_wall[r5, c5].all(), path.name
        # (b) components
        n_fine = ndi.label(fine.free, np.ones((3, 3)))[1]
        n_coarse = ndi.label(coarse.free, np.ones((3, 3)))[1]
        assert n_fine == n_coarse == 1, path.name
        # (c) geodesic distances from two seeds well inside free space
        inner = np.argwhere(ndi.distance_transform_edt(coarse.free) >= 3)
        rng = np.random.default_rng(0)
        rr, cc = np.nonzero(coarse.free)
        x, y = coarse.pixel_to_world(rr, cc)
        r1, c1 = fine.world_to_pixel(x, y)
        on_fine = fine.free[r1, c1]
        for seed in inner[rng.choice(len(inner), 2, replace=False)]:
            d5 = geodesic(coarse, seed)[rr, cc]
            sx, sy = coarse.pixel_to_world(*seed)
            d1 = geodesic(fine, fine.world_to_pixel(sx, sy))[r1, c1]
            ok = on_fine & np.isfinite(d1)
            assert np.isfinite(d5[ok]).all(), path.name
            assert (d5[ok] >= d1[ok] - 0.15).all(), path.name  # no hole in any wall
            assert (d5[ok] <= 1.1 * d1[ok] + 0.25).all(), path.name  # no door closed
