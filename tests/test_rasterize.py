"""Exact rasterisation: scanline fill at pixel centres and 4-connected line traces."""

import numpy as np
import pytest
import shapely
from matplotlib.path import Path as MplPath
from scipy import ndimage as ndi

from map2map.maps.rasterize import fill_exact, segment_pixels, trace


def centres(shape):
    rows, cols = np.mgrid[0 : shape[0], 0 : shape[1]]
    return np.stack([cols.ravel() + 0.5, rows.ravel() + 0.5], axis=1)


@pytest.mark.parametrize("seed", range(6))
def test_fill_matches_point_in_polygon_at_every_centre(seed):
    rng = np.random.default_rng(seed)
    shape = (37, 45)
    # a random star-shaped polygon with vertices off the grid, some of it off the raster
    angles = np.sort(rng.uniform(0, 2 * np.pi, 12))
    radii = rng.uniform(5, 25, 12)
    ring = np.stack([22 + radii * np.cos(angles), 18 + radii * np.sin(angles)], axis=1)
    got = fill_exact(shape, [ring])
    expect = MplPath(ring).contains_points(centres(shape)).reshape(shape)
    assert np.array_equal(got, expect)


def test_fill_even_odd_holes_and_nonzero_union():
    outer = np.array([[2.0, 2.0], [20.0, 2.0], [20.0, 14.0], [2.0, 14.0]])
    hole = np.array([[6.0, 6.0], [12.0, 6.0], [12.0, 10.0], [6.0, 10.0]])
    m = fill_exact((16, 24), [outer, hole])
    assert m.sum() == 18 * 12 - 6 * 4 and not m[8, 8] and m[3, 3]
    a = shapely.box(1.2, 1.7, 9.3, 8.1)
    b = shapely.box(5.4, 3.3, 14.9, 12.6)
    rings = [np.asarray(shapely.orient_polygons(g).exterior.coords) for g in (a, b)]
    union = fill_exact((16, 24), rings, rule="nonzero")
    expect = shapely.contains_xy(shapely.union(a, b), *centres((16, 24)).T).reshape(16, 24)
    assert np.array_equal(union, expect)
    assert (fill_exact((16, 24), rings) != union).sum() > 0  # even-odd leaves the overlap out


def test_fill_of_nothing_and_of_degenerate_rings():
    assert not fill_exact((4, 4), []).any()
    assert not fill_exact((4, 4), [np.array([[0.0, 1.0], [3.0, 1.0], [1.0, 1.0]])]).any()


@pytest.mark.parametrize("seed", range(5))
def test_segment_pixels_is_an_exact_4_connected_supercover(seed):
    rng = np.random.default_rng(seed)
    p0, p1 = rng.uniform(0, 20, (2, 2))
    rows, cols = segment_pixels(p0[None], p1[None])
    got = set(zip(rows.tolist(), cols.tolist(), strict=True))
    t = np.linspace(0, 1, 200001)
    pts = p0 + t[:, None] * (p1 - p0)
    crossed = set(
        zip(
            np.floor(pts[:, 1]).astype(int).tolist(),
            np.floor(pts[:, 0]).astype(int).tolist(),
            strict=True,
        )
    )
    assert crossed <= got and len(got - crossed) <= 2
    mask = trace((21, 21), [np.array([p0, p1])])
    assert ndi.label(mask)[1] == 1  # 4-connected
