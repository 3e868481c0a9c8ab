"""The main job on the embedded default: every stage of map2map on a generated plan.

The demo is a list of steps (:data:`STAGES`), each ``step(ctx: DemoContext) -> None``:
it runs library functions and jobs (:mod:`map2map.jobs`) on what earlier steps left in
the typed :class:`DemoContext`, records the files it wrote with
:meth:`DemoContext.wrote` and leaves its result in the context for later steps. It is
the top of the package: it imports the jobs and domain packages, nothing imports it
(but the command line).

Steps: ``plan`` (a generated apartment) -> ``prep`` (thesis sec. 4.1 preprocessing)
-> ``parametric`` (thesis sec. 3.2 model, additive and EKF) -> ``simulate``
(five simulated minutes, mapped by the default ``rbpf`` SLAM backend from odometry and scans)
-> ``slam`` (the simulated log replayed through rbpf and graph SLAM, as ``map2map
slam`` does) -> ``evaluate`` (appendix paper Algorithm 1: the SLAM and modelled maps
against the plan). Every step records its key numbers (:meth:`DemoContext.say`, also
printed) and files; :func:`write_index` then writes ``index.html`` and ``README.md``
into the output folder: one section per step, what it did, its numbers, its files.

Where each map lies: the plan and everything drawn over it use the plan's frame; a
SLAM map's own frame is the robot's first pose. The simulator knows the true start
pose, so the ``simulate`` and ``slam`` figures are drawn in the plan frame (their
titles say so); the files ``slam/<backend>/map.yaml`` stay in the map frame, as
``map2map slam`` writes them, and the evaluation aligns them to the plan itself.
"""

from __future__ import annotations

import html
import inspect
import os
import time
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
from tqdm.auto import tqdm

from .core._io import atomic_dir, atomic_path, check_output_dir
from .core.grid import OccupancyMap

__all__ = ["DemoContext", "STAGES", "run_demo", "write_index"]

#: Simulated seconds of the demo's exploration run: five minutes map the generated
#: apartment (98.9 % of its reachable free space, seed 0; one minute mapped 39.9 %, one
#: room, which auto-correct, trained on whole buildings, is not made for), about 4 s
#: more than one minute on a 2-core machine.
SIM_SECONDS = 300.0


@dataclass
class DemoContext:
    """State handed from step to step: the output folder, the seed and every result."""

    out: Path
    seed: int
    #: Simulated seconds of the ``simulate`` step (tests shorten it).
    sim_seconds: float = SIM_SECONDS
    #: Print :meth:`say` lines as they come.
    verbose: bool = True
    plan: OccupancyMap | None = None
    prep: OccupancyMap | None = None
    parametric: Any = None  # map2map.parametric.DeformResult (additive)
    parametric_ekf: Any = None  # the same trajectory converted by EKF-SLAM
    sim: Any = None  # map2map.sim.runner.SimResult
    sim_log: Path | None = None
    slam: dict[str, Any] = field(default_factory=dict)  # backend -> SlamResult
    slam_maps: dict[str, OccupancyMap] = field(default_factory=dict)  # in the plan frame
    evaluation: dict[str, dict] = field(default_factory=dict)  # name -> chosen chain errors
    ate: dict[str, float] = field(default_factory=dict)  # map name -> path ATE (m), plan frame
    autocorrected: OccupancyMap | None = None  # the auto-corrected plan of the simulated SLAM map
    written: list[tuple[str, Path]] = field(default_factory=list)
    timings: dict[str, float] = field(default_factory=dict)
    #: The step running now (set by :func:`run_demo`); files and lines are filed under it.
    step: str = ""
    files: dict[str, list[tuple[str, Path]]] = field(default_factory=dict)  # step -> files
    summary: dict[str, list[str]] = field(default_factory=dict)  # step -> key numbers

    def wrote(self, what: str, path: Path) -> None:
        """Record a file the current step wrote (``what`` says what it holds)."""
        self.written.append((what, Path(path)))
        self.files.setdefault(self.step, []).append((what, Path(path)))

    def say(self, line: str) -> None:
        """Record (and print, if ``verbose``) one line of the current step's key numbers."""
        self.summary.setdefault(self.step, []).append(line)
        if self.verbose:
            print(line, flush=True)


