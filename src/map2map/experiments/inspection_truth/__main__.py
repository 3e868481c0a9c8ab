"""Inspection verdicts against the true wall deviations of parametric deformations.

Usage::

    python -m map2map.experiments.inspection_truth [--plans 20] [--seed 0]
        [--tolerance 0.05] [--scales 0.05,0.1,0.2,0.4] [--csv walls.csv]

Prints, per field scale, the walls by verdict and by truth (within / beyond the
tolerance), the contradictions (a wall failed that is within, or passed that is beyond)
and the share of verdicts that agree; ``--csv`` writes one row per observed wall.
"""

from __future__ import annotations

import argparse
import csv
import sys
import time

import numpy as np

from map2map.core.grid import OCCUPIED, OccupancyMap
from map2map.evaluate.pipeline import evaluate_maps
from map2map.evaluate.walls import inspect_walls
from map2map.maps.floorplan import generate_floorplan
from map2map.parametric.field import DisplacementField, warp_map
from map2map.parametric.params import ParametricParams
from map2map.parametric.pipeline import deform, make_trajectory


def true_deviation(seg, field: DisplacementField, observed: np.ndarray, walls: np.ndarray,
                   to_plan) -> float:
    """The p95 across the wall (pixels) of where the field moved the wall's observed
    pixels, once the evaluation's mapping ``to_plan`` (map pixels -> plan pixels) maps
    them back; NaN when none of its pixels was observed (or for an arc: the generated
    plans have none)."""
    if seg.shape != "line":
        return float("nan")
    x0, y0, x1, y1 = seg.px
    n = max(2, int(np.ceil(np.hypot(x1 - x0, y1 - y0))) + 1)
    t = np.linspace(0.0, 1.0, n)
    p = np.stack([x0 + t * (x1 - x0), y0 + t * (y1 - y0)], 1)
    r = np.clip(np.floor(p[:, 1]).astype(int), 0, field.shape[0] - 1)
    c = np.clip(np.floor(p[:, 0]).astype(int), 0, field.shape[1] - 1)
    keep = observed[r, c] & walls[r, c]
    if not keep.any():
        return float("nan")
    p, r, c = p[keep], r[keep], c[keep]
    q = p + np.stack([field.dx[r, c], field.dy[r, c]], 1)
    back = to_plan(q)
    u = np.array([x1 - x0, y1 - y0], float)
    u /= max(np.hypot(*u), 1e-12)
    normal = np.array([-u[1], u[0]])
    return float(np.percentile(np.abs((back - p) @ normal), 95))


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(prog="python -m map2map.experiments.inspection_truth",
                                 description=__doc__.splitlines()[0])
    ap.add_argument("--plans", type=int, default=20, help="deformed plans (default 20)")
    ap.add_argument("--seed", type=int, default=0, help="first plan seed (default 0)")
    ap.add_argument("--tolerance", type=float, default=0.05, help="metres (default 0.05)")
    ap.add_argument("--scales", default="0.05,0.1,0.2,0.4",
                    help="factors on the model's field, plan i takes scale i mod len")
    ap.add_argument("--csv", help="one row per observed wall")
    args = ap.parse_args(argv)
    scales = [float(s) for s in args.scales.split(",")]
    tol_cm = 100.0 * args.tolerance
    rows = []
    t0 = time.perf_counter()
    for i in range(args.plans):
        seed = args.seed + i
        plan = generate_floorplan(seed)
        rng = np.random.default_rng(seed)
        params = ParametricParams()
        traj, _ = make_trajectory(plan, params, rng, tour=8)
        res = deform(plan, traj, "additive", params, rng)
        k = scales[i % len(scales)]
        field = DisplacementField(res.field.dx * k, res.field.dy * k)
        built = OccupancyMap(warp_map(plan.data, field, res.observed), plan.resolution,
                             plan.origin)
        ev = evaluate_maps(built, plan, resolution=plan.resolution)
        insp = inspect_walls(ev, plan, tolerance=args.tolerance)
        chain = 0 if ev.chosen == "rigid" else 1

        def to_plan(q, ev=ev, chain=chain):
            return ev.registration.map_points(q)[chain]

        walls = plan.data == OCCUPIED
        for s in insp.segments:
            if s.status == "not observed":
                continue
            truth = true_deviation(s, field, res.observed, walls, to_plan)
            if not np.isfinite(truth):
                continue
            truth_cm = truth * plan.resolution * 100.0
            wrong = ((s.status == "fail" and truth_cm <= tol_cm)
                     or (s.status == "pass" and truth_cm > tol_cm))
            rows.append({"plan": seed, "scale": k, "chain": ev.chosen, "wall": s.id,
                         "status": s.status, "deviation_cm": round(s.deviation_cm, 2),
                         "lo_cm": round(s.deviation_lo_cm, 2),
                         "hi_cm": round(s.deviation_hi_cm, 2),
                         "true_cm": round(truth_cm, 2), "beyond": truth_cm > tol_cm,
                         "contradicts": wrong})
        print(f"plan {seed} (scale {k:g}, {ev.chosen}): "
              + ", ".join(f"{v} {c}" for c, v in insp.counts.items()), flush=True)
    if args.csv:
        with open(args.csv, "w", newline="") as fh:
            w = csv.DictWriter(fh, fieldnames=list(rows[0]))
            w.writeheader()
            w.writerows(rows)
    print(f"\n{args.plans} plans, {len(rows)} observed walls, tolerance {tol_cm:g} cm "
          f"({time.perf_counter() - t0:.0f} s)")
    print(f"{'scale':>6s} {'walls':>6s} {'beyond':>7s} {'pass':>5s} {'uncert':>6s} "
          f"{'fail':>5s} {'contra':>6s}")
    for k in [*scales, None]:
        sel = [r for r in rows if k is None or r["scale"] == k]
        if not sel:
            continue
        st = [r["status"] for r in sel]
        print(f"{'all' if k is None else f'{k:g}':>6s} {len(sel):6d} "
              f"{sum(r['beyond'] for r in sel):7d} {st.count('pass'):5d} "
              f"{st.count('uncertain'):6d} {st.count('fail'):5d} "
              f"{sum(r['contradicts'] for r in sel):6d}")
    agree = 1.0 - sum(r["contradicts"] for r in rows) / max(1, len(rows))
    print(f"verdicts that agree with the truth: {agree:.1%} (target >= 95 %)")
    bad = [r for r in rows if r["contradicts"]]
    for r in bad[:10]:
        print(f"  contradiction: plan {r['plan']} wall {r['wall']}: {r['status']}, measured "
              f"{r['deviation_cm']} [{r['lo_cm']}, {r['hi_cm']}] cm, true {r['true_cm']} cm")
    return 0


if __name__ == "__main__":
    sys.exit(main())
