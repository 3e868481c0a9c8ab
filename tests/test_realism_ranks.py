"""Realism judged per plan (issue #33): ranks among simulated runs, the classifier
two-sample test, and the per-plan benchmark end to end on a small simulated dataset."""

from __future__ import annotations

import importlib
import json

import numpy as np
import pytest
from _realism_data import room_dataset

from map2map.core.grid import FREE, OCCUPIED, UNKNOWN
from map2map.experiments.realism.ranks import (
    EXTREME_MAX,
    perfect_chance,
    plan_ranks,
    rank_table,
    shuffled_runs,
)


def _runs(n, k, rng, *, integer=False):
    """``k`` exchangeable runs of ``n`` plans whose statistics differ much more between
    plans than between runs of a plan."""
    plan = rng.normal(0, 10, n)
    runs = [{"x": plan + rng.normal(0, 1, n), "y": rng.poisson(2 + plan.clip(0, 5), n)
             if integer else plan * 2 + rng.normal(0, 1, n)} for _ in range(k)]
    return runs


@pytest.mark.parametrize("integer", [False, True])
def test_ranks_of_a_perfect_generator_are_uniform(integer):
    rng = np.random.default_rng(3)
    gen, runs = shuffled_runs(_runs(3000, 4, rng, integer=integer), seed=5)
    rows = rank_table(plan_ranks(gen, runs, stats=("x", "y"), seed=1), 3)
    for r in rows:
        assert r.plans == 3000
        assert abs(r.extreme - 0.5) < 0.035, r     # 3.8 standard errors at 3,000 plans
        assert abs(r.ends) < 0.045, r              # 3.5 standard errors
        assert r.p_uniform > 1e-3 and r.p_extreme > 1e-3, r
        assert r.met


def test_ties_are_broken_at_random_not_towards_an_end():
    """Equal values (a count statistic where every map scores 0) rank uniformly."""
    zeros = {"x": np.zeros(4000)}
    rows = rank_table(plan_ranks(zeros, [zeros] * 3, stats=("x",), seed=0), 3)
    assert abs(rows[0].low - 0.25) < 0.03 and abs(rows[0].high - 0.25) < 0.03
    again = plan_ranks(zeros, [zeros] * 3, stats=("x",), seed=0)["x"]
    assert np.array_equal(again, plan_ranks(zeros, [zeros] * 3, stats=("x",), seed=0)["x"])


def test_a_shifted_generator_is_caught_at_its_end():
    rng = np.random.default_rng(4)
    runs = _runs(600, 4, rng)
    gen, runs = runs[0], runs[1:]
    gen = {"x": gen["x"] + 1.0, "y": gen["y"] - 1.0}    # one within-plan sd up / down
    rows = {r.statistic: r for r in rank_table(plan_ranks(gen, runs, stats=("x", "y")), 3)}
    assert rows["x"].extreme > EXTREME_MAX and rows["x"].high > rows["x"].low + 0.2
    assert rows["y"].low > rows["y"].high + 0.2
    assert rows["x"].p_extreme < 1e-6 and rows["x"].p_ends < 1e-6 and not rows["x"].met


def test_the_holm_verdict_flags_a_perfect_generator_rarely_and_a_shifted_one_surely():
    """Calibrated verdict: over 12 statistics and 100 perfect generators at 600 plans, a
    statistic is told apart (Holm < 0.05) in at most about 5 % of the tables; a generator
    shifted on one statistic by half a within-plan sd is told apart there, and only
    there."""
    from map2map.experiments.realism.ranks import ALPHA, format_rank_table

    rng = np.random.default_rng(7)
    stats = tuple(f"s{j}" for j in range(12))
    flagged = 0
    for t in range(100):
        plan = rng.normal(0, 10, (12, 600))
        runs = [{s: plan[j] + rng.normal(0, 1, 600) for j, s in enumerate(stats)}
                for _ in range(4)]
        gen, others = shuffled_runs(runs, seed=t)
        rows = rank_table(plan_ranks(gen, others, stats=stats, seed=t), 3)
        flagged += any(r.holm < ALPHA for r in rows)
    assert flagged <= 12                              # 5 % expected; binomial 99.9 % bound
    plan = rng.normal(0, 10, (12, 600))
    runs = [{s: plan[j] + rng.normal(0, 1, 600) for j, s in enumerate(stats)}
            for _ in range(4)]
    gen = dict(runs[0], s3=runs[0]["s3"] + 0.5)
    rows = rank_table(plan_ranks(gen, runs[1:], stats=stats), 3)
    assert [r.statistic for r in rows if r.holm < ALPHA] == ["s3"]
    assert "told apart on 1 of 12: s3" in format_rank_table(rows)


