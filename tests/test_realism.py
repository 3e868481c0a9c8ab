"""Realism statistics (issue #15) and the second simulated run of a dataset pair that
they are normalised by. Tiny maps and a 2-pair, 8 s simulated dataset."""

from __future__ import annotations

import json
import math

import numpy as np
import pytest
from _realism_data import room_dataset

from map2map.core.errors import InputError
from map2map.core.grid import FREE, OCCUPIED, UNKNOWN, OccupancyMap
from map2map.datasets.pair import BuildParams, read_pair_meta
from map2map.datasets.pairfolder import pair_dir
from map2map.datasets.rerun import rerun_pair
from map2map.experiments.realism.measure import (
    STATS,
    TARGET_RATIO,
    NullRatios,
    format_null,
    format_realism_table,
    map_stats,
    null_ratios,
    realism_table,
    simulated_references,
)


def _plan(n=48) -> np.ndarray:
    p = np.full((n, n), UNKNOWN, np.uint8)
    p[4:-4, 4:-4] = FREE
    p[4, 4:-4] = p[-5, 4:-4] = p[4:-4, 4] = p[4:-4, -5] = OCCUPIED
    p[4:-4, n // 2] = OCCUPIED
    return p


def test_map_stats_of_hand_made_maps():
    plan = _plan()
    s = map_stats(plan, plan)
    assert list(s) == list(STATS) == ["wall_err", "wall_seen", "free_mapped", "unknown",
                                      "spurious", "thickness", "bend", "doubled", "room_rot",
                                      "frontier_open", "frontier_rough", "streaks"]
    assert s["wall_err"] == 0 and s["wall_seen"] == 1 and s["free_mapped"] == 1
    assert s["unknown"] == 0 and s["spurious"] == 0
    # issue #33's SLAM errors (tests/test_realism_stats.py): none on the plan itself
    assert s["doubled"] == s["room_rot"] == s["frontier_open"] == s["streaks"] == 0
    assert math.isnan(s["frontier_rough"])
    m = plan.copy()
    m[:, 30:] = np.where(m[:, 30:] == FREE, UNKNOWN, m[:, 30:])
    m[10:12, 12:14] = OCCUPIED                      # a spurious blob 8 px from any wall
    m2 = np.roll(plan, 2, axis=0)                    # drift: walls 2 px off
    s, s2 = map_stats(m, plan), map_stats(m2, plan)
    assert s["spurious"] == 1 and 0 < s["free_mapped"] < 1 and s["unknown"] > 0.2
    assert s2["wall_err"] > 0.5 and s2["spurious"] == 0
    bent = plan.copy()
    bent[4:-4, plan.shape[0] // 2] = FREE
    rr = np.arange(5, plan.shape[0] - 5)
    bent[rr, (plan.shape[0] // 2 + 4 * np.sin(rr / 6)).astype(int)] = OCCUPIED
    assert map_stats(bent, plan)["bend"] > map_stats(plan, plan)["bend"]
    with pytest.raises(ValueError):
        map_stats(plan[:10], plan)


def test_realism_table_ratios():
    plan = np.stack([_plan()] * 6)
    rng = np.random.default_rng(0)

    def runs(shift):
        out = plan.copy()
        for k in range(len(out)):
            out[k] = np.roll(out[k], int(rng.integers(0, shift + 1)), axis=1)
        return out

    sim1, sim2 = runs(1), runs(1)
    rows = realism_table(sim2, sim1, sim2, plan)
    assert [r.statistic for r in rows] == list(STATS)
    assert all(r.ratio == 1.0 or math.isnan(r.ratio) or r.w_sims == 0 for r in rows)
    far = realism_table(runs(6), sim1, sim2, plan)
    err = next(r for r in far if r.statistic == "wall_err")
    assert err.ratio > 1.5 and err.met is False
    text = format_realism_table(far, "far")
    assert "NOT met" in text and "wall_err" in text


@pytest.fixture(scope="module")
def tiny_dataset(tmp_path_factory):
    return room_dataset(tmp_path_factory.mktemp("plans"), tmp_path_factory.mktemp("ds") / "DS",
                        2, 3)


def test_rerun_reproduces_run_1_and_run_2_is_another_run_on_the_same_pixels(tiny_dataset):
    import cv2

    ds = tiny_dataset
    meta = read_pair_meta(pair_dir(ds, 0))
    b1 = cv2.imread(str(pair_dir(ds, 0) / "B.png"), 0)
    same = rerun_pair(ds, 0, sim_seed=meta["sim_seed"])     # the pair code, run 1's seed
    assert same.a_matches and np.array_equal(same.b_n, b1)
    assert tuple(same.meta["start_pose"]) == tuple(meta["start_pose"])
    two = rerun_pair(ds, 0, 2)
    assert two.a_matches and two.b_n.shape == b1.shape
    assert two.meta["sim_seed"] != meta["sim_seed"]
    assert tuple(two.meta["start_pose"]) == tuple(meta["start_pose"])
    assert np.array_equal(rerun_pair(ds, 0, 2).b_n, two.b_n)   # seeded


def test_a_rerun_started_where_its_seed_puts_the_robot_is_drawn_as_the_build_drew(
        tiny_dataset):
    """``start="own"``: the start is drawn from the run's seed as the build drew run 1's
    (so run 1's own seed gives run 1 again, pixel for pixel), not the pair's pose."""
    import cv2

    ds = tiny_dataset
    meta = read_pair_meta(pair_dir(ds, 0))
    b1 = cv2.imread(str(pair_dir(ds, 0) / "B.png"), 0)
    again = rerun_pair(ds, 0, sim_seed=meta["sim_seed"], start="own")
    assert np.array_equal(again.b_n, b1) and again.meta["start_from"] == "own"
    own = rerun_pair(ds, 0, 2, start="own")
    pair = rerun_pair(ds, 0, 2)
    assert own.meta["sim_seed"] == pair.meta["sim_seed"] != meta["sim_seed"]
    assert tuple(pair.meta["start_pose"]) == tuple(meta["start_pose"])
    assert tuple(own.meta["start_pose"]) != tuple(meta["start_pose"])
    assert np.array_equal(rerun_pair(ds, 0, 2, start="own").b_n, own.b_n)     # seeded
    with pytest.raises(InputError, match="start: must be one of pair, own"):
        rerun_pair(ds, 0, 2, start="random")


def test_references_start_where_asked_and_do_not_depend_on_the_workers(tiny_dataset,
                                                                       tmp_path):
    """Runs 2 drawn on two worker processes are those drawn in this one; ``start`` is
    part of the cache's key (a ``pair`` cache is not read as an ``own`` one)."""
    from map2map.datasets.build import open_dataset

    with open_dataset(tiny_dataset) as man:
        rows = man.rows("done")
    split = "all" if len({r["split"] for r in rows}) > 1 else rows[0]["split"]
    cache = tmp_path / "own.npz"
    one = simulated_references(tiny_dataset, split=split, cache=cache, progress=False)
    two = simulated_references(tiny_dataset, split=split, progress=False, workers=2)
    assert len(one.indices) == 2 and np.array_equal(one.indices, two.indices)
    assert np.array_equal(one.sim2, two.sim2)
    assert np.array_equal(one.parametric, two.parametric)
    assert one.meta == two.meta
    starts = [tuple(read_pair_meta(pair_dir(tiny_dataset, int(i)))["start_pose"])
              for i in one.indices]
    assert all(tuple(m["start_pose"]) != s for m, s in zip(one.meta, starts, strict=True))
    pair = simulated_references(tiny_dataset, split=split, cache=cache, progress=False,
                                start="pair")
    assert [tuple(m["start_pose"]) for m in pair.meta] == starts
    with np.load(cache) as z:                      # rewritten for the pair's start
        assert "start" not in json.loads(str(z["key"]))
    with pytest.raises(InputError, match="start: must be one of"):
        simulated_references(tiny_dataset, split=split, progress=False, start="random")


def test_simulated_references_are_cached(tiny_dataset, tmp_path, monkeypatch):
    from map2map.datasets.build import open_dataset

    with open_dataset(tiny_dataset) as man:
        split = man.rows("done")[0]["split"]
    cache = tmp_path / "refs.npz"
    refs = simulated_references(tiny_dataset, split=split, n=1, cache=cache, progress=False)
    assert refs.a.shape == refs.sim1.shape == refs.sim2.shape == refs.parametric.shape
    assert refs.a.shape[1:] == (32, 32) and cache.is_file()
    import map2map.datasets.rerun as R

    monkeypatch.setattr(R, "rerun_pair", lambda *a, **k: pytest.fail("simulated again"))
    again = simulated_references(tiny_dataset, split=split, n=1, cache=cache, progress=False)
    assert np.array_equal(again.sim2, refs.sim2)
    # each square's metres per pixel: the pair's crop window over 32 px (the drift's scale)
    from map2map.datasets.pair import crop_box, window_resolution
    from map2map.maps.formats import load_map

    folder = pair_dir(tiny_dataset, int(refs.indices[0]))
    a, b = load_map(folder / "A.yaml"), load_map(folder / "B.yaml")
    assert refs.resolution.tolist() == [window_resolution(a, crop_box(a, b), 32)]
    assert refs.resolution[0] >= a.resolution * max(a.shape) / 32 * 0.5
    rows = realism_table(refs.parametric, refs.sim1, refs.sim2, refs.a)
    assert len(rows) == len(STATS)


def _untrained(size):
    torch = pytest.importorskip("torch")
    from map2map.learn.ab.model import ABModel
    from map2map.learn.nets.progressive import StochasticUNet

    torch.manual_seed(0)
    return ABModel(StochasticUNet(size=16, channels=8), resolution=16, alpha=1.0,
                   data_size=size, header={}, source="untrained")


def test_fig514_from_a_dataset_and_from_plans(tiny_dataset, tmp_path):
    from map2map.datasets.build import open_dataset
    from map2map.experiments.fig514.measure import METHODS, run_fig514

    with open_dataset(tiny_dataset) as man:
        split = man.rows("done")[0]["split"]
    f = run_fig514(tiny_dataset, 1, _untrained(32), split=split, progress=False)
    assert [r["method"] for r in f.rows] == list(METHODS)
    assert all(set(r) >= {"plan", "method", "error_px", "wall_recall"} for r in f.rows)
    assert f.info[f.plan_ids[0]]["reproduces_dataset_map"] is True
    assert f.drift.startswith("parametric (additive x1")
    assert f.info[f.plan_ids[0]]["square_resolution_m"] > 0
    assert set(f.summary) >= {"n", "model", *METHODS} and f.summary["n"] == 1
    for m in METHODS:
        assert f.maps[m].shape == (1, 32, 32)
    f.figure(tmp_path / "f.png")
    f.write_csv(tmp_path / "f.csv")
    assert (tmp_path / "f.png").stat().st_size > 1000
    assert len((tmp_path / "f.csv").read_text().splitlines()) == 1 + len(METHODS)
    d = np.full((50, 70), 127, np.uint8)
    d[2:-2, 2:-2] = 0
    d[4:-4, 4:-4] = 255
    p = BuildParams(source="simulate", duration=8.0, size=32, fov=360.0)
    g = run_fig514([OccupancyMap(d, 0.05)], 1, _untrained(32), params=p, progress=False,
                   drift="none")
    assert g.drift == "none"
    assert g.plan_ids == ["plan 0"] and len(g.rows) == len(METHODS)


def test_native_seen_maps_the_plans_own_exploration_onto_the_square(tiny_dataset):
    from map2map.datasets.build import open_dataset
    from map2map.datasets.pair import crop_box, preprocess_pair
    from map2map.experiments.realism.measure import native_seen
    from map2map.learn.ab.coverage import ExploreParams
    from map2map.maps.formats import load_map

    with open_dataset(tiny_dataset) as man:
        idx = sorted(int(r["idx"]) for r in man.rows("done"))
    ep = ExploreParams(duration=60.0, fov=360.0)
    seen = native_seen(tiny_dataset, idx, 32, seed=3, params=ep, progress=False)
    assert seen.shape == (len(idx), 32, 32) and seen.dtype == bool
    assert np.array_equal(seen, native_seen(tiny_dataset, idx, 32, seed=3, params=ep,
                                            progress=False))
    for j, i in enumerate(idx):
        folder = pair_dir(tiny_dataset, i)
        a, b = load_map(folder / "A.yaml"), load_map(folder / "B.yaml")
        sq, _ = preprocess_pair(a, b, 32, 0, crop_box(a, b))
        # the room explored for a minute: its square's free pixels are seen, the square's
        # unknown padding around the plan is not (but for a few hits past the walls)
        assert seen[j][sq == FREE].mean() > 0.95
        pad = ndimage_far(sq != UNKNOWN, 2)
        assert pad.sum() > 100 and seen[j][pad].mean() < 0.05
    short = native_seen(tiny_dataset, idx[:1], 32, seed=3, progress=False,
                        params=ExploreParams(duration=0.5, fov=180.0))
    assert short[0].sum() < seen[0].sum()           # half a second sees less


def ndimage_far(known: np.ndarray, d: int) -> np.ndarray:
    from scipy import ndimage

    return ndimage.distance_transform_edt(~known) > d


def test_synthesize_squares_hides_what_given_seen_cells_leave_out():
    from map2map.learn.ab.synthesize import synthesize_squares

    net = _untrained(32)
    plans = np.stack([_plan(32)] * 2)
    seen = np.zeros(plans.shape, bool)
    seen[0] = True
    seen[1, :8, :8] = True
    out = synthesize_squares(net, plans, drift="none", coverage="explore", seen=seen)
    ref = synthesize_squares(net, plans, drift="none")
    assert np.array_equal(out[0], ref[0])                    # all seen: nothing hidden
    from scipy import ndimage

    from map2map.learn.ab.coverage import ExploreParams

    k = ExploreParams().margin(net.wall_px)                  # the rendered walls' band
    keep = ndimage.binary_dilation(seen[1], np.ones((3, 3), bool), iterations=k)
    assert np.all(out[1][~keep] == UNKNOWN) and np.array_equal(out[1][keep], ref[1][keep])
    assert (out[1] != ref[1]).any()
    with pytest.raises(ValueError, match="differ in shape"):
        synthesize_squares(net, plans, drift="none", coverage="explore", seen=seen[:1])
    with pytest.raises(ValueError, match="coverage='explore'"):
        synthesize_squares(net, plans, drift="none", seen=seen)


def test_fig514_draws_model_ab_as_synthesize_does(tiny_dataset):
    from map2map.datasets.build import open_dataset
    from map2map.experiments.fig514.measure import run_fig514

    with open_dataset(tiny_dataset) as man:
        split = man.rows("done")[0]["split"]
    kw = dict(split=split, progress=False, drift="none", coverage="explore")
    sq = run_fig514(tiny_dataset, 1, _untrained(32), **kw)
    nat = run_fig514(tiny_dataset, 1, _untrained(32), explore_at="native", **kw)
    full = run_fig514(tiny_dataset, 1, _untrained(32), explore_at="native", traces="lidar",
                      **{**kw, "drift": "rooms"})
    assert "explored at native resolution" in nat.drift and "square" in sq.drift
    assert full.drift.startswith("rooms") and "LIDAR traces" in full.drift
    assert nat.maps["simulated"].tobytes() == sq.maps["simulated"].tobytes()
    assert nat.maps["model_ab"].shape == (1, 32, 32)
    assert nat.maps["model_ab"].tobytes() != sq.maps["model_ab"].tobytes()
    with pytest.raises(ValueError, match="explore_at"):
        run_fig514(tiny_dataset, 1, _untrained(32), explore_at="moon", **kw)


def test_realism_table_halves_are_the_ratio_on_every_other_plan():
    from scipy.stats import wasserstein_distance as W

    rng = np.random.default_rng(1)
    st = [{s: rng.normal(m, 1.0, 50) for s in STATS} for m in (0.4, 0.0, 0.0)]
    st[0]["wall_err"][3] = np.nan                        # a map without walls
    rows = realism_table(*st, None, halves=True)
    plain = realism_table(*st, None)
    assert [r.ratio for r in plain] == [r.ratio for r in rows]    # the ratio unchanged
    assert all(math.isnan(r.ratio_even) for r in plain)
    g, r1, r2 = (x["bend"][1::2] for x in st)
    assert math.isclose(rows[STATS.index("bend")].ratio_odd, W(g, r1) / W(r2, r1))
    g, r1, r2 = (x["wall_err"][0::2] for x in st)
    assert np.isnan(g).sum() == 0 and rows[0].ratio_even == W(g, r1) / W(r2, r1)
    assert math.isfinite(rows[0].ratio_odd)                  # the NaN map is left out
    text = format_realism_table(rows, "g")
    assert "even / odd" in text.splitlines()[0] and " / " in text.splitlines()[1]
    assert "even / odd" not in format_realism_table(plain, "g")
    long = format_realism_table(plain, "AB:model.safetensors [cover explore, traces lidar]")
    assert long.splitlines()[0].startswith("generator: AB:model.safetensors [cover")
    assert long.splitlines()[1].split()[:2] == ["statistic", "generated"]


def test_null_ratios_are_a_perfect_generators_scatter_and_flag_a_shifted_one():
    """null_ratios: per plan, three exchangeable runs' roles shuffled. Its draws centre on
    1 (the runs are alike) yet scatter widely (a ratio of two sample distances), the
    same seed gives the same draws, and a generator shifted by a tenth of a run's spread
    ranks above every draw."""
    rng = np.random.default_rng(3)
    n = 300
    plan_effect = {s: rng.normal(0, 1, n) for s in STATS}  # plans differ; runs of a plan less
    runs = [{s: plan_effect[s] + rng.normal(0, 0.3, n) for s in STATS} for _ in range(3)]
    null = null_ratios(runs, draws=300, seed=1)
    assert null.ratios.shape == (300, len(STATS)) and (null.runs, null.plans) == (3, n)
    assert np.array_equal(null.ratios, null_ratios(runs, draws=300, seed=1).ratios)
    med = np.median(null.ratios, 0)
    assert np.all((med > 0.75) & (med < 1.35))
    p = null.p_within()
    assert 0.0 < p["worst"] < min(p[s] for s in STATS) <= 1.0  # all at once: rarer
    q = null.quantiles()
    assert q["worst"][0] >= max(q[s][0] for s in STATS) and q["worst"][3] > TARGET_RATIO
    shifted = {s: plan_effect[s] + rng.normal(0, 0.3, n) + 0.1 for s in STATS}
    r = realism_table(shifted, runs[0], runs[1], None)[0]
    assert null.rank(r.statistic, r.ratio) > 0.99
    assert null.rank("worst", 0.0) == 0.0
    # a NaN (map without walls) is left out of its statistic, as realism_table does
    runs[2]["bend"][:5] = np.nan
    assert np.isfinite(null_ratios(runs, draws=5).ratios).all()
    with pytest.raises(ValueError, match=">= 3"):
        null_ratios(runs[:2])
    text = format_null(NullRatios(np.full((2, len(STATS)), 2.0), 3, 5))
    assert text.splitlines()[-1].split()[0] == "worst" and text.endswith("0.000")


def test_benchmark_third_run_is_measured_as_a_generator(tiny_dataset, tmp_path, capsys):
    """map2map.experiments.realism --third-run: a third simulation of every plan, measured like a
    generator (the benchmark's noise floor), cached in its own file."""
    import importlib

    from map2map.datasets.build import open_dataset

    with open_dataset(tiny_dataset) as man:
        split = man.rows("done")[0]["split"]
    mod = importlib.import_module("map2map.experiments.realism.__main__")
    c2, c3 = tmp_path / "refs2.npz", tmp_path / "refs3.npz"
    assert mod.main(["--data", str(tiny_dataset), "--split", split, "--plans", "1",
                     "--cache", str(c2), "--third-run", str(c3), "--model"]) == 0
    out = capsys.readouterr().out
    assert "statistic simulated run 3" in out and c3.is_file()
    assert "a perfect generator on these 1 plans" in out  # the null table
    run2 = simulated_references(tiny_dataset, split=split, n=1, cache=c2, progress=False)
    run3 = simulated_references(tiny_dataset, split=split, n=1, cache=c3, run=3,
                                progress=False)
    assert run3.meta[0]["sim_seed"] != run2.meta[0]["sim_seed"]
    # with a Model_AB generator: its ratios beside run 3's, per statistic and worst
    rows = [{"generator": g, "statistic": st, "ratio": r}
            for g, rs in (("parametric", (9.0, 9.0)), ("simulated run 3", (1.2, 0.8)),
                          ("Model_AB [x]", (3.0, 2.5)))
            for st, r in zip(("wall_err", "bend"), rs, strict=True)]
    mod._against_floor(rows)
    out = capsys.readouterr().out.splitlines()
    assert "Model_AB [x]" in out[2] and "parametric" not in out[2]
    assert out[3].split() == ["wall_err", "1.20", "3.00"]
    assert out[-1].split() == ["worst", "1.20", "3.00"]
    null = NullRatios(np.ones((4, len(STATS))), 3, 1)  # every draw scores 1
    mod._against_floor(rows, null)
    out = capsys.readouterr().out.splitlines()
    assert out[3].split() == ["wall_err", "1.20", "(100.0%)", "3.00", "(100.0%)"]


def test_a_failed_second_run_leaves_its_plan_out_and_is_cached(tiny_dataset, tmp_path,
                                                               monkeypatch):
    """A second simulation can fail where the first ran (a gen6400 test plan's robot
    could not move with run 2's seed): the plan is left out with a warning, not the
    whole benchmark, and the failure is not simulated again."""
    import map2map.datasets.rerun as R
    from map2map.core.errors import InputError
    from map2map.datasets.build import open_dataset

    with open_dataset(tiny_dataset) as man:
        split = man.rows("done")[0]["split"]
    cache = tmp_path / "refs.npz"
    good = simulated_references(tiny_dataset, split=split, n=1, cache=tmp_path / "ok.npz",
                                progress=False)
    assert len(good.only([]).indices) == 0
    assert np.array_equal(good.only(good.indices).sim2, good.sim2)

    def stuck(ds, index, run=2, **kw):
        raise InputError(None, "the robot could not move (drove 0.00 m)")

    monkeypatch.setattr(R, "rerun_pair", stuck)
    with pytest.warns(UserWarning, match="could not move"), \
            pytest.raises(InputError, match="no .* plan has a simulated run 2"):
        simulated_references(tiny_dataset, split=split, n=1, cache=cache, progress=False)
    monkeypatch.setattr(R, "rerun_pair", lambda *a, **k: pytest.fail("simulated again"))
    with pytest.warns(UserWarning, match="1 of 1 plans left out"), \
            pytest.raises(InputError):
        simulated_references(tiny_dataset, split=split, n=1, cache=cache, progress=False)


def test_fig514_draws_synthesizes_default_scans(tiny_dataset, tmp_path):
    """``model="scans"``: the generated column is ``synthesize``'s default (no network),
    named so in the table, the figure and the drift line, and it is the same map as
    ``synthesize`` itself makes of the pair's plan (hypothesis 0, seed + index), cut with
    the pair's window."""
    import warnings

    from map2map.datasets.build import open_dataset
    from map2map.datasets.pair import crop_box, preprocess_pair
    from map2map.datasets.pairfolder import PLAN_YAML, SLAM_YAML, pair_dir
    from map2map.experiments.fig514.measure import run_fig514
    from map2map.learn.ab.synthesize import SCANS, synthesize
    from map2map.maps.formats import load_map

    with open_dataset(tiny_dataset) as man:
        row = man.rows("done")[0]
    f = run_fig514(tiny_dataset, 1, "scans", split=row["split"], progress=False, seed=3)
    assert f.summary["model"] == "scans" and f.drift.startswith("scans: ")
    assert "synthesize (scans)" in f.table()
    i = f.indices[0]
    a, b = load_map(pair_dir(tiny_dataset, i) / PLAN_YAML), load_map(pair_dir(tiny_dataset, i)
                                                                     / SLAM_YAML)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        h = synthesize(a, SCANS, samples=1, seed=3 + i).maps[0]
    want = preprocess_pair(a, h, f.plans.shape[-1], 0, crop_box(a, b))[1]
    assert np.array_equal(f.maps["model_ab"][0], want)
    f.figure(tmp_path / "s.png")
    assert (tmp_path / "s.png").stat().st_size > 1000
    assert not any("not used by scans" in w for w in f.warnings)
    g = run_fig514(tiny_dataset, 1, "scans", split=row["split"], progress=False, seed=3,
                   drift="rooms", traces="lidar")
    assert any(w.startswith("drift, traces: Model_AB's options") for w in g.warnings)
