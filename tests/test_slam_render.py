"""Model_AB's resolution raising with SLAM-like walls (map2map.learn.ab.render), on
hand-made network outputs (numpy only, no torch)."""

from __future__ import annotations

import numpy as np
import pytest
from scipy import ndimage

from map2map.core.grid import FREE, OCCUPIED, UNKNOWN
from map2map.learn.ab.render import (
    class_memberships,
    render,
    render_plain,
    render_slam,
    save_render_figure,
    snap,
)
from map2map.maps.preprocess import wall_thickness_px


def _rooms(n: int = 16) -> np.ndarray:
    """A grey n x n output: two rooms split by a 3-cell wall, a 3-cell outer wall, unknown
    outside the building."""
    g = np.full((n, n), float(UNKNOWN), np.float32)
    g[1:n - 1, 1:n - 1] = 0.0                     # building block, all wall
    g[4:n - 4, 4:7] = 240.0                      # room 1
    g[4:n - 4, 10:n - 4] = 240.0                 # room 2 (wall between: cells 7-9)
    return g


@pytest.mark.parametrize("wall_px", [1.0, 2.0, 3.0])
def test_walls_come_out_with_the_given_thickness(wall_px):
    r = render_slam(_rooms(), 128, wall_px=wall_px)   # 8 px per cell: walls 24 px thick
    occ = r.map == OCCUPIED
    assert set(np.unique(r.map)) <= {OCCUPIED, UNKNOWN, FREE}
    # every straight face is exactly wall_px thick: across the split wall, row 64
    row = r.map[64]
    runs = np.diff(np.flatnonzero(np.diff(np.r_[0, row == OCCUPIED, 0])))[::2]
    assert runs.tolist() == [int(wall_px)] * 4     # outer left, split wall x2, outer right
    assert wall_thickness_px(r.map[None]) == pytest.approx(wall_px, abs=0.35)
    # the walls' insides are unknown, as a SLAM map shows them; nothing else changed
    assert np.all(r.map[r.snapped != OCCUPIED] == r.snapped[r.snapped != OCCUPIED])
    assert np.all(r.map[(r.snapped == OCCUPIED) & ~occ] == UNKNOWN)
    assert r.interior == int(((r.snapped == OCCUPIED) & ~occ).sum()) > 0


def test_no_wall_is_lost_where_a_face_exists():
    rng = np.random.default_rng(3)
    g = rng.choice([0.0, 127.0, 250.0], size=(24, 24), p=[0.3, 0.3, 0.4]).astype(np.float32)
    r = render_slam(g, 96, wall_px=2.0)
    occ0, free0 = r.snapped == OCCUPIED, r.snapped == FREE
    face = occ0 & ndimage.binary_dilation(free0, structure=np.ones((3, 3)))
    assert face.any() and np.all(r.map[face] == OCCUPIED)   # every face pixel kept
    lab, n = ndimage.label(occ0, structure=np.ones((3, 3)))
    touching = np.unique(lab[face])
    kept = np.unique(lab[r.map == OCCUPIED])
    assert set(touching.tolist()) <= set(kept.tolist())    # every faced wall survives


def test_wall_without_free_space_beside_it_becomes_unknown():
    g = np.full((8, 8), float(UNKNOWN), np.float32)
    g[3:5, 2:6] = 0.0                               # a wall floating in unknown space
    g[0, 0] = 255.0                                 # free space far away
    r = render_slam(g, 32, wall_px=2.0)
    assert not np.any(r.map == OCCUPIED) and np.any(r.snapped == OCCUPIED)
    assert not np.any(render_slam(np.zeros((4, 4)), 16).map == OCCUPIED)   # no free at all


def test_thin_walls_stay_whole_and_no_unknown_halo_between_wall_and_room():
    g = np.full((16, 16), 250.0, np.float32)
    g[:, 8] = 5.0                                   # one cell: 4 px at 64
    r = render_slam(g, 64, wall_px=3.0)
    row = r.map[30]
    assert np.count_nonzero(row == UNKNOWN) == 0     # wall meets its rooms directly
    assert 3 <= np.count_nonzero(row == OCCUPIED) <= 5
    plain = render_plain(g, 64)[30]
    assert np.count_nonzero(plain == OCCUPIED) == 4 and np.count_nonzero(plain == UNKNOWN) == 0