def test_nan_values_leave_their_plan_out_of_that_statistic():
    g = {"x": np.array([1.0, np.nan, 3.0])}
    runs = [{"x": np.array([2.0, 2.0, np.nan])}]
    rk = plan_ranks(g, runs, stats=("x",))["x"]
    assert rk.tolist() == [1, 0, 0]
    assert rank_table({"x": rk}, 1)[0].plans == 1


def test_perfect_chance_of_the_issue_target_grows_with_the_plans():
    one_600, all_600 = perfect_chance(600, 3, 12, draws=5000)
    one_3000, _ = perfect_chance(3000, 3, 12, draws=5000)
    assert 0.85 < one_600 < 0.95 and all_600 < 0.5 and one_3000 > 0.99


def _maps(n, speckle_seed, doubled):
    """16 plans (one wall each, the same for every call) and a map of each: the wall,
    speckle drawn from ``speckle_seed``, and the wall saved a second time if ``doubled``."""
    rng, speck = np.random.default_rng(0), np.random.default_rng(speckle_seed)
    plans = np.full((n, 64, 64), FREE, np.uint8)
    plans[:, :, :4] = UNKNOWN
    maps = plans.copy()
    for i, c in enumerate(rng.integers(16, 48, n)):
        plans[i, :, c:c + 2] = OCCUPIED
        maps[i, :, c:c + 2] = OCCUPIED
        maps[i, speck.random(64) < 0.1, int(speck.integers(8, 60))] = OCCUPIED
        if doubled:
            maps[i, :, c + 4:c + 6] = OCCUPIED
    return plans, maps


def test_classifier_tells_a_generator_apart_and_is_deterministic_per_seed():
    pytest.importorskip("torch")
    from map2map.learn.two_sample import two_sample_auc

    plans, a = _maps(16, 1, False)
    _, b = _maps(16, 2, True)                            # walls saved twice
    r1 = two_sample_auc(plans, a, b, crop=32, steps=80, seed=2)
    r2 = two_sample_auc(plans, a, b, crop=32, steps=80, seed=2)
    assert r1.auc == r2.auc and r1.paired == r2.paired
    assert r1.auc > 0.9 and r1.paired > 0.9
    _, c = _maps(16, 3, False)                           # the same process: no signal
    same = two_sample_auc(plans, a, c, crop=32, steps=80, seed=2)
    assert same.auc < 0.8


def test_classifier_early_stopping_keeps_the_best_held_out_step():
    """patience > 0: each fold keeps the network of its lowest held-out loss, checked every
    ``check_every`` steps, stopped early or at ``steps``; deterministic per seed; the
    fixed-steps result records ``steps`` per fold."""
    pytest.importorskip("torch")
    from map2map.learn.two_sample import two_sample_auc

    plans, a = _maps(20, 1, False)
    _, b = _maps(20, 2, True)
    kw = dict(crop=32, steps=400, seed=1, patience=2, check_every=40)
    r1, r2 = two_sample_auc(plans, a, b, **kw), two_sample_auc(plans, a, b, **kw)
    assert r1.auc == r2.auc and r1.trained == r2.trained
    assert len(r1.trained) == 2
    assert all(0 < t <= 400 and t % 40 == 0 for t in r1.trained)
    assert r1.auc > 0.9
    fixed = two_sample_auc(plans, a, b, crop=32, steps=60, seed=1)
    assert fixed.trained == (60, 60)


