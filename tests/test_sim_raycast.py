"""Ray casting against an exact geometric reference (slab intersection with wall boxes)."""

import math

import numpy as np
import pytest

from map2map.core.grid import OccupancyMap
from map2map.sim.lidar import Lidar, LidarConfig, Scene
from map2map.sim.raycast import cast_rays, cast_rays_many, make_cast_grid


def reference_cast(solid, x0, y0, angles, max_dist):
    """Analytic: first entry of the ray into any closed unit box of a solid cell."""
    rows, cols = np.nonzero(solid)
    out = np.full(len(angles), np.inf)
    for i, a in enumerate(angles):
        dx, dy = math.cos(a), math.sin(a)
        with np.errstate(divide="ignore", invalid="ignore"):
            if dx != 0:
                t1, t2 = (cols - x0) / dx, (cols + 1 - x0) / dx
                txa, txb = np.minimum(t1, t2), np.maximum(t1, t2)
            else:
                inside = (cols <= x0) & (x0 <= cols + 1)
                txa = np.where(inside, -np.inf, np.inf)
                txb = np.where(inside, np.inf, -np.inf)
            if dy != 0:
                t1, t2 = (rows - y0) / dy, (rows + 1 - y0) / dy
                tya, tyb = np.minimum(t1, t2), np.maximum(t1, t2)
            else:
                inside = (rows <= y0) & (y0 <= rows + 1)
                tya = np.where(inside, -np.inf, np.inf)
                tyb = np.where(inside, np.inf, -np.inf)
        t_in = np.maximum(txa, tya)
        t_out = np.minimum(txb, tyb)
        ok = (t_in <= t_out) & (t_out >= 0)
        if ok.any():
            t = max(float(t_in[ok].min()), 0.0)
            if t <= max_dist:
                out[i] = t
    return out


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_cast_matches_analytic_boxes(seed):
    rng = np.random.default_rng(seed)
    solid = rng.random((60, 80)) < 0.04
    # one-pixel walls: straight, diagonal staircases touching only at corners
    solid[10, 5:70] = True
    solid[:, 40] = True
    for i in range(45):
        solid[12 + i, 20 + i] = True
    field = make_cast_grid(solid)
    free_r, free_c = np.nonzero(~solid)
    pick = rng.choice(len(free_r), 40, replace=False)
    angles = rng.uniform(-np.pi, np.pi, 90)
    for k in pick:
        x0 = free_c[k] + rng.random()
        y0 = free_r[k] + rng.random()
        got = cast_rays(field, x0, y0, angles, 70.0)
        ref = reference_cast(solid, x0, y0, angles, 70.0)
        assert np.array_equal(np.isinf(got), np.isinf(ref))
        fin = np.isfinite(ref)
        np.testing.assert_allclose(got[fin], ref[fin], atol=1e-6)


def test_batch_equals_single_and_outside_origin():
    rng = np.random.default_rng(5)
    solid = rng.random((30, 30)) < 0.05
    field = make_cast_grid(solid)
    rel = np.deg2rad(np.arange(0, 360, 7.0))
    xs, ys, hs = np.array([3.3, -4.0]), np.array([7.7, 12.2]), np.array([0.4, 0.1])
    many = cast_rays_many(field, xs, ys, hs, rel, 50.0)
    for k in range(2):
        one = cast_rays(field, xs[k], ys[k], hs[k] + rel, 50.0)
        np.testing.assert_allclose(many[k], one, atol=1e-9)
        ref = reference_cast(solid, xs[k], ys[k], hs[k] + rel, 50.0)
        assert np.array_equal(np.isinf(many[k]), np.isinf(ref))
        fin = np.isfinite(ref)
        np.testing.assert_allclose(many[k][fin], ref[fin], atol=1e-6)


def test_no_leak_through_diagonal_corners():
    solid = np.zeros((30, 30), bool)
    for i in range(30):
        solid[i, i] = True  # cells touch only at corners
    field = make_cast_grid(solid)
    # from (5.5, 16.5) along (1, -1) the ray passes exactly through the corners
    # between wall cells; it must stop at the corner (11, 11)
    d = cast_rays(field, 5.5, 16.5, np.array([-np.pi / 4]), 100.0)
    assert d[0] == pytest.approx(5.5 * math.sqrt(2), abs=1e-9)


def test_start_inside_solid_is_zero_and_max_dist_respected():
    solid = np.zeros((10, 10), bool)
    solid[5, 5] = True
    solid[:, 9] = True
    field = make_cast_grid(solid)
    assert cast_rays(field, 5.5, 5.5, np.array([0.3]), 10.0)[0] == 0.0
    d = cast_rays(field, 0.5, 0.5, np.array([0.0]), 5.0)
    assert np.isinf(d[0])  # wall at 8.5 px, beyond max_dist 5
    d = cast_rays(field, 0.5, 0.5, np.array([0.0]), 9.0)
    assert d[0] == pytest.approx(8.5)


