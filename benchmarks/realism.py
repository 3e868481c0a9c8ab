"""Realism of Model_AB's SLAM maps against simulated ones (issue #15; the thesis judged it
by eye). The statistics and the table are :mod:`map2map.learn.realism`'s; this script
only picks the data and prints.

On the held-out plans of a ``map2map dataset build`` dataset (``--split test``: plans
never seen in training), run 1 is the dataset's own simulated SLAM map, run 2 a second
simulation + SLAM of the same plan from the same start with another seed
(:func:`map2map.datasets.rerun.rerun_pair`; slow, cached in ``--cache``). Generators: each
``--model`` (Model_AB weights: ``pretrained``, a run folder, a weights file) and the
parametric model (``deform`` additive along run 2's trajectory), as a baseline. Per
statistic: W(generated, run 1) / W(run 2, run 1); target every ratio <= 1.5.

    python3 benchmarks/realism.py --data DS [--model pretrained RUN ...] [--plans N]
        [--cache refs.npz] [--csv out.csv] [--render slam plain] [--measures]

``--render`` measures each model with each resolution raising
(:mod:`map2map.learn.slam_render`: ``slam``, SLAM-like walls, the default of ``map2map
synthesize``; ``plain``, the previous snap + nearest upsampling). ``--measures`` adds Fig.
5.14's measures on every plan (:func:`map2map.learn.fig514.measure`: appendix-metric error
after alignment, wall recall and precision at 2 px) for the simulated runs, the parametric
model and every generator: mean (median) error, plans not aligned, mean recall, mean
precision.
"""

from __future__ import annotations

import argparse
import csv
import sys
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "src"))

from map2map.learn.realism import (  # noqa: E402
    format_realism_table,
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
    ap.add_argument("--measures", action="store_true",
                    help="also Fig. 5.14's measures (appendix error, wall recall/precision) "
                    "on every plan")
    args = ap.parse_args(argv)
    t0 = time.perf_counter()
    refs = simulated_references(args.data, split=args.split, n=args.plans, cache=args.cache)
    plans = refs.a
    st1, st2 = stats_of(refs.sim1, plans), stats_of(refs.sim2, plans)
    gens = {"parametric": refs.parametric}
    if args.model:
        from map2map.learn.synthesize import load_ab_model, synthesize_squares

        for m in args.model:
            net = load_ab_model(m)
            base = "Model_AB" if m == "pretrained" else f"AB:{Path(m).name}"
            for how in args.render:
                name = base if len(args.render) == 1 else f"{base} [{how}]"
                gens[name] = synthesize_squares(net, plans, seed=args.seed, render=how)
            print(f"{base}: {net.source} ({net.resolution} px, target walls "
                  f"{net.wall_px:.2f} px, note: {str(net.header.get('note', ''))[:90]})")
    print(f"{len(plans)} held-out '{args.split}' plans of {args.data} "
          f"({plans.shape[-1]} px); run 1: the dataset's simulated SLAM maps, run 2: a second "
          "simulation (same plan and start, another seed); parametric: deform additive on "
          "run 2's trajectory")
    out_rows = []
    for name, maps in gens.items():
        rows = realism_table(stats_of(maps, plans), st1, st2, plans)
        print()
        print(format_realism_table(rows, name))
        out_rows += [{"generator": name, **r.as_dict()} for r in rows]
    if args.measures:
        _measures({"simulated run 1": refs.sim1, "simulated run 2": refs.sim2, **gens}, plans)
    if args.csv:
        with open(args.csv, "w", newline="") as fh:
            w = csv.DictWriter(fh, fieldnames=list(out_rows[0]))
            w.writeheader()
            w.writerows(out_rows)
    print(f"\n{time.perf_counter() - t0:.0f} s")
    return 0


def _measures(gens: dict, plans) -> None:
    """Fig. 5.14's measures of every generator on every plan, one line each."""
    import numpy as np

    from map2map.learn.fig514 import measure

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
