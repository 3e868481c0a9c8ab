"""Auto-correct on maps beyond the training scale (issue #14, session 11): the drawn wall
thickness (``thickness``), open frontiers (``open_frontiers``) and maps corrected in tiles
or refused (``large``). Stand-in models isolate each rule from what a network learnt."""

from __future__ import annotations

import numpy as np
import pytest

pytest.importorskip("torch")

from map2map.core.grid import FREE, OCCUPIED, UNKNOWN, OccupancyMap  # noqa: E402
from map2map.learn.ba.autocorrect import LARGE_SHRINK, autocorrect_many, drawn_wall_px  # noqa: E402
from map2map.learn.ba.model import BAModel  # noqa: E402
from map2map.learn.ba.pieces import frontier_walls  # noqa: E402
from map2map.learn.ba.squares import TILE_SHRINK, stitch_tiles, tile_grid  # noqa: E402
from map2map.learn.training.data import downsample_target  # noqa: E402
from map2map.maps.preprocess import wall_thickness_px  # noqa: E402


class _Identity(BAModel):
    """Returns its input, reduced with walls kept; records what it was given."""

    def __init__(self, size=64, data_size=256, wall=3.0):
        super().__init__(None, size, data_size, wall, {}, "identity")
        self.seen = []

    def predict(self, inputs, batch=256):
        self.seen.append(np.asarray(inputs).copy())
        return downsample_target(inputs, self.size).astype(np.float32)


def _rooms(side=1300, step=130, wall=3, res=0.05):
    """A large, fully explored building: a grid of rooms with one-pixel door gaps left
    out (walls ``wall`` px thick), ``side`` px, unknown around it."""
    d = np.full((side + 100, side + 100), UNKNOWN, np.uint8)
    d[50:50 + side, 50:50 + side] = FREE
    for k in range(50, 51 + side, step):
        d[k:k + wall, 50:50 + side + wall] = OCCUPIED
        d[50:50 + side + wall, k:k + wall] = OCCUPIED
    return OccupancyMap(d, res)


def _outer_thickness(out: np.ndarray, side=1300) -> int:
    """How many rows the top outer wall (seen from inside only) spans at a column in the
    middle of a room."""
    col = out[:, 50 + 65]
    rows = np.flatnonzero(col[:120] == OCCUPIED)
    return int(rows.max() - rows.min() + 1) if len(rows) else 0


def test_thickness_modes_set_the_drawn_walls():
    """``shrink`` grows the walls with the building (the old rule), ``resolution`` keeps
    the training walls' metres, a number is that many pixels."""
    m = _rooms()
    net = _Identity()
    shrink = (m.shape[0] - 100 + 3) / 256          # about 5x the dataset's size
    assert shrink > LARGE_SHRINK
    got = {}
    for mode in ("shrink", "resolution", 7.0):
        (res,) = autocorrect_many([m], net, workers=1, thickness=mode)
        got[mode] = res.map.data
    # one-sided outer wall: its face where the input's, its body behind it
    t_shrink = _outer_thickness(got["shrink"])
    t_res = _outer_thickness(got["resolution"])
    assert t_shrink >= 0.8 * net.target_wall_px * shrink
    assert abs(t_res - net.target_wall_px) <= 1            # 0.05 m/px: the training px
    assert abs(_outer_thickness(got[7.0]) - 7) <= 1
    # two-sided walls grow with the same factor: thin with "resolution"
    assert wall_thickness_px(got["resolution"][None]) < 0.5 * wall_thickness_px(
        got["shrink"][None])
    # the resolution rule reads the map's resolution; the shrink rule does not
    half = OccupancyMap(m.data, 0.025)
    assert drawn_wall_px(net, half, shrink, "resolution") == pytest.approx(
        2 * net.target_wall_px)
    assert drawn_wall_px(net, half, shrink, "shrink") == drawn_wall_px(net, m, shrink,
                                                                       "shrink")
    with pytest.raises(ValueError):
        drawn_wall_px(net, m, shrink, "thick")


def test_thickness_input_follows_the_input_walls():
    """``input``: walls as thick as the training SLAM maps' give the training thickness;
    thicker input walls give thicker drawn walls, never more than the shrink's."""
    from map2map.learn.ba.autocorrect import SLAM_WALL_PX

    net = _Identity()
    thin = _rooms(wall=2)
    thick = _rooms(wall=6)
    sq = lambda m: m.data[50:-50, 50:-50]  # noqa: E731
    a = drawn_wall_px(net, thin, 5.0, "input", sq(thin))
    b = drawn_wall_px(net, thick, 5.0, "input", sq(thick))
    assert a == pytest.approx(net.target_wall_px * max(1.0, wall_thickness_px(
        sq(thin)[None]) / SLAM_WALL_PX))
    assert b > a and b <= 5.0 * net.target_wall_px
    assert drawn_wall_px(net, thick, 1.2, "input", sq(thick)) == pytest.approx(
        1.2 * net.target_wall_px)