@pytest.fixture(scope="module")
def small_dataset(tmp_path_factory):
    return room_dataset(tmp_path_factory.mktemp("plans"), tmp_path_factory.mktemp("ds") / "DS",
                        4, 7)


def test_per_plan_benchmark_end_to_end(small_dataset, tmp_path, capsys):
    pytest.importorskip("torch")
    mod = importlib.import_module("map2map.experiments.realism.per_plan.__main__")
    out_json, fig, maps = tmp_path / "r.json", tmp_path / "f.png", tmp_path / "maps.npz"
    args = ["--data", str(small_dataset), "--split", "all", "--cache2",
            str(tmp_path / "c2.npz"), "--cache3", str(tmp_path / "c3.npz"),
            "--maps-cache", str(maps), "--classifier-steps", "20", "--json", str(out_json),
            "--figure", str(fig)]
    assert mod.main(args) == 0
    out = capsys.readouterr().out
    assert "4 plans ('all'" in out
    assert "run 3 among run 1 and run 2" in out and "parametric: rank among 3" in out
    assert "Model_AB network alone: rank among 3" in out and "Model_AB synthesize" in out
    assert "run 2 (floor)" in out and fig.stat().st_size > 1000 and maps.is_file()
    rep = json.loads(out_json.read_text())
    assert rep["plans"] == 4 and set(rep["classifier"]) == {
        "run 2 (floor)", "parametric", "Model_AB network alone", "Model_AB synthesize"}
    assert all(r["plans"] <= 4 for r in rep["ranks"]["parametric"])
    # three classifier seeds by default: the AUC reported is their mean
    for c in rep["classifier"].values():
        assert c["seeds"] == [0, 1, 2] and len(c["aucs"]) == 3
        assert c["auc"] == pytest.approx(np.mean(c["aucs"])) and c["sd"] >= 0
    div = rep["diversity"]["pretrained"]
    assert 0 < div["network"] <= div["synthesize"] and div["ratio"] > 0
    from map2map.experiments.realism.per_plan.summary import sentences

    said = sentences(rep)      # ranks and classifier per Model_AB generator, diversity
    assert len(said) == 5 and all(line.endswith(".") for line in said)
    # runs and hypotheses are cached: a second call simulates and synthesizes nothing and
    # prints the same figures
    assert mod.main(args) == 0
    out = capsys.readouterr().out
    assert "simulating" not in out
    rep2 = json.loads(out_json.read_text())
    for r in (rep, rep2):
        for c in r["classifier"].values():
            c.pop("seconds")
    assert rep2 == rep


def test_per_plan_variants_ranks_each_synthesize_variant(small_dataset, tmp_path, capsys):
    pytest.importorskip("torch")
    mod = importlib.import_module("map2map.experiments.realism.per_plan.__main__")
    caches = ["--cache2", str(tmp_path / "c2.npz"), "--cache3", str(tmp_path / "c3.npz")]
    assert mod.main(["--data", str(small_dataset), "--split", "all", *caches,
                     "--classifier-steps", "0"]) == 0       # runs 2 and 3 cached
    capsys.readouterr()
    from map2map.experiments.realism.per_plan.variants import main

    assert main(["--data", str(small_dataset), *caches, "--plans", "3",
                 "--variant", "explore", '{"coverage": "explore"}',
                 "--variant", "rays", '{"coverage": "rays", "traces": {"floor_px": 0.8}, '
                 '"explore": {"duration": 30.0}}']) == 0
    out = capsys.readouterr().out
    assert "explore: 3 plans" in out and "rays: 3 plans" in out
    assert "rays: rank among 3 simulated runs of its plan, 3 plans" in out
    assert "frontier_rough" in out