def stage_plan(ctx: DemoContext) -> None:
    """Generate the embedded default floor plan (a seeded apartment), save and draw it.

    A plan already in the context (:func:`run_demo`'s ``plan``) is saved and drawn as is.
    """
    from .maps.floorplan import generate_floorplan
    from .maps.formats import save_map
    from .maps.render import save_map_figure

    kind = "given plan"
    if ctx.plan is None:
        ctx.plan = generate_floorplan(ctx.seed, kind="apartment")
        kind = f"generated apartment, seed {ctx.seed}"
    path = ctx.out / "plan.yaml"
    save_map(ctx.plan, path)
    ctx.wrote("floor plan (ROS map, plan frame)", path)
    ctx.wrote("floor plan image of the ROS map", path.with_suffix(".pgm"))
    fig_path = ctx.out / "plan.png"
    save_map_figure(ctx.plan, fig_path, title=kind[0].upper() + kind[1:])
    ctx.wrote("floor plan figure", fig_path)
    p = ctx.plan
    ctx.say(
        f"plan: {kind}: {p.width} x {p.height} px at "
        f"{100 * p.resolution:g} cm/px ({p.width * p.resolution:.1f} x "
        f"{p.height * p.resolution:.1f} m), {p.free.sum() * p.resolution**2:.1f} m^2 free"
    )


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
    ctx.say(
        f"prep: plan cropped, squared and resized to {ctx.prep.width} x {ctx.prep.height} px "
        f"({100 * ctx.prep.resolution:.1f} cm/px), walls thickened by 1 px"
    )


