"""The main job on the embedded default: every stage of map2map on a generated plan.

The demo is a list of steps (:data:`STAGES`), each ``step(ctx: DemoContext) -> None``:
it runs library functions and jobs (:mod:`map2map.jobs`) on what earlier steps left in
the typed :class:`DemoContext`, records the files it wrote with
:meth:`DemoContext.wrote` and leaves its result in the context for later steps. It is
the top of the package: it imports the jobs and domain packages, nothing imports it
(but the command line).

Steps: ``plan`` (a generated apartment) -> ``prep`` (thesis sec. 4.1 preprocessing)
-> ``parametric`` (thesis sec. 3.2 model, additive and EKF) -> ``simulate`` (one
simulated minute, oracle mapper) -> ``slam`` (the simulated log through rbpf and
graph SLAM) -> ``evaluate`` (appendix paper Algorithm 1 on the maps above).
"""

from __future__ import annotations

import time
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
from tqdm.auto import tqdm

from .core._io import ensure_output_dir
from .core.grid import OccupancyMap

__all__ = ["DemoContext", "STAGES", "run_demo"]


@dataclass
class DemoContext:
    """State handed from step to step: the output folder, the seed and every result."""

    out: Path
    seed: int
    plan: OccupancyMap | None = None
    prep: OccupancyMap | None = None
    parametric: Any = None  # map2map.parametric.DeformResult (additive)
    parametric_ekf: Any = None  # the same trajectory converted by EKF-SLAM
    sim: Any = None  # map2map.sim.runner.SimResult
    sim_log: Path | None = None
    slam: dict[str, Any] = field(default_factory=dict)  # backend -> SlamResult
    slam_maps: dict[str, OccupancyMap] = field(default_factory=dict)  # in the plan frame
    evaluation: dict[str, dict] = field(default_factory=dict)  # name -> chosen chain errors
    written: list[tuple[str, Path]] = field(default_factory=list)
    timings: dict[str, float] = field(default_factory=dict)

    def wrote(self, what: str, path: Path) -> None:
        self.written.append((what, Path(path)))


def stage_plan(ctx: DemoContext) -> None:
    """Generate the embedded default floor plan and draw it."""
    from .maps.floorplan import generate_floorplan
    from .maps.formats import save_map
    from .maps.render import save_map_figure

    ctx.plan = generate_floorplan(ctx.seed, kind="apartment")
    path = ctx.out / "plan.yaml"
    save_map(ctx.plan, path)
    ctx.wrote("floor plan (ROS map)", path)
    fig_path = ctx.out / "plan.png"
    save_map_figure(ctx.plan, fig_path, title=f"Generated apartment, seed {ctx.seed}")
    ctx.wrote("floor plan figure", fig_path)


def stage_prep(ctx: DemoContext) -> None:
    """Square, resize to 256 and thicken the plan (thesis sec. 4.1); save it and a figure."""
    from .maps.formats import save_map
    from .maps.preprocess import preprocess, save_preprocess_figure

    ctx.prep = preprocess(ctx.plan, size=256, thicken=1, crop=True, margin=4)
    path = ctx.out / "plan_256.png"
    save_map(ctx.prep, path)
    ctx.wrote("plan preprocessed to 256x256 (thesis 4.1)", path)
    fig_path = ctx.out / "prep.png"
    save_preprocess_figure(
        ctx.plan, ctx.prep, fig_path, title="crop, square, resize to 256, thicken 1 px"
    )
    ctx.wrote("preprocessing figure", fig_path)


def stage_parametric(ctx: DemoContext) -> None:
    """The parametric CAD->SLAM model (thesis sec. 3.2) on the plan, additive and EKF.

    The robot tours four roadmap nodes. Writes under ``parametric/`` the roadmap and
    trajectory (thesis Fig. 3.3), the files ``map2map deform`` writes for the additive
    method of [58] and the EKF method's figure (thesis Figs. 5.13, 5.15). Plans larger
    than 320 pixels on a side are reduced first (:func:`map2map.maps.preprocess.reduce_plan`),
    as the thesis did for its EKF runs.
    """
    from .jobs.deform import sample_rngs, write_result
    from .maps.preprocess import reduce_plan
    from .parametric.figures import deform_figure, roadmap_figure
    from .parametric.params import ParametricParams
    from .parametric.pipeline import deform, make_trajectory

    plan = reduce_plan(ctx.plan)
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
    ctx.parametric, ctx.parametric_ekf = res, ekf


def stage_simulate(ctx: DemoContext) -> None:
    """Explore the plan for one simulated minute with the oracle mapper (``simulate/``)."""
    from .jobs.simulate import SimulateSpec, simulate

    run = simulate(
        SimulateSpec(
            ctx.plan, ctx.out / "simulate", seed=ctx.seed, duration=60.0, mapper="oracle",
            gif=True, progress=False,
        )
    )  # fmt: skip
    ctx.sim, ctx.sim_log = run.result, run.written["log"]
    labels = {
        "slam_map": "simulated SLAM map (ROS, plan frame)",
        "log": "simulated run (CARMEN log)",
        "report": "simulation report",
        "figure": "simulation figure",
        "gif": "exploration animation",
    }
    for key, what in labels.items():
        if key in run.written:
            ctx.wrote(what, run.written[key])