class _Closer(_Identity):
    """Adds two walls the input does not show: one just beyond the right edge of the
    known area (closing the open frontier) and one along the unknown strip inside the
    room (a wall the laser missed between two seen spaces)."""

    def predict(self, inputs, batch=256):
        out = super().predict(inputs, batch)
        for o, x in zip(out, inputs, strict=True):
            r = downsample_target(x[None], self.size)[0]
            known = r != UNKNOWN
            cols = np.flatnonzero(known.any(axis=0))
            rows = np.flatnonzero(known.any(axis=1))
            if cols.max() + 1 < self.size:                                 # the frontier
                o[rows.min() + 2:rows.max() - 1, cols.max() + 1] = OCCUPIED
            inner = rows[2:-2]
            strip = inner[(r[inner, cols.min() + 3:cols.min() + 20] == UNKNOWN).all(axis=1)]
            if len(strip):
                o[strip.min():strip.max() + 1, cols.min() + 2:cols.max() - 8] = OCCUPIED
        return out


def test_open_frontiers_leaves_the_edge_of_the_known_area_open():
    """A partial map: a room seen on three sides, open (free running into unknown) on
    the right, with a strip across it the laser missed. The stand-in network closes the
    frontier and puts a wall on the strip; ``open_frontiers`` drops the first (seen
    space on one side only) and keeps the second (seen space on both sides)."""
    d = np.full((240, 300), UNKNOWN, np.uint8)
    d[40:200, 30:260] = FREE
    d[40:42, 30:260] = OCCUPIED
    d[198:200, 30:260] = OCCUPIED
    d[40:200, 30:32] = OCCUPIED
    d[114:126, 32:200] = UNKNOWN
    m = OccupancyMap(d, 0.05)
    closed, opened = (autocorrect_many([m], _Closer(), workers=1, open_frontiers=f)[0].map.data
                      for f in (False, True))
    edge = slice(258, 275)                       # the last known column and beyond
    assert (closed[60:180, edge] == OCCUPIED).any(axis=1).mean() > 0.8
    assert (opened[60:180, edge] == OCCUPIED).any(axis=1).mean() < 0.1
    for out in (closed, opened):                 # the wall on the strip stays
        assert (out[110:130, 60:180] == OCCUPIED).any(axis=0).mean() > 0.8


def test_frontier_walls_marks_walls_beyond_the_known_area():
    g = np.full((60, 80), FREE, np.uint8)
    g[:, 60:] = UNKNOWN
    segs = np.array([[10.0, 30, 50, 30], [60.0, 5, 60, 55], [70.0, 5, 70, 55],
                     [200.0, 5, 210, 5]])        # the last one outside the map
    assert frontier_walls(segs, g, tol=4).tolist() == [False, True, True, True]
    # the share: a wall whose first quarter only runs along the frontier is kept
    g2 = np.full((60, 80), FREE, np.uint8)
    g2[:15, 31:] = UNKNOWN
    assert frontier_walls(np.array([[30.0, 0, 30, 59]]), g2, 2).tolist() == [False]
    assert frontier_walls(np.array([[30.0, 0, 30, 59]]), g2, 2, share=0.2).tolist() == [True]
    assert frontier_walls(segs[:1], np.full((60, 80), FREE, np.uint8), 4).tolist() == [False]


def test_tile_grid_covers_the_square_at_the_training_scale():
    for n in (641, 1000, 1600, 2500):
        count, stride = tile_grid(n, 256)
        assert (count + 1) * stride >= n
        assert 2 * stride <= TILE_SHRINK * 256 + 1
        assert count == 1 or 2 * (stride - 1) > (TILE_SHRINK * 256) / 2  # not needlessly small


def test_stitch_tiles_keeps_each_tile_centre():
    """Tile (i, j)'s centre half lands at cells [32 i + 16, 32 i + 48) of the stitched
    grid (64-cell tiles), the first and last tiles out to the border."""
    count = 3
    o = np.zeros((count * count, 64, 64), np.float32)
    for k in range(count * count):
        o[k] = k
    s = stitch_tiles(o, count)
    assert s.shape == (128, 128)
    assert s[0, 0] == 0 and s[47, 47] == 0 and s[48, 48] == 4 and s[79, 79] == 4
    assert s[80, 80] == 8 and s[127, 127] == 8 and s[0, 127] == 2 and s[127, 0] == 6


