"""Demo stage: the parametric CAD->SLAM model on the demo's generated plan (a few seconds).

The robot tours four roadmap nodes spread over the plan. Writes under
``<out>/parametric/``: the roadmap and trajectory (thesis Fig. 3.3), the
modelled SLAM map and its displacement field by the additive method of [58] (the files
``map2map deform`` writes) and, for comparison, the EKF method's figure (thesis Figs.
5.13, 5.15). Plans larger than 320 pixels on a side are reduced by an integer factor
first (a cell is a wall if any of its pixels is), as the thesis did for its EKF runs.
"""

from __future__ import annotations

import numpy as np

from ..core.grid import FREE, OCCUPIED, UNKNOWN, OccupancyMap
from ..jobs.deform import sample_rngs, write_result
from .figures import deform_figure, roadmap_figure
from .params import ParametricParams
from .pipeline import deform, make_trajectory

__all__ = ["reduce_plan", "stage_parametric"]

#: Largest side (pixels) the demo runs the model at.
MAX_SIDE = 320


def reduce_plan(plan: OccupancyMap, max_side: int = MAX_SIDE) -> OccupancyMap:
    """Reduce a plan by the smallest integer factor that fits ``max_side``.

    A reduced cell is occupied if any of its pixels is, else free if any is free, else
    unknown, so that walls and doors survive.

    >>> m = OccupancyMap(np.full((700, 500), 255, np.uint8), 0.05)
    >>> r = reduce_plan(m)
    >>> r.shape, round(r.resolution, 9)
    ((234, 167), 0.15)
    """
    f = int(np.ceil(max(plan.shape) / max_side))
    if f <= 1:
        return plan
    h, w = plan.shape
    hh, ww = -(-h // f) * f, -(-w // f) * f
    data = np.full((hh, ww), UNKNOWN, np.uint8)
    data[hh - h :, :w] = plan.data  # pad at the top/right so the origin corner stays put
    blocks = data.reshape(hh // f, f, ww // f, f)
    occ = (blocks == OCCUPIED).any(axis=(1, 3))
    free = (blocks == FREE).any(axis=(1, 3))
    out = np.full(occ.shape, UNKNOWN, np.uint8)
    out[free] = FREE
    out[occ] = OCCUPIED
    return OccupancyMap(out, plan.resolution * f, plan.origin, dict(plan.meta))


def stage_parametric(ctx) -> None:
    """Model SLAM maps of ``ctx.results["plan"]`` (additive and EKF) and draw them."""
    plan = reduce_plan(ctx.results["plan"])
    folder = ctx.out / "parametric"
    params = ParametricParams()
    traj_rng, model_rng = sample_rngs(ctx.seed)
    traj, rm = make_trajectory(plan, params, traj_rng, tour=4)
    roadmap = folder / "roadmap.png"
    folder.mkdir(parents=True, exist_ok=True)
    roadmap_figure(plan, rm, traj, roadmap)
    ctx.wrote("roadmap and trajectory (Fig. 3.3)", roadmap)
    res = deform(plan, traj, "additive", params, model_rng)
    run = {"method": "additive", "seed": ctx.seed, "sample": 0, "source": "map2map demo"}
    paths = write_result(plan, res, folder, run)
    ctx.wrote("modelled SLAM map (additive [58])", paths[0])
    ctx.wrote("displacement field dx, dy [px]", paths[2])
    ctx.wrote("plan / field / SLAM map figure (Fig. 5.15)", paths[-1])
    ekf = deform(plan, traj, "ekf", params, sample_rngs(ctx.seed)[1])
    ekf_fig = folder / "figure_ekf.png"
    deform_figure(plan, ekf, ekf_fig, title=f"Modelled SLAM map (EKF, seed {ctx.seed})")
    ctx.wrote("EKF conversion for comparison (Fig. 5.13)", ekf_fig)
    ctx.results["parametric"] = res
    ctx.results["parametric_ekf"] = ekf
