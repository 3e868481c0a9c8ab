"""Thesis Table 5.3 / Fig. 5.12 as a command, one row per model: do the correctors of
``map2map autocorrect`` bring SLAM maps closer to their plans, and does the network add
anything to the classical cleaning (``none``)? A thin caller of
:mod:`map2map.experiments.table53.measure` (the metric, the improvement rule, the guards and
the sign tests are documented there and in :mod:`map2map.experiments.table53.table`).

    python3 -m map2map.experiments.table53                        # 100 generated held-out pairs
    python3 -m map2map.experiments.table53 --quick                # 12 pairs
    python3 -m map2map.experiments.table53 --models thesis none       # rows, newest last
    python3 -m map2map.experiments.table53 --data DS --model RUN  # none, thesis and a run
    python3 -m map2map.experiments.table53 --data DS --ac open_frontiers=true  # autocorrect option
    python3 -m map2map.experiments.table53 --data DS1 --data DS2 --split test val \\
        --cleaner DS1/cleaner.skops                      # several builds, merged by plan

``--models`` names the rows (``map2map autocorrect --model`` names or weights paths;
default ``none thesis``), ``--model`` adds one more after them. ``--data`` takes a dataset
folder (read-only, even while its build runs; cleaned pairs ``complete`` only, ``--all``
for every finished pair; ``--cleaner`` applies another dataset's cleaner in memory to a
dataset not cleaned yet) or a packed ``.npz``; several ``--data`` are merged, each plan
once. Writes ``OUT/table53.csv`` (one row per model), ``OUT/table53_<model>.csv`` (per
map), ``OUT/table53.txt`` (the printed table), ``OUT/fig512.png``, ``OUT/examples.png``
and ``OUT/heldout.npz`` (the held-out pairs measured, so that another model is compared
on the same maps with ``--data OUT/heldout.npz``).
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import numpy as np

from map2map.datasets.packed import save_packed
from map2map.experiments.table53.measure import (
    DEFAULT_MODELS,
    IMPROVED_MARGIN_PX,
    ac_options,
    generated_heldout_pairs,
    heldout_pairs_from_dataset,
    merge_pairs,
    run_table53,
)


def _covered(pairs, ds, min_coverage):
    """The pairs of dataset folder ``ds`` whose coverage (``meta.json``) is at least
    ``min_coverage`` (all of them when it is None or ``ds`` is a packed file)."""
    from map2map.datasets.packed import PackedPairs
    from map2map.datasets.pair import read_pair_meta
    from map2map.datasets.pairfolder import pair_dir

    idx = pairs.meta.get("heldout", {}).get("indices")
    if min_coverage is None or idx is None or not Path(ds).is_dir():
        return pairs
    keep = [k for k, i in enumerate(idx)
            if (read_pair_meta(pair_dir(ds, i)).get("coverage") or 0.0) >= min_coverage]
    sel = np.array(keep, int)
    return PackedPairs(pairs.a[sel], pairs.b[sel], pairs.plan_id[sel], pairs.split[sel],
                       pairs.meta)


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--data", action="append", help="dataset folder or .npz (repeatable)")
    ap.add_argument("--split", nargs="+", default=["test"], help="splits (default: test)")
    ap.add_argument("--all", action="store_true", help="every finished pair, not only "
                    "those the cleaner kept as complete")
    ap.add_argument("--cleaner", help="cleaner.skops applied to datasets not yet cleaned")
    ap.add_argument("--models", nargs="+", default=None, metavar="MODEL",
                    help="the rows, newest last: 'none', 'thesis' (map2map autocorrect "
                         "--model names) or weights paths (default: "
                         f"{' '.join(DEFAULT_MODELS)})")
    ap.add_argument("--model", default=None, metavar="MODEL",
                    help="one more row after --models (e.g. a training run)")
    ap.add_argument("--margin", type=float, default=IMPROVED_MARGIN_PX,
                    help="improved: Error(gen) lower than Error(sim) by more than this, px "
                         f"(default {IMPROVED_MARGIN_PX}), and wall recall not lower")
    ap.add_argument("--n", type=int, default=None, help="at most N held-out pairs "
                    "(default: all of a dataset's split, 100 generated)")
    ap.add_argument("--min-coverage", type=float, default=None, metavar="C",
                    help="dataset folders: only pairs whose exploration covered at least "
                         "this share of the plan (issue #32's test sets: 0.8)")
    ap.add_argument("--quick", action="store_true", help="12 pairs")
    ap.add_argument("--seed", type=int, default=0, help="metric seed")
    ap.add_argument("--out", default="table53_out")
    ap.add_argument("--no-anchor", action="store_true", help="walls placed by the network, "
                    "not anchored on the input (autocorrect --no-anchor)")
    ap.add_argument("--ac", action="append", default=[], metavar="KEY=VALUE",
                    help="an option of autocorrect (repeatable), e.g. thickness=resolution, "
                         "open_frontiers=true")
    ap.add_argument("--draw-option", action="append", default=[], metavar="KEY=VALUE",
                    help="a tolerance of the plan drawer for the drawn models (repeatable; "
                         "map2map autocorrect --draw-option), e.g. bridge_run=0")
    args = ap.parse_args(argv)
    n = 12 if args.quick else args.n
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    if args.data:
        keep = () if args.all else ("complete",)
        pairs = merge_pairs(*(_covered(heldout_pairs_from_dataset(
            d, tuple(args.split), keep=keep, cleaner=args.cleaner), d, args.min_coverage)
                              for d in args.data))
        pairs.meta["heldout"] = {"source": " + ".join(args.data) + f" ({'/'.join(args.split)}"
                                 f" split{'s' if len(args.split) > 1 else ''})"}
    else:
        n = n or 100
        pairs = generated_heldout_pairs(n, cache=out / f"heldout_{n}.npz")
    if n is not None and len(pairs) > n:
        from map2map.datasets.packed import PackedPairs

        pairs = PackedPairs(pairs.a[:n], pairs.b[:n], pairs.plan_id[:n], pairs.split[:n],
                            pairs.meta)
    save_packed(out / "heldout.npz", pairs)
    models = list(args.models or DEFAULT_MODELS) + ([args.model] if args.model else [])
    if args.draw_option:
        from map2map.jobs.autocorrect import MODELS, corrector, parse_draw_options

        drawn = parse_draw_options(args.draw_option)
        models = [corrector(m, draw_options=drawn) if m in MODELS and MODELS[m].drawn
                  else m for m in models]
    table = run_table53(pairs, models, seed=args.seed, anchor=not args.no_anchor,
                        margin=args.margin, autocorrect_kw=ac_options(args.ac))
    text = table.format()
    print(text)
    (out / "table53.txt").write_text(text + "\n")
    csvs = table.to_csv(out)
    table.figure(out / "fig512.png")
    table.examples_figure(out / "examples.png")
    print(f"wrote {', '.join(str(c) for c in csvs)}, {out / 'table53.txt'}, "
          f"{out / 'fig512.png'}, {out / 'examples.png'} and {out / 'heldout.npz'}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