def test_memberships_argmax_is_snap_and_plain_is_the_previous_output():
    g = np.random.default_rng(0).uniform(0, 255, (12, 12)).astype(np.float32)
    p = class_memberships(g)
    assert np.allclose(p.sum(-1), 1.0) and p.min() >= 0
    same = render_slam(g, 12, wall_px=100.0)         # no upsampling, no thinning
    assert np.array_equal(same.snapped, snap(g)) and np.array_equal(same.map, snap(g))
    assert np.array_equal(render(g, 12, "plain"), snap(g))
    assert np.array_equal(render(g, 48, "slam", 2.0), render_slam(g, 48, 2.0).map)
    with pytest.raises(ValueError, match="render"):
        render(g, 12, "blur")


def test_render_figure_is_written(tmp_path):
    g = _rooms()
    save_render_figure(g, render_slam(g, 64, 2.0), tmp_path / "r.png",
                       plan=np.full((64, 64), FREE, np.uint8), title="t")
    assert (tmp_path / "r.png").stat().st_size > 1000


# --- LIDAR traces (session 11): metric band, ragged back edge, stray hits -------------

def _block(n: int = 16) -> np.ndarray:
    """A grey n x n output: one room inside a thick (3-cell) wall block, unknown outside."""
    g = np.full((n, n), float(UNKNOWN), np.float32)
    g[1:n - 1, 1:n - 1] = 0.0
    g[4:n - 4, 4:n - 4] = 240.0
    return g


def test_metric_band_is_thinner_in_px_on_coarser_squares():
    from map2map.learn.ab.render import TraceParams, band_px, trace_rng

    tp = TraceParams(floor_px=1.0, wall_m=0.05)
    assert band_px(0.025, tp) == pytest.approx(3.0) and band_px(0.1, tp) == pytest.approx(1.5)
    th = [wall_thickness_px(render_slam(_block(), 128, band_px(r, tp), tp.rough_px,
                                        trace_rng(0, 0)).map[None]) for r in (0.025, 0.05, 0.1)]
    assert th[0] > th[1] > th[2]                        # the same metres, fewer pixels
    assert th[0] == pytest.approx(3.0, abs=0.5) and th[2] == pytest.approx(1.5, abs=0.4)


def test_ragged_edge_draws_fractional_bands_seeded_and_keeps_every_face():
    from map2map.learn.ab.render import trace_rng

    plain = render_slam(_block(), 128, 1.5)             # floored: 1 px
    a = render_slam(_block(), 128, 1.5, 1.0, trace_rng(3, 0))
    b = render_slam(_block(), 128, 1.5, 1.0, trace_rng(3, 0))
    c = render_slam(_block(), 128, 1.5, 1.0, trace_rng(4, 0))
    assert a.map.tobytes() == b.map.tobytes() and a.map.tobytes() != c.map.tobytes()
    row = plain.map[64]
    assert np.count_nonzero(row == OCCUPIED) == 2       # the plain band: 1 px a face
    # the ragged band: 1 or 2 px deep, about half of each, every face pixel kept
    free = a.snapped == FREE
    d = ndimage.distance_transform_edt(~free)
    occ = a.map == OCCUPIED
    assert np.all(occ[(a.snapped == OCCUPIED) & (d <= 1)])
    second = (a.snapped == OCCUPIED) & (d == 2)
    assert 0.35 < occ[second].mean() < 0.65 and not occ[(a.snapped == OCCUPIED) & (d > 2.5)].any()
    with pytest.raises(ValueError):
        render_slam(_block(), 64, 1.5, 1.0)             # rough edge without an rng


