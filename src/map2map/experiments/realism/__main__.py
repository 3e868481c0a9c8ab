"""Realism of Model_AB's SLAM maps against simulated ones (issue #15; the thesis judged it
by eye). The statistics and the table are :mod:`map2map.experiments.realism.measure`'s; this script
only picks the data and prints.

On the held-out plans of a ``map2map dataset build`` dataset (``--split test``: plans
never seen in training), run 1 is the dataset's own simulated SLAM map, run 2 a second
simulation + SLAM of the same plan from the same start with another seed
(:func:`map2map.datasets.rerun.rerun_pair`; slow, cached in ``--cache``). Generators: each
``--model`` (Model_AB weights: ``pretrained``, a run folder, a weights file) and the
parametric model (``deform`` additive along run 2's trajectory), as a baseline. Per
statistic: W(generated, run 1) / W(run 2, run 1); target every ratio <= 1.5.

    python3 -m map2map.experiments.realism --data DS [--model pretrained RUN ...] [--plans N]
        [--cache refs.npz] [--csv out.csv] [--render slam plain] [--measures]
        [--drift parametric none] [--drift-method additive] [--drift-scale 1 ...]
        [--diversity K] [--coverage none explore] [--drift-route tour explore]
        [--traces none lidar] [--trace-params '{"wall_m": 0.045}']
        [--room-params '{"conserve": true, "scale": 0.7}']
        [--explore-at square native] [--explore-seconds 420] [--no-halves]
        [--as-synthesize] [--third-run refs3.npz]

``--as-synthesize`` measures what ``map2map synthesize`` makes by default (session 13:
``--drift rooms --coverage explore --traces lidar --explore-at native``).

``--third-run CACHE`` (session 14) adds a third simulation + SLAM of every plan (seed of
run 3) as one more generator: W(run 3, run 1) / W(run 2, run 1) is what a generator as
good as the simulator itself scores on these plans, so a ratio above 1.5 there says how
far the 1.5 target is below this benchmark's noise at this many plans. With three runs
a plan, the benchmark also draws what a perfect generator scores
(:func:`map2map.experiments.realism.measure.null_ratios`, session 15: per plan, the three runs'
roles --
generated, run 1, run 2 -- shuffled, ``--null-draws`` times): each ratio's quantiles and
the chance that every ratio is <= 1.5. With a Model_AB generator, a last table sets each
of its ratios beside run 3's, with the share of perfect-generator draws that score
lower (100 %: no perfect generator scores that badly).

Each ratio comes with the same ratio on the even- and on the odd-numbered plans alone
(session 13): how much it moves with the plan set (``--no-halves`` leaves them out).

``--render`` measures each model with each resolution raising
(:mod:`map2map.learn.ab.render`: ``slam``, SLAM-like walls, the default of ``map2map
synthesize``; ``plain``, the previous snap + nearest upsampling). ``--measures`` adds Fig.
5.14's measures on every plan (:func:`map2map.experiments.fig514.measure.measure`: appendix-metric
error
after alignment, wall recall and precision at 2 px) for the simulated runs, the parametric
model and every generator: mean (median) error, plans not aligned, mean recall, mean
precision.

``--drift`` measures each model with and without the parametric drift of
:mod:`map2map.learn.ab.drift` (default ``parametric``, ``map2map synthesize``'s default before
session 11, kept here so that the commands of docs/synthesize.md reproduce; each square
at its own metric resolution, :func:`map2map.experiments.realism.measure.pair_square_resolution`)
and
with the room-wise rigid drift of :mod:`map2map.learn.ab.room_drift` (``rooms``),
``--drift-scale`` with each factor on the drift field (for tuning: tune on ``--split
val``, report on ``test``). ``--diversity K`` adds, per generator, the mean pairwise
disagreement of ``K`` hypotheses (:func:`map2map.learn.ab.synthesize.synthesize`, test-time
dropout + the drift) over the plans.

``--coverage`` and ``--drift-route`` (:mod:`map2map.learn.ab.coverage`) measure each model
with the network's own extent (``none``) and/or only what its own ``oracle`` exploration
of the square saw (``explore``), and the drift along the roadmap tour (``tour``) and/or
the exploration's path (``explore``): every combination given is one generator (default
``none`` and ``tour``).

``--traces`` (:class:`map2map.learn.ab.render.TraceParams`, session 11) measures each
model without (``none``) and/or with (``lidar``) what a LIDAR + SLAM leaves beyond the
faces: a metric wall band with a ragged back edge and stray hits (default ``none``;
``--render plain`` is measured without); ``--trace-params`` (JSON) replaces fields of the
``lidar`` settings (for tuning on ``--split val``). ``map2map synthesize``'s default since
session 11 is measured by ``--drift rooms --coverage explore --traces lidar``; the
script's own defaults stay session 9's (``parametric``, ``none``, ``none``).
``--explore-at native`` (session 13) explores each plan at its own resolution
(:func:`map2map.experiments.realism.measure.native_seen`, as ``map2map synthesize`` does) instead of
the dataset's square, whose coarse pixels and thickened walls can close doors;
``--explore-seconds`` sets the exploration's simulated time. ``--room-params`` (JSON)
replaces fields of the ``rooms`` drift's
:class:`~map2map.learn.ab.room_drift.RoomDriftParams` (session 12: ``conserve``, the
parametric field's divergence-free part only).
"""

