"""SLAM grids that grow as the robot goes (issue #35, item 2): tiles on first touch,
shared between particles until written, and the memory check of ``map2map slam``."""

from __future__ import annotations

import numpy as np
import pytest

from map2map.cli.main import main
from map2map.robotlog.base import LaserScan, OdometryReading
from map2map.robotlog.carmen import CarmenLog, write_carmen
from map2map.slam.gridmap import TILE, CountGrid, TilePool
from map2map.slam.offline import (
    BASE_BYTES,
    backend_options,
    map_tiles_estimate,
    memory_estimate,
    run_slam,
)

ANGLES = np.deg2rad(np.arange(0.0, 360.0, 1.0))


def _scan(g: CountGrid, x: float, y: float, rng, reach=4.0) -> None:
    r = rng.uniform(0.3, reach, ANGLES.size)
    r[rng.random(ANGLES.size) < 0.1] = np.inf
    g.register_scan((x, y, rng.uniform(-np.pi, np.pi)), r, ANGLES, 3.0, 3.5, True)


def _snapshot(g: CountGrid):
    return tuple(a.copy() for a in g.counts()), g.to_occupancy_map().data.copy()


def _same(a, b) -> bool:
    return all(np.array_equal(x, y) for x, y in zip(a[0], b[0], strict=True)) and np.array_equal(
        a[1], b[1]
    )


