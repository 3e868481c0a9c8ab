"""Thesis Table 5.3 / Fig. 5.12 as a command: does Model_BA bring SLAM maps closer to
their plans? A thin caller of :mod:`map2map.experiments.table53.measure` (the metric, the guards and
the sign test are documented there).

    python3 -m map2map.experiments.table53                        # 100 generated held-out pairs
    python3 -m map2map.experiments.table53 --quick                # 12 pairs
    python3 -m map2map.experiments.table53 --data DS --model RUN  # a dataset's test split, a run
    python3 -m map2map.experiments.table53 --data DS --ac open_frontiers=true  # autocorrect option
    python3 -m map2map.experiments.table53 --data DS1 --data DS2 --split test val \\
        --cleaner DS1/cleaner.skops                      # several builds, merged by plan

``--data`` takes a dataset folder (read-only, even while its build runs; cleaned pairs
``complete`` only, ``--all`` for every finished pair; ``--cleaner`` applies another
dataset's cleaner in memory to a dataset not cleaned yet) or a packed ``.npz``; several
``--data`` are merged, each plan once. Writes ``OUT/table53.csv``, ``OUT/fig512.png``,
``OUT/examples.png`` and ``OUT/heldout.npz`` (the held-out pairs measured, so that
another model is compared on the same maps with ``--data OUT/heldout.npz``).
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

from map2map.datasets.packed import save_packed
from map2map.experiments.table53.measure import (
    ac_options,
    generated_heldout_pairs,
    heldout_pairs_from_dataset,
    merge_pairs,
    run_table53,
)


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--data", action="append", help="dataset folder or .npz (repeatable)")
    ap.add_argument("--split", nargs="+", default=["test"], help="splits (default: test)")
    ap.add_argument("--all", action="store_true", help="every finished pair, not only "
                    "those the cleaner kept as complete")
    ap.add_argument("--cleaner", help="cleaner.skops applied to datasets not yet cleaned")
    ap.add_argument("--model", default="pretrained")
    ap.add_argument("--n", type=int, default=None, help="at most N held-out pairs "
                    "(default: all of a dataset's split, 100 generated)")
    ap.add_argument("--quick", action="store_true", help="12 pairs")
    ap.add_argument("--seed", type=int, default=0, help="metric seed")
    ap.add_argument("--out", default="table53_out")
    ap.add_argument("--no-anchor", action="store_true", help="walls placed by the network, "
                    "not anchored on the input (autocorrect --no-anchor)")
    ap.add_argument("--ac", action="append", default=[], metavar="KEY=VALUE",
                    help="an option of autocorrect (repeatable), e.g. thickness=resolution, "
                         "open_frontiers=true")
    args = ap.parse_args(argv)
    n = 12 if args.quick else args.n
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    if args.data:
        keep = () if args.all else ("complete",)
        pairs = merge_pairs(*(heldout_pairs_from_dataset(d, tuple(args.split), keep=keep,
                                                         cleaner=args.cleaner)
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
    table = run_table53(pairs, args.model, seed=args.seed, anchor=not args.no_anchor,
                        autocorrect_kw=ac_options(args.ac))
    print(table.format())
    table.to_csv(out / "table53.csv")
    table.figure(out / "fig512.png")
    table.examples_figure(out / "examples.png")
    print(f"wrote {out / 'table53.csv'}, {out / 'fig512.png'}, {out / 'examples.png'} and "
          f"{out / 'heldout.npz'}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