def stage_parametric(ctx: DemoContext) -> None:
    """The parametric CAD->SLAM model (thesis sec. 3.2) on the plan, additive and EKF.

    A model of the SLAM map a robot would build, not a SLAM run: the robot tours four
    roadmap nodes and the model displaces the plan by a drawn field. Writes under
    ``parametric/`` the roadmap and trajectory (thesis Fig. 3.3), the files ``map2map
    deform`` writes for the additive method and the EKF method's figure (thesis Figs.
    5.13, 5.15). Plans larger than 320 pixels on a side are reduced first
    (:func:`map2map.maps.preprocess.reduce_plan`), as the thesis did for its EKF runs.

    The additive method is the one the thesis takes from its reference [58] (thesis eqs.
    3.81-3.90): odometry errors that grow linearly with the distance driven and the angle
    turned (E_lin = 0.09 dl + sigma, E_ang = 0.095 dtheta + alpha, fitted to experimental
    data in [58]) become errors of the map pixels the lidar sees, added up at every
    re-observation. The EKF method propagates them through EKF-SLAM instead (eqs.
    3.54-3.80): much slower, and the thesis found the two deformations similar (Fig. 5.13).
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
    labels = [
        "modelled SLAM map (additive method of the thesis's ref. [58], ROS, plan frame)",
        "modelled SLAM map image",
        "displacement field dx, dy [px]",
        "trajectory of the modelled run (t,x,y,theta,v,omega)",
        "model parameters and drawn coefficients",
        "plan / field / SLAM map figure (Fig. 5.15)",
    ]
    for what, path in zip(labels, paths, strict=True):
        ctx.wrote(what, path)
    ekf = deform(plan, traj, "ekf", params, sample_rngs(ctx.seed)[1])
    ekf_fig = folder / "figure_ekf.png"
    deform_figure(plan, ekf, ekf_fig, title=f"Modelled SLAM map (EKF, seed {ctx.seed})")
    ctx.wrote("EKF conversion for comparison (Fig. 5.13)", ekf_fig)
    ctx.parametric, ctx.parametric_ekf = res, ekf
    length = float(np.hypot(np.diff(traj.x), np.diff(traj.y)).sum())
    for name, r in (("additive", res), ("EKF", ekf)):
        mag = np.hypot(r.field.dx, r.field.dy)[r.observed]
        top = float(mag.max()) if mag.size else 0.0
        ctx.say(
            f"parametric model ({name}; a model, not SLAM), {length:.1f} m tour: true "
            f"displacement max {top:.2f} px = {100 * top * plan.resolution:.1f} cm, "
            f"{100 * r.observed.mean():.0f} % of the plan observed"
        )


def stage_simulate(ctx: DemoContext) -> None:
    """Explore the plan for five simulated minutes, mapped by the default SLAM backend.

    The simulated robot (TurtleBot3, LDS-01 lidar, noisy odometry) explores like
    ``explore_lite``; the default mapper of ``map2map simulate`` (``rbpf``, GMapping-style)
    builds the map from odometry and scans only, exactly as ``map2map simulate`` does.
    Coverage is of the reachable free space; ATE compares the mapper's path with the
    true one (plan frame, no alignment). Files under ``simulate/``.
    """
    from .jobs.simulate import SimulateSpec, simulate

    run = simulate(
        SimulateSpec(
            ctx.plan, ctx.out / "simulate", seed=ctx.seed, duration=ctx.sim_seconds,
            gif=True, progress=False,
        )
    )  # fmt: skip
    ctx.sim, ctx.sim_log = run.result, run.written["log"]
    res = run.result
    mapper = res.info.get("mapper", "?")
    labels = {
        "slam_map": f"{mapper} SLAM map of the run (ROS, resampled to the plan frame)",
        "trajectory_true": "true path (t,x,y,theta, plan frame)",
        "trajectory_estimated": f"{mapper} estimated path (t,x,y,theta, plan frame)",
        "log": "simulated run (CARMEN log: odometry, scans, true poses)",
        "report": "simulation report (coverage, ATE, path, collisions)",
        "figure": f"plan with paths, {mapper} map in the plan frame, coverage",
        "gif": "exploration animation",
    }
    for key, path in run.written.items():
        ctx.wrote(labels.get(key, key.replace("_", " ")), path)
        if key == "slam_map":
            ctx.wrote(f"{mapper} SLAM map image", path.with_suffix(".pgm"))
    rep = res.report()
    ctx.ate[f"simulate_{mapper}"] = rep["ate_rmse_m"]
    ctx.say(
        f"simulated run ({res.sim_seconds:.0f} s simulated, {res.path_length:.1f} m driven, "
        f"{res.collisions} collisions), {mapper} SLAM map: coverage {100 * res.coverage:.1f} % "
        f"of the reachable free space, ATE {rep['ate_rmse_m']:.3f} m"
    )


def _path_ate(res_b, log, frame) -> float:
    """RMSE (m) of a SLAM path (map frame, placed at ``frame``) vs the log's true poses."""
    from .core.geometry import compose_pose
    from .slam.quality import ate_rmse

    traj = res_b.trajectory
    if log.true_poses is None or frame is None or not len(traj):
        return float("nan")
    est = compose_pose(np.asarray(frame, float), traj[:, 1:4])
    t = np.array([s.t for s in log.scans], float)
    true = np.column_stack([np.interp(traj[:, 0], t, log.true_poses[:, k]) for k in (0, 1)])
    return ate_rmse(est, true, align=False)


