"""``map2map deform`` as a job: read the plan and route, run the parametric model, write.

:func:`deform` takes a :class:`DeformSpec` and returns a :class:`DeformRun`: the files
written (``written``, name -> path) and, per sample, the in-memory
:class:`~map2map.parametric.pipeline.DeformResult` (thesis sec. 3.2). Everything is
validated (plan, parameters, route, every sample's trajectory, the output folder)
before any work; the outputs go to a temporary folder renamed whole at the end
(:func:`map2map.core._io.atomic_dir`: an existing output folder is replaced).

Seeds: sample ``k`` of a run with ``--seed N`` uses seed ``N + k``, split into two
independent streams (:class:`numpy.random.SeedSequence`): one plans the trajectory, the
other draws the model. So ``map2map deform PLAN --seed S --params params.yaml
--trajectory trajectory.csv`` with a sample's own files and seed repeats it byte for
byte (the recipe is written into its ``params.yaml``).

Coordinates (``start``, ``goal``, ``waypoints``, ``trajectory``) are in the plan's own
frame: for a HouseExpo JSON plan HouseExpo's (y down), converted by
:func:`map2map.maps.houseexpo.plan_poses_to_world` as ``map2map simulate`` does;
``route_frame="world"`` takes them in the map's ROS frame as they are (what a sample's
own ``trajectory.csv`` is written in).

Examples
--------
>>> import numpy as np, tempfile, pathlib
>>> from map2map.core.grid import OccupancyMap
>>> data = np.full((60, 100), 255, np.uint8); data[[0, -1], :] = 0; data[:, [0, -1]] = 0
>>> out = pathlib.Path(tempfile.mkdtemp()) / "m"
>>> run = deform(DeformSpec(OccupancyMap(data, 0.05), out, start=(0.5, 0.5),
...                         goal=(4.0, 2.0), figures=False, progress=False))
>>> sorted(run.written), run.results[0].method
(['displacement', 'params', 'slam_map', 'slam_map_pgm', 'trajectory'], 'additive')
"""

from __future__ import annotations

import dataclasses
import os
import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
from tqdm.auto import tqdm

from .._version import __version__
from ..core._io import atomic_dir, check_output_dir, ensure_output_dir
from ..core.errors import InputError, warnings_unless_error
from ..core.grid import FREE, OccupancyMap
from ..parametric.figures import deform_figure
from ..parametric.params import ParametricParams, load_params, save_params
from ..parametric.pipeline import DeformResult, make_trajectory
from ..parametric.pipeline import deform as run_model
from ..trajectory.timing import Trajectory, read_trajectory, read_waypoints
from ._common import check_positive, check_seed, final_paths

__all__ = [
    "DeformSpec",
    "DeformSample",
    "DeformRun",
    "DeformJob",
    "deform",
    "run_deform",
    "load_plan",
    "sample_rngs",
    "write_result",
]

ROUTE_FRAMES = ("plan", "world")


@dataclass
class DeformSpec:
    """What ``map2map deform`` is asked to do.

    Parameters
    ----------
    plan : path-like or OccupancyMap
        The floor plan: a file (any format :func:`map2map.maps.formats.load_map` reads,
        with ``read_options`` and ``resolution``) or a map in memory.
    out : path-like
        Output folder (replaced whole if it exists).
    method : {"additive", "ekf"}
        Odometry-to-map conversion (thesis eqs. 3.81-3.90 or 3.54-3.80).
    seed, samples : int
        Seed of sample 0; number of maps (sample ``k`` uses ``seed + k``; with more than
        one, each goes to ``sample_KKK/``).
    start, goal : (x, y) or None
        Route end points [m]; both or neither.
    waypoints, trajectory : path-like or None
        A waypoints file or a recorded trajectory CSV (at most one route source).
    fov : float or None
        LIDAR field of view in degrees (default from the parameters: 360).
    params : path-like or None
        Model parameters YAML overriding the defaults.
    resolution : float or None
        Metres per pixel of a plan without its own.
    read_options : MapReadOptions or None
        How to read the plan file.
    route_frame : {"plan", "world"}
        Frame of the route coordinates: the plan's own (HouseExpo: y down, converted)
        or the map's ROS world frame as given.
    figures, progress : bool
        Write ``figure.png`` per sample; show a tqdm bar.
    plan_name : str or None
        Names an in-memory plan in messages and ``params.yaml``.
    """

    plan: str | os.PathLike | OccupancyMap
    out: str | os.PathLike
    method: str = "additive"
    seed: int = 0
    samples: int = 1
    start: tuple[float, float] | None = None
    goal: tuple[float, float] | None = None
    waypoints: str | os.PathLike | None = None
    trajectory: str | os.PathLike | None = None
    fov: float | None = None
    params: str | os.PathLike | None = None
    resolution: float | None = None
    read_options: Any = None  # maps.formats.MapReadOptions
    route_frame: str = "plan"
    figures: bool = True
    progress: bool = True
    plan_name: str | os.PathLike | None = None


#: The old name of :class:`DeformSpec`.
DeformJob = DeformSpec


