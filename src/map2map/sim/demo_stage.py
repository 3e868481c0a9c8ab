"""Demo stage: a short simulated exploration of the demo's generated plan."""

from __future__ import annotations

__all__ = ["stage_simulate"]


def stage_simulate(ctx) -> None:
    """Explore ``ctx.results["plan"]`` for one simulated minute with the oracle mapper.

    Writes the run's outputs (map, trajectories, CARMEN log, report, figure, gif)
    under ``simulate/`` and leaves the :class:`~map2map.sim.runner.SimResult` in
    ``ctx.results["sim"]`` (its CARMEN log path in ``ctx.results["sim_log"]``).
    """
    from .runner import save_run, simulate

    plan = ctx.results["plan"]
    res = simulate(
        plan, mapper="oracle", seed=ctx.seed, duration=60.0, frame_every=2.0, progress=False
    )
    paths = save_run(res, ctx.out / "simulate", gif=True)
    ctx.results["sim"] = res
    ctx.results["sim_log"] = paths["log"]
    labels = {
        "slam_map": "simulated SLAM map (ROS, plan frame)",
        "log": "simulated run (CARMEN log)",
        "report": "simulation report",
        "figure": "simulation figure",
        "gif": "exploration animation",
    }
    for key, what in labels.items():
        if key in paths:
            ctx.wrote(what, paths[key])