def stage_slam(ctx: DemoContext) -> None:
    """Replay the simulated run's CARMEN log through ``rbpf`` and ``graph`` (``slam/``).

    Exactly what ``map2map slam run.log --backend rbpf|graph`` does, seeing only odometry
    and scans: the map files are in the map frame (the robot's first pose); the figures
    are drawn in the plan frame (the log carries the simulator's true start pose), over
    the plan's walls. Without an earlier ``simulate`` step it simulates the five minutes
    itself (oracle mapper: only the log is used).
    """
    from .jobs.slam import write_slam_outputs
    from .robotlog.carmen import write_carmen
    from .robotlog.logs import load_log
    from .sim.mapping import resample_to_frame
    from .sim.runner import simulate
    from .slam.offline import run_slam

    out = ctx.out / "slam"
    log_path = ctx.sim_log
    plan = ctx.sim.plan if ctx.sim is not None else ctx.plan
    if log_path is None:
        res = simulate(
            ctx.plan, seed=ctx.seed, duration=ctx.sim_seconds, mapper="oracle", progress=False
        )
        log_path = out / "run.log"
        out.mkdir(parents=True, exist_ok=True)
        start = dict(zip(("map2map_start_x", "map2map_start_y", "map2map_start_theta"),
                         res.start, strict=True))  # fmt: skip
        records = zip(res.odometry, res.scans, [tuple(p) for p in res.true_poses], strict=True)
        write_carmen(log_path, records, params=start)
        ctx.wrote("simulated run (CARMEN log: odometry, scans, true poses)", log_path)
    log = load_log(log_path)
    frame = log.plan_start_pose()
    for backend, title in (("rbpf", "GMapping-style RBPF"), ("graph", "graph SLAM")):
        res_b = run_slam(log, backend, seed=ctx.seed)
        paths = write_slam_outputs(
            res_b, out / backend, title=f"{title} on the simulated log", frame=frame, plan=plan
        )
        what = [
            f"{backend} SLAM map (ROS, map frame = first pose)",
            f"{backend} SLAM map image",
            f"{backend} estimated path (t,x,y,theta, map frame)",
            f"{backend} map and path drawn in the plan frame over the plan's walls",
        ]
        for w, p in zip(what, paths, strict=False):
            ctx.wrote(w, p)
        ctx.slam[backend] = res_b
        ate = _path_ate(res_b, log, frame)
        ctx.ate[f"slam_{backend}"] = ate
        m = res_b.map
        ctx.say(
            f"map2map slam on the simulated log, {backend} SLAM: {len(log)} scans, "
            f"{m.occupied.sum()} wall cells, {m.free.sum() * m.resolution**2:.1f} m^2 mapped "
            f"free, ATE {ate:.3f} m vs the true path"
        )
    if frame is not None and plan is not None:
        # the maps in the plan's frame (the map frame starts at the true start pose)
        ctx.slam_maps = {k: resample_to_frame(r.map, frame, plan) for k, r in ctx.slam.items()}


def _maps_to_evaluate(ctx: DemoContext) -> list[tuple[str, OccupancyMap, OccupancyMap, str]]:
    """(name, map, plan it models, what made it) of the maps the earlier steps left.

    The SLAM maps are evaluated in their own frame (the first pose), as a user
    evaluates ``map.yaml``: the alignment finds the placement itself.
    """
    from .maps.preprocess import reduce_plan

    found: list[tuple[str, OccupancyMap, OccupancyMap, str]] = []
    if ctx.sim is not None:
        mapper = ctx.sim.info.get("mapper", "?")
        what = f"{mapper} SLAM map of the simulated run"
        found.append((f"simulate_{mapper}", ctx.sim.slam_map, ctx.sim.plan, what))
    if "graph" in ctx.slam:  # the other backend (rbpf ran online above)
        plan = ctx.sim.plan if ctx.sim is not None else ctx.plan
        found.append(("slam_graph", ctx.slam["graph"].map, plan, "graph SLAM map of the log"))
    for name, res, what in (
        ("parametric", ctx.parametric, "parametric model map, additive method, not SLAM"),
        ("parametric_ekf", ctx.parametric_ekf, "parametric model map, EKF method, not SLAM"),
    ):
        if res is not None:
            found.append((name, res.map, reduce_plan(ctx.plan), what))  # the plan it ran on
    return found


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