@dataclass
class DeformSample:
    """One modelled map: its folder, seed, files, the model's result and field statistics."""

    folder: Path
    seed: int
    written: dict[str, Path]
    result: DeformResult
    stats: dict[str, Any]


@dataclass
class DeformRun:
    """What :func:`deform` wrote (name -> path; ``sample_KKK/name`` with several samples)
    and every sample in memory."""

    written: dict[str, Path]
    samples: list[DeformSample] = field(default_factory=list)

    @property
    def results(self) -> list[DeformResult]:
        """The :class:`~map2map.parametric.pipeline.DeformResult` of every sample."""
        return [s.result for s in self.samples]


def load_plan(path: Path, resolution: float | None = None, options=None) -> OccupancyMap:
    """Read a plan with :func:`map2map.maps.formats.load_map` (any supported format);
    ``options`` is a :class:`~map2map.maps.formats.MapReadOptions` (thresholds...)."""
    from ..maps.formats import load_map

    return load_map(path, options, resolution=resolution)


def sample_rngs(seed: int) -> tuple[np.random.Generator, np.random.Generator]:
    """(trajectory, model) generators of one sample's seed."""
    a, b = np.random.SeedSequence(int(seed)).spawn(2)
    return np.random.default_rng(a), np.random.default_rng(b)


def _check_trajectory(plan: OccupancyMap, traj: Trajectory, source: Path) -> None:
    rows, cols = plan.world_to_pixel(traj.x, traj.y)
    inside = plan.contains(rows, cols)
    if not inside.all():
        i = int(np.flatnonzero(~inside)[0])
        raise InputError(source, f"pose {i} ({traj.x[i]:g}, {traj.y[i]:g}) m lies outside the map")
    v = plan.data[rows, cols]
    if v[0] != FREE:
        raise InputError(
            source, f"the first pose ({traj.x[0]:g}, {traj.y[0]:g}) m is not in free space"
        )


_NAMES = ("slam_map", "slam_map_pgm", "displacement", "trajectory", "params", "figure")


def write_result(
    plan: OccupancyMap,
    res: DeformResult,
    folder: Path,
    run: dict[str, Any],
    *,
    figures: bool = True,
) -> list[Path]:
    """Write one sample's files into ``folder``; returns their paths.

    ``slam_map.yaml`` + ``.pgm``, ``displacement.npz``, ``trajectory.csv``,
    ``params.yaml`` (with ``run``) and, with ``figures``, ``figure.png``.
    """
    from ..maps.ros import save_ros_map

    folder = ensure_output_dir(folder)
    paths = [folder / n for n in ("slam_map.yaml", "displacement.npz", "trajectory.csv",
                                  "params.yaml", "figure.png")]  # fmt: skip
    pgm = save_ros_map(res.map, paths[0])
    res.field.save_npz(paths[1])
    res.trajectory.to_csv(paths[2])
    save_params(res.params, paths[3], run=run, drawn=res.drawn)
    if not figures:
        return [paths[0], Path(pgm), *paths[1:4]]
    deform_figure(
        plan, res, paths[4], title=f"Modelled SLAM map ({res.method}, seed {run['seed']})"
    )
    return [paths[0], Path(pgm), *paths[1:]]


def _flip_trajectory(traj: Trajectory) -> Trajectory:
    """A trajectory given in a HouseExpo plan's frame (y down) in the map's ROS frame."""
    from ..maps.houseexpo import plan_poses_to_world

    xyt = plan_poses_to_world(np.column_stack([traj.x, traj.y, traj.theta]))
    return dataclasses.replace(traj, x=xyt[:, 0], y=xyt[:, 1], theta=xyt[:, 2], omega=-traj.omega)


def _check_spec(spec: DeformSpec) -> None:
    check_seed(spec.seed)
    if spec.samples < 1:
        raise InputError("samples", f"must be at least 1, got {spec.samples}")
    if spec.method not in ("additive", "ekf"):
        raise InputError("method", f"must be additive or ekf, got {spec.method!r}")
    if spec.route_frame not in ROUTE_FRAMES:
        raise InputError("route_frame", f"must be plan or world, got {spec.route_frame!r}")
    sources = [
        spec.start is not None or spec.goal is not None,
        spec.waypoints is not None,
        spec.trajectory is not None,
    ]
    if sum(sources) > 1:
        raise InputError(None, "use only one of start/goal, waypoints, trajectory")
    if (spec.start is None) != (spec.goal is None):
        raise InputError("start" if spec.start is None else "goal", "give both start and goal")
    check_positive(spec.resolution, "resolution")


