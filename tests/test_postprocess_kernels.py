"""The numba kernels of Model_BA's post-processing against their plain-numpy references."""

import numpy as np
import pytest

from map2map.core.grid import FREE, OCCUPIED, UNKNOWN
from map2map.learn.postprocess import (
    _faces_kernel,
    _paint_walls,
    _surface_masks,
    anchored_walls,
)

pytest.importorskip("torch")
from map2map.learn.autocorrect import dominant_angle  # noqa: E402


def _face(mask, top, offset, min_cover):
    """The plain-numpy reference (the code the kernel replaced): median position
    (+ ``offset``) of the first (``top``) or last face pixel of each column of ``mask``,
    or None when under ``min_cover`` of the columns have one."""
    has = mask.any(0)
    if has.sum() < min_cover * max(1, mask.shape[1]):
        return None
    idx = np.argmax(mask, 0) if top else mask.shape[0] - 1 - np.argmax(mask[::-1], 0)
    return offset + int(np.round(np.median(idx[has])))


def _noisy_map(rng, size=64):
    g = rng.choice(np.array([FREE, UNKNOWN, OCCUPIED], np.uint8), (size, size),
                   p=[0.6, 0.2, 0.2])
    g[rng.integers(0, size, 6)] = OCCUPIED  # some full rows and columns: long faces
    g[:, rng.integers(0, size, 6)] = OCCUPIED
    return g


@pytest.mark.parametrize("seed", range(6))
def test_faces_kernel_matches_reference(seed):
    rng = np.random.default_rng(seed)
    g = _noisy_map(rng)
    H, W = g.shape
    up, dn, lf, rt = _surface_masks(g)
    n = 200
    horiz = rng.random(n) < 0.5
    c = rng.integers(-3, H + 3, n).astype(float)
    lo = rng.integers(-5, W, n)
    hi = np.maximum(0, lo + rng.integers(0, 40, n))  # segments end inside the map
    band = rng.choice([1.0, 2.5, 3.0, 6.0])
    lim = np.where(horiz, H, W)
    a = np.maximum(0, np.floor(c - band)).astype(np.int64)
    b = np.minimum(lim - 1, np.ceil(c + band)).astype(np.int64)
    ok = a <= b
    horiz, c, lo, hi, a, b = horiz[ok], c[ok], lo[ok], hi[ok], a[ok], b[ok]
    for cover in (0.0001, 0.3, 0.9):
        got = _faces_kernel(up, dn, lf, rt, horiz, a, b, lo, hi, cover)
        for k in range(len(horiz)):
            span = slice(max(0, lo[k]), min(W if horiz[k] else H, hi[k] + 1))
            if horiz[k]:
                first, last = up[a[k]:b[k] + 1, span], dn[a[k]:b[k] + 1, span]
            else:
                first, last = lf[span, a[k]:b[k] + 1].T, rt[span, a[k]:b[k] + 1].T
            for side, m, top in ((0, first, True), (1, last, False)):
                want = _face(m, top, int(a[k]), cover) if m.any() else None
                assert got[k, side] == (-1 if want is None else want), (k, side)


def test_paint_walls_matches_slices():
    rng = np.random.default_rng(3)
    free = rng.random((40, 50)) < 0.5
    n = 60
    horiz = rng.random(n) < 0.5
    r0 = rng.integers(-4, 45, n)
    r1 = r0 + rng.integers(-2, 5, n)
    lo = rng.integers(-4, 50, n)
    hi = lo + rng.integers(-2, 20, n)
    stop = rng.random(n) < 0.5
    got = np.zeros((40, 50), bool)
    _paint_walls(got, free, horiz, r0, r1, lo, hi, stop)
    want = np.zeros((40, 50), bool)
    for k in range(n):
        across = slice(max(0, r0[k]), max(0, r1[k] + 1))
        along = slice(max(0, lo[k]), max(0, hi[k] + 1))
        box = (across, along) if horiz[k] else (along, across)
        if stop[k]:
            want[box] |= ~free[box]
        else:
            want[box] = True
    np.testing.assert_array_equal(got, want)


def test_anchored_walls_seen_from_both_sides_and_one():
    g = np.full((30, 40), UNKNOWN, np.uint8)
    g[5:25, 5:35] = FREE
    g[14:17, 5:35] = OCCUPIED              # seen from both sides: rows 14..16
    g[5:14, 20] = OCCUPIED                 # a vertical wall, one pixel thick
    m, c = anchored_walls(g, np.array([[5.0, 15.0, 34.0, 15.0], [20.0, 5.0, 20.0, 13.0]]),
                          band=3, wall_px=2)
    assert set(np.nonzero(m[:, 10])[0].tolist()) == {14, 15, 16}
    assert m[8, 20] and c.shape == (2, 4)


@pytest.mark.parametrize("angle", [0.0, 7.0, 20.0, -33.0])
def test_dominant_angle_matches_the_complex_formula(angle):
    import cv2

    img = np.full((160, 160), FREE, np.uint8)
    cv2.rectangle(img, (40, 50), (120, 110), 0, 2)
    cv2.line(img, (80, 50), (80, 110), 0, 1)
    rot = cv2.warpAffine(img, cv2.getRotationMatrix2D((80, 80), angle, 1), (160, 160),
                         flags=cv2.INTER_NEAREST, borderValue=FREE)
    occ = cv2.GaussianBlur((rot == OCCUPIED).astype(np.float32), (0, 0), 2.0)
    gx = cv2.Sobel(occ, cv2.CV_32F, 1, 0, ksize=3).astype(float)
    gy = cv2.Sobel(occ, cv2.CV_32F, 0, 1, ksize=3).astype(float)
    mag = np.hypot(gx, gy)
    z = np.sum(mag * np.exp(4j * np.arctan2(gy, gx)))
    a, coh = dominant_angle(rot)
    assert a == pytest.approx(np.degrees(np.angle(z) / 4), abs=1e-6)
    assert coh == pytest.approx(abs(z) / mag.sum(), abs=1e-7)
    assert a == pytest.approx(-angle if angle <= 45 else 0, abs=1.5)


def test_autocorrect_many_same_with_any_number_of_threads():
    from map2map.core.grid import OccupancyMap
    from map2map.learn.autocorrect import autocorrect_many

    rng = np.random.default_rng(5)
    maps = []
    for k in range(5):
        g = np.full((120 + 10 * k, 150), UNKNOWN, np.uint8)
        r0, c0 = rng.integers(5, 20, 2)
        g[r0:r0 + 90, c0:c0 + 110] = FREE
        g[r0:r0 + 90, [c0, c0 + 109, c0 + 50 + k]] = OCCUPIED
        g[[r0, r0 + 89], c0:c0 + 110] = OCCUPIED
        maps.append(OccupancyMap(g, 0.05))
    maps.append(OccupancyMap(np.full((40, 40), UNKNOWN, np.uint8), 0.05))  # nothing known
    with pytest.warns(UserWarning):
        one = autocorrect_many(maps, workers=1)
    with pytest.warns(UserWarning):
        three = autocorrect_many(maps, workers=3)
    for a, b in zip(one, three, strict=True):
        np.testing.assert_array_equal(a.map.data, b.map.data)
        np.testing.assert_array_equal(a.segments, b.segments)
        assert a.warnings == b.warnings
