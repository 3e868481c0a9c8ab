"""Table 5.3 as a library (map2map.experiments.table53.measure) and the input-anchored walls of
autocorrect's post-processing (map2map.learn.ba.postprocess.anchored_walls)."""

from __future__ import annotations

import numpy as np
import pytest

pytest.importorskip("torch")

from map2map.core.errors import InputError  # noqa: E402
from map2map.core.grid import FREE, OCCUPIED, UNKNOWN  # noqa: E402
from map2map.datasets.manifest import Manifest  # noqa: E402
from map2map.datasets.packed import PackedPairs  # noqa: E402
from map2map.datasets.pairfolder import pair_dir  # noqa: E402
from map2map.experiments.table53.measure import (  # noqa: E402
    heldout_pairs_from_dataset,
    merge_pairs,
    run_table53,
)
from map2map.learn.ba.anchor import anchored_walls  # noqa: E402
from map2map.learn.ba.postprocess import postprocess  # noqa: E402


def _plan(n=96, seed=0) -> np.ndarray:
    """A building of two rooms with 4-px walls, unknown outside."""
    rng = np.random.default_rng(seed)
    a = np.full((n, n), UNKNOWN, np.uint8)
    r0, c0 = rng.integers(8, 14, 2)
    r1, c1 = n - rng.integers(8, 14, 2)
    a[r0:r1, c0:c1] = OCCUPIED
    a[r0 + 4:r1 - 4, c0 + 4:c1 - 4] = FREE
    mid = int(rng.integers(c0 + 12, c1 - 15))
    a[r0:r1, mid:mid + 4] = OCCUPIED
    a[r0 + 30:r0 + 40, mid:mid + 4] = FREE                    # a door
    return a


def _slam(plan: np.ndarray, seed=0) -> np.ndarray:
    """What a laser sees of it: the faces only (one pixel), some of them one pixel off."""
    rng = np.random.default_rng(seed)
    free = plan == FREE
    near = np.zeros_like(free)
    near[1:] |= free[:-1]
    near[:-1] |= free[1:]
    near[:, 1:] |= free[:, :-1]
    near[:, :-1] |= free[:, 1:]
    face = (plan == OCCUPIED) & near
    b = np.where(free, FREE, UNKNOWN).astype(np.uint8)
    r, c = np.nonzero(face)
    jitter = rng.random(len(r)) < 0.3           # 30 % of the face pixels one pixel inwards
    b[r[~jitter], c[~jitter]] = OCCUPIED
    b[r[jitter], c[jitter]] = FREE
    rr = np.clip(r[jitter] + np.sign(r[jitter] - plan.shape[0] / 2).astype(int) * -1, 0, None)
    b[rr, c[jitter]] = OCCUPIED
    return b


class _Corrector:
    """A stand-in model: returns fixed outputs (the plans: a perfect correction)."""

    def __init__(self, outputs, name="oracle"):
        self.outputs, self.name, self.source = outputs, name, name

    def correct(self, maps):
        return [o.copy() for o in self.outputs]


def _pairs3():
    plans = np.stack([_plan(seed=s) for s in range(3)])
    slam = np.stack([_slam(p, s) for s, p in enumerate(plans)])
    return PackedPairs(plans, slam, ["p0", "p1", "p2"], ["test"] * 3)


