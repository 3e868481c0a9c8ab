"""The numba kernels of Model_BA's post-processing against their plain-numpy references."""

import numpy as np
import pytest

from map2map.core.grid import FREE, OCCUPIED, UNKNOWN
from map2map.learn.ba.anchor import anchored_walls
from map2map.learn.ba.faces import faces_kernel, paint_walls, surface_masks

pytest.importorskip("torch")
from map2map.learn.ba.squares import dominant_angle  # noqa: E402


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
    up, dn, lf, rt = surface_masks(g)
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
        got, _ = faces_kernel(up, dn, lf, rt, horiz, a, b, lo, hi, cover, np.zeros(len(a)))
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
    paint_walls(got, free, horiz, r0, r1, lo, hi, stop, np.zeros(n))
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


def _tilted_reference(g, horiz, a, b, lo, hi, slope):
    """Plain-numpy faces along tilted lines: per position j the band rows shifted by
    round(slope (j - m)); the median offset of the first/last face pixel (rounded half to
    even), and the slope of a straight line through them."""
    H, W = g.shape
    up, dn, lf, rt = surface_masks(g)
    mid = (lo + hi) / 2
    first, last = [], []
    for j in range(max(0, lo), min(W if horiz else H, hi + 1)):
        sh = int(np.round(slope * (j - mid)))
        i0, i1 = max(0, a + sh), min((H if horiz else W) - 1, b + sh)
        f = up[i0:i1 + 1, j] if horiz else lf[j, i0:i1 + 1]
        la = dn[i0:i1 + 1, j] if horiz else rt[j, i0:i1 + 1]
        if f.any():
            first.append((j - mid, i0 + int(np.argmax(f)) - a - sh))
        if la.any():
            last.append((j - mid, i0 + len(la) - 1 - int(np.argmax(la[::-1])) - a - sh))
    return first, last


@pytest.mark.parametrize("seed", range(4))
def test_faces_kernel_tilted_matches_reference(seed):
    rng = np.random.default_rng(10 + seed)
    g = _noisy_map(rng, 80)
    n = 60
    horiz = rng.random(n) < 0.5
    c = rng.integers(4, 76, n).astype(float)
    lo = rng.integers(0, 60, n)
    hi = lo + rng.integers(5, 40, n)
    band = 3.0
    a = np.maximum(0, np.floor(c - band)).astype(np.int64)
    b = np.minimum(79, np.ceil(c + band)).astype(np.int64)
    slope = rng.uniform(-0.1, 0.1, n)
    up, dn, lf, rt = surface_masks(g)
    got, fit = faces_kernel(up, dn, lf, rt, horiz, a, b, lo, hi, 0.0001, slope)
    for k in range(n):
        first, last = _tilted_reference(g, horiz[k], a[k], b[k], lo[k], hi[k], slope[k])
        for side, pts in ((0, first), (1, last)):
            want = -1 if not pts else a[k] + int(np.round(np.median([p[1] for p in pts])))
            assert got[k, side] == want, (k, side)
        assert fit[k, 1] <= len(first) + len(last)


def test_line_fit_trims_outliers():
    from map2map.learn.ba.faces import _line_fit

    x = np.arange(40, dtype=float)
    y = 0.05 * x + 3.0
    y[[5, 20]] += 6.0  # two stray pixels
    q, m = _line_fit(x, y, 40, 1.5)
    assert q == pytest.approx(0.05) and m == 38


def test_paint_walls_tilted():
    free = np.zeros((30, 60), bool)
    got = np.zeros((30, 60), bool)
    # one horizontal wall rows 10..11 rising 1 px per 10 px, one vertical wall
    paint_walls(got, free, np.array([True, False]), np.array([10, 40]), np.array([11, 40]),
                 np.array([0, 5]), np.array([59, 24]), np.array([False, False]),
                 np.array([0.1, -0.1]))
    for j in (0, 29, 30, 59):
        sh = int(np.round(0.1 * (j - 29.5)))
        assert np.flatnonzero(got[:, j] & (np.arange(30) < 25)).tolist() == [10 + sh, 11 + sh]
    for r in (5, 24):
        sh = int(np.round(-0.1 * (r - 14.5)))
        assert got[r, 40 + sh] and got[r, 35:46].sum() == 1


