"""Realism of Model_AB's SLAM maps, measured (issue #15; the thesis judged it by eye).

A generated map is realistic if it is as close to a reference SLAM map of the same plan as
two independent reference runs are to each other. On held-out plans, per map (on the
dataset's square, in pixels of the dataset's size):

* ``wall_err``     mean distance (px) of occupied cells to the nearest plan wall;
* ``wall_seen``    share of plan wall pixels with an occupied cell within 2 px;
* ``free_mapped``  share of plan free pixels that are free in the map;
* ``unknown``      unknown share of the plan's known pixels;
* ``spurious``     occupied 8-connected fragments farther than 3 px from every plan wall;
* ``thickness``    wall thickness (px), :func:`map2map.learn.postprocess.wall_thickness_px`;
* ``bend``         bent-wall curvature: RMS distance of a fragment's pixels to its own
  principal line, over fragments of >= 20 px (0 for straight walls). Crude: a fragment
  joining walls at an L or T junction counts as bent too, so the ratio is only
  meaningful between maps whose walls connect alike.

Each statistic's distribution over generated maps is compared with that over reference
run 1 by the Wasserstein distance, normalised by the same distance between reference runs
1 and 2 (two seeds of the same plans). Target: every ratio <= 1.5.

The references: the dataset's SLAM maps (run 1) and a second run of the same plans with
another seed (run 2). For datasets of :func:`map2map.learn.synthetic.make_pairs` (the
only ones this script can re-run) both runs are the **parametric** model's (additive),
not simulated exploration + SLAM; with a ``map2map dataset build`` dataset the second
seed would need the simulation re-run (not implemented here).

    python3 benchmarks/realism.py --data DS [--model pretrained|RUN] [--plans 20] [--quick]
"""

from __future__ import annotations

import argparse
import sys
import warnings
from pathlib import Path

import numpy as np
from scipy import ndimage
from scipy.stats import wasserstein_distance

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "src"))

from map2map.core.grid import FREE, OCCUPIED, UNKNOWN, OccupancyMap  # noqa: E402
from map2map.learn.data import downsample_target, load_pairs  # noqa: E402
from map2map.learn.postprocess import wall_thickness_px  # noqa: E402

STATS = ("wall_err", "wall_seen", "free_mapped", "unknown", "spurious", "thickness", "bend")


def second_run(seed: int, size: int, alt: int) -> np.ndarray:
    """The SLAM map of ``make_pair(seed)``'s plan from another trajectory/noise seed."""
    from map2map.maps.floorplan import generate_floorplan
    from map2map.maps.preprocess import preprocess
    from map2map.parametric.params import ParametricParams
    from map2map.parametric.pipeline import deform, make_trajectory

    rng = np.random.default_rng(seed)   # the plan as make_pair draws it
    kind = "office" if rng.random() < 0.25 else "apartment"
    plan = generate_floorplan(int(rng.integers(2**31)), kind=kind)
    rng2 = np.random.default_rng([seed, alt])
    traj, _ = make_trajectory(plan, ParametricParams(), rng2, tour=5)
    slam = deform(plan, traj, rng=rng2).map
    r0, r1, c0, c1 = plan.content_bbox()
    window = (r0 - 4, r1 + 4, c0 - 4, c1 + 4)
    return preprocess(slam.crop(*window), size).data


def map_stats(m: np.ndarray, plan: np.ndarray) -> dict[str, float]:
    """The statistics of the module doc for SLAM map ``m`` of ``plan`` (same square)."""
    walls = plan == OCCUPIED
    d_wall = ndimage.distance_transform_edt(~walls) if walls.any() else np.full(m.shape, 1e9)
    occ = m == OCCUPIED
    known_plan = plan != UNKNOWN
    near = ndimage.binary_dilation(occ, iterations=2)
    lab, n = ndimage.label(occ, structure=np.ones((3, 3)))
    spurious, bends = 0, []
    for sl, k in zip(ndimage.find_objects(lab), range(1, n + 1), strict=True):
        part = lab[sl] == k
        rr, cc = np.nonzero(part)
        if d_wall[sl][part].min() > 3:
            spurious += 1
        if len(rr) >= 20:
            pts = np.stack([rr, cc], 1).astype(float)
            pts -= pts.mean(0)
            sv = np.linalg.svd(pts, compute_uv=False)
            bends.append(float(sv[-1] / np.sqrt(len(pts))))
    return {
        "wall_err": float(d_wall[occ].mean()) if occ.any() else float("nan"),
        "wall_seen": float(near[walls].mean()) if walls.any() else float("nan"),
        "free_mapped": float((m[plan == FREE] == FREE).mean()) if (plan == FREE).any() else 0.0,
        "unknown": float((m[known_plan] == UNKNOWN).mean()) if known_plan.any() else 1.0,
        "spurious": float(spurious),
        "thickness": float(wall_thickness_px(m[None])) if occ.any() else 0.0,
        "bend": float(np.mean(bends)) if bends else 0.0,
    }


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--data", required=True, help="packed dataset of make_pairs")
    ap.add_argument("--model", default="pretrained")
    ap.add_argument("--plans", type=int, default=20)
    ap.add_argument("--quick", action="store_true", help="6 plans")
    args = ap.parse_args(argv)
    from map2map.learn.synthesize import synthesize

    pairs = load_pairs(args.data)
    meta = pairs.meta
    if meta.get("generator") != "map2map.learn.synthetic.make_pairs":
        print(f"{args.data}: not a make_pairs dataset; cannot re-run a second seed",
              file=sys.stderr)
        return 2
    test = np.flatnonzero(pairs.split == "test")
    test = test[:6 if args.quick else args.plans]
    size = pairs.a.shape[-1]
    rows = {"generated": [], "reference 1": [], "reference 2": []}
    for i in test:
        plan, ref1 = pairs.a[i], pairs.b[i]
        seed = int(str(pairs.plan_id[i]).rsplit("-", 1)[1])
        ref2 = second_run(seed, size, alt=1)
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            gen = synthesize(OccupancyMap(plan, 0.05), args.model, samples=1).maps[0].data
        for name, m in (("generated", gen), ("reference 1", ref1), ("reference 2", ref2)):
            rows[name].append(map_stats(downsample_target(m[None], size)[0], plan))
    print(f"{len(test)} held-out plans of {args.data} ({size} px); model {args.model}; "
          "references: the dataset's SLAM maps and a second seed (parametric model)")
    print(f"{'statistic':>12} {'generated':>10} {'ref 1':>8} {'ref 2':>8} {'W(gen,1)':>9} "
          f"{'W(2,1)':>8} {'ratio':>7}")
    worst = 0.0
    for s in STATS:
        g, r1, r2 = (np.array([r[s] for r in rows[k]], float) for k in rows)
        g, r1, r2 = (v[np.isfinite(v)] for v in (g, r1, r2))
        if not (len(g) and len(r1) and len(r2)):
            print(f"{s:>12}  (no values)")
            continue
        w_g, w_r = wasserstein_distance(g, r1), wasserstein_distance(r2, r1)
        ratio = w_g / max(w_r, 1e-9)
        worst = max(worst, ratio)
        print(f"{s:>12} {g.mean():>10.3f} {r1.mean():>8.3f} {r2.mean():>8.3f} {w_g:>9.3f} "
              f"{w_r:>8.3f} {ratio:>7.2f}")
    print(f"worst ratio {worst:.2f} (target <= 1.5): "
          f"{'met' if worst <= 1.5 else 'NOT met'}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