def test_run_table53_counts_improved_maps_and_its_guards():
    pairs = _pairs3()
    plans, slam = pairs.a, pairs.b
    dropped = plans.copy()        # an output that drops every wall it can
    dropped[:, :, :48][dropped[:, :, :48] == OCCUPIED] = FREE
    t = run_table53(pairs, [_Corrector(slam, "identity"), _Corrector(dropped, "dropped"),
                            _Corrector(plans, "perfect")], progress=False)
    same = t.model("identity")
    assert same.summary["n"] == 3 and same.summary["improved"] == 0
    assert all(r["diff"] == 0 and r["diff_all"] == 0 for r in same.rows)
    perfect = t.model("perfect")
    s = perfect.summary
    assert s["improved"] == 3 and s["share_improved"] == 1.0 and s["improved_all"] == 3
    assert s["sign_test_p"] == pytest.approx(0.125)                 # 0.5 ** 3, one-sided
    assert s["median_error_gen"] < t.summary["median_error_sim"]
    assert s["median_error_gen_all"] < t.summary["median_error_sim_all"]
    assert s["median_gen_wall_recall"] == 1.0 > t.summary["median_sim_wall_recall"]
    assert s["improved_but_lost_recall"] == 0
    # dropping walls: never counted improved, counted apart when it scores better
    d = t.model("dropped")
    lost = [r for r in d.rows if r["diff"] > 0.05 and r["gen_wall_recall"] < r["sim_wall_recall"]]
    assert d.summary["improved_but_lost_recall"] == len(lost)
    assert not any(r["improved"] for r in d.rows
                   if r["gen_wall_recall"] < r["sim_wall_recall"])
    # the newest model (perfect, last) against the input: 3 better of 3
    assert t.newest is perfect and t.tests["vs_input"]["better"] == 3
    assert "vs_none" not in t.tests                                    # no none row
    assert len(t.examples_figure().axes) == 3 * 5    # 3 maps x (input, 3 models, plan)
    assert len(t.figure().axes) == 2                          # matched, every point
    text = t.format()
    assert "3/3 100%" in text and "every point" in text


def test_improved_needs_the_margin_and_the_recall():
    from map2map.experiments.table53.table import IMPROVED_MARGIN_PX, improved

    assert IMPROVED_MARGIN_PX == 0.05
    e_sim = np.array([1.00, 1.00, 1.00, 1.00, 1.00, np.nan])
    e_gen = np.array([0.94, 0.96, 0.94, 0.80, 1.20, 0.50])
    r_sim = np.full(6, 0.6)
    r_gen = np.array([0.6, 0.9, 0.59, 0.7, 0.9, 0.9])
    assert improved(e_sim, e_gen, r_sim, r_gen).tolist() == [
        True,     # 0.06 lower, recall kept
        False,    # 0.04 lower: within the margin
        False,    # lower, but recall lost
        True,     # lower, recall up
        False,    # higher
        False]    # alignment failed
    assert improved(e_sim, e_gen, r_sim, r_gen, margin=0.0).tolist()[1] is True
    assert improved(1.0, 0.9, 0.5, 0.5, margin=0.2) == np.False_


def test_sign_test_is_one_sided_towards_the_model_and_leaves_ties_out():
    from map2map.experiments.table53.table import sign_test

    better = sign_test([0.3, 0.2, 0.1, 0.4, 0.5, 0.0, 0.0])          # 5 of 5, 2 ties
    assert (better["better"], better["worse"], better["ties"]) == (5, 0, 2)
    assert better["p"] == pytest.approx(0.5 ** 5)
    worse = sign_test([-0.3, -0.2, -0.1, -0.4, -0.5])
    assert worse["p"] == pytest.approx(1.0)                  # one-sided: no evidence
    assert np.isnan(sign_test([0.0, np.nan])["p"])


def test_the_newest_model_is_tested_against_none(tmp_path):
    """With a ``none`` row before it, the newest model gets its sign test against none
    and the share of maps where it beats none by more than the margin; the CSVs are one
    per model plus the summary."""
    pairs = _pairs3()
    t = run_table53(pairs, [_Corrector(pairs.b, "none"), _Corrector(pairs.a, "perfect")],
                    progress=False)
    assert t.tests["vs_none"]["better"] == 3 and t.tests["share_beats_none"] == 1.0
    assert t.tests["vs_none_all"]["p"] == pytest.approx(0.125)
    paths = t.to_csv(tmp_path)
    assert [p.name for p in paths] == ["table53.csv", "table53_none.csv",
                                       "table53_perfect.csv"]
    import csv

    with open(paths[0]) as fh:
        rows = list(csv.DictReader(fh))
    assert [r["model"] for r in rows] == ["input", "none", "perfect"]
    assert "beats none by > 0.05 px" in t.format()