def stage_autocorrect(ctx: DemoContext) -> None:
    """Auto-correct the simulated rbpf SLAM map into a CAD-like plan, as ``map2map
    autocorrect`` does by default (:data:`map2map.jobs.autocorrect.DEFAULT_MODEL`: the
    classical cleaning drawn like a plan; ``--model thesis`` is the thesis's Model_BA).

    Writes ``autocorrect/cad.yaml`` (+ ``.pgm``), ``autocorrect/walls.dxf`` (the same walls
    as line segments) and ``autocorrect/before_after.png``. The default model needs no
    network (no PyTorch). Skipped, saying so, when no SLAM map was made.
    """
    import warnings

    slam = getattr(ctx.sim, "slam_map_plan", None)
    if not isinstance(slam, OccupancyMap):
        ctx.say("autocorrect: no SLAM map in this demo run; skipped")
        return
    from .jobs.autocorrect import DEFAULT_MODEL, corrector
    from .learn.ba.correction import Correction
    from .learn.training.figures import save_before_after
    from .maps.formats import save_map

    out = ctx.out / "autocorrect"
    out.mkdir(parents=True, exist_ok=True)
    model = corrector(DEFAULT_MODEL)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        res = Correction.of(model.correct_many([slam])[0])
    save_map(res.map, out / "cad.yaml")
    ctx.wrote(f"auto-corrected plan (--model {model.name}, ROS map)", out / "cad.yaml")
    ctx.wrote(f"auto-corrected plan (--model {model.name}, ROS map pixels)", out / "cad.pgm")
    res.save_dxf(out / "walls.dxf")
    ctx.wrote("auto-corrected walls (DXF lines and arcs)", out / "walls.dxf")
    save_before_after(
        slam,
        res.map,
        out / "before_after.png",
        res.map.meta["autocorrect"]["segments_px"],
        title=f"autocorrect --model {model.name}: rbpf SLAM map -> CAD-like plan",
        label=model.name,
    )
    ctx.wrote("auto-correct before/after figure", out / "before_after.png")
    ctx.say(
        f"autocorrect: rbpf SLAM map -> CAD-like plan (--model {model.name}, drawn like a "
        f"plan): {len(res.segments)} wall segments"
    )
    for w in res.warnings:
        ctx.say(f"autocorrect: warning: {w}")
    ctx.autocorrected = res.map


def stage_evaluate(ctx: DemoContext) -> None:
    """Evaluate every SLAM and modelled map against the plan (appendix paper Algorithm 1).

    Each map is aligned to the plan (any rotation, translation, scale) and the local
    error of its walls measured (appendix paper eq. 7); wall mean / max leave out
    points that match no plan wall (clutter, stray points), counted beside them.
    Writes ``report.json``, ``overlay.png``, ``error_map.png`` and ``points.csv`` per map
    under ``evaluate/<name>/``, and for the first map (the simulated SLAM map) the
    as-built inspection report an inspector reads (``map2map evaluate --report``):
    ``inspection.html`` with its Markdown twin and one CSV row per plan wall, pass or
    fail at 5 cm. Without maps from earlier steps it bends the plan by a smooth *known*
    field and prints the measured errors beside the true ones.
    """
    from .evaluate.pipeline import evaluate_maps
    from .jobs.evaluate import write_evaluation
    from .reports.inspection import write_inspection

    plan = ctx.plan
    if plan is None:
        from .maps.synthetic import draw_walls, office_walls

        plan = OccupancyMap(draw_walls((280, 360), office_walls(360, 280, thickness=4)), 0.05)
    maps = _maps_to_evaluate(ctx) if ctx.plan is not None else []
    truth = None
    if not maps:
        bent, truth = _known_errors(plan, ctx.seed)
        maps = [("known_bend", bent, plan, "the plan bent by a known smooth field")]
    for name, m, ref, made_by in maps:
        out = ctx.out / "evaluate" / name
        out.mkdir(parents=True, exist_ok=True)
        res = ref.resolution
        ev = evaluate_maps(m, ref, resolution=res, rigid_scale=m.resolution / res,
                           names=(name, "plan"))  # fmt: skip
        paths = write_evaluation(ev, ref, out, res)
        for what, p in paths.items():
            ctx.wrote(f"evaluation of the {made_by}: {what.replace('_', ' ')}", p)
        inspected = None
        if name == maps[0][0]:
            files = write_inspection(
                ev, ref, out / "inspection.html", tolerance=0.05,
                overlay_png=paths["overlay"].read_bytes(),
                error_map_png=paths["error_map"].read_bytes(),
            )  # fmt: skip
            ctx.wrote(f"as-built inspection report of the {made_by} (HTML)", files.html)
            ctx.wrote("as-built inspection report (Markdown)", files.md)
            for k, fig in enumerate(sorted(files.md.parent.glob(files.md.stem + "_files/*"))):
                ctx.wrote(f"as-built inspection report, figure {k + 1}", fig)
            ctx.wrote("as-built inspection, one row per plan wall (CSV)", files.csv)
            inspected = f"inspect {name}: plan walls {files.summary()} (inspection.html)"
        e = ev.report["errors"][ev.chosen]
        ctx.evaluation[name] = e
        line = (
            f"evaluate {name} ({made_by}) against the plan, {ev.chosen} chain: walls mean "
            f"{100 * e['mean_m']:.1f} cm, max {100 * e['max_m']:.1f} cm; "
            f"{e['unmatched_points']} of {e['points_all']} points match no plan wall"
        )
        if name in ctx.ate:
            line += f"; its path's ATE {ctx.ate[name]:.3f} m"
        if truth is not None:
            X = ev.registration.X
            ch = ev.errors[ev.chosen]
            r, c = np.floor(X[:, 1]).astype(int), np.floor(X[:, 0]).astype(int)
            true = np.abs(((ch.X_rigid - (X - truth[r, c])) * ev.registration.normals).sum(1))
            true = true[ch.valid] * res
            line += f" (true: mean {100 * true.mean():.1f} cm, max {100 * true.max():.1f} cm)"
        for w in ev.report["warnings"]:
            line += f"\n  warning: {w}"
        for w in ev.report.get("notes", []):
            line += f"\n  note: {w}"
        ctx.say(line)
        if inspected:
            ctx.say(inspected)


