"""Accuracy of the error metric (Algorithm 1) on maps with known errors.

Usage::

    python3 benchmarks/metric_accuracy.py

Generated office plans are rebuilt with walls out of place by known amounts, or bent
by smooth known displacement fields (and, when :mod:`map2map.parametric` is
installed, by the parametric CAD->SLAM model's field along a robot trajectory). The
true local error of every SLAM wall point is the distance, across its wall, from its
rigidly aligned position to where it belongs on the plan; the reported mean and max
are compared with the true ones (target: within 5%).
"""

from __future__ import annotations

import sys
from pathlib import Path

import cv2
import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "src"))

from map2map.evaluate.pipeline import evaluate_maps  # noqa: E402
from map2map.evaluate.synthetic import (  # noqa: E402
    deform,
    draw_walls,
    gaussian_field,
    office_walls,
    wall_displacement,
)
from map2map.maps.grid import OccupancyMap  # noqa: E402

W, H = 320, 240


def true_errors(ev, u):
    X, n = ev.registration.X, ev.registration.normals
    e = ev.errors[ev.chosen]
    r, c = np.floor(X[:, 1]).astype(int), np.floor(X[:, 0]).astype(int)
    return np.abs(((e.X_rigid - (X - u[r, c])) * n).sum(1))[e.valid]


def case(name, plan, slam, u, rows):
    ev = evaluate_maps(OccupancyMap(slam, 0.05), OccupancyMap(plan, 0.05), resolution=0.05)
    true = true_errors(ev, u)
    rep = ev.report["errors"][ev.chosen]
    dm = rep["mean_px"] / true.mean() - 1
    dx = rep["max_px"] / true.max() - 1
    rows.append((dm, dx))
    print(
        f"{name:<34s} {ev.chosen:<8s} mean {rep['mean_px']:6.3f} / {true.mean():6.3f} px "
        f"({100 * dm:+5.1f}%)  max {rep['max_px']:6.2f} / {true.max():6.2f} px ({100 * dx:+5.1f}%)",
        flush=True,
    )


def main() -> int:
    walls = office_walls(W, H, thickness=4)
    plan = draw_walls((H, W), walls)
    rows: list[tuple[float, float]] = []
    print("case                               chain    reported / true")
    for cs, ps in [((-6.0, 0.0), (7.0, -5.0)), ((0.0, 4.0), (0.0, 0.0)), ((3.0, 3.0), (-8.0, 2.0))]:
        built_walls = office_walls(W, H, thickness=4, corridor_shift=cs, partition_shift=ps)
        u = wall_displacement((H, W), walls, built_walls)
        case(f"walls moved {cs} {ps}", plan, draw_walls((H, W), built_walls), u, rows)
    for cx, cy, ax, ay, sg in [
        (0.8, 0.8, 0, 8, 60),
        (0.7, 0.3, 7, 0, 40),
        (0.95, 0.5, 8, 0, 70),
        (0.9, 0.4, 6, 4, 60),
        (0.5, 0.9, 0, 6, 50),
    ]:
        field = gaussian_field(plan.shape, (cx * W, cy * H), (ax, ay), sg)
        slam, u = deform(plan, field)
        case(f"bend at ({cx}, {cy}) by ({ax}, {ay}) px", plan, slam, u, rows)
    try:
        from map2map.parametric import deform as parametric_deform
        from map2map.parametric import make_trajectory
        from map2map.parametric.params import ParametricParams
    except ImportError:
        print("(map2map.parametric not installed: parametric-model fields skipped)")
    else:
        pm = OccupancyMap(plan, 0.05)
        for seed in (0, 1):
            rng = np.random.default_rng(seed)
            p = ParametricParams()
            traj, _ = make_trajectory(pm, p, rng, tour=5)
            res = parametric_deform(pm, traj, params=p, rng=rng)
            # the model's field is defined where the LIDAR saw free space and is ~0 on the
            # walls themselves; smoothed (sigma 5 px) it moves each wall with its
            # surroundings, so that the true surface displacement is well defined
            field = np.stack(
                [cv2.GaussianBlur(a, (0, 0), 5.0) for a in (res.field.dx, res.field.dy)], -1
            )
            slam, u = deform(plan, field)
            case(f"parametric model field (smoothed), seed {seed}", plan, slam, u, rows)
    a = np.abs(np.array(rows))
    print(
        f"\n{len(a)} cases: mean within 5% in {(a[:, 0] <= 0.05).sum()}, max within 5% in "
        f"{(a[:, 1] <= 0.05).sum()}; worst mean {100 * a[:, 0].max():.1f}%, "
        f"worst max {100 * a[:, 1].max():.1f}%"
    )
    return 0


if __name__ == "__main__":
    sys.exit(main())
