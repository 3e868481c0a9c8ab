"""The wall segments of autocorrect's post-processing (what ``--dxf`` writes) against its
raster (issue #14): every segment lies on the walls drawn, every straight wall drawn has
a segment."""

from __future__ import annotations

from dataclasses import replace

import cv2
import numpy as np
import pytest

from map2map.core.grid import FREE, OCCUPIED, UNKNOWN
from map2map.learn.ba.postprocess import postprocess
from map2map.learn.training.data import downsample_target
from map2map.learn.training.synthetic import make_pair
from map2map.maps.segments import straight_segments


def _points(seg: np.ndarray, step: float = 0.25) -> tuple[np.ndarray, np.ndarray]:
    """Pixel (row, col) of points every ``step`` px along a segment (x0, y0, x1, y1;
    pixel ``i`` spans ``[i - 0.5, i + 0.5)``)."""
    x0, y0, x1, y1 = seg
    t = np.linspace(0.0, 1.0, int(np.ceil(np.hypot(x1 - x0, y1 - y0) / step)) + 2)
    return (np.floor(y0 + t * (y1 - y0) + 0.5).astype(int),
            np.floor(x0 + t * (x1 - x0) + 0.5).astype(int))


def _off_walls(segs: np.ndarray, occ: np.ndarray) -> list:
    """Segments with a point farther than one pixel (8-neighbourhood) from a wall pixel."""
    near = cv2.dilate(occ.astype(np.uint8), np.ones((3, 3), np.uint8)) > 0
    H, W = occ.shape
    bad = []
    for s in segs:
        r, c = _points(s)
        inside = (r >= 0) & (r < H) & (c >= 0) & (c < W)
        if not inside.all() or not near[r, c].all():
            bad.append(s.tolist())
    return bad


def _uncovered(segs: np.ndarray, occ: np.ndarray, cell: float) -> tuple[int, float]:
    """The straight walls of the raster (:func:`straight_segments` of its wall pixels, at
    least two model cells long) against the segments: points (one per pixel along them)
    farther from every segment than the wall's half thickness there plus one pixel;
    (the longest run of such points, their share of all points)."""
    drawn = np.zeros(occ.shape, np.uint8)
    for x0, y0, x1, y1 in segs:
        cv2.line(drawn, (int(round(x0)), int(round(y0))), (int(round(x1)), int(round(y1))), 1)
    d = cv2.distanceTransform((1 - drawn).astype(np.uint8), cv2.DIST_L2, 5)
    half = cv2.distanceTransform(occ.astype(np.uint8), cv2.DIST_L2, 5)
    longest, n, n_off = 0, 0, 0
    for s in straight_segments(occ, cell):
        if np.hypot(s[2] - s[0], s[3] - s[1]) < 2 * cell:
            continue
        r, c = _points(s, 1.0)
        r, c = np.clip(r, 0, occ.shape[0] - 1), np.clip(c, 0, occ.shape[1] - 1)
        off = (d[r, c] > half[r, c] + 1.0).astype(np.int8)
        edges = np.diff(np.concatenate([[0], off, [0]]))
        runs = np.flatnonzero(edges == -1) - np.flatnonzero(edges == 1)
        longest = max(longest, int(runs.max()) if len(runs) else 0)
        n, n_off = n + len(off), n_off + int(off.sum())
    return longest, n_off / max(1, n)