def stage_slam(ctx: DemoContext) -> None:
    """Replay the simulated run's CARMEN log through ``rbpf`` and ``graph`` (``slam/``).

    Exactly what ``map2map slam run.log --backend rbpf|graph`` does, seeing only odometry
    and scans. Without an earlier ``simulate`` step it simulates the minute itself.
    """
    from .jobs.slam import write_slam_outputs
    from .robotlog.carmen import write_carmen
    from .robotlog.logs import load_log
    from .sim.mapping import resample_to_frame
    from .sim.runner import simulate
    from .slam.offline import run_slam

    out = ctx.out / "slam"
    log_path = ctx.sim_log
    if log_path is None:
        res = simulate(ctx.plan, seed=ctx.seed, duration=60.0, mapper="oracle", progress=False)
        log_path = out / "run.log"
        out.mkdir(parents=True, exist_ok=True)
        write_carmen(log_path, list(zip(res.odometry, res.scans, res.true_poses, strict=True)))
        ctx.wrote("simulated run (CARMEN log)", log_path)
    log = load_log(log_path)
    for backend, title in (("rbpf", "GMapping-style RBPF"), ("graph", "graph SLAM")):
        res_b = run_slam(log, backend, seed=ctx.seed)
        for p in write_slam_outputs(res_b, out / backend, title=f"{title} on the simulated log"):
            ctx.wrote(f"{backend} {p.suffix[1:]}", p)
        ctx.slam[backend] = res_b
    if ctx.sim is not None and log_path == ctx.sim_log:
        # the maps in the plan's frame (the map frame starts at the true start pose)
        ctx.slam_maps = {
            k: resample_to_frame(r.map, ctx.sim.start, ctx.sim.plan) for k, r in ctx.slam.items()
        }


def _maps_to_evaluate(ctx: DemoContext) -> list[tuple[str, OccupancyMap, OccupancyMap]]:
    """(name, SLAM-like map, plan it models) of the maps the earlier steps left (<= 3)."""
    from .maps.preprocess import reduce_plan

    found: list[tuple[str, OccupancyMap, OccupancyMap]] = []
    if ctx.sim is not None:
        found.append(("simulated_slam", ctx.sim.slam_map, ctx.sim.plan))
    for name, res in (("parametric", ctx.parametric), ("parametric_ekf", ctx.parametric_ekf)):
        if res is not None:
            found.append((name, res.map, reduce_plan(ctx.plan)))  # the plan the model ran on
    for k, m in ctx.slam_maps.items():
        found.append((f"slam_maps_{k}", m, ctx.plan))
    return found[:3]  # a few seconds each at most


def _known_errors(plan: OccupancyMap, seed: int) -> tuple[OccupancyMap, np.ndarray]:
    """The plan bent by a smooth known field (about 0.3 m at its peak)."""
    from .maps.synthetic import deform, gaussian_field

    rng = np.random.default_rng(seed)
    h, w = plan.shape
    centre = (rng.uniform(0.6, 0.9) * w, rng.uniform(0.6, 0.9) * h)
    amp = 0.3 / plan.resolution
    field_ = gaussian_field(plan.shape, centre, (amp, 0.5 * amp), 0.2 * max(h, w))
    data, u = deform(plan.data, field_)
    return OccupancyMap(data, plan.resolution, plan.origin), u


def stage_evaluate(ctx: DemoContext) -> None:
    """Evaluate every SLAM-like map against the plan (appendix paper Algorithm 1).

    Writes ``report.json``, ``overlay.png`` and ``error_map.png`` per map under
    ``evaluate/<name>/``. Without maps from earlier steps it bends the plan by a smooth
    *known* field and prints the measured errors beside the true ones.
    """
    from .evaluate.pipeline import evaluate_maps
    from .jobs.evaluate import write_evaluation

    plan = ctx.plan
    if plan is None:
        from .maps.synthetic import draw_walls, office_walls

        plan = OccupancyMap(draw_walls((280, 360), office_walls(360, 280, thickness=4)), 0.05)
    maps = _maps_to_evaluate(ctx) if ctx.plan is not None else []
    truth = None
    if not maps:
        bent, truth = _known_errors(plan, ctx.seed)
        maps = [("known_bend", bent, plan)]
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
        ctx.evaluation[name] = e
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


#: (name, step) of the demo, in order.
STAGES: list[tuple[str, Callable[[DemoContext], None]]] = [
    ("plan", stage_plan),
    ("prep", stage_prep),
    ("parametric", stage_parametric),
    ("simulate", stage_simulate),
    ("slam", stage_slam),
    ("evaluate", stage_evaluate),  # keep last: it evaluates the maps the steps above made
]


def run_demo(out: str | Path = "demo_out", seed: int = 0, progress: bool = True) -> DemoContext:
    """Run every step on a generated plan; return the context listing what was written."""
    out_dir = ensure_output_dir(out)
    ctx = DemoContext(out=out_dir, seed=int(seed))
    bar = tqdm(STAGES, desc="map2map demo", unit="stage", disable=not progress)
    for name, stage in bar:
        bar.set_postfix_str(name)
        t0 = time.perf_counter()
        stage(ctx)
        ctx.timings[name] = time.perf_counter() - t0
    bar.close()
    return ctx