def test_anchored_walls_follow_the_map_angle():
    """A room turned by 2 degrees: the anchored walls follow the turned walls instead of
    cutting them along the grid (half the wall pixels off what the map shows, or fewer),
    and every straight wall gets the map's angle."""
    import cv2

    from map2map.maps.segments import straight_segments

    img = np.full((200, 200), UNKNOWN, np.uint8)
    cv2.rectangle(img, (30, 40), (170, 160), FREE, -1)
    cv2.rectangle(img, (30, 40), (170, 160), OCCUPIED, 2)
    cv2.line(img, (100, 40), (100, 160), OCCUPIED, 2)
    rot = cv2.warpAffine(img, cv2.getRotationMatrix2D((100, 100), 2.0, 1), (200, 200),
                         flags=cv2.INTER_NEAREST, borderValue=UNKNOWN)
    segs = straight_segments(rot == OCCUPIED, 4.0)
    seen = rot == OCCUPIED
    m, c = anchored_walls(rot, segs, band=3, wall_px=2)
    m0, _ = anchored_walls(rot, segs, band=3, wall_px=2, tilt=False)
    assert (m & ~seen).sum() < 0.5 * (m0 & ~seen).sum()   # measured 40 vs 105 pixels
    ang = np.degrees(np.arctan2(c[:, 3] - c[:, 1], c[:, 2] - c[:, 0])) % 90
    assert np.all(np.abs((ang + 45) % 90 - 45 + 2.0) < 0.5)  # image rows down: -2 degrees


def test_drop_free_specks():
    from map2map.learn.ba.pieces import drop_free_specks

    g = np.full((30, 30), UNKNOWN, np.uint8)
    g[2:20, 2:28] = FREE
    g[20, 2:28] = OCCUPIED
    g[23:25, 5:7] = FREE                      # 4 free pixels beyond the wall
    out = drop_free_specks(g, 5)
    assert (out[23:25, 5:7] == UNKNOWN).all() and (out[2:20, 2:28] == FREE).all()
    assert (drop_free_specks(g, 4) == g).all()


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
    from map2map.learn.ba.autocorrect import autocorrect_many

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


def test_anchored_postprocess_leaves_no_free_specks():
    """Free pixels beyond an outer wall (rays through it) become unknown in the anchored
    output: the wall gets no second face there (before, it was drawn around them)."""
    from map2map.learn.ba.postprocess import postprocess

    g = np.full((128, 128), UNKNOWN, np.uint8)
    g[20:100, 20:100] = FREE
    g[20:100, [20, 21, 98, 99]] = OCCUPIED
    g[[20, 21, 98, 99], 20:100] = OCCUPIED
    g[101:103, 40:42] = FREE                          # specks beyond the bottom wall
    g[102, 70] = FREE
    low = np.full((32, 32), 127.0, np.float32)         # the network sees the same room
    low[5:25, 5:25] = 255.0
    low[5:25, [5, 24]] = 0.0
    low[[5, 24], 5:25] = 0.0
    out, _ = postprocess(low, g.shape, g, wall_px=4, data_px=0.5)
    assert (out[100:, :] != FREE).all()
    assert (out[30:90, 30:90] == FREE).all()
    assert (out[98:100, 30:90] == OCCUPIED).all()


def _merge_loop(segs, axis, tol, gap):
    """The plain-Python merge that ``segments._merge`` vectorises (reference)."""
    if len(segs) == 0:
        return np.zeros((0, 4))
    c = segs[:, 1] if axis == 0 else segs[:, 0]
    lo = np.minimum(segs[:, 0], segs[:, 2]) if axis == 0 else np.minimum(segs[:, 1], segs[:, 3])
    hi = np.maximum(segs[:, 0], segs[:, 2]) if axis == 0 else np.maximum(segs[:, 1], segs[:, 3])
    order = np.argsort(c, kind="stable")
    groups, cur = [], [order[0]]
    for i in order[1:]:
        if c[i] - c[cur[-1]] <= tol:
            cur.append(i)
        else:
            groups.append(cur)
            cur = [i]
    groups.append(cur)
    out = []

    def seg(m, start, end):
        w = np.maximum(hi[m] - lo[m], 1.0)
        k = float(np.sum(c[m] * w) / np.sum(w))
        return [start, k, end, k] if axis == 0 else [k, start, k, end]

    for g in groups:
        g = np.asarray(g)
        g = g[np.argsort(lo[g], kind="stable")]
        start, end, members = lo[g[0]], hi[g[0]], [g[0]]
        for i in g[1:]:
            if lo[i] <= end + gap:
                end = max(end, hi[i])
                members.append(i)
                continue
            out.append(seg(members, start, end))
            start, end, members = lo[i], hi[i], [i]
        out.append(seg(members, start, end))
    return np.array(out, float)


