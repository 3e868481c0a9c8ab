"""Demo stage: evaluate the demo's SLAM-like maps against its floor plan.

Takes the plan from ``ctx.results["plan"]`` and the SLAM-like maps earlier stages
left: the simulator's SLAM map (``ctx.results["sim"].slam_map``), the parametric
model's maps (``ctx.results["parametric"]``, ``["parametric_ekf"]``, on the reduced
plan they were modelled on) and any ``deformed_maps`` / ``slam_map(s)``. When there
is none, it bends the plan by a smooth *known* field itself and prints the measured
errors beside the true ones.
"""

from __future__ import annotations

import numpy as np

from ..maps.grid import OccupancyMap
from .outputs import write_evaluation
from .pipeline import evaluate_maps

__all__ = ["stage_evaluate"]


def _slam_maps(results: dict, plan: OccupancyMap) -> list[tuple[str, OccupancyMap, OccupancyMap]]:
    """(name, SLAM-like map, plan it models) of every map the earlier stages left."""
    found: list[tuple[str, OccupancyMap, OccupancyMap]] = []
    sim = results.get("sim")
    if isinstance(getattr(sim, "slam_map", None), OccupancyMap):
        found.append(("simulated_slam", sim.slam_map, getattr(sim, "plan", plan)))
    for key in ("parametric", "parametric_ekf"):
        res = results.get(key)
        if isinstance(getattr(res, "map", None), OccupancyMap):
            from ..parametric.demo_stage import reduce_plan  # the plan the model ran on

            found.append((key, res.map, reduce_plan(plan)))
    for key in ("deformed_maps", "sim_map", "slam_map", "slam_maps"):
        v = results.get(key)
        items = v.items() if isinstance(v, dict) else enumerate(v or ()) if isinstance(
            v, list | tuple) else [("", v)]  # fmt: skip
        for k, m in items:
            if isinstance(m, OccupancyMap):
                found.append((f"{key}_{k}".rstrip("_"), m, plan))
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
    maps = _slam_maps(ctx.results, plan)
    truth = None
    if not maps:
        bent, truth = _known_errors(plan, ctx.seed)
        maps = [("known_bend", bent, plan)]
    summary = {}
    for name, m, ref in maps:
        out = ctx.out / "evaluate" / name
        out.mkdir(parents=True, exist_ok=True)
        res = ref.resolution
        ev = evaluate_maps(m, ref, resolution=res, rigid_scale=m.resolution / res,
                           names=(name, "plan"))  # fmt: skip
        paths = write_evaluation(ev, ref, out, res)
        for what, p in paths.items():
            ctx.wrote(f"evaluation {name}: {what.replace('_', ' ')}", p)
        e = ev.report["errors"][ev.chosen]
        summary[name] = e
        line = (
            f"evaluate {name}: walls mean {100 * e['mean_m']:.1f} cm, max {100 * e['max_m']:.1f} "
            f"cm; {e['unmatched_points']} of {e['points_all']} points match no plan wall"
        )
        if truth is not None:
            X = ev.registration.X
            ch = ev.errors[ev.chosen]
            r, c = np.floor(X[:, 1]).astype(int), np.floor(X[:, 0]).astype(int)
            true = np.abs(((ch.X_rigid - (X - truth[r, c])) * ev.registration.normals).sum(1))
            true = true[ch.valid] * res
            line += f" (true: mean {100 * true.mean():.1f} cm, max {100 * true.max():.1f} cm)"
        for w in ev.report["warnings"]:
            line += f"\n  warning: {w}"
        print(line)
    ctx.results["evaluation"] = summary
