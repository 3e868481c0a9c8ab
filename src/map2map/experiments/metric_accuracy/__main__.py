"""Accuracy of the error metric (Algorithm 1) on maps with known errors.

Usage::

    python3 -m map2map.experiments.metric_accuracy

Generated office plans are rebuilt with walls out of place by known amounts, or bent
by smooth known displacement fields (and, when :mod:`map2map.parametric` is
installed, by the parametric CAD->SLAM model's field along a robot trajectory). The
true local error of every SLAM wall point is the distance, across its wall, from its
rigidly aligned position to where it belongs on the plan; the reported mean and max
are compared with the true ones (target: within 5%).
"""

from __future__ import annotations

import sys

import cv2
import numpy as np

from map2map.core.grid import OccupancyMap
from map2map.evaluate.validation import known_error_case
from map2map.maps.synthetic import (
    deform,
    draw_walls,
    gaussian_field,
    min_jacobian,
    office_walls,
    true_errors,
    wall_displacement,
)

W, H = 320, 240


def case(name, plan, slam, u, rows, field=None):
    """Evaluate one map with known errors (library: known_error_case) and print it."""
    c = known_error_case(name, plan, slam, u)
    rep, true = c.reported[c.chosen], c.true[c.chosen]
    dm, dx = c.relative()
    rows.append((dm, dx))
    extra = ""
    if field is not None:
        # the field's own (continuous) displacement of the same faces: the map draws
        # each face on whole pixels, so this differs from the drawn truth by rounding
        reg = c.evaluation.registration
        tf = np.abs(true_errors(reg.X, reg.normals, reg.alignment.rigid, plan, u, field))
        tf = tf[c.evaluation.errors[c.chosen].valid].mean()
        extra = f"  [field itself: mean {tf:.3f}]"
    print(
        f"{name:<44s} {c.chosen:<8s} mean {rep['mean_px']:6.3f} / {true['mean_px']:6.3f} px "
        f"({100 * dm:+5.1f}%)  max {rep['max_px']:6.2f} / {true['max_px']:6.2f} px "
        f"({100 * dx:+5.1f}%)" + extra,
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
        case(f"bend at ({cx}, {cy}) by ({ax}, {ay}) px", plan, slam, u, rows, field)
    try:
        from map2map.parametric import deform as parametric_deform
        from map2map.parametric import make_trajectory
        from map2map.parametric.params import ParametricParams
    except ImportError:
        print("(map2map.parametric not installed: parametric-model fields skipped)")
    else:
        pm = OccupancyMap(plan, 0.05)
        # the model's field is defined where the LIDAR saw free space and is ~0 on the
        # walls themselves; smoothed it moves each wall with its surroundings, so that
        # the true face displacement is well defined. Scaled up (stronger drift) it is
        # smoothed more and scaled at most so far that walls are compressed at most 2x
        # (Jacobian of p -> p + d(p) >= 0.5): a field that folds (Jacobian <= 0) has no
        # true error, and one that squeezes a 4 px wall to one pixel leaves a line
        # without faces, whose side no metric can tell.
        for seed in (0, 1, 2):
            rng = np.random.default_rng(seed)
            p = ParametricParams()
            traj, _ = make_trajectory(pm, p, rng, tour=5)
            res = parametric_deform(pm, traj, params=p, rng=rng)
            for sigma, scale in ((5.0, 1.0), (12.0, 3.0)):
                field = np.stack(
                    [cv2.GaussianBlur(a, (0, 0), sigma) for a in (res.field.dx, res.field.dy)], -1
                )
                while scale > 1.0 and min_jacobian(scale * field) < 0.5:
                    scale -= 0.25
                field = scale * field
                jac = min_jacobian(field)
                slam, u = deform(plan, field)
                name = f"parametric seed {seed}, x{scale:g} (smooth {sigma:g}, J>={jac:.2f})"
                case(name, plan, slam, u, rows, field)
    a = np.abs(np.array(rows))
    print(
        f"\n{len(a)} cases: mean within 5% in {(a[:, 0] <= 0.05).sum()}, max within 5% in "
        f"{(a[:, 1] <= 0.05).sum()}; worst mean {100 * a[:, 0].max():.1f}%, "
        f"worst max {100 * a[:, 1].max():.1f}%"
    )
    return 0


if __name__ == "__main__":
    sys.exit(main())