#: (name, step) of the demo, in order.
STAGES: list[tuple[str, Callable[[DemoContext], None]]] = [
    ("plan", stage_plan),
    ("prep", stage_prep),
    ("parametric", stage_parametric),
    ("simulate", stage_simulate),
    ("slam", stage_slam),
    ("autocorrect", stage_autocorrect),
    ("evaluate", stage_evaluate),  # keep last: it evaluates the maps the steps above made
]


def _description(stage: Callable) -> str:
    """A step's docstring as prose: its paragraphs, reST markup removed."""
    doc = inspect.getdoc(stage) or ""
    paras = [" ".join(p.split()) for p in doc.split("\n\n") if p.strip()]
    text = "\n\n".join(paras)
    for a, b in ((":func:", ""), (":meth:", ""), (":mod:", ""), ("``", ""), ("*", "")):
        text = text.replace(a, b)
    return text.replace("`~", "").replace("`", "")


def write_index(ctx: DemoContext) -> list[Path]:
    """Write ``index.html`` and ``README.md`` into the demo folder: what every step did.

    One section per step that ran: its description (the step's docstring), its key
    numbers (the lines of :meth:`DemoContext.say`) and a relative link to every file it
    wrote (pictures shown inline in ``index.html``). Both open offline. No run times:
    the same seed gives the same index byte for byte. Returns the two paths (also
    recorded in ``ctx.written``).
    """
    ctx.step = "index"
    names = [n for n, _ in STAGES if n in ctx.timings or n in ctx.files]
    docs = dict(STAGES)
    rel = {p: os.path.relpath(p, ctx.out).replace(os.sep, "/") for _, p in ctx.written}
    md = [
        "# map2map demo",
        "",
        f"Seed {ctx.seed}; {len(ctx.written) + 2} files, this index included. "
        "One section per step: what it did, its key numbers, its files (paths relative "
        "to this folder). Maps in the plan frame are drawn as the plan is; a SLAM map's "
        "own frame is the robot's first pose.",
        "",
    ]
    h = [
        "<!DOCTYPE html>",
        '<html lang="en"><head><meta charset="utf-8"><title>map2map demo</title>',
        "<style>body{font-family:sans-serif;max-width:60em;margin:auto;padding:1em}"
        "img{max-width:100%;border:1px solid #ccc}td{padding:0 .6em}"
        "pre{background:#f4f4f4;padding:.5em;white-space:pre-wrap}</style></head><body>",
        "<h1>map2map demo</h1>",
        f"<p>{html.escape(md[2])}</p>",
        '<p>The same index as Markdown: <a href="README.md">README.md</a>.</p>',
    ]
    for name in names:
        title = f"{names.index(name) + 1}. {name}"
        took = f" ({len(ctx.files.get(name, []))} files)"
        text = _description(docs[name]) if name in docs else ""
        lines = ctx.summary.get(name, [])
        files = ctx.files.get(name, [])
        md += [f"## {title}{took}", "", text, ""]
        h += [f"<h2>{html.escape(title + took)}</h2>"]
        h += [f"<p>{html.escape(p)}</p>" for p in text.split("\n\n") if p]
        if lines:
            md += ["```text", *lines, "```", ""]
            h.append("<pre>" + html.escape("\n".join(lines)) + "</pre>")
        if files:
            md += ["| file | what it holds |", "|---|---|"]
            md += [f"| [{rel[p]}]({rel[p]}) | {w} |" for w, p in files]
            md.append("")
            md += [f"![{w}]({rel[p]})" for w, p in files if p.suffix in {".png", ".gif"}]
            md.append("")
            h.append("<table>")
            for w, p in files:
                link = html.escape(rel[p], quote=True)
                h.append(f'<tr><td><a href="{link}">{html.escape(rel[p])}</a></td>'
                         f"<td>{html.escape(w)}</td></tr>")  # fmt: skip
            h.append("</table>")
            for w, p in files:
                if p.suffix in {".png", ".gif"}:
                    link = html.escape(rel[p], quote=True)
                    h.append(f'<figure><a href="{link}"><img src="{link}" alt="{html.escape(w)}">'
                             f"</a><figcaption>{html.escape(w)}</figcaption></figure>")  # fmt: skip
    h.append("</body></html>")
    paths = [ctx.out / "index.html", ctx.out / "README.md"]
    for path, text in zip(paths, ["\n".join(h) + "\n", "\n".join(md).rstrip() + "\n"],
                          strict=True):  # fmt: skip
        with atomic_path(path) as tmp:
            tmp.write_text(text, encoding="utf-8")
    ctx.wrote("index of this folder (HTML, pictures inline)", paths[0])
    ctx.wrote("index of this folder (Markdown)", paths[1])
    return paths


