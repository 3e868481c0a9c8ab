"""Procedural floor plans: determinism, connectivity for a 0.2 m robot, doors, sizes, closure."""

from __future__ import annotations

import numpy as np
import pytest
from scipy import ndimage

from map2map.core.errors import InputError
from map2map.core.grid import FREE, OCCUPIED, UNKNOWN, OccupancyMap
from map2map.maps.floorplan import connectivity, generate_floorplan

ROBOT = 0.2


def scipy_connectivity(m: OccupancyMap, radius: float = ROBOT) -> tuple[int, int]:
    """Independent check with scipy.ndimage: (components of the eroded free space, unreachable px).

    The eroded free space is every free pixel farther than ``radius`` from any
    non-free pixel. A free pixel is reachable when it lies within
    ``radius * sqrt(2)`` (+ half a pixel) of it: a disc robot reaches no closer
    to a square room corner.
    """
    free = m.data == FREE
    core = ndimage.distance_transform_edt(free) > radius / m.resolution
    _, n = ndimage.label(core)
    away = ndimage.distance_transform_edt(~core)
    unreachable = free & (away > radius / m.resolution * np.sqrt(2) + 0.5)
    return n, int(unreachable.sum())


def leaks(m: OccupancyMap) -> bool:
    """Does an 8-connected flood fill from the border via non-occupied cells reach free space?"""
    open_ = m.data != OCCUPIED
    labels, _ = ndimage.label(open_, structure=np.ones((3, 3), bool))
    border = np.unique(np.r_[labels[0], labels[-1], labels[:, 0], labels[:, -1]])
    border = border[border > 0]
    return bool(np.isin(labels[m.data == FREE], border).any())