from __future__ import annotations

import argparse
import csv
import sys
import time
from pathlib import Path

import numpy as np

from map2map.experiments.realism.measure import (
    STAT_WIDTH,
    format_null,
    format_realism_table,
    null_ratios,
    realism_table,
    simulated_references,
    stats_of,
)


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--data", required=True, help="a 'map2map dataset build' folder")
    ap.add_argument("--model", nargs="*", default=["pretrained"],
                    help="Model_AB weights to measure (none: the parametric model only)")
    ap.add_argument("--split", default="test")
    ap.add_argument("--plans", type=int, help="the first N pairs of the split (default all)")
    ap.add_argument("--cache", help=".npz keeping the second runs between calls")
    ap.add_argument("--csv", help="write every row here")
    ap.add_argument("--seed", type=int, default=0, help="Model_AB's seed (dropout off)")
    ap.add_argument("--render", nargs="+", choices=("slam", "plain"), default=["slam"],
                    help="Model_AB's resolution raising(s) to measure (default slam)")
    ap.add_argument("--drift", nargs="+", choices=("parametric", "rooms", "none"),
                    default=["parametric"],
                    help="Model_AB's drift(s) to measure (default parametric, map2map "
                    "synthesize's before session 11; rooms: the room-wise rigid drift of "
                    "map2map.learn.ab.room_drift, its default since)")
    ap.add_argument("--drift-method", choices=("additive", "ekf"), default=None,
                    help="the parametric drift's odometry-to-map conversion (default "
                    "additive)")
    ap.add_argument("--drift-scale", nargs="+", type=float, default=[None],
                    help="factor(s) on the drift field (default 1: the parametric model's "
                    "own magnitudes)")
    ap.add_argument("--diversity", type=int, default=0, metavar="K",
                    help="also the mean pairwise disagreement of K hypotheses per plan")
    ap.add_argument("--coverage", nargs="+", choices=("none", "explore"), default=["none"],
                    help="Model_AB's coverage(s): none (the network's extent, default) or "
                    "explore (unknown where its own exploration of the plan did not see; "
                    "map2map synthesize's default since session 11); synthesize's rays is "
                    "ranked per plan by realism.per_plan.variants")
    ap.add_argument("--drift-route", nargs="+", choices=("tour", "explore"), default=["tour"],
                    help="the drift's route(s): tour (roadmap tour, default) or explore (the "
                    "exploration's true path)")
    ap.add_argument("--traces", nargs="+", choices=("none", "lidar"), default=["none"],
                    help="LIDAR traces (map2map.learn.ab.render.TraceParams): none "
                    "(default) and/or lidar (map2map synthesize's default since session 11)")
    ap.add_argument("--trace-params", default="{}",
                    help="JSON fields replacing the lidar traces' defaults")
    ap.add_argument("--room-params", default="{}",
                    help="JSON fields replacing the rooms drift's defaults "
                    "(map2map.learn.ab.room_drift.RoomDriftParams; session 12's val choice: "
                    "'{\"conserve\": true, \"scale\": 0.7}' with --trace-params "
                    "'{\"floor_px\": 0.85}')")
    ap.add_argument("--explore-at", choices=("square", "native"), default="square",
                    help="where --coverage explore's robot explores: the dataset's 256 px "
                    "square (default, sessions 10-12's figures; 0.04-0.12 m a pixel, walls "
                    "thickened, so doors can close) or each plan at its own resolution "
                    "(native: what map2map synthesize does; realism.native_seen)")
    ap.add_argument("--explore-seconds", type=float, default=None,
                    help="the exploration's simulated seconds (default ExploreParams': 275)")
    ap.add_argument("--no-halves", action="store_true",
                    help="leave out each ratio on the even- and odd-numbered plans alone")
    ap.add_argument("--measures", action="store_true",
                    help="also Fig. 5.14's measures (appendix error, wall recall/precision) "
                    "on every plan")
    ap.add_argument("--third-run", metavar="CACHE",
                    help="also measure a third simulated run of every plan (another seed; "
                    "second runs' cache format, kept in CACHE) as a generator: the ratio a "
                    "perfect generator gets on these plans, the benchmark's noise floor")
    ap.add_argument("--null-draws", type=int, default=2000,
                    help="with --third-run: random relabellings of the three simulated runs "
                    "drawn for the perfect generator's ratios (default 2000)")
    ap.add_argument("--as-synthesize", action="store_true",
                    help="measure map2map synthesize's defaults: --drift rooms --coverage "
                    "explore --traces lidar --explore-at native")
    args = ap.parse_args(argv)
    if args.as_synthesize:
        args.drift, args.coverage, args.traces, args.explore_at = \
            ["rooms"], ["explore"], ["lidar"], "native"
    t0 = time.perf_counter()
    refs = simulated_references(args.data, split=args.split, n=args.plans, cache=args.cache)
    run3 = None
    if args.third_run:
        run3 = simulated_references(args.data, split=args.split, n=args.plans,
                                    cache=args.third_run, run=3)
        both = np.intersect1d(refs.indices, run3.indices)
        refs, run3 = refs.only(both), run3.only(both)   # plans whose runs 2 and 3 both ran
    plans = refs.a
    st1, st2 = stats_of(refs.sim1, plans), stats_of(refs.sim2, plans)
    gens = {"parametric": refs.parametric}
    known: dict = {}  # statistics already computed, by generator
    if run3 is not None:
        gens["simulated run 3"] = run3.sim2
        known["simulated run 3"] = stats_of(run3.sim2, plans)
    div: dict = {}
    if args.model:
        import json

        from map2map.learn.ab.coverage import ExploreParams
        from map2map.learn.ab.model import load_ab_model
        from map2map.learn.ab.render import TraceParams
        from map2map.learn.ab.room_drift import RoomDriftParams
        from map2map.learn.ab.synthesize import synthesize_squares

        ep = ExploreParams() if args.explore_seconds is None else \
            ExploreParams(duration=args.explore_seconds)
        seen = None
        if args.explore_at == "native" and "explore" in args.coverage:
            from map2map.experiments.realism.measure import native_seen

            if "explore" in args.drift_route:
                ap.error("--explore-at native gives no trajectory: use --drift-route tour")
            t1 = time.perf_counter()
            seen = native_seen(args.data, refs.indices, plans.shape[-1], seed=args.seed,
                               params=ep)
            print(f"explored {len(plans)} plans at their own resolution: "
                  f"{time.perf_counter() - t1:.0f} s")
        lidar = TraceParams(**json.loads(args.trace_params))
        rooms = RoomDriftParams(**json.loads(args.room_params))
        variants = [(how, d, sc, cov, rt, tr) for how in args.render for d in args.drift
                    for sc in (args.drift_scale if d != "none" else [None])
                    for cov in args.coverage
                    for rt in (args.drift_route if d == "parametric" else ["tour"])
                    for tr in (args.traces if how == "slam" else ["none"])]
        for m in args.model:
            net = load_ab_model(m)
            base = "Model_AB" if m == "pretrained" else f"AB:{Path(m).name}"
            for how, d, sc, cov, rt, tr in variants:
                tags = [how] * (len(args.render) > 1)
                if len(args.drift) > 1 or len(args.drift_scale) > 1:
                    kind = "rooms drift" if d == "rooms" else "drift"
                    tags.append("no drift" if d == "none" else
                                f"{kind} x{sc:g}" if len(args.drift_scale) > 1 else kind)
                if len(args.coverage) > 1 or cov != "none":
                    tags.append(f"cover {cov}")
                if len(args.drift_route) > 1 or rt != "tour":
                    tags.append(f"route {rt}")
                if cov == "explore" and (args.explore_at != "square"
                                         or args.explore_seconds is not None):
                    tags.append(f"{args.explore_at} {ep.duration:g} s")
                if len(args.traces) > 1 or tr != "none":
                    tags.append(f"traces {tr}")
                name = f"{base} [{', '.join(tags)}]" if tags else base
                t1 = time.perf_counter()
                drift = rooms if d == "rooms" else d  # --room-params for the rooms drift
                gens[name] = synthesize_squares(
                    net, plans, seed=args.seed, render=how, drift=drift,
                    drift_method=args.drift_method, drift_scale=sc, resolution=refs.resolution,
                    coverage=cov, drift_route=rt, traces=lidar if tr == "lidar" else "none",
                    explore=ep, seen=seen if cov == "explore" else None)
                if args.diversity > 1:
                    div[name] = _diversity(net, plans, refs.resolution, args.diversity,
                                           args.seed, how, drift, args.drift_method, sc,
                                           cov, rt,
                                           lidar if tr == "lidar" else "none")
                print(f"{name}: {time.perf_counter() - t1:.0f} s")
            for d in ("parametric", "rooms"):
                if d in args.drift:
                    from map2map.learn.ab.drift import drift_params

                    print("drift: " + drift_params(rooms if d == "rooms" else d,
                                                   args.drift_method).describe())
            if "lidar" in args.traces:
                print(f"traces lidar: {lidar}")
            print(f"{base}: {net.source} ({net.resolution} px, target walls "
                  f"{net.wall_px:.2f} px, note: {str(net.header.get('note', ''))[:90]})")
    print(f"{len(plans)} held-out '{args.split}' plans of {args.data} "
          f"({plans.shape[-1]} px); run 1: the dataset's simulated SLAM maps, run 2: a second "
          "simulation (same plan and start, another seed); parametric: deform additive on "
          "run 2's trajectory"
          + ("; even / odd: each ratio on the even- and the odd-numbered plans alone"
             if not args.no_halves else ""))
    out_rows = []
    for name, maps in gens.items():
        st = known[name] if name in known else stats_of(maps, plans)
        rows = realism_table(st, st1, st2, plans, halves=not args.no_halves)
        print()
        print(format_realism_table(rows, name))
        out_rows += [{"generator": name, **r.as_dict()} for r in rows]
    if run3 is not None:
        t1 = time.perf_counter()
        null = null_ratios([st1, st2, known["simulated run 3"]], draws=args.null_draws)
        print(f"\na perfect generator on these {len(plans)} plans: each ratio's quantiles over "
              f"{args.null_draws} draws, per plan the three simulated runs' roles (generated, "
              f"run 1, run 2) shuffled ({time.perf_counter() - t1:.0f} s; valid if a plan's "
              "runs are exchangeable, which run 1's selection by the dataset's cleaner may "
              "bend); P: the share of draws that meet the target")
        print(format_null(null))
        if len(gens) > 2:
            _against_floor(out_rows, null)
    if div:
        print(f"\ndiversity: mean pairwise disagreement of {args.diversity} hypotheses "
              f"(share of the plan's known pixels), mean (min, max) over {len(plans)} plans")
        for name, v in div.items():
            print(f"{name:<40} {np.mean(v):.2%} ({np.min(v):.2%}, {np.max(v):.2%})")
    if args.measures:
        _measures({"simulated run 1": refs.sim1, "simulated run 2": refs.sim2, **gens}, plans)
    if args.csv:
        with open(args.csv, "w", newline="") as fh:
            w = csv.DictWriter(fh, fieldnames=list(out_rows[0]))
            w.writeheader()
            w.writerows(out_rows)
    print(f"\n{time.perf_counter() - t0:.0f} s")
    return 0