def run_demo(
    out: str | Path = "demo_out",
    seed: int = 0,
    progress: bool = True,
    *,
    plan: OccupancyMap | None = None,
    sim_seconds: float = SIM_SECONDS,
    verbose: bool = True,
) -> DemoContext:
    """Run every step on a generated plan, write the folder's index; return the context.

    ``plan`` replaces the generated apartment (the ``plan`` step then only saves and
    draws it) and ``sim_seconds`` the simulated time: both for quick tests.
    ``verbose`` prints every step's key numbers as they come.

    The folder is written whole or not at all (:func:`map2map.core._io.atomic_dir`): the
    steps write under a temporary sibling name that is renamed to ``out`` at the end, so
    an interrupted demo leaves no half-written folder and a finished one replaces an
    older ``out`` as a whole.
    """
    final = check_output_dir(out)
    with atomic_dir(final) as tmp:
        ctx = DemoContext(out=tmp, seed=int(seed), sim_seconds=sim_seconds, verbose=verbose)
        ctx.plan = plan
        bar = tqdm(STAGES, desc="map2map demo", unit="stage", disable=not progress)
        for name, stage in bar:
            bar.set_postfix_str(name)
            ctx.step = name
            t0 = time.perf_counter()
            stage(ctx)
            ctx.timings[name] = time.perf_counter() - t0
        bar.close()
        write_index(ctx)
    # the folder was written whole under a temporary name, then renamed: point there
    ctx.written = [(what, final / p.relative_to(tmp)) for what, p in ctx.written]
    ctx.out = final
    return ctx