# 60 plans across both kinds, random and explicit sizes, resolutions, furniture on/off
CASES = [
    (
        seed,
        ("apartment", "office")[seed % 2],
        None if seed % 3 else ((4.0, 4.0), (6.0, 9.5), (30.0, 20.0), (12.0, 5.0))[seed // 3 % 4],
        (0.05, 0.1, 0.05, 0.025)[seed % 4],
        seed % 5 < 2,
    )
    for seed in range(60)
]


@pytest.fixture(scope="module")
def plans():
    return [(case, generate_floorplan(*case)) for case in CASES]


def test_same_seed_same_bytes():
    a = generate_floorplan(11, "office", furniture=True)
    b = generate_floorplan(11, "office", furniture=True)
    assert a.data.tobytes() == b.data.tobytes()
    assert a.meta == b.meta
    assert (a.resolution, a.origin) == (b.resolution, b.origin) == (0.05, (0.0, 0.0, 0.0))


def test_generator_argument_is_used_and_seeds_differ():
    a = generate_floorplan(1, size=(10, 8))
    b = generate_floorplan(2, size=(10, 8))
    assert a.shape == b.shape and not np.array_equal(a.data, b.data)
    c = generate_floorplan(np.random.default_rng(1), size=(10, 8))
    assert np.array_equal(a.data, c.data)


def test_connectivity_rule_over_many_seeds(plans):
    for case, m in plans:
        n, unreachable = scipy_connectivity(m)
        assert n == 1, f"{case}: free space splits into {n} components for a 0.2 m robot"
        assert unreachable == 0, f"{case}: {unreachable} free pixels unreachable"
        assert connectivity(m).ok


def test_values_and_walls_close_the_building(plans):
    for case, m in plans:
        assert set(np.unique(m.data).tolist()) == {OCCUPIED, UNKNOWN, FREE}, case
        assert not leaks(m), f"{case}: free space reachable from outside"
        # a small unknown margin all around
        assert (m.data[0] == UNKNOWN).all() and (m.data[:, -1] == UNKNOWN).all(), case


def test_rooms_doors_and_sizes(plans):
    for (seed, kind, size, res, _), m in plans:
        meta = m.meta
        rooms = [r for r in meta["rooms"] if r["kind"] == "room"]
        assert len(rooms) >= 3, (seed, kind, size)
        assert meta["doors"], (seed, kind)
        for d in meta["doors"]:
            assert 0.7 - 1e-9 <= d["width"] <= 1.0 + 1e-9, (seed, d)
            # the door centre is free space
            r, c = m.world_to_pixel(d["x"], d["y"])
            assert m.data[r, c] == FREE, (seed, d)
        x0, y0, x1, y1 = meta["building_bbox"]
        w, h = x1 - x0, y1 - y0
        if size is not None:
            assert abs(w - size[0]) <= res and abs(h - size[1]) <= res, (seed, size, w, h)
        else:
            assert 6.0 - res <= min(w, h) and max(w, h) <= 30.0 + res, (seed, kind, w, h)
        # the known content is exactly the building
        r0, r1, c0, c1 = m.content_bbox()
        assert abs((c1 - c0) * res - w) < 1e-6 and abs((r1 - r0) * res - h) < 1e-6
        labels = {r["category"] for r in meta["rooms"]}
        assert labels <= set(meta["room_category"]), seed
        if kind == "office":
            assert "Office" in labels or "Meeting_Room" in labels, labels


def test_walls_are_thick_enough(plans):
    for (seed, _, _, res, _), m in plans[:12]:
        t_in = m.meta["wall_thickness"]["interior"]
        t_out = m.meta["wall_thickness"]["outer"]
        assert t_in >= max(res, 0.1 - res / 2) and t_out >= max(2 * res, 0.2 - res / 2), seed
        # the outer wall: walking in from the margin we cross t_out of occupied cells
        row = m.data[m.height // 2]
        first = int(np.flatnonzero(row != UNKNOWN)[0])
        run = int(np.flatnonzero(row[first:] != OCCUPIED)[0])
        assert run * res >= t_out - 1e-9, seed


def test_furniture_is_inside_rooms_and_keeps_doors_clear():
    m = generate_floorplan(5, "apartment", size=(14, 10), furniture=True)
    bare = generate_floorplan(5, "apartment", size=(14, 10), furniture=False)
    assert m.meta["furniture"], "furniture requested but none placed"
    # furniture only turns free cells into occupied ones: same layout otherwise
    assert m.meta["rooms"] == bare.meta["rooms"] and m.meta["doors"] == bare.meta["doors"]
    assert ((m.data != bare.data) <= ((bare.data == FREE) & (m.data == OCCUPIED))).all()
    assert (m.data == OCCUPIED).sum() > (bare.data == OCCUPIED).sum()
    assert connectivity(m).ok


def test_explicit_wall_thickness_and_kinds():
    m = generate_floorplan(0, "office", size=(20, 12), wall_thickness=(0.15, 0.3))
    assert m.meta["wall_thickness"] == {"interior": 0.15, "outer": 0.3}
    assert any(r["category"] == "Hallway" for r in m.meta["rooms"])


@pytest.mark.parametrize(
    ("kwargs", "message"),
    [
        ({"size": (3.0, 10.0)}, "at least 4"),
        ({"size": (10.0, 0.0)}, "at least 4"),
        ({"resolution": 0.0}, "positive"),
        ({"resolution": -0.05}, "positive"),
        ({"resolution": 0.5}, "between"),
        ({"kind": "castle"}, "unknown building kind"),
        ({"size": "big"}, "two numbers"),
        ({"seed": -1}, "non-negative"),
        ({"seed": 1.5}, "non-negative"),
    ],
)
def test_bad_arguments(kwargs, message):
    kwargs = {"seed": 0, **kwargs}
    with pytest.raises(InputError, match=message):
        generate_floorplan(**kwargs)


def test_connectivity_detects_pockets_and_splits():
    data = np.full((60, 100), UNKNOWN, np.uint8)
    data[5:55, 5:95] = OCCUPIED
    data[10:50, 10:48] = FREE
    data[10:50, 52:90] = FREE
    m = OccupancyMap(data.copy(), 0.05)
    assert connectivity(m).components == 2
    data[20:36, 48:52] = FREE  # a 0.8 m door
    assert connectivity(OccupancyMap(data.copy(), 0.05)).ok
    data[20:23, 48:52] = data[33:36, 48:52] = OCCUPIED  # now 0.5 m: still passable
    assert connectivity(OccupancyMap(data.copy(), 0.05)).ok
    data[10:20, 30:46] = OCCUPIED  # a cabinet leaving a 0.1 m slot against the wall
    res = connectivity(OccupancyMap(data, 0.05))
    assert res.components == 1 and res.unreachable.any()


@pytest.mark.parametrize("kind", ["apartment", "office"])
def test_every_size_from_4_to_30_m(kind):
    sides = (4.0, 5.5, 7.0, 9.0, 13.0, 20.0, 30.0)
    for i, w in enumerate(sides):
        for j, h in enumerate(sides):
            furniture = (i + j) % 2 == 1
            m = generate_floorplan(i * 7 + j, kind, (w, h), resolution=0.1, furniture=furniture)
            n, unreachable = scipy_connectivity(m)
            assert n == 1 and unreachable == 0, (kind, w, h)
            assert sum(r["kind"] == "room" for r in m.meta["rooms"]) >= 3, (kind, w, h)
            assert m.meta["size_m"] == [w, h]


def test_room_boxes_follow_the_houseexpo_convention():
    from map2map.maps.houseexpo import room_labels

    m = generate_floorplan(8, "apartment", size=(11, 8))
    for r in m.meta["rooms"]:
        x0, y0, x1, y1 = r["world_bbox"]
        assert r["bbox"] == [x0, -y1, x1, -y0]
        assert r["bbox"] in m.meta["room_category"][r["category"]]
    labels, names = room_labels(m)  # the HouseExpo reader's helper places them right
    assert names == [r["category"] for r in m.meta["rooms"]]
    for k, r in enumerate(m.meta["rooms"]):
        area = (labels == k + 1).sum() * m.resolution**2
        assert area >= 0.5 * r["area"], (k, r["category"], area, r["area"])