def test_large_tile_runs_the_network_on_tiles_and_keeps_the_frame():
    """``large="tile"``: the network sees tiles at most ``TILE_SHRINK`` x the dataset's
    size, and the identity model's walls come back where the input has them."""
    m = _rooms()
    net = _Identity()
    (res,) = autocorrect_many([m], net, workers=1, large="tile", thickness="resolution")
    n_tiles = res.map.meta["autocorrect"]["tiles"]
    assert n_tiles > 1 and sum(len(s) for s in net.seen) == n_tiles
    out = res.map.data
    assert out.shape == m.shape
    # every inner wall column comes back (within 2 px), over most of the building
    for k in range(180, 1300, 130):
        near = (out[100:1300, k - 2:k + 5] == OCCUPIED).any(axis=1).mean()
        assert near > 0.9, k
    assert not any("larger than the maps the model" in w for w in res.warnings)
    # a map within the training scale is not tiled
    small = OccupancyMap(m.data[:500, :500].copy(), 0.05)
    (r2,) = autocorrect_many([small], _Identity(), workers=1, large="tile")
    assert "tiles" not in r2.map.meta["autocorrect"]


def test_large_refuse_returns_the_map_with_a_warning():
    m = _rooms()
    small = OccupancyMap(m.data[:500, :500].copy(), 0.05)
    net = _Identity()
    with pytest.warns(UserWarning, match="not corrected"):
        big, ok = autocorrect_many([m, small], net, workers=1, large="refuse")
    assert big.map == m and big.map.meta["autocorrect"]["refused"]
    assert "refused" not in ok.map.meta["autocorrect"] and len(net.seen[0]) == 1
    with pytest.raises(ValueError):
        autocorrect_many([m], net, large="split")


def test_cli_passes_the_new_options(tmp_path, capsys):
    """``map2map autocorrect --large refuse`` returns a large map as it is, with the
    warning (drawn or not); ``--thickness`` and ``--open-frontiers`` reach the library."""
    from map2map.cli.main import main
    from map2map.maps.formats import load_map, save_map

    save_map(_rooms(), tmp_path / "big.yaml")
    rc = main(["autocorrect", str(tmp_path / "big.yaml"), "--out", str(tmp_path / "o.yaml"),
               "--large", "refuse"])
    assert rc == 0 and "not corrected" in capsys.readouterr().err
    assert np.array_equal(load_map(tmp_path / "o.yaml").data, _rooms().data)
    small = OccupancyMap(_rooms().data[:400, :400].copy(), 0.05)
    save_map(small, tmp_path / "small.yaml")
    outs = {}
    for t in ("2", "9"):
        assert main(["autocorrect", str(tmp_path / "small.yaml"), "--out",
                     str(tmp_path / f"s{t}.yaml"), "--thickness", t, "--open-frontiers",
                     "--model", "thesis"]) == 0       # the thesis's output, not redrawn
        outs[t] = (load_map(tmp_path / f"s{t}.yaml").data == OCCUPIED).sum()
    assert outs["9"] > outs["2"]
    assert main(["autocorrect", str(tmp_path / "small.yaml"), "--out",
                 str(tmp_path / "x.yaml"), "--thickness", "thick"]) != 0


def test_tiled_maps_leave_frontiers_open_unless_told():
    """``open_frontiers=None``: on for a map corrected in tiles, the module default for
    one corrected whole; an explicit value holds for both."""
    from map2map.learn.ba.autocorrect import OPEN_FRONTIERS, _open

    assert _open(None, True) is True and _open(None, False) is OPEN_FRONTIERS
    assert _open(False, True) is False and _open(True, False) is True


def test_tiled_map_frontier_is_left_open_by_default():
    """A large partial map corrected in tiles: the stand-in closes each tile's open edge;
    by default (tiles) the frontier of the whole map stays open, with
    ``open_frontiers=False`` it is closed."""
    d = np.full((1000, 1400), UNKNOWN, np.uint8)
    d[100:900, 50:900] = FREE
    d[100:103, 50:900] = OCCUPIED
    d[897:900, 50:900] = OCCUPIED
    d[100:900, 50:53] = OCCUPIED
    m = OccupancyMap(d, 0.05)
    outs = {f: autocorrect_many([m], _Closer(), workers=1, large="tile",
                                open_frontiers=f)[0].map.data for f in (None, False)}
    edge = slice(895, 930)                       # the last known columns and beyond
    assert (outs[False][200:800, edge] == OCCUPIED).any(axis=1).mean() > 0.5
    assert (outs[None][200:800, edge] == OCCUPIED).any(axis=1).mean() < 0.05
