"""Tuning ``synthesize`` on a dev set: its options' effect on the per-plan ranks.

For the first ``--plans`` plans of a dataset whose runs 2 and 3 are cached (as
:mod:`map2map.experiments.realism.per_plan` leaves them), each ``--variant`` (a name and
the keyword arguments of :func:`map2map.learn.ab.synthesize.synthesize` as JSON; nested
``explore`` and ``traces`` objects become :class:`~map2map.learn.ab.coverage.ExploreParams`
and :class:`~map2map.learn.ab.render.TraceParams`) makes ``--samples`` (3) hypotheses per
plan (seed ``--seed`` + the pair's index, as ``per_plan``), cut with the pair's window; the
first is ranked among the plan's runs 1-3 per statistic; the medians of every statistic
over the plans are printed for the runs and each variant. Tune on a set that is not the final test
(docs/synthesize.md, "Tuning ``--coverage rays``")::

    python -m map2map.experiments.realism.per_plan.variants --data HELD --cache2 refs2.npz \\
        --cache3 refs3.npz --plans 120 --variant before '{"coverage": "explore",
        "traces": {"floor_px": 1.05}}' --variant rays '{"coverage": "rays"}'

A variant may name its own ``"model"`` (``"scans"``: ``synthesize --model scans``, its
settings under ``"scans"`` as :class:`~map2map.learn.ab.scans.ScanMapParams` fields, the
room drift under ``"rooms"``; its maps are the first hypothesis of ``synthesize``, and
the variants of one exploration setting share each plan's exploration,
:func:`~map2map.learn.ab.scans.drawn_hypothesis`); ``--classifier-steps`` adds the
classifier's AUC. The
comparison that chose ``--model scans``'s settings (docs/synthesize.md; run then by a
script outside the package, with other seeds) reads::

    python -m map2map.experiments.realism.per_plan.variants --data HELD --cache2 refs2.npz \\
        --cache3 refs3.npz --plans 160 --classifier-steps 600 --variant network '{}' \\
        --variant scans '{"model": "scans"}'
"""

from __future__ import annotations

import argparse
import json
import sys
import time
import warnings
from dataclasses import replace
from pathlib import Path

import numpy as np

from map2map.datasets.rerun import STARTS
from map2map.experiments.realism.per_plan import (
    add_classifier_options,
    check_classifier_options,
    classifier_auc,
)


def _kwargs(text: str) -> dict:
    """``synthesize``'s keyword arguments from a variant's JSON.

    Examples
    --------
    >>> kw = _kwargs('{"coverage": "rays", "traces": {"floor_px": 0.8}}')
    >>> kw["coverage"], kw["traces"].floor_px, kw["traces"].wall_m == 0.055
    ('rays', 0.8, True)
    >>> kw = _kwargs('{"model": "scans", "scans": {"global_deg": 1, "rooms": {"rot_deg": 2}}}')
    >>> kw["model"], kw["scans"].global_deg, kw["scans"].rooms.rot_deg, kw["scans"].rooms.parametric
    ('scans', 1, 2, False)
    >>> _kwargs('{"model": "scans", "scans": {"rooms": {"lin": 0.01}}}')["scans"].rooms.rot_deg
    1.0
    """
    from map2map.learn.ab.coverage import ExploreParams
    from map2map.learn.ab.render import TraceParams
    from map2map.learn.ab.scans import ScanMapParams

    kw = json.loads(text)
    if isinstance(kw.get("explore"), dict):
        kw["explore"] = ExploreParams(**kw["explore"])
    if isinstance(kw.get("traces"), dict):
        kw["traces"] = TraceParams(**kw["traces"])
    if isinstance(kw.get("scans"), dict):
        sc = dict(kw["scans"])
        if isinstance(sc.get("rooms"), dict):
            # on top of the scans default's room drift (not RoomDriftParams' own defaults)
            sc["rooms"] = replace(ScanMapParams().rooms, **sc["rooms"])
        kw["scans"] = ScanMapParams(**sc)
    return kw


_NETS: dict = {}


