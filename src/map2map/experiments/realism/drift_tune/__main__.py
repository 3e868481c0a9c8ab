"""Tune Model_AB's parametric drift (:mod:`map2map.learn.ab.drift`) against simulated SLAM
maps: the realism ratios (:mod:`map2map.experiments.realism.measure`) of the shipped Model_AB's maps
warped along drift fields of each ``--variant`` (``DriftParams`` fields as JSON), on the
plans of ``--split`` (tune on ``val``; report on ``test`` with ``map2map.experiments.realism``).
The network runs once; each variant only redraws the drift.

    python3 -m map2map.experiments.realism.drift_tune --data DS --cache refs_val.npz [--split val]
        [--plans N] [--model pretrained] --variant '{}' '{"scale": 2, "smooth_m": 0.3}' ...

A variant with ``"rooms": true`` is a room-wise drift (:mod:`map2map.learn.ab.room_drift`;
its other fields are ``RoomDriftParams``'), e.g. ``'{"rooms": true, "rot_deg": 1.5}'``.

Prints, per variant, every statistic's ratio
(:data:`~map2map.experiments.realism.measure.STATS`) and the worst, then the generated
maps' means.
"""

from __future__ import annotations

import argparse
import json
import sys
import time
import warnings

import numpy as np

from map2map.experiments.realism.measure import (
    STATS,
    realism_table,
    simulated_references,
    stats_of,
)


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--data", required=True, help="a 'map2map dataset build' folder")
    ap.add_argument("--split", default="val", help="plans to tune on (default val)")
    ap.add_argument("--plans", type=int, help="the first N pairs of the split")
    ap.add_argument("--cache", help=".npz keeping the second runs between calls")
    ap.add_argument("--model", default="pretrained")
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--variant", nargs="+", default=["{}"],
                    help="DriftParams fields as JSON objects ({}: the defaults)")
    args = ap.parse_args(argv)
    from map2map.learn.ab.drift import DriftParams, drift_maps
    from map2map.learn.ab.model import load_ab_model
    from map2map.learn.ab.room_drift import RoomDriftParams
    from map2map.learn.ab.synthesize import synthesize_squares

    t0 = time.perf_counter()
    refs = simulated_references(args.data, split=args.split, n=args.plans, cache=args.cache)
    plans = refs.a
    st1, st2 = stats_of(refs.sim1, plans), stats_of(refs.sim2, plans)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        base = synthesize_squares(load_ab_model(args.model), plans, seed=args.seed,
                                  drift="none")
    print(f"{len(plans)} '{args.split}' plans of {args.data}; ratio W(gen, sim 1) / "
          "W(sim 2, sim 1), target <= 1.5")
    head = f"{'variant':<44}" + "".join(f"{s[:10]:>11}" for s in STATS) + f"{'worst':>8}"
    print(head)
    ref = realism_table(st1, st1, st2, plans)
    print(f"{'sim 1 / sim 2 means':<44}" + "".join(f"{r.sim1:>5.2f}/{r.sim2:<5.2f}"
                                                   for r in ref))

    def quantiles(v):
        v = v[np.isfinite(v)]
        return " ".join(f"{x:.2f}" for x in np.percentile(v, (10, 50, 90, 99)))

    print(f"{'  wall_err q10/50/90/99: sim 1':<44} {quantiles(st1['wall_err'])}; sim 2 "
          f"{quantiles(st2['wall_err'])}")

    def show(name, maps):
        st = stats_of(maps, plans)
        rows = realism_table(st, st1, st2, plans)
        print(f"{name[:44]:<44}" + "".join(f"{r.ratio:>11.2f}" for r in rows)
              + f"{max(r.ratio for r in rows):>8.2f}")
        print(f"{'  means':<44}" + "".join(f"{r.generated:>11.3f}" for r in rows))
        print(f"{'  wall_err q10/50/90/99':<44} {quantiles(st['wall_err'])}", flush=True)

    show("parametric model (run 2's trajectory)", refs.parametric)
    show("Model_AB, no drift", base)
    for v in args.variant:
        kw = json.loads(v)
        dp = RoomDriftParams(**kw) if kw.pop("rooms", False) else DriftParams(**kw)
        out, warns = drift_maps(base, plans, refs.resolution, args.seed, dp)
        show(v, out)
        for w in warns:
            print(f"  warning: {w}")
    print(f"{time.perf_counter() - t0:.0f} s")
    return 0


if __name__ == "__main__":
    sys.exit(main())