def test_grid_grows_along_a_long_path_without_holding_its_bounding_box():
    g = CountGrid.around(0.0, 0.0, 2.0, 0.05)
    rng = np.random.default_rng(0)
    path = [(x, -0.4 * x) for x in np.arange(0.0, 300.0, 2.0)]  # 300 m east, 120 m south
    for x, y in path:
        _scan(g, x, y, rng)
    m = g.to_occupancy_map()
    r, c = m.world_to_pixel(np.array([p[0] for p in path]), np.array([p[1] for p in path]))
    assert (m.data[r, c] == 255).all()  # every pose of the path is mapped free
    bbox_tiles = (m.shape[0] // TILE) * (m.shape[1] // TILE)
    assert g.n_tiles < bbox_tiles / 10  # tiles along the path, not its bounding box
    assert g.pool.capacity < 1.3 * g.n_tiles + 100


def test_growth_towards_negative_cells_keeps_the_ros_origin():
    """The map's origin is the world corner of its lower-left pixel, wherever the grid grew."""
    g = CountGrid.around(0.0, 0.0, 2.0, 0.05)
    g.register_scan((-50.0, -30.0, 0.0), np.full(360, 1.02), ANGLES, usable_range=3.0)
    m = g.to_occupancy_map()
    h, _ = m.shape
    x, y = m.pixel_to_world(np.array([h - 1]), np.array([0]))
    assert np.allclose([x[0] - 0.025, y[0] - 0.025], m.origin[:2])
    rows, cols = np.nonzero(m.data == 0)
    wx, wy = m.pixel_to_world(rows, cols)
    d = np.hypot(wx + 50.0, wy + 30.0)
    assert rows.size > 100 and np.all(np.abs(d - 1.02) < 0.08)  # the ring, where it was
    r, c = m.world_to_pixel(np.array([-50.0]), np.array([-30.0]))
    assert m.data[r[0], c[0]] == 255
    assert g.tx0 < 0 and g.ty0 < 0  # the table grew towards negative tiles


def test_copies_share_tiles_and_never_leak_writes():
    rng = np.random.default_rng(3)
    a = CountGrid.around(0.0, 0.0, 10.0, 0.05)
    _scan(a, 0.0, 0.0, rng)
    b = a.copy()
    assert a.pool is b.pool and a.pool.used == a.n_tiles  # shared, not copied
    before_a = _snapshot(a)
    _scan(b, 0.5, 0.2, rng)  # b writes where a has tiles: b copies them first
    assert _same(_snapshot(a), before_a)
    before_b = _snapshot(b)
    _scan(a, -0.4, 0.3, rng)
    assert _same(_snapshot(b), before_b) and not _same(_snapshot(a), before_a)
    shared = int(((a.table == b.table) & (a.table >= 0)).sum())
    assert 0 <= shared < a.n_tiles
    b.release()
    assert a.pool.used == a.n_tiles and (a.pool.refs[a.table[a.table >= 0]] == 1).all()


def test_pool_growth_in_place_keeps_every_tile():
    rng = np.random.default_rng(5)
    small = CountGrid.around(0.0, 0.0, 2.0, 0.05, pool=TilePool(1))
    big = CountGrid.around(0.0, 0.0, 2.0, 0.05, pool=TilePool(4000))
    for k in range(40):
        seed = rng.integers(1 << 30)
        _scan(small, 0.7 * k, 0.3 * k, np.random.default_rng(seed))
        _scan(big, 0.7 * k, 0.3 * k, np.random.default_rng(seed))
    assert small.pool.capacity < 4000  # it grew
    assert np.array_equal(small.to_occupancy_map().data, big.to_occupancy_map().data)


def _corridor_log(length=120.0, step=0.25):
    """A robot driving a 2 m wide corridor with posts every 3 m, far past the first grid."""
    scans, odo = [], []
    angles = np.deg2rad(np.arange(-90.0, 90.0, 1.0))
    for k, x in enumerate(np.arange(0.0, length, step)):
        a = angles
        with np.errstate(divide="ignore"):
            side = np.where(np.sin(a) != 0, 1.0 / np.abs(np.sin(a)), np.inf)
        r = np.minimum(side, 8.0)
        # posts: bumps in range every 3 m of corridor make x observable
        wall_x = x + r * np.cos(a)
        r = np.where((np.mod(wall_x, 3.0) < 0.3) & (np.abs(np.sin(a)) > 0.2), r - 0.2, r)
        scans.append(LaserScan(0.2 * k, r.astype(np.float32), -np.pi / 2, np.pi / 180, 0.0, 20.0))
        odo.append(OdometryReading(0.2 * k, x, 0.0, 0.0))
    return CarmenLog(odo, scans)


@pytest.mark.parametrize("backend", ["rbpf", "graph"])
def test_a_log_far_beyond_the_first_grid_maps_whole_and_the_same_twice(backend):
    log = _corridor_log()
    kw = {"particles": 5} if backend == "rbpf" else {}  # the growth, not the filter, is tested
    a = run_slam(log, backend, seed=4, **kw)
    b = run_slam(log, backend, seed=4, **kw)
    assert np.array_equal(a.map.data, b.map.data) and a.map.origin == b.map.origin
    traj = a.trajectory[:, 1:3]
    assert traj[:, 0].max() > 100.0  # the initial grid is 20 m wide
    r, c = a.map.world_to_pixel(traj[:, 0], traj[:, 1])
    assert (a.map.data[r, c] == 255).mean() > 0.95  # the whole path lies in mapped space
    # the estimate checked before mapping covers the tiles the run allocated
    planned = memory_estimate(log, backend, **backend_options(log, backend, **kw)) - BASE_BYTES
    assert 0 < a.mapper.memory_bytes() <= planned


def test_memory_estimate_grows_with_the_path_not_its_bounding_box():
    log = _corridor_log(60.0)
    long = _corridor_log(120.0)
    t1, t2 = map_tiles_estimate(log, 0.05, 8.0), map_tiles_estimate(long, 0.05, 8.0)
    assert 1.6 < t2 / t1 < 2.4
    assert memory_estimate(long, "rbpf", particles=30) > memory_estimate(long, "rbpf", particles=5)


def test_slam_refuses_past_max_memory_with_the_way_out(tmp_path, capsys):
    log = tmp_path / "long.log"
    write_carmen(log, [(o, s, None) for o, s in _corridor_log(40.0)])
    out = tmp_path / "out"
    rc = main(["slam", str(log), "--out", str(out), "--max-memory", "0.1", "--quiet"])
    assert rc == 2 and not out.exists()
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and "Traceback" not in err
    assert "long.log" in err and "would need about" in err and "--max-memory" in err
    assert "--resolution" in err and "--particles" in err and "--backend graph" in err
    rc = main(["slam", str(log), "--out", str(out), "--max-memory", "0", "--quiet"])
    assert rc == 0 and (out / "map.pgm").is_file()


def test_a_map_larger_than_the_figure_is_drawn_reduced(tmp_path, monkeypatch):
    import map2map.jobs.slam as job
    import map2map.maps.render as render
    from map2map.core.grid import OccupancyMap
    from map2map.slam.offline import SlamResult

    seen = []
    reduce = render.display_map
    monkeypatch.setattr(job, "FIGURE_MAX_PIXELS", 100)
    monkeypatch.setattr(render, "display_map", lambda m, n: seen.append(n) or reduce(m, n))
    data = np.full((400, 300), 255, np.uint8)
    data[:, 150] = 0
    res = SlamResult(OccupancyMap(data, 0.05), np.zeros((1, 4)), np.zeros((1, 4)), None, "rbpf")
    paths = job.write_slam_outputs(res, tmp_path)
    assert seen == [100] and paths[-1].is_file()


def test_an_unbounded_usable_range_maps_up_to_the_farthest_reading():
    g = CountGrid.around(0.0, 0.0, 2.0, 0.05)
    r = np.full(360, 2.0)
    r[::7] = np.inf  # no returns, skipped (no_return_free off)
    g.register_scan((0.0, 0.0, 0.0), r, ANGLES, np.inf, 5.0, False)
    m = g.to_occupancy_map()
    rows, cols = np.nonzero(m.data == 0)
    wx, wy = m.pixel_to_world(rows, cols)
    assert rows.size > 200 and np.all(np.abs(np.hypot(wx, wy) - 2.0) < 0.08)