def test_per_plan_benchmark_measures_synthesize_scans(small_dataset, tmp_path, capsys):
    """``--model scans``: one generator (no network alone), its diversity without a
    network's share, and the sentences for ``reproduce``."""
    pytest.importorskip("torch")
    mod = importlib.import_module("map2map.experiments.realism.per_plan.__main__")
    out_json = tmp_path / "r.json"
    args = ["--data", str(small_dataset), "--split", "all", "--cache2",
            str(tmp_path / "c2.npz"), "--cache3", str(tmp_path / "c3.npz"), "--model", "scans",
            "--maps-cache", str(tmp_path / "maps.npz"), "--classifier-steps", "20",
            "--classifier-patience", "1", "--json", str(out_json)]
    assert mod.main(args) == 0
    out = capsys.readouterr().out
    assert "scans synthesize: rank among 3" in out and "network alone" not in out
    assert "early stopping, patience 1, at most 20 steps" in out and "steps kept" in out
    rep = json.loads(out_json.read_text())
    assert set(rep["classifier"]) == {"run 2 (floor)", "parametric", "scans synthesize"}
    assert all(len(t) == 2 and max(t) <= 20 for t in rep["classifier"]["parametric"]["trained"])
    assert rep["diversity"]["scans"]["ratio"] > 0 and "network" not in rep["diversity"]["scans"]
    from map2map.experiments.realism.per_plan.summary import sentences

    said = sentences(rep)
    assert len(said) == 3 and "no network" in said[-1]
    # the hypotheses are cached: the second call synthesizes nothing, same figures
    assert mod.main(args) == 0
    rep2 = json.loads(out_json.read_text())
    for r in (rep, rep2):
        for c in r["classifier"].values():
            c.pop("seconds")
    assert rep2 == rep
    # --samples 1 (no diversity) on one process: hypothesis 0 of each plan is the one
    # that three hypotheses on two processes began with
    one = tmp_path / "one.npz"
    capsys.readouterr()
    assert mod.main(args[:-2] + ["--samples", "1", "--workers", "1", "--classifier-steps",
                                 "0", "--maps-cache", str(one)]) == 0
    assert "Diversity" not in capsys.readouterr().out
    with np.load(one) as z1, np.load(tmp_path / "maps.npz") as z3:
        assert json.loads(str(z1["key"]))["samples"] == 1
        assert z1["synthesize"].shape[1] == 1 and z3["synthesize"].shape[1] == 3
        assert np.array_equal(z1["synthesize"][:, 0], z3["synthesize"][:, 0])
    # --start pair: runs 2, 3 and the hypotheses start at run 1's pose (their own keys)
    assert mod.main(args + ["--start", "pair", "--classifier-steps", "0"]) == 0
    rep3 = json.loads(out_json.read_text())
    assert "scans synthesize, pair's start" in {r for r in rep3["ranks"]}
    with np.load(tmp_path / "maps.npz") as z:
        assert json.loads(str(z["key"]))["start"] == "pair"
    with np.load(tmp_path / "c2.npz") as z:
        assert "start" not in json.loads(str(z["key"]))


