"""The ``slam`` stage of ``map2map demo``: a short simulated exploration mapped by the RBPF.

It explores the demo's floor plan for 60 simulated seconds with the GMapping-style
particle filter (the robot sees only odometry and scans), then replays the recorded
CARMEN log through graph SLAM, and writes both maps, trajectories and figures --
a few seconds in all.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

if TYPE_CHECKING:
    from ..demo import DemoContext

__all__ = ["stage_slam"]


def stage_slam(ctx: DemoContext) -> None:
    """Simulate 60 s with ``rbpf``, replay the log with ``graph``; write maps and figures."""
    from ..maps.floorplan import generate_floorplan
    from ..sim.carmen import write_carmen
    from ..sim.runner import simulate
    from .logs import load_log
    from .offline import SlamResult, odometry_in_map_frame, run_slam, write_slam_outputs
    from .rbpf import make_rbpf

    plan = ctx.results.get("plan") or generate_floorplan(ctx.seed, kind="apartment")
    mapper = make_rbpf(plan.resolution, seed=ctx.seed)
    res = simulate(plan, seed=ctx.seed, mapper=mapper, duration=60.0, progress=False)
    out = ctx.out / "slam"
    log_path = out / "run.log"
    out.mkdir(parents=True, exist_ok=True)
    write_carmen(log_path, list(zip(res.odometry, res.scans, res.true_poses, strict=True)))
    ctx.wrote("simulated run (CARMEN log)", log_path)
    log = load_log(log_path)
    rb = SlamResult(res.slam_map, mapper.trajectory(), odometry_in_map_frame(log), mapper, "rbpf")
    for p in write_slam_outputs(rb, out / "rbpf", title="rbpf (GMapping-style), 60 s"):
        ctx.wrote(f"rbpf {p.suffix[1:]}", p)
    gr = run_slam(log, "graph", resolution=plan.resolution)
    for p in write_slam_outputs(gr, out / "graph", title="graph SLAM replay of the same log"):
        ctx.wrote(f"graph {p.suffix[1:]}", p)
    ctx.results["slam"] = {"rbpf": rb, "graph": gr, "sim": res}
