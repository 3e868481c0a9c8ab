"""Thesis Fig. 5.14 reproduced (issue #15): for N held-out plans, the simulated SLAM map,
the parametric model (deform, additive) on the same trajectory, and Model_AB, each with
its appendix-metric error and wall recall. :func:`map2map.experiments.fig514.measure.run_fig514`
does
the work; this script writes ``fig514.png`` and ``fig514.csv`` into ``--out`` and prints
the table.

    python3 -m map2map.experiments.fig514 --data DS --n 6 --out DIR \
        [--model pretrained|scans|RUN] [--seed 0]
        [--render slam|plain] [--drift parametric|none] [--drift-method additive|ekf]
        [--drift-scale F] [--coverage none|explore] [--drift-route tour|explore]
        [--traces none|lidar] [--explore-at square|native] [--as-synthesize]

``--model scans`` draws ``map2map synthesize``'s default instead of Model_AB: the robot's
own scans at its particle filter's poses, no network (the Model_AB options do not apply).
``--as-synthesize`` draws Model_AB as ``map2map synthesize --model pretrained`` makes it
(session 13: ``--drift rooms --coverage explore --traces lidar --explore-at native``);
without it the defaults stay session 9's (parametric drift, the network's extent, no
traces), as in ``map2map reproduce``.
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

from map2map.experiments.fig514.measure import run_fig514


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--data", required=True, help="a 'map2map dataset build' folder")
    ap.add_argument("--n", type=int, default=6, help="plans (the first N of the split)")
    ap.add_argument("--out", required=True, help="folder for fig514.png and fig514.csv")
    ap.add_argument("--model", default="pretrained",
                    help="Model_AB: pretrained (default) or a run; scans: synthesize's "
                    "default, no network")
    ap.add_argument("--split", default="test")
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--render", choices=("slam", "plain"), default="slam",
                    help="Model_AB's resolution raising (slam: SLAM-like walls, default)")
    ap.add_argument("--drift", choices=("parametric", "rooms", "none"), default="parametric",
                    help="Model_AB's parametric drift (default), the room-wise drift "
                    "(rooms, synthesize's default) or none")
    ap.add_argument("--drift-method", choices=("additive", "ekf"), default=None,
                    help="the drift's odometry-to-map conversion (default additive)")
    ap.add_argument("--drift-scale", type=float, default=None,
                    help="factor on the drift field (default: the tuned drift's)")
    ap.add_argument("--coverage", choices=("none", "explore"), default="none",
                    help="Model_AB's coverage: the network's extent (none, default) or only "
                    "what its own exploration saw (explore)")
    ap.add_argument("--drift-route", choices=("tour", "explore"), default="tour",
                    help="the drift's route: roadmap tour (default) or the exploration's path")
    ap.add_argument("--traces", choices=("none", "lidar"), default="none",
                    help="LIDAR traces beyond the faces (lidar: synthesize's default)")
    ap.add_argument("--explore-at", choices=("square", "native"), default="square",
                    help="where --coverage explore's robot explores: the 256 px square "
                    "(default) or the plan at its own resolution (native: as synthesize)")
    ap.add_argument("--as-synthesize", action="store_true",
                    help="Model_AB as map2map synthesize --model pretrained draws it: "
                    "--drift rooms --coverage explore --traces lidar --explore-at native")
    args = ap.parse_args(argv)
    if args.as_synthesize:
        args.drift, args.coverage, args.traces, args.explore_at = \
            "rooms", "explore", "lidar", "native"
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    f = run_fig514(args.data, args.n, args.model, args.seed, split=args.split,
                   render=args.render, drift=args.drift, drift_method=args.drift_method,
                   drift_scale=args.drift_scale, coverage=args.coverage,
                   drift_route=args.drift_route, traces=args.traces,
                   explore_at=args.explore_at)
    f.figure(out / "fig514.png")
    f.write_csv(out / "fig514.csv")
    (out / "fig514_summary.json").write_text(json.dumps(
        {**f.summary, "plans": f.info, "warnings": f.warnings, "drift": f.drift}, indent=1,
        sort_keys=True))
    print(f.table())
    for w in f.warnings:
        print(f"warning: {w}")
    print(f"wrote {out / 'fig514.png'}, {out / 'fig514.csv'}, {out / 'fig514_summary.json'}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