def _network_like(plan: np.ndarray, size: int = 64) -> np.ndarray:
    """A stand-in network output: the plan at the model's size with its walls one cell
    thicker (the network's bands), and a wall it imagined across the largest room."""
    low = downsample_target(plan[None], size)[0].astype(np.float32)
    walls = cv2.erode(low, np.ones((3, 3), np.uint8)) == OCCUPIED
    free = low == FREE
    n, lab, stats, _ = cv2.connectedComponentsWithStats(free.astype(np.uint8), connectivity=4)
    if n > 1:
        k = 1 + int(np.argmax(stats[1:, cv2.CC_STAT_AREA]))
        x, y, w, h = stats[k, :4]
        col = x + w // 2
        rows = np.flatnonzero(lab[y:y + h, col] == k) + y
        low[rows[len(rows) // 4:3 * len(rows) // 4], col] = OCCUPIED
    low[walls] = OCCUPIED
    return low


@pytest.mark.parametrize("seed", range(6))
def test_segments_and_raster_agree_on_generated_maps(seed):
    plan, slam = make_pair(seed)
    low = _network_like(plan)
    out, segs = postprocess(low, plan.shape, slam, wall_px=5.5)
    occ = out == OCCUPIED
    assert len(segs) > 4
    assert _off_walls(segs, occ) == []      # every segment lies on the walls drawn
    # every straight wall drawn has its segment; only short pieces of the input's own
    # wall pixels (kept as they are: corners, bits a straight wall does not explain)
    # may lack one, under three model cells long, a few percent of the walls' length
    cell = plan.shape[0] / low.shape[0]
    longest, share = _uncovered(segs, occ, cell)
    assert longest < 4 * cell and share < 0.05


def test_imagined_wall_across_a_room_seen_free_has_no_segment():
    g = np.full((96, 96), UNKNOWN, np.uint8)
    g[16:80, 16:80] = FREE
    g[14:16, 14:82] = g[80:82, 14:82] = OCCUPIED
    g[14:82, 14:16] = g[14:82, 80:82] = OCCUPIED
    low = downsample_target(g[None], 24)[0].astype(np.float32)  # cells of 4 px
    low[8:16, 12] = OCCUPIED                # the network's wall through the empty room
    out, segs = postprocess(low, g.shape, g, wall_px=4)
    assert (out[20:76, 40:60] == FREE).all()                       # not drawn ...
    vertical = segs[:, 0] == segs[:, 2]
    assert not (vertical & (np.abs(segs[:, 0] - 49.5) < 4)).any()   # ... nor in the DXF
    assert _off_walls(segs, out == OCCUPIED) == []


def test_drawn_pieces_cut_at_gaps():
    from map2map.learn.ba.pieces import drawn_pieces

    occ = np.zeros((10, 40), bool)
    occ[4, 2:10] = occ[4, 20:28] = True
    occ[8, 35] = True                       # a lone pixel: 1.5 px of line within 1 px
    segs = np.array([[2.0, 4.0, 38.0, 4.0], [3.0, 0.0, 3.0, 9.0], [35.0, 8.0, 39.0, 8.0]])
    got = drawn_pieces(segs, occ)
    # one pixel of tolerance (pixel i spans [i - 0.5, i + 0.5)): up to the pixel borders
    want = [[2.0, 4.0, 10.5, 4.0], [18.5, 4.0, 28.5, 4.0],
            [3.0, 2.5, 3.0, 5.5], [35.0, 8.0, 36.5, 8.0]]
    np.testing.assert_allclose(got, want, atol=1e-3)
    # a slanted segment that clips pixel corners: exact, not sampled
    diag = np.zeros((40, 40), bool)
    diag[np.arange(5, 30), np.arange(5, 30)] = True
    cut = drawn_pieces(np.array([[0.0, 3.0, 39.0, 33.0]]), diag)
    assert len(cut) == 1 and _off_walls(cut, diag) == []
    assert _off_walls(got, occ) == []
    assert drawn_pieces(segs, np.zeros_like(occ)).shape == (0, 4)


def test_network_band_behind_an_input_wall_does_not_double_it():
    """The demo's doubled outer walls: the input sees the outer walls from inside only;
    the network draws them as bands two cells thick lying beyond them (the plans' outer
    walls are thick). The band's centre line is farther than ``ANCHOR.new`` from the
    input's wall, so it was drawn as a second wall with a gap between the two; its band
    reaches the input's wall: it is that wall's body, drawn with it as one wall."""
    n = 128
    g = np.full((n, n), UNKNOWN, np.uint8)
    g[32:96, 32:96] = FREE
    g[30:32, 30:98] = g[96:98, 30:98] = OCCUPIED
    g[30:98, 30:32] = g[30:98, 96:98] = OCCUPIED
    low = np.full((32, 32), UNKNOWN, np.float32)  # cells of 4 px
    low[8:24, 8:24] = FREE
    low[5:7, 5:27] = low[25:27, 5:27] = OCCUPIED
    low[5:27, 5:7] = low[5:27, 25:27] = OCCUPIED
    out, segs = postprocess(low, (n, n), g, wall_px=4)
    wall = list(range(22, 32)) + list(range(96, 106))   # one run across each wall, no gap
    assert np.flatnonzero(out[:, 64] == OCCUPIED).tolist() == wall
    assert np.flatnonzero(out[64] == OCCUPIED).tolist() == wall
    # and one centre line across each wall in the DXF
    h = segs[(segs[:, 1] == segs[:, 3]) & (np.minimum(segs[:, 0], segs[:, 2]) <= 64)
             & (np.maximum(segs[:, 0], segs[:, 2]) >= 64)]
    v = segs[(segs[:, 0] == segs[:, 2]) & (np.minimum(segs[:, 1], segs[:, 3]) <= 64)
             & (np.maximum(segs[:, 1], segs[:, 3]) >= 64)]
    assert len(h) == 2 and len(v) == 2
    assert _off_walls(segs, out == OCCUPIED) == []




def _drawn_pieces_numpy(segs, occ):
    """The NumPy version ``drawn_pieces`` had before its numba kernel (the reference)."""
    import cv2

    s = np.asarray(segs, float).reshape(-1, 4)
    H, W = occ.shape
    near = cv2.dilate(occ.astype(np.uint8), np.ones((3, 3), np.uint8)) > 0
    out = []
    for x0, y0, x1, y1 in s:
        ts = [np.array([0.0, 1.0])]
        for a, b in ((x0, x1), (y0, y1)):
            if b != a:
                k = np.arange(np.ceil(min(a, b) - 0.5), np.floor(max(a, b) - 0.5) + 1)
                ts.append((k + 0.5 - a) / (b - a))
        t = np.unique(np.clip(np.concatenate(ts), 0.0, 1.0))
        if len(t) < 2:
            continue
        m = (t[:-1] + t[1:]) / 2
        r = np.floor(y0 + m * (y1 - y0) + 0.5).astype(np.int64)
        c = np.floor(x0 + m * (x1 - x0) + 0.5).astype(np.int64)
        inside = (r >= 0) & (r < H) & (c >= 0) & (c < W)
        on = np.zeros(len(m), bool)
        on[inside] = near[r[inside], c[inside]]
        edges = np.diff(np.concatenate([[0], on.astype(np.int8), [0]]))
        for a, b in zip(np.flatnonzero(edges == 1), np.flatnonzero(edges == -1), strict=True):
            ta, tb = t[a] + 1e-6, t[b] - 1e-6
            p = [x0 + ta * (x1 - x0), y0 + ta * (y1 - y0), x0 + tb * (x1 - x0),
                 y0 + tb * (y1 - y0)]
            if np.hypot(p[2] - p[0], p[3] - p[1]) >= 1.0:
                out.append(p)
    return np.array(out, float).reshape(-1, 4)


def test_drawn_pieces_kernel_equals_the_numpy_reference():
    """Bit for bit, on random and axis-aligned segments (integer and half-pixel ends,
    segments leaving the grid, points) over random walls."""
    from map2map.learn.ba.pieces import drawn_pieces

    rng = np.random.default_rng(3)
    for trial in range(30):
        occ = rng.random((40, 50)) < 0.15
        occ[rng.integers(0, 40), :] = True
        n = 40
        segs = rng.uniform(-5, 55, (n, 4))
        segs[: n // 4] = np.round(segs[: n // 4])                  # integer ends
        segs[n // 4: n // 2] = np.round(segs[n // 4: n // 2] * 2) / 2  # half-pixel ends
        segs[n // 2: n // 2 + 5, 3] = segs[n // 2: n // 2 + 5, 1]   # horizontal
        segs[n // 2 + 5: n // 2 + 10, 2] = segs[n // 2 + 5: n // 2 + 10, 0]  # vertical
        segs[-1, 2:] = segs[-1, :2]                                 # a point
        want = _drawn_pieces_numpy(segs, occ)
        got = drawn_pieces(segs, occ)
        assert got.shape == want.shape and np.array_equal(got, want), trial


def test_join_supported_bridges_hough_cuts_but_not_doors():
    from map2map.maps.segments import join_supported

    walls = np.zeros((80, 80), bool)
    walls[10:70, 20:22] = True                      # a vertical wall, whole
    walls[40:42, 22:60] = True                      # a T-junction on it
    walls[10:70, 50:52] = True                      # a second one, with a door
    walls[30:45, 50:52] = False
    segs = np.array([[20.5, 10, 20.5, 35], [21.0, 47, 21.0, 69],      # cut at the T
                     [50.5, 10, 50.5, 29], [50.5, 46, 50.5, 69],      # cut by the door
                     [22.0, 40.5, 59, 40.5]])
    out = join_supported(segs, walls, 1.5, 16)
    vert = out[out[:, 0] == out[:, 2]]
    assert len(vert) == 3 and len(out) == 4
    whole = vert[np.argmax(vert[:, 3] - vert[:, 1])]
    assert whole[1] == 10 and whole[3] == 69 and 20.5 < whole[0] < 21.0
    assert sorted(vert[vert[:, 0] == 50.5][:, 1].tolist()) == [10, 46]   # the door stays
    assert len(join_supported(segs, walls, 1.5, 10)) == 5    # a gap longer than max_gap
    far = segs.copy()
    far[1, [0, 2]] = 24.0                                    # not collinear within tol
    assert len(join_supported(far, walls, 1.5, 16)) == 5
    assert join_supported(np.zeros((0, 4)), walls, 1.5, 16).shape == (0, 4)
    # junction=: only the cut at the T (the horizontal segment ends on the line) joins
    assert len(join_supported(segs, walls, 1.5, 16, junction=4)) == 4
    alone = segs[[0, 1, 2, 3]]                              # the T's other wall gone
    assert len(join_supported(alone, walls, 1.5, 16, junction=4)) == 4
    assert len(join_supported(alone, walls, 1.5, 16)) == 3


def test_anchored_walls_join_a_wall_hough_cut_at_a_t_junction(monkeypatch):
    from map2map.learn.ba import postprocess as P

    guide = np.full((80, 80), FREE, np.uint8)
    guide[10:70, 20:22] = OCCUPIED                         # a whole wall in the input ...
    guide[40:42, 22:60] = OCCUPIED                         # ... with a T-junction
    cut = np.array([[20.5, 10, 20.5, 35], [20.5, 47, 20.5, 69], [22.0, 40.5, 59, 40.5]])
    monkeypatch.setattr(P, "straight_segments", lambda occ, cell: cut.copy())

    def drawn():
        data, _ = P._anchored(np.zeros((0, 4)), guide, 2.0, 1.0)
        return data[34:49, 20:22]

    assert P.ANCHOR.join > 0                                # on by default
    assert np.all(drawn() == OCCUPIED)                     # drawn through the cut
    monkeypatch.setattr(P, "ANCHOR", replace(P.ANCHOR, join=0.0))
    assert np.any(drawn() == FREE)                         # without: a hole at the cut