def test_lidar_metric_frame_and_people():
    data = np.full((80, 100), 255, np.uint8)
    data[0, :] = data[-1, :] = data[:, 0] = data[:, -1] = 0
    m = OccupancyMap(data, 0.05, origin=(-1.0, 2.0, 0.0))
    cfg = LidarConfig(noise_sigma=0.0, p_short=0, p_max=0, p_rand=0, range_max=10.0)
    lidar = Lidar(cfg)
    scene = Scene.from_map(m)
    # robot at pixel centre (row 40, col 30) -> world coordinates
    x, y = (float(v[0]) for v in m.pixel_to_world([40], [30]))
    r = lidar.true_ranges(scene, (x, y, 0.0))
    # east wall face at column 99 -> x = 99 px from origin; robot at 30.5 px
    assert r[0] == pytest.approx((99 - 30.5) * 0.05)
    assert r[90] == pytest.approx((40.5 - 1) * 0.05)  # north (up = row 0 side)
    assert r[180] == pytest.approx((30.5 - 1) * 0.05)
    assert r[270] == pytest.approx((79 - 40.5) * 0.05)
    scene.circles = np.array([[x + 1.0, y, 0.2]])
    r2 = lidar.true_ranges(scene, (x, y, 0.0))
    assert r2[0] == pytest.approx(0.8)
    assert r2[180] == r[180]


def test_lidar_noise_quantised_and_outliers():
    data = np.full((100, 100), 255, np.uint8)
    data[0, :] = data[-1, :] = data[:, 0] = data[:, -1] = 0
    m = OccupancyMap(data, 0.05)
    scene = Scene.from_map(m)
    lidar = Lidar(LidarConfig(p_short=0.1, p_max=0.1, p_rand=0.1))
    scan = lidar.scan(scene, (2.5, 2.5, 0.3), 1.0, np.random.default_rng(0))
    assert scan.ranges.dtype == np.float32 and scan.n_beams == 360
    fin = scan.ranges[np.isfinite(scan.ranges)]
    np.testing.assert_allclose(fin * 1000, np.round(fin * 1000), atol=1e-3)
    assert np.isinf(scan.ranges).sum() > 10  # max-range failures
    again = lidar.scan(scene, (2.5, 2.5, 0.3), 1.0, np.random.default_rng(0))
    assert np.array_equal(scan.ranges, again.ranges)
    half = Lidar(LidarConfig(fov_deg=180))
    assert half.config.n_beams == 181
    assert half.config.angle_min == pytest.approx(-np.pi / 2)


def test_boxed_field_casts_like_the_whole_grid():
    """A plan in a wide unknown canvas (a HouseExpo render): the Scene's field over the
    known cells plus the range gives the whole grid's ranges to the bit, and World's
    clearance and reachable cells (computed on boxes) equal the whole-grid formulas."""
    from scipy import ndimage

    from map2map.sim.world import World

    rng = np.random.default_rng(5)
    data = np.full((400, 380), 127, np.uint8)
    room = np.full((120, 150), 255, np.uint8)
    room[[0, -1], :] = 0
    room[:, [0, -1]] = 0
    room[60, 10:90] = 0
    room[rng.integers(1, 119, 40), rng.integers(1, 149, 40)] = 0
    room[30, 0] = 127  # a gap in the outer wall into the canvas
    data[150:270, 120:270] = room
    plan = OccupancyMap(data, 0.05)
    world = World.build(plan, start=(0.0, 0.0, 0.0), rng=rng)
    whole = Scene(plan, plan.occupied)
    whole._field, whole._reach = make_cast_grid(plan.occupied), math.inf  # the whole grid's
    angles = np.linspace(-math.pi, math.pi, 360, endpoint=False)
    for _ in range(30):
        r, c = rng.integers(151, 269), rng.integers(121, 269)
        if not plan.free[r, c]:
            continue
        x, y = plan.pixel_to_world([r], [c])
        got = world.scene.cast(float(x[0]) + 0.013, float(y[0]), 0.3, angles, 3.5)
        ref = whole.cast(float(x[0]) + 0.013, float(y[0]), 0.3, angles, 3.5)
        assert np.array_equal(got, ref) and np.isfinite(got).sum() > 100
    edt = ndimage.distance_transform_edt(~world.blocked)
    assert np.array_equal(world.clearance, ((edt - 0.5) * 0.05).astype(np.float64))
    ok = world.clearance >= 0.25
    r, c = np.argwhere(ok)[len(np.argwhere(ok)) // 2]
    x, y = plan.pixel_to_world([r], [c])
    start = (float(x[0]), float(y[0]), 0.0)
    lab, _ = ndimage.label(ok)
    yy, xx = np.mgrid[-4:5, -4:5]
    disk = xx**2 + yy**2 <= 4.0**2
    ref = ndimage.binary_dilation(lab == lab[r, c], disk) & ~world.blocked
    assert ref.sum() > 1000
    assert np.array_equal(world.reachable_cells(start, 0.2, 0.05), ref)