def variant_maps(item) -> tuple[int, dict]:
    """One plan's map of every variant, cut to its pair's square (a task of
    :func:`main`, run in a worker process for the scans variants).

    ``item = (ds, i, variants, models, seed, size, samples, start)``: ``variants`` maps a
    name to ``synthesize``'s keyword arguments (:func:`_kwargs`, without ``"model"``),
    ``models`` a name to its model (``"scans"`` or Model_AB weights). A scans variant
    whose only setting is ``"scans"`` is ``synthesize``'s first hypothesis made as
    :func:`~map2map.learn.ab.scans.drawn_hypothesis` makes it, the variants of one
    exploration setting sharing the plan's exploration. Returns ``(i, {name: (map,
    seconds)})``.
    """
    from map2map.datasets.pair import crop_box, preprocess_pair, read_pair_meta
    from map2map.datasets.pairfolder import PLAN_YAML, SLAM_YAML, pair_dir
    from map2map.learn.ab.model import load_ab_model
    from map2map.learn.ab.scans import ScanMapParams, drawn_hypothesis, explore
    from map2map.learn.ab.synthesize import SCANS, synthesize
    from map2map.maps.formats import load_map

    ds, i, variants, models, seed, size, samples, start = item
    folder = pair_dir(ds, i)
    a, b = load_map(folder / PLAN_YAML), load_map(folder / SLAM_YAML)
    box = crop_box(a, b)
    explored = {}                  # one exploration per plan serves every scans variant
    at = tuple(read_pair_meta(folder)["start_pose"]) if start == "pair" else None
    got = {}
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        for name, kw in variants.items():
            t0 = time.perf_counter()
            if models[name] == SCANS and set(kw) <= {"scans"}:
                # the first hypothesis of synthesize(a, SCANS, seed=...): scan_map's
                sp = kw.get("scans") or ScanMapParams()
                key = (sp.duration, sp.fov, sp.explore_map)
                if key not in explored:
                    explored[key] = explore(a, seed + i, 0, sp, at)
                m = drawn_hypothesis(a, explored[key], seed + i, 0, sp).map
            else:
                if models[name] == SCANS:
                    net = SCANS
                    if at is not None:
                        kw = {**kw, "start": at}
                else:
                    if models[name] not in _NETS:
                        _NETS[models[name]] = load_ab_model(models[name])
                    net = _NETS[models[name]]
                m = synthesize(a, net, samples=samples, seed=seed + i, **kw).maps[0]
            got[name] = (preprocess_pair(a, m, size, 0, box)[1],
                         time.perf_counter() - t0)
    return i, got


