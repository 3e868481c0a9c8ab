"""Exploration coverage with the oracle mapper over many plans (issue 4 "done when").

Target: >= 90 % of the reachable free space mapped within 7 simulated minutes on
procedural apartments and on HouseExpo plans. "coverage" counts the free cells
the robot's body can cover keeping 5 cm from walls (what a navigation stack can
reach); "strict" counts every cell the body could touch, squeezing through any
gap at all and including the cells right next to walls. Prints one line per plan and the
distribution (min, quartiles, mean, share of plans reaching 90 %).

Run: ``python3 -m benchmarks.bench_sim_coverage [--apartments 12] [--renders 10]
[--fov 360] [--duration 420]`` (about 2-5 s per plan).
"""

from __future__ import annotations

import argparse
import time

import numpy as np

from benchmarks._sim_plans import HOUSEEXPO, apartments, houseexpo_json, houseexpo_renders
from map2map.sim.runner import simulate


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--apartments", type=int, default=12)
    ap.add_argument("--renders", type=int, default=10)
    ap.add_argument("--fov", type=float, default=360.0)
    ap.add_argument("--duration", type=float, default=420.0)
    ap.add_argument("--obstacles", type=int, default=0)
    ap.add_argument("--people", type=int, default=0)
    args = ap.parse_args()
    groups = {"apartments": apartments(args.apartments)}
    if HOUSEEXPO.is_dir():
        groups["houseexpo"] = houseexpo_json() + houseexpo_renders(args.renders)
    else:
        print(f"(no shared data at {HOUSEEXPO}: procedural apartments only)")
    simulate(groups["apartments"][0][1], mapper="oracle", seed=0, duration=10, progress=False)
    print(
        f"oracle exploration, fov {args.fov:g} deg, budget {args.duration:g} s, "
        f"obstacles {args.obstacles}, people {args.people}"
    )
    print(
        f"{'group':11s} {'plan':9s} {'size m':>11s} {'reach m2':>8s} {'coverage':>8s}"
        f" {'strict':>7s} {'sim s':>6s} {'path m':>6s} {'coll':>4s} {'wall s':>6s}  stop"
    )
    all_cov, all_strict = [], []
    for group, plans in groups.items():
        covs, stricts = [], []
        for i, (name, plan) in enumerate(plans):
            t0 = time.perf_counter()
            res = simulate(
                plan, mapper="oracle",
                seed=i,
                duration=args.duration,
                fov=args.fov,
                obstacles=args.obstacles,
                people=args.people,
                progress=False,
            )
            wall = time.perf_counter() - t0
            w, h = plan.size_m
            reach = float(res.reachable.sum()) * plan.resolution**2
            covs.append(res.coverage)
            stricts.append(res.info["coverage_strict"])
            print(
                f"{group:11s} {name:9s} {w:5.1f}x{h:<5.1f} {reach:8.1f} {100 * res.coverage:7.1f}%"
                f" {100 * res.info['coverage_strict']:6.1f}%"
                f" {res.sim_seconds:6.0f} {res.path_length:6.1f} {res.collisions:4d}"
                f" {wall:6.2f}  {res.stop_reason}"
            )
        all_cov += covs
        all_strict += stricts
        summary(group, covs)
        summary(group + " (strict)", stricts)
    summary("all", all_cov)
    summary("all (strict)", all_strict)


def summary(name: str, covs: list[float]) -> None:
    c = 100 * np.array(covs)
    q = np.percentile(c, [0, 25, 50, 75, 100])
    print(
        f"== {name}: n={len(c)}  min {q[0]:.1f}  q25 {q[1]:.1f}  median {q[2]:.1f}  "
        f"q75 {q[3]:.1f}  max {q[4]:.1f}  mean {c.mean():.1f}  >=90%: {(c >= 90).sum()}/{len(c)}"
    )


if __name__ == "__main__":
    main()