@pytest.mark.parametrize("axis", [0, 1])
def test_segment_merge_matches_the_loop(axis):
    """The vectorised merge of collinear segments gives the loop's segments (random sets
    with shared lines, overlaps, gaps, negative coordinates and duplicates)."""
    from map2map.maps.segments import _merge

    rng = np.random.default_rng(7 + axis)
    for _ in range(200):
        n = int(rng.integers(1, 40))
        fixed = rng.choice(np.arange(-5, 30, 0.5), n)  # shared lines (ties) and near ones
        a, b = rng.uniform(-20, 120, (2, n)).round(1)
        segs = (np.stack([a, fixed, b, fixed], 1) if axis == 0
                else np.stack([fixed, a, fixed, b], 1))  # fmt: skip
        if n > 3:
            segs[1] = segs[0]  # an exact duplicate
        tol, gap = float(rng.uniform(0.5, 3)), float(rng.uniform(0, 10))
        got, ref = _merge(segs, axis, tol, gap), _merge_loop(segs, axis, tol, gap)
        assert got.shape == ref.shape
        np.testing.assert_allclose(got, ref, rtol=0, atol=1e-12)
    assert _merge(np.zeros((0, 4)), axis, 1.0, 1.0).shape == (0, 4)


def test_collinear_faces_snap_pieces_of_one_line():
    """Pieces of one wall line displaced by drift go to their length-weighted mean line
    (the long piece dominates); a face farther than ``tol`` and a face of the other side
    stay; with ``gap`` a piece far along the line is its own group."""
    from map2map.learn.ba.faces import collinear_faces

    h = np.array([True, True, True, True, False])
    side = np.array([0, 0, 0, 1, 0])
    face = np.array([30, 32, 36, 31, 32])
    lo = np.array([0, 60, 0, 0, 0])
    hi = np.array([79, 69, 79, 79, 79])
    out = collinear_faces(h, side, face, lo, hi, np.zeros(5), tol=2.5)
    assert out.tolist() == [30, 30, 36, 31, 32]     # (30*80 + 32*10) / 90 = 30.2


@pytest.mark.parametrize("seed", range(4))
def test_collinear_faces_matches_the_loop(seed):
    """The vectorised grouping gives the plain loop's faces on random face sets."""
    from map2map.learn.ba.faces import collinear_faces

    rng = np.random.default_rng(seed)
    n = 60
    h, side = rng.random(n) < 0.5, rng.integers(0, 2, n)
    face, lo = rng.integers(0, 200, n), rng.integers(0, 150, n)
    hi = lo + rng.integers(3, 80, n)
    q = np.where(h, 0.03, -0.03)
    got = collinear_faces(h, side, face, lo, hi, q, tol=3)
    mid = (lo + hi) / 2
    icpt = face - q * mid
    ref = face.copy()
    for hh in (True, False):
        for sd in (0, 1):
            idx = np.flatnonzero((h == hh) & (side == sd))
            idx = idx[np.argsort(icpt[idx], kind="stable")]
            for g in np.split(idx, np.flatnonzero(np.diff(icpt[idx]) > 3) + 1):
                if len(g) > 1:
                    line = np.average(icpt[g], weights=hi[g] - lo[g] + 1)
                    ref[g] = np.round(line + q[g] * mid[g])
    np.testing.assert_array_equal(got, ref)


def test_collinear_faces_follow_the_map_angle():
    """On a map turned by its heading error the faces of one line differ by the slope
    times their distance along it: they are compared where their line crosses the axis,
    so collinear tilted pieces stay where they are and a displaced one joins them."""
    from map2map.learn.ba.faces import collinear_faces

    q = 0.05
    lo, hi = np.array([0, 100, 200]), np.array([59, 159, 259])
    mid = (lo + hi) / 2
    face = np.round(40 + q * mid).astype(int)            # one tilted line: 41, 46, 51
    h, side = np.ones(3, bool), np.zeros(3, int)
    assert collinear_faces(h, side, face, lo, hi, np.full(3, q), tol=2).tolist() \
        == face.tolist()
    moved = face + np.array([0, 2, 0])                   # the middle piece drifted 2 px
    assert collinear_faces(h, side, moved, lo, hi, np.full(3, q), tol=2.5).tolist() \
        == [42, 47, 52]          # the mean line, 39.525 + 2/3 px, plus q m: all rounded
    # along the grid (slope 0) the same faces are 5 px apart: no group
    assert collinear_faces(h, side, face, lo, hi, np.zeros(3), tol=2).tolist() \
        == face.tolist()