def format_medians(st: dict) -> str:
    """One row per map set (runs, then variants), the median of every statistic over its
    plans (NaN left out): the tells' sizes, beside the ranks' directions.

    Examples
    --------
    >>> st = {"run 1": {"bend": np.array([0.3, 0.4, np.nan])}, "v": {"bend": np.array([0.6])}}
    >>> print(format_medians(st))
    median        bend
     run 1       0.350
         v       0.600
    """
    names = list(next(iter(st.values())))
    w = [max(11, len(n) + 1) for n in names]
    lines = ["median " + "".join(f"{n:>{k}s}" for n, k in zip(names, w, strict=True))]
    for who, vals in st.items():
        med = [float(np.nanmedian(vals[n])) if np.isfinite(vals[n]).any() else float("nan")
               for n in names]
        lines.append(f"{who:>6s} " + "".join(f"{v:{k}.3f}" for v, k in zip(med, w, strict=True)))
    return "\n".join(lines)


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(prog="python -m map2map.experiments.realism.per_plan.variants",
                                 description=__doc__.split("\n\n")[0])
    ap.add_argument("--data", required=True, help="a 'map2map dataset build' folder")
    ap.add_argument("--split", default="all", help="which plans (default all)")
    ap.add_argument("--plans", type=int, default=120, help="the first N plans (default 120)")
    ap.add_argument("--cache2", required=True, help=".npz keeping run 2 of every plan")
    ap.add_argument("--cache3", required=True, help=".npz keeping run 3 of every plan")
    ap.add_argument("--model", default="pretrained", help="Model_AB weights")
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--start", choices=STARTS, default="own",
                    help="where runs 2 and 3 and the scans variants' robot start: each where "
                    "its seed draws a start (default) or at run 1's start pose (as per_plan)")
    ap.add_argument("--samples", type=int, default=3,
                    help="hypotheses made per plan, the first ranked (default 3, as per_plan; "
                    "with --model scans the first does not depend on it: 1 is 3x faster)")
    ap.add_argument("--variant", nargs=2, action="append", required=True,
                    metavar=("NAME", "JSON"), help="a name and synthesize's keyword arguments "
                    '(a "model" key replaces --model, e.g. "scans" with "scans" settings)')
    add_classifier_options(ap, 0, "also the classifier two-sample AUC against run 3, with "
                           "this many Adam steps per fold (the most, with a patience; "
                           "per_plan's: 12000, patience 5; default 0: none)")
    ap.add_argument("--floor", action="store_true",
                    help="with --classifier-steps: also the same classifier on run 2 against "
                    "run 3 (the floor a generator is measured against; per_plan prints it)")
    ap.add_argument("--workers", type=int, default=None,
                    help="worker processes making the scans variants' maps (default one per "
                    "core; the maps do not depend on it; with a network variant: 1)")
    ap.add_argument("--save-maps", metavar="DIR",
                    help="write each variant's maps (and the plans and runs) to "
                    "DIR/NAME.npz, to score them again without making them again")
    args = ap.parse_args(argv)
    check_classifier_options(ap, args)

    from tqdm.auto import tqdm

    from map2map.core.parallel import default_workers, process_map
    from map2map.experiments.realism.measure import simulated_references, stats_of_sets
    from map2map.experiments.realism.ranks import format_rank_table, plan_ranks, rank_table
    from map2map.learn.ab.synthesize import SCANS

    variants = {name: _kwargs(text) for name, text in args.variant}
    r2 = simulated_references(args.data, split=args.split, cache=args.cache2, progress=False,
                              start=args.start)
    r3 = simulated_references(args.data, split=args.split, cache=args.cache3, run=3,
                              progress=False, start=args.start)
    both = np.intersect1d(r2.indices, r3.indices)[:args.plans]
    r2, r3 = r2.only(both), r3.only(both)
    size = r2.a.shape[-1]
    models = {name: kw.pop("model", args.model) for name, kw in variants.items()}
    gens = {name: [] for name in variants}
    took = dict.fromkeys(variants, 0.0)
    nets = {m for m in models.values() if m != SCANS}
    # a network is loaded once per process: with one, the maps are made in this one
    workers = 1 if nets else (default_workers() if args.workers is None else args.workers)
    items = [(args.data, int(i), variants, models, args.seed, size, args.samples,
              args.start) for i in both]
    step = max(1, 8 * workers)
    with tqdm(total=len(items), desc="variants", unit="plan", file=sys.stderr) as bar:
        for c in range(0, len(items), step):
            for _, got in process_map(variant_maps, items[c:c + step], workers=workers,
                                      min_items=2):
                for name, (m, sec) in got.items():
                    gens[name].append(m)
                    took[name] += sec
            bar.update(len(items[c:c + step]))
    for name in variants:
        gens[name] = np.stack(gens[name])
        print(f"{name}: {len(both)} plans in {took[name]:.0f} s")
        if args.save_maps:
            from map2map.core._io import atomic_path

            out = Path(args.save_maps) / f"{name}.npz"
            out.parent.mkdir(parents=True, exist_ok=True)
            with atomic_path(out) as tmp, open(tmp, "wb") as fh:
                np.savez_compressed(fh, indices=both, maps=gens[name], plans=r2.a,
                                    run1=r2.sim1, run2=r2.sim2, run3=r3.sim2)
    runs = {"run 1": r2.sim1, "run 2": r2.sim2, "run 3": r3.sim2}
    st = stats_of_sets({**runs, **gens}, r2.a)
    print()
    print(format_medians(st))
    if args.floor and args.classifier_steps > 0:
        res = classifier_auc(args, r2.a, runs["run 3"], runs["run 2"])
        print(f"\nrun 2 (floor): classifier {res} over {len(res.runs)} seed(s) against run 3 "
              f"(paired {res.paired:.3f})")
    for name in gens:
        rows = rank_table(plan_ranks(st[name], [st[r] for r in runs], seed=args.seed), 3)
        print()
        print(format_rank_table(rows, name))
        if args.classifier_steps > 0:
            res = classifier_auc(args, r2.a, runs["run 3"], gens[name])
            print(f"{name}: classifier {res} over {len(res.runs)} seed(s) against run 3 "
                  f"(paired {res.paired:.3f})")
    return 0


if __name__ == "__main__":
    sys.exit(main())
