"""The ``slam`` stage of ``map2map demo``: the simulated run mapped by both SLAM backends.

It replays the CARMEN log that the ``simulate`` stage recorded (one simulated
minute of the demo plan) through the GMapping-style particle filter and through
graph SLAM -- exactly what ``map2map slam run.log --backend rbpf|graph`` does, seeing
only odometry and scans -- and writes each map (ROS yaml + pgm), trajectory and
figure under ``slam/``, and leaves the maps resampled into the plan's frame in
``ctx.results["slam_maps"]``. Without an earlier ``simulate`` stage it simulates the
minute itself. A few seconds in all.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

if TYPE_CHECKING:
    from ..demo import DemoContext

__all__ = ["stage_slam"]


def stage_slam(ctx: DemoContext) -> None:
    """Map the demo's simulated run with ``rbpf`` and ``graph``; write maps and figures."""
    from ..maps.floorplan import generate_floorplan
    from ..robotlog.carmen import write_carmen
    from ..robotlog.logs import load_log
    from ..sim.runner import simulate
    from .offline import run_slam, write_slam_outputs

    out = ctx.out / "slam"
    log_path = ctx.results.get("sim_log")
    if log_path is None:
        plan = ctx.results.get("plan") or generate_floorplan(ctx.seed, kind="apartment")
        res = simulate(plan, seed=ctx.seed, duration=60.0, mapper="oracle", progress=False)
        log_path = out / "run.log"
        out.mkdir(parents=True, exist_ok=True)
        write_carmen(log_path, list(zip(res.odometry, res.scans, res.true_poses, strict=True)))
        ctx.wrote("simulated run (CARMEN log)", log_path)
    log = load_log(log_path)
    results = {}
    for backend, title in (("rbpf", "GMapping-style RBPF"), ("graph", "graph SLAM")):
        res_b = run_slam(log, backend, seed=ctx.seed)
        for p in write_slam_outputs(res_b, out / backend, title=f"{title} on the simulated log"):
            ctx.wrote(f"{backend} {p.suffix[1:]}", p)
        results[backend] = res_b
    ctx.results["slam"] = results
    sim = ctx.results.get("sim")
    if sim is not None and log_path == ctx.results.get("sim_log"):
        # the maps in the plan's frame (the map frame starts at the true start pose),
        # for stages that compare maps with the plan
        from ..sim.mapping import resample_to_frame

        ctx.results["slam_maps"] = {
            k: resample_to_frame(r.map, sim.start, sim.plan) for k, r in results.items()
        }