def test_per_plan_variants_takes_a_model_per_variant_and_the_classifier(small_dataset,
                                                                       tmp_path, capsys):
    pytest.importorskip("torch")
    mod = importlib.import_module("map2map.experiments.realism.per_plan.__main__")
    caches = ["--cache2", str(tmp_path / "c2.npz"), "--cache3", str(tmp_path / "c3.npz")]
    assert mod.main(["--data", str(small_dataset), "--split", "all", *caches,
                     "--classifier-steps", "0"]) == 0
    capsys.readouterr()
    from map2map.experiments.realism.per_plan.variants import main

    assert main(["--data", str(small_dataset), *caches, "--plans", "4", "--samples", "1",
                 "--classifier-steps", "10", "--classifier-seeds", "2", "--floor",
                 "--save-maps", str(tmp_path / "saved"), "--variant", "scans",
                 '{"model": "scans", "scans": {"duration": 60, "rooms": {"rot_deg": 2}}}',
                 "--variant", "still", '{"model": "scans", "scans": {"duration": 60, '
                 '"jitter_m": 0, "jitter_deg": 0}}']) == 0
    out = capsys.readouterr().out
    assert "scans: 4 plans" in out and "scans: rank among 3 simulated runs" in out
    # the two variants share each plan's exploration (drawn_hypothesis); each map is
    # still synthesize's first hypothesis with the variant's settings
    from dataclasses import replace

    from map2map.datasets.pair import crop_box, preprocess_pair
    from map2map.datasets.pairfolder import PLAN_YAML, SLAM_YAML, pair_dir
    from map2map.learn.ab.scans import ScanMapParams
    from map2map.learn.ab.synthesize import SCANS, synthesize
    from map2map.maps.formats import load_map

    sp = ScanMapParams(duration=60, rooms=replace(ScanMapParams().rooms, rot_deg=2))
    for name, params in (("scans", sp), ("still", ScanMapParams(duration=60, jitter_m=0,
                                                                jitter_deg=0))):
        with np.load(tmp_path / "saved" / f"{name}.npz") as z:
            i, got, size = int(z["indices"][1]), z["maps"][1], z["plans"].shape[-1]
        a, b = (load_map(pair_dir(small_dataset, i) / f) for f in (PLAN_YAML, SLAM_YAML))
        want = synthesize(a, SCANS, samples=1, seed=i, scans=params).maps[0]
        assert np.array_equal(got, preprocess_pair(a, want, size, 0, crop_box(a, b))[1])
    assert "scans: classifier AUC" in out and "over 2 seed(s)" in out
    assert "run 2 (floor): classifier AUC" in out      # --floor: run 2 against run 3
    with np.load(tmp_path / "saved" / "scans.npz") as z:     # scored again from these
        assert z["maps"].shape == z["plans"].shape == z["run3"].shape
        assert z["maps"].shape[0] == len(z["indices"]) == 4
        assert not np.array_equal(z["maps"], z["run1"])
    # what gives the variant away: the classifier's most telling crops of held-out plans
    from map2map.experiments.realism.per_plan.tells import main as tells

    fig = tmp_path / "tells.png"
    assert tells([str(tmp_path / "saved" / "scans.npz"), "--out", str(fig), "--steps", "20",
                  "--top", "2"]) == 0
    told = capsys.readouterr().out
    assert "held-out AUC" in told and fig.stat().st_size > 1000
    assert tells([str(tmp_path / "c2.npz"), "--out", str(fig)]) == 2     # not a saved file
    assert "not a per_plan.variants --save-maps file" in capsys.readouterr().err
    medians = out[out.index("median "):].splitlines()
    assert "bend" in medians[0] and "streaks" in medians[0]
    assert [r.split()[0] for r in medians[1:5]] == ["run", "run", "run", "scans"]
    assert all(len(r.split()) == len(medians[0].split()) + (r.startswith(" run")) for r in
               medians[1:5])


def test_per_plan_variants_maps_do_not_depend_on_workers(small_dataset, tmp_path, capsys):
    pytest.importorskip("torch")
    mod = importlib.import_module("map2map.experiments.realism.per_plan.__main__")
    caches = ["--cache2", str(tmp_path / "c2.npz"), "--cache3", str(tmp_path / "c3.npz")]
    assert mod.main(["--data", str(small_dataset), "--split", "all", *caches,
                     "--classifier-steps", "0"]) == 0
    from map2map.experiments.realism.per_plan.variants import main

    for w in (1, 2):
        assert main(["--data", str(small_dataset), *caches, "--plans", "4", "--samples", "1",
                     "--workers", str(w), "--save-maps", str(tmp_path / f"w{w}"),
                     "--variant", "drawn", '{"model": "scans", "scans": {"duration": 60, '
                     '"pose_error": "drawn"}}']) == 0
    capsys.readouterr()
    with np.load(tmp_path / "w1" / "drawn.npz") as a, np.load(tmp_path / "w2" / "drawn.npz") as b:
        assert np.array_equal(a["indices"], b["indices"]) and len(a["indices"]) == 4
        assert np.array_equal(a["maps"], b["maps"])