def _run_record(spec: DeformSpec, plan_name, seed: int, k: int, houseexpo: bool) -> dict:
    if spec.trajectory:
        source = str(spec.trajectory)
    elif spec.waypoints:
        source = str(spec.waypoints)
    elif spec.start:
        source = f"start {list(spec.start)} goal {list(spec.goal)}"
    else:
        source = "random start and goal"
    run = {
        "map2map_version": __version__,
        "plan": str(plan_name),
        "method": spec.method,
        "seed": seed,
        "sample": k,
        "trajectory_source": source,
        "repeat": (
            f"map2map deform {plan_name} --out OUT --method {spec.method} --seed {seed} "
            f"--params params.yaml --trajectory trajectory.csv"
        ),
    }
    if houseexpo:  # trajectory.csv is in the map's ROS frame, not HouseExpo's
        run["repeat"] += " --route-frame world"
    if spec.resolution:
        run["resolution"] = spec.resolution
        run["repeat"] += f" --resolution {spec.resolution!r}"
    if spec.read_options is not None and spec.read_options.to_args():
        run["repeat"] += " " + " ".join(spec.read_options.to_args())
    return run


def deform(spec: DeformSpec) -> DeformRun:
    """Run ``map2map deform``: every input and the output folder checked before any work.

    Parameters
    ----------
    spec : DeformSpec
        The plan, route, model parameters and output folder.

    Returns
    -------
    DeformRun
        ``written`` (name -> path, ``sample_KKK/name`` with several samples) and every
        sample's :class:`~map2map.parametric.pipeline.DeformResult` and statistics.

    Raises
    ------
    InputError
        A bad parameter, plan, route or output folder (nothing is written).
    """
    from ..maps.houseexpo import is_houseexpo, plan_poses_to_world

    _check_spec(spec)
    inputs = (None if isinstance(spec.plan, OccupancyMap) else spec.plan,
              spec.waypoints, spec.trajectory, spec.params)  # fmt: skip
    check_output_dir(spec.out, protect=inputs)
    params = load_params(spec.params) if spec.params else ParametricParams()
    if spec.fov is not None:
        params = dataclasses.replace(params, fov_deg=float(spec.fov))
    plan_name = spec.plan_name if isinstance(spec.plan, OccupancyMap) else spec.plan
    with warnings_unless_error():  # a refused plan: the error alone
        if isinstance(spec.plan, OccupancyMap):
            plan = spec.plan
        else:
            plan = load_plan(spec.plan, spec.resolution, spec.read_options)
        if not plan.free.any():
            raise InputError(plan_name, "the plan has no free space")
    flip = is_houseexpo(plan) and spec.route_frame == "plan"  # HouseExpo's y points down
    start, goal = spec.start, spec.goal
    if flip and start is not None:
        start, goal = (tuple(map(float, plan_poses_to_world(np.array([p], float))[0]))
                       for p in (start, goal))  # fmt: skip
    waypoints = read_waypoints(spec.waypoints) if spec.waypoints else None
    if flip and waypoints is not None:
        waypoints = plan_poses_to_world(waypoints)
    recorded = None
    if spec.trajectory:
        recorded = read_trajectory(spec.trajectory, v_max=params.v_max, omega_max=params.omega_max)
        if flip:
            recorded = _flip_trajectory(recorded)
        _check_trajectory(plan, recorded, spec.trajectory)
    # plan every sample's trajectory first: bad start/goal/waypoints fail before writing
    plans: list[tuple[int, Trajectory, np.random.Generator]] = []
    for k in range(spec.samples):
        seed = spec.seed + k
        traj_rng, model_rng = sample_rngs(seed)
        if recorded is not None:
            traj = recorded
        else:
            try:
                traj, _ = make_trajectory(
                    plan, params, traj_rng, start=start, goal=goal, waypoints=waypoints
                )
            except InputError as exc:  # name the file the bad point is checked against
                raise InputError(spec.waypoints or plan_name, exc.problem) from None
        plans.append((seed, traj, model_rng))
    samples: list[DeformSample] = []
    written: dict[str, Path] = {}
    with atomic_dir(spec.out, protect=inputs) as tmp:
        bar = tqdm(plans, desc=f"deform ({spec.method})", unit="map", disable=not spec.progress)
        for k, (seed, traj, model_rng) in enumerate(bar):
            t0 = time.perf_counter()
            res = run_model(plan, traj, spec.method, params, model_rng)
            sub = "" if spec.samples == 1 else f"sample_{k:03d}"
            run = _run_record(spec, plan_name, seed, k, is_houseexpo(plan))
            paths = write_result(plan, res, tmp / sub, run, figures=spec.figures)
            names = {(f"{sub}/{n}" if sub else n): p
                     for n, p in zip(_NAMES, paths, strict=False)}  # fmt: skip
            stats = res.field.stats(res.observed)
            stats.update(method=spec.method, seconds=time.perf_counter() - t0)
            folder = Path(spec.out) / sub if sub else Path(spec.out)
            files = final_paths(names, tmp, spec.out)
            samples.append(DeformSample(folder, seed, files, res, stats))
            written.update(files)
        bar.close()
    return DeformRun(written, samples)


def run_deform(job: DeformSpec, progress: bool = True) -> list[tuple[Path, dict]]:
    """The old entry point: :func:`deform`, returning (folder, field statistics) per sample."""
    run = deform(dataclasses.replace(job, progress=progress))
    return [(s.folder, s.stats) for s in run.samples]