def test_table53_quick_from_the_command_line_prints_both_variants(tmp_path, capsys):
    """``python -m map2map.experiments.table53`` on 2 tiny pairs with two models (none
    and the shipped thesis)."""
    from map2map.datasets.packed import save_packed
    from map2map.experiments.table53.__main__ import main

    p = _pairs3()
    save_packed(tmp_path / "h.npz", PackedPairs(p.a[:2], p.b[:2], p.plan_id[:2], p.split[:2]))
    assert main(["--data", str(tmp_path / "h.npz"), "--models", "none", "thesis",
                 "--out", str(tmp_path / "out")]) == 0
    out = capsys.readouterr().out
    assert "improved all" in out and "Error all" in out and "every point" in out
    assert "\nnone " in out and "\nthesis " in out and "vs none" in out
    for f in ("table53.csv", "table53_none.csv", "table53_thesis.csv", "table53.txt",
              "fig512.png", "examples.png", "heldout.npz"):
        assert (tmp_path / "out" / f).is_file()


def _tiny_dataset(tmp_path, splits):
    import cv2

    ds = tmp_path / "ds"
    ds.mkdir()
    with Manifest(ds / "manifest.sqlite") as man:
        for i, sp in enumerate(splits):
            folder = pair_dir(ds, i)
            folder.mkdir(parents=True)
            a = _plan(64, seed=i)
            cv2.imwrite(str(folder / "A.png"), a)
            cv2.imwrite(str(folder / "B.png"), _slam(a, i))
            man.record_done(i, f"gen-0-{i:06d}", "simulate", {}, split=sp, wall_seconds=1.0)
    return ds


def test_heldout_pairs_from_a_dataset_folder_read_only(tmp_path):
    ds = _tiny_dataset(tmp_path, ["train", "test", "val", "test"])
    before = {p.name: p.read_bytes() for p in ds.iterdir() if p.is_file()}
    assert "manifest.sqlite" in before
    got = heldout_pairs_from_dataset(ds, "test", keep=())
    assert got.plan_id.tolist() == ["gen-0-000001", "gen-0-000003"]
    assert got.a.shape == (2, 64, 64) and (got.a[0] == _plan(64, seed=1)).all()
    both = heldout_pairs_from_dataset(ds, ("test", "val"), n=2, keep=())
    assert both.plan_id.tolist() == ["gen-0-000001", "gen-0-000002"]
    with pytest.raises(InputError, match="not been cleaned"):
        heldout_pairs_from_dataset(ds, "test")                 # complete only: needs a cleaner
    with Manifest(ds / "manifest.sqlite") as man:
        man.set_clean([(1, 0.9, None, "complete"), (3, 0.1, None, "partial")])
    assert heldout_pairs_from_dataset(ds, "test").plan_id.tolist() == ["gen-0-000001"]
    assert len(merge_pairs(got, got)) == 2                      # each plan once


def test_heldout_reading_writes_nothing(tmp_path):
    ds = _tiny_dataset(tmp_path, ["test", "val"])
    before = {p.name: p.read_bytes() for p in ds.iterdir() if p.is_file()}
    assert len(heldout_pairs_from_dataset(ds, ("test", "val"), keep=())) == 2
    after = {p.name: p.read_bytes() for p in ds.iterdir() if p.is_file()}
    # the manifest is unchanged (SQLite's WAL mode adds its -wal/-shm index files to a
    # reader, as a running build has them anyway); no pair picture touched
    assert after["manifest.sqlite"] == before["manifest.sqlite"]
    assert set(after) - set(before) <= {"manifest.sqlite-wal", "manifest.sqlite-shm"}
    assert not after.get("manifest.sqlite-wal")


