"""CountGrid.copy into a spare grid copies only the blocks that differ, and is exact."""

from __future__ import annotations

import numpy as np

from map2map.slam.gridmap import TILE, CountGrid

ANGLES = np.deg2rad(np.arange(0.0, 360.0, 1.0))


def _scan(g: CountGrid, x: float, y: float, rng) -> None:
    r = rng.uniform(0.3, 4.0, ANGLES.size)
    r[rng.random(ANGLES.size) < 0.1] = np.inf
    g.register_scan((x, y, rng.uniform(-np.pi, np.pi)), r, ANGLES, 3.0, 3.5, True)


def _same(a: CountGrid, b: CountGrid) -> bool:
    arrays = ("hits", "visits", "sx", "sy")
    same = all(np.array_equal(getattr(a, k), getattr(b, k)) for k in arrays)
    return same and np.array_equal(a.mean, b.mean, equal_nan=True) and (a.x0, a.y0) == (b.x0, b.y0)


def test_copy_into_a_diverged_grid_equals_a_full_copy():
    rng = np.random.default_rng(3)
    a = CountGrid.around(0.0, 0.0, 10.0, 0.05)
    _scan(a, 0.0, 0.0, rng)
    b = a.copy()  # common history
    for k in range(6):  # both go on, apart
        _scan(a, 0.5 * k, 0.2, rng)
        _scan(b, -0.4 * k, 6.0, rng)
    differ = int((a.tile_id != b.tile_id).sum())
    assert 0 < differ < a.tile_id.size  # some blocks are shared, some are not
    full = a.copy()
    into = a.copy(out=b)
    assert into is b and _same(into, full) and _same(into, a)
    # a block far from every scan was not touched and keeps its shared id
    assert a.tile_id[0, 0] == into.tile_id[0, 0]
    # the copy goes on independently of its source
    _scan(into, 1.0, 1.0, rng)
    assert not _same(into, a)


def test_copy_after_growth_and_into_a_grid_of_another_shape():
    rng = np.random.default_rng(4)
    a = CountGrid.around(0.0, 0.0, 3.0, 0.05)
    b = a.copy()
    _scan(a, 2.5, 0.0, rng)  # near the edge: a grows
    assert a.shape != b.shape
    c = a.copy(out=b)  # shapes differ: a new grid, b untouched
    assert c is not b and _same(c, a)
    d = CountGrid.around(0.0, 0.0, 8.0, 0.05)
    _scan(d, 0.0, 0.0, rng)
    e = CountGrid.around(0.0, 0.0, 8.0, 0.05)  # same shape, independent ids: all copied
    assert (d.tile_id != e.tile_id).all() and _same(d.copy(out=e), d)
    assert d.tile_id.shape == (-(-d.shape[0] // TILE), -(-d.shape[1] // TILE))
