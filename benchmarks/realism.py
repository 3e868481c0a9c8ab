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
        [--cache refs.npz] [--csv out.csv]
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
            name = "Model_AB" if m == "pretrained" else f"AB:{Path(m).name}"
            gens[name] = synthesize_squares(net, plans, seed=args.seed)
            print(f"{name}: {net.source} ({net.resolution} px, note: "
                  f"{str(net.header.get('note', ''))[:90]})")
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
    if args.csv:
        with open(args.csv, "w", newline="") as fh:
            w = csv.DictWriter(fh, fieldnames=list(out_rows[0]))
            w.writeheader()
            w.writerows(out_rows)
    print(f"\n{time.perf_counter() - t0:.0f} s")
    return 0


if __name__ == "__main__":
    sys.exit(main())
