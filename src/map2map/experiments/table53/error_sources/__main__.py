"""Where a SLAM map's appendix-metric error comes from: whole walls displaced, or scatter
of the wall faces about their wall's position? (``git show e59abf4^:docs/learn.md``,
"Table 5.3 on 104 held-out builder maps".)

For each held-out pair, Error(sim) (the chosen chain's mean local error, px, as in
:mod:`map2map.experiments.table53.measure`) is split: the metric's points are grouped by the plan
wall
they match (orientation, the plan face's coordinate across the wall, runs along it cut at
gaps > 10 px); ``floor`` is the mean over points of the absolute mean signed offset of
their wall -- what a correction that keeps every wall where the SLAM map has it and only
straightens its faces cannot remove.

    python3 -m map2map.experiments.table53.error_sources table53_out/heldout.npz [--n 104]
"""

from __future__ import annotations

import argparse
import sys
import warnings

import numpy as np

from map2map.core.grid import OccupancyMap
from map2map.datasets.packed import load_packed
from map2map.evaluate.pipeline import EvaluateParams, evaluate_maps


def per_wall_floor(slam: np.ndarray, plan: np.ndarray, seed: int = 0) -> tuple[float, float]:
    """(Error(sim), its per-wall-displacement part), pixels."""
    ev = evaluate_maps(OccupancyMap(slam, 0.05), OccupancyMap(plan, 0.05),
                       params=EvaluateParams(seed=seed))
    e = ev.errors[ev.chosen]
    v = e.valid
    vec = e.X_rigid[v] - e.X_corr[v]
    horiz = np.abs(vec[:, 1]) >= np.abs(vec[:, 0])     # displaced across a horizontal wall
    across = np.where(horiz, np.round(e.X_corr[v, 1]), np.round(e.X_corr[v, 0]))
    along = np.where(horiz, e.X_corr[v, 0], e.X_corr[v, 1])
    signed = np.where(horiz, vec[:, 1], vec[:, 0])
    keys = np.stack([horiz.astype(int), across], 1)
    floor = np.zeros(int(v.sum()))
    for k in np.unique(keys, axis=0):
        idx = np.flatnonzero((keys == k).all(1))
        idx = idx[np.argsort(along[idx])]
        for g in np.split(idx, np.flatnonzero(np.diff(along[idx]) > 10) + 1):
            floor[g] = abs(signed[g].mean())
    return float(e.distances[v].mean()), float(floor.mean())


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("pairs", help="held-out pairs (.npz, e.g. table53.py's OUT/heldout.npz)")
    ap.add_argument("--n", type=int, default=None)
    args = ap.parse_args(argv)
    p = load_packed(args.pairs)
    n = len(p) if args.n is None else min(args.n, len(p))
    out = []
    warnings.simplefilter("ignore")
    for i in range(n):
        try:
            out.append(per_wall_floor(p.b[i], p.a[i]))
        except Exception as exc:  # noqa: BLE001 - an alignment failure skips the map
            print(f"map {i + 1}: alignment failed ({exc})")
    o = np.array(out)
    print(f"{len(o)} maps: median Error(sim) {np.median(o[:, 0]):.3f} px, median per-wall "
          f"displacement part {np.median(o[:, 1]):.3f} px, median share "
          f"{np.median(o[:, 1] / o[:, 0]):.2f}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
