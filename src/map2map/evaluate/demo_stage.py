"""Demo stage: evaluate the demo's SLAM-like maps against its floor plan.

Takes the plan from ``ctx.results["plan"]`` and every SLAM-like map earlier stages
left (``deformed_maps``, ``sim_map``, ``slam_map``, ``slam_maps``). When there is
none, it builds one itself with *known* errors (two walls built out of place and a
smooth bend) and prints the measured errors beside the true ones.
"""

from __future__ import annotations

import numpy as np

from ..maps.grid import OccupancyMap
from .outputs import write_evaluation
from .pipeline import evaluate_maps

__all__ = ["stage_evaluate"]

_KEYS = ("deformed_maps", "sim_map", "slam_map", "slam_maps")


def _slam_maps(results: dict) -> list[tuple[str, OccupancyMap]]:
    found = []
    for key in _KEYS:
        v = results.get(key)
        if isinstance(v, OccupancyMap):
            found.append((key, v))
        elif isinstance(v, dict):
            found += [(f"{key}_{k}", m) for k, m in v.items() if isinstance(m, OccupancyMap)]
        elif isinstance(v, list | tuple):
            found += [(f"{key}_{i}", m) for i, m in enumerate(v) if isinstance(m, OccupancyMap)]
    return found[:3]  # a few seconds each at most


def _known_errors(plan: OccupancyMap, seed: int) -> tuple[OccupancyMap, np.ndarray]:
    """The plan bent by a smooth known field (about 0.3 m at its peak)."""
    from .synthetic import deform, gaussian_field

    rng = np.random.default_rng(seed)
    h, w = plan.shape
    centre = (rng.uniform(0.6, 0.9) * w, rng.uniform(0.6, 0.9) * h)
    amp = 0.3 / plan.resolution
    field = gaussian_field(plan.shape, centre, (amp, 0.5 * amp), 0.2 * max(h, w))
    data, u = deform(plan.data, field)
    return OccupancyMap(data, plan.resolution, plan.origin), u


def stage_evaluate(ctx) -> None:
    """Evaluate every SLAM-like map of the demo against the plan (report, overlay, error map)."""
    plan = ctx.results.get("plan")
    if not isinstance(plan, OccupancyMap):
        from .synthetic import draw_walls, office_walls

        plan = OccupancyMap(draw_walls((280, 360), office_walls(360, 280, thickness=4)), 0.05)
    maps = _slam_maps(ctx.results)
    truth = None
    if not maps:
        bent, truth = _known_errors(plan, ctx.seed)
        maps = [("known_bend", bent)]
    summary = {}
    for name, m in maps:
        out = ctx.out / "evaluate" / name
        out.mkdir(parents=True, exist_ok=True)
        res = plan.resolution
        ev = evaluate_maps(m, plan, resolution=res, rigid_scale=m.resolution / res,
                           names=(name, "plan"))  # fmt: skip
        paths = write_evaluation(ev, plan, out, res)
        for what, p in paths.items():
            ctx.wrote(f"evaluation {name}: {what.replace('_', ' ')}", p)
        e = ev.report["errors"][ev.chosen]
        summary[name] = e
        line = f"evaluate {name}: mean {100 * e['mean_m']:.1f} cm, max {100 * e['max_m']:.1f} cm"
        if truth is not None:
            X = ev.registration.X
            ch = ev.errors[ev.chosen]
            r, c = np.floor(X[:, 1]).astype(int), np.floor(X[:, 0]).astype(int)
            true = np.abs(((ch.X_rigid - (X - truth[r, c])) * ev.registration.normals).sum(1))
            true = true[ch.valid] * res
            line += f" (true: mean {100 * true.mean():.1f} cm, max {100 * true.max():.1f} cm)"
        print(line)
    ctx.results["evaluation"] = summary