def _against_floor(rows: list, null=None) -> None:
    """Every generator's ratio beside the third simulated run's (the floor), per statistic;
    with ``null`` (:class:`~map2map.experiments.realism.measure.NullRatios`), each ratio's rank
    among a
    perfect generator's draws in brackets."""
    gens = list(dict.fromkeys(r["generator"] for r in rows))
    ratio = {(r["generator"], r["statistic"]): r["ratio"] for r in rows}
    stats = list(dict.fromkeys(r["statistic"] for r in rows))
    others = [g for g in gens if g not in ("simulated run 3", "parametric")]

    def cell(v: float, st: str, w: int) -> str:
        text = f"{v:.2f}" + ("" if null is None else f" ({null.rank(st, v):.1%})")
        return f"{text:>{w}}"

    print("\nagainst the floor: each ratio beside a third simulated run's on the same plans"
          + ("; in brackets the share of a perfect generator's draws scoring lower"
             if null is not None else ""))
    print(f"{'statistic':>{STAT_WIDTH}} {'run 3':>16} "
          + " ".join(f"{g[:28]:>28}" for g in others))
    for st in stats:
        print(f"{st:>{STAT_WIDTH}} {cell(ratio['simulated run 3', st], st, 16)} "
              + " ".join(cell(ratio[g, st], st, 28) for g in others))
    worst = {g: max(ratio[g, st] for st in stats) for g in ["simulated run 3"] + others}
    print(f"{'worst':>{STAT_WIDTH}} {cell(worst['simulated run 3'], 'worst', 16)} "
          + " ".join(cell(worst[g], "worst", 28) for g in others))