def test_stray_hits_land_off_the_walls_on_unknown_or_free_space_only():
    from map2map.experiments.realism.measure import map_stats
    from map2map.learn.ab.render import TraceParams, stray_hits, trace_rng

    m = render_slam(_block(32), 256, 2.0).map
    plan = m.copy()                                    # the map itself as the plan
    tp = TraceParams(strays=30.0, stray_spread=0.0)
    out = stray_hits(m, trace_rng(1, 0), 0.05, tp)
    assert out.tobytes() == stray_hits(m, trace_rng(1, 0), 0.05, tp).tobytes()
    new = (out == OCCUPIED) & (m != OCCUPIED)
    assert new.any() and np.all(out[m == OCCUPIED] == OCCUPIED)       # walls untouched
    assert np.all(np.isin(m[new], [UNKNOWN, FREE]))
    assert np.all(out[~new] == m[~new])
    lab, n = ndimage.label(new, structure=np.ones((3, 3)))
    assert np.bincount(lab.ravel())[1:].max() <= 3                   # 1-3 px hits
    d = ndimage.distance_transform_edt(m != OCCUPIED)
    assert d[new].min() >= 2.5                                      # off the walls
    assert np.any(new & (m == UNKNOWN)) and np.any(new & (m == FREE))  # both kinds
    assert map_stats(out, plan)["spurious"] >= 0.5 * n > 0 == map_stats(m, plan)["spurious"]
    none = stray_hits(m, trace_rng(1, 0), 0.05, TraceParams(strays=0.0))
    assert none.tobytes() == m.tobytes()
    counts = [np.count_nonzero(stray_hits(m, trace_rng(s, 0), 0.05, TraceParams(
        strays=5.0, stray_spread=0.8)) != m) for s in range(40)]
    assert np.var(counts) > np.mean(counts)           # overdispersed: some maps get many


def test_inset_moves_the_faces_into_the_network_wall_cells():
    g = _rooms()
    base = render_slam(g, 128, 2.0)
    ins = render_slam(g, 128, 2.0, inset_px=1.0)
    row0, row1 = base.map[64], ins.map[64]
    occ0, occ1 = np.flatnonzero(row0 == OCCUPIED), np.flatnonzero(row1 == OCCUPIED)
    assert len(occ0) == len(occ1) == 8                   # four 2 px faces either way
    # each face one pixel deeper into its wall: the rooms one pixel wider a side
    assert np.count_nonzero(row1 == FREE) == np.count_nonzero(row0 == FREE) + 4
    assert np.all(ins.map[base.map == FREE] == FREE)


def test_inset_leaves_thin_walls_whole():
    g = np.full((16, 16), 250.0, np.float32)
    g[:, 8] = 5.0                                   # one cell: 4 px at 64
    thin = render_slam(g, 64, 2.0, inset_px=1.0)
    assert np.count_nonzero(thin.map[30] == OCCUPIED) >= 2
    g2 = np.full((64, 64), 250.0, np.float32)
    g2[:, 32] = 5.0                                 # one pixel at 64: nothing deeper
    assert np.array_equal(render_slam(g2, 64, 1.0, inset_px=1.0).map,
                          render_slam(g2, 64, 1.0).map)


def test_stray_hits_without_a_wall_face_go_to_the_rooms_or_nowhere():
    from map2map.learn.ab.render import TraceParams, stray_hits, trace_rng

    tp = TraceParams(strays=30.0, stray_spread=0.0)
    m = np.full((64, 64), UNKNOWN, np.uint8)
    m[4:30, 4:30] = FREE
    m[50:54, 50:54] = OCCUPIED                 # a wall that borders no free space
    out = stray_hits(m, trace_rng(0, 0), 0.05, tp)   # raised IndexError before
    new = (out == OCCUPIED) & (m != OCCUPIED)
    assert new.any() and np.all(m[new] == FREE)
    small = np.full((64, 64), UNKNOWN, np.uint8)
    small[10:14, 12] = FREE                     # no free pixel 3 px from a wall either
    small[8:16, 14] = OCCUPIED
    assert stray_hits(small, trace_rng(0, 0), 0.05, tp).tobytes() == small.tobytes()
