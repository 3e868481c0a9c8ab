"""Straight pixel runs (:mod:`map2map.core.runs`): exact for every length, where OpenCV's
opening with an even line kernel shifts the runs by a pixel."""

from __future__ import annotations

import cv2
import numpy as np
import pytest

from map2map.core.runs import open_runs, run_through


def _runs_ref(m: np.ndarray, n: int) -> np.ndarray:
    """Horizontal runs of at least n, one row at a time (the plain definition)."""
    out = np.zeros(m.shape, bool)
    for r, row in enumerate(m != 0):
        c = 0
        while c < len(row):
            if not row[c]:
                c += 1
                continue
            e = c
            while e < len(row) and row[e]:
                e += 1
            out[r, c:e] = e - c >= n
            c = e
    return out


@pytest.mark.parametrize("n", range(1, 14))
def test_open_runs_is_exact_for_every_length(n):
    rng = np.random.default_rng(n)
    m = (rng.random((40, 70)) < 0.75).astype(np.uint8)
    np.testing.assert_array_equal(open_runs(m, n, axis=1), _runs_ref(m, n))
    np.testing.assert_array_equal(open_runs(m.T, n, axis=0), _runs_ref(m, n).T)


def test_opencv_opening_with_an_even_kernel_is_not():
    """The reason for :func:`open_runs`: should OpenCV change this, it can be dropped."""
    m = np.zeros((1, 20), np.uint8)
    m[0, 5:11] = 1
    cv = cv2.morphologyEx(m, cv2.MORPH_OPEN, np.ones((1, 6), np.uint8)) > 0
    assert not np.array_equal(cv, m > 0)
    np.testing.assert_array_equal(open_runs(m, 6, axis=1), m > 0)


def test_run_through_matches_the_runs():
    rng = np.random.default_rng(0)
    m = (rng.random((30, 50)) < 0.6).astype(np.uint8)
    rr, cc = np.nonzero(m)
    got = run_through(m, rr, cc)
    for r, c, g in zip(rr, cc, got, strict=True):
        a = c
        while a > 0 and m[r, a - 1]:
            a -= 1
        b = c
        while b < m.shape[1] - 1 and m[r, b + 1]:
            b += 1
        assert g == b - a + 1


@pytest.mark.parametrize("seed", range(6))
def test_pixels_is_nonzero(seed):
    """``pixels`` lists a mask's pixels exactly as ``np.nonzero`` (order and int64), for
    bool, uint8 (any nonzero value), transposed views, empty and full masks."""
    from map2map.core.runs import pixels

    rng = np.random.default_rng(seed)
    H, W = rng.integers(1, 90, 2)
    m = rng.random((H, W)) < rng.random() * 0.6
    for x in (m, m.astype(np.uint8) * 7, m.T, np.zeros((H, W), bool), np.ones((H, W), bool)):
        want, got = np.nonzero(x), pixels(x)
        assert all(g.dtype == np.int64 and np.array_equal(w, g)
                   for w, g in zip(want, got, strict=True))