def _diversity(net, plans, resolution, k, seed, render, drift, method, scale,
               coverage="none", drift_route="tour", traces="none") -> list:
    """Per plan: mean pairwise disagreement of ``k`` hypotheses of ``synthesize``."""
    import warnings

    from map2map.core.grid import OccupancyMap
    from map2map.learn.ab.synthesize import synthesize

    out = []
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        for a, r in zip(plans, resolution, strict=True):
            res = synthesize(OccupancyMap(a, float(r)), net, samples=k, seed=seed,
                             render=render, drift=drift, drift_method=method,
                             drift_scale=scale, coverage=coverage, drift_route=drift_route,
                             traces=traces)
            out.append(res.diversity)
    return out


def _measures(gens: dict, plans) -> None:
    """Fig. 5.14's measures of every generator on every plan, one line each."""
    import numpy as np

    from map2map.experiments.fig514.measure import measure

    print(f"\nFig. 5.14 measures on {len(plans)} plans (appendix metric, px of the "
          f"{plans.shape[-1]} px square; wall recall / precision at 2 px)")
    print(f"{'maps':<28} {'error mean (median)':>20} {'not aligned':>12} {'recall':>7} "
          f"{'precision':>9}")
    for name, maps in gens.items():
        rows = [measure(m, p) for m, p in zip(maps, plans, strict=True)]
        err = np.array([r["error_px"] for r in rows])
        ok = np.isfinite(err)
        e = f"{err[ok].mean():.2f} ({np.median(err[ok]):.2f})" if ok.any() else "-"
        print(f"{name:<28} {e:>20} {int((~ok).sum()):>12} "
              f"{np.nanmean([r['wall_recall'] for r in rows]):>7.2f} "
              f"{np.nanmean([r['wall_precision'] for r in rows]):>9.2f}")


if __name__ == "__main__":
    sys.exit(main())