def test_anchored_walls_straighten_noisy_faces_where_they_were_seen():
    g = np.full((40, 60), FREE, np.uint8)
    g[20:22, 5:55] = OCCUPIED                       # an interior wall, faces at rows 20 and 21
    g[19, 5:55:4] = OCCUPIED                        # laser noise above it
    g[:8] = UNKNOWN                                 # an outer wall seen from below only
    g[8, 5:55] = OCCUPIED
    segs = np.array([[5.0, 22.0, 54.0, 22.0],        # the network's walls, 1-2 px off
                     [5.0, 7.0, 54.0, 7.0]])
    mask, centre = anchored_walls(g, segs, band=3, wall_px=4)
    rows = np.flatnonzero(mask[:, 30])
    assert rows.tolist() == [5, 6, 7, 8, 20, 21]     # faces kept, noise gone, outer wall
    assert centre[:, 1].tolist() == [20.5, 6.5]      # 4 px thick, grown into the unknown
    # the extension of a one-sided wall stops at space the input saw free
    g2 = g.copy()
    g2[:8] = FREE
    g2[9:, :] = UNKNOWN
    g2[8, 5:55] = OCCUPIED
    m2, _ = anchored_walls(g2, segs[1:], band=3, wall_px=4)
    assert np.flatnonzero(m2[:, 30]).tolist() == [8, 9, 10, 11]


def test_postprocess_anchor_keeps_the_input_faces_and_completes_unseen_walls():
    n = 128
    guide = np.full((n, n), UNKNOWN, np.uint8)
    guide[20:100, 20:100] = FREE
    guide[19, 19:101] = OCCUPIED
    guide[100, 19:101] = OCCUPIED
    guide[19:101, 19] = OCCUPIED                     # the right wall was never seen
    out = np.full((32, 32), 255.0, np.float32)       # the network: all four walls
    out[4:26, 4] = out[4:26, 25] = 0.0
    out[4, 4:26] = out[25, 4:26] = 0.0
    data, segs = postprocess(out, (n, n), guide, wall_px=3, data_px=n / 256)
    assert (data[19, 30:90] == OCCUPIED).all() and (data[20, 30:90] == FREE).all()
    assert (data[100, 30:90] == OCCUPIED).all() and (data[99, 30:90] == FREE).all()
    right = np.flatnonzero((data[30:90] == OCCUPIED).mean(0) > 0.9)
    assert any(95 <= c <= 106 for c in right)        # completed from the network's output
    old, _ = postprocess(out, (n, n), guide, wall_px=3, anchor=False)
    assert not (old[20, 30:90] == FREE).all() or not (old[19, 30:90] == OCCUPIED).all()


def test_postprocess_anchor_drops_clutter_the_network_does_not_see_as_wall():
    n = 128
    guide = np.full((n, n), UNKNOWN, np.uint8)
    guide[20:100, 20:100] = FREE
    guide[19, 19:101] = guide[100, 19:101] = OCCUPIED
    guide[19:101, 19] = guide[19:101, 100] = OCCUPIED
    guide[55:58, 55:58] = OCCUPIED                   # a chair in the middle of the room
    guide[30:33, 70:73] = OCCUPIED                   # a pillar the network keeps
    out = np.full((32, 32), 255.0, np.float32)
    out[4:26, 4] = out[4:26, 25] = out[4, 4:26] = out[25, 4:26] = 0.0
    out[8, 18] = 0.0                                 # the pillar's cell
    data, _ = postprocess(out, (n, n), guide, wall_px=3, data_px=n / 256)
    assert (data[55:58, 55:58] == FREE).all()
    assert (data[30:33, 70:73] == OCCUPIED).all()
    assert (data[19, 30:90] == OCCUPIED).all() and (data[20, 30:90] == FREE).all()