def test_anchored_walls_collinear_moves_a_displaced_piece():
    """A corridor wall cut by a door, its short piece drawn 2 px off by drift: with
    ``collinear`` both pieces' faces are on one line; without, each keeps its own."""
    g = np.full((40, 120), UNKNOWN, np.uint8)
    g[5:30, 2:118] = FREE
    g[20:23, 2:80] = OCCUPIED                  # long piece, faces rows 20 and 22
    g[22:25, 90:110] = OCCUPIED                # short piece 2 px lower
    segs = np.array([[2.0, 21.0, 79.0, 21.0], [90.0, 23.0, 109.0, 23.0]])
    m0, _ = anchored_walls(g, segs, band=3, wall_px=2)
    m1, _ = anchored_walls(g, segs, band=3, wall_px=2, collinear=3)
    assert np.nonzero(m0[:, 100])[0].tolist() == [22, 23, 24]
    assert np.nonzero(m1[:, 100])[0].tolist() == [20, 21, 22]
    assert (m1[:, 40] == m0[:, 40]).all()      # the long piece dominates: it stays


def test_anchored_walls_thicken_two_sided():
    """A wall seen from both rooms, traced 2 px thin: with ``min_thick`` it is grown to
    the plan's thickness, one pixel out on each side (its centre stays); a wall seen from
    one side only keeps its face and ``wall_px``."""
    g = np.full((40, 60), UNKNOWN, np.uint8)
    g[5:35, 2:58] = FREE
    g[19:21, 2:58] = OCCUPIED                  # two-sided, rows 19-20
    segs = np.array([[2.0, 19.5, 57.0, 19.5]])
    m0, _ = anchored_walls(g, segs, band=3, wall_px=4)
    m1, _ = anchored_walls(g, segs, band=3, wall_px=4, min_thick=5)
    assert np.nonzero(m0[:, 30])[0].tolist() == [19, 20]
    assert np.nonzero(m1[:, 30])[0].tolist() == [18, 19, 20, 21]   # 3 missing: 1 a side
    h = np.full((40, 60), UNKNOWN, np.uint8)
    h[5:20, 2:58] = FREE
    h[20, 2:58] = OCCUPIED                     # seen from above only
    one = np.array([[2.0, 20.0, 57.0, 20.0]])
    a, _ = anchored_walls(h, one, band=3, wall_px=4)
    b, _ = anchored_walls(h, one, band=3, wall_px=4, min_thick=5)
    assert (a == b).all() and np.nonzero(b[:, 30])[0].tolist() == [20, 21, 22, 23]


def test_anchored_output_has_no_unknown_pocket_where_the_input_is_free(monkeypatch):
    """The network's unknown inside a room the input shows free (far from walls, so the
    streak rule makes it unknown) goes back to free: a plan has no such pocket."""
    from map2map.core.grid import FREE, OCCUPIED, UNKNOWN
    from map2map.learn.ba import postprocess as pp

    guide = np.full((64, 64), UNKNOWN, np.uint8)
    guide[8:57, 8:57] = OCCUPIED
    guide[10:55, 10:55] = FREE
    low = np.full((16, 16), 127.0, np.float32)
    low[2:14, 2:14] = 0.0
    low[3:13, 3:13] = 255.0
    low[7:9, 7:9] = 127.0                      # the network's unknown pocket mid-room
    out, _ = pp.postprocess(low, (64, 64), guide, wall_px=2.0, data_px=1.0)
    from dataclasses import replace

    from map2map.learn.ba import anchor

    monkeypatch.setattr(pp, "ANCHOR", replace(anchor.ANCHOR, fill_pockets=False))
    old, _ = pp.postprocess(low, (64, 64), guide, wall_px=2.0, data_px=1.0)
    assert (old[28:36, 28:36] == UNKNOWN).any()  # what the streak rule alone leaves
    assert (out[10:55, 10:55] == FREE).all()
    assert ((out != old) <= ((old == UNKNOWN) & (out == FREE))).all()  # only pockets move
    assert (out[:6] == UNKNOWN).all()            # outside the building stays unknown


@pytest.mark.parametrize("seed", range(4))
def test_fill_holes_is_scipys(seed):
    """The cleaning's hole filling (one OpenCV labelling) is ``binary_fill_holes``."""
    from scipy import ndimage

    from map2map.learn.ba.postprocess import _fill_holes

    rng = np.random.default_rng(seed)
    for _ in range(40):
        H, W = rng.integers(1, 50, 2)
        m = rng.random((H, W)) < rng.random()
        assert np.array_equal(_fill_holes(m), ndimage.binary_fill_holes(m))
