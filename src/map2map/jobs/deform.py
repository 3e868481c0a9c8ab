"""Running the parametric model on files: what ``map2map deform`` does, as a library call.

Everything is validated (plan, parameters, trajectory source, every sample's trajectory)
before the first file is written; each file is written atomically.

Seeds: sample ``k`` of a run with ``--seed N`` uses seed ``N + k``, split into two
independent streams (:class:`numpy.random.SeedSequence`): one plans the trajectory, the
other draws the model. So ``map2map deform PLAN --seed S --params params.yaml
--trajectory trajectory.csv`` with a sample's own files and seed repeats it byte for
byte (the recipe is written into its ``params.yaml``).
"""

from __future__ import annotations

import dataclasses
import time
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
from tqdm.auto import tqdm

from .._version import __version__
from ..core._io import ensure_output_dir
from ..core.errors import InputError, warnings_unless_error
from ..core.grid import FREE, OccupancyMap
from ..parametric.figures import deform_figure
from ..parametric.params import ParametricParams, load_params, save_params
from ..parametric.pipeline import DeformResult, deform, make_trajectory
from ..trajectory.timing import Trajectory, read_trajectory, read_waypoints

__all__ = ["DeformJob", "load_plan", "sample_rngs", "write_result", "run_deform"]


@dataclass
class DeformJob:
    """Arguments of ``map2map deform``."""

    plan: Path
    out: Path
    method: str = "additive"
    seed: int = 0
    samples: int = 1
    start: tuple[float, float] | None = None
    goal: tuple[float, float] | None = None
    waypoints: Path | None = None
    trajectory: Path | None = None
    fov: int | None = None
    params: Path | None = None
    resolution: float | None = None
    read_options: object | None = None  # maps.formats.MapReadOptions


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


def write_result(
    plan: OccupancyMap,
    res: DeformResult,
    folder: Path,
    run: dict[str, Any],
) -> list[Path]:
    """Write one sample's files into ``folder``; returns their paths."""
    from ..maps.ros import save_ros_map

    folder = ensure_output_dir(folder)
    paths = [folder / n for n in ("slam_map.yaml", "displacement.npz", "trajectory.csv",
                                  "params.yaml", "figure.png")]  # fmt: skip
    pgm = save_ros_map(res.map, paths[0])
    res.field.save_npz(paths[1])
    res.trajectory.to_csv(paths[2])
    save_params(res.params, paths[3], run=run, drawn=res.drawn)
    deform_figure(
        plan, res, paths[4], title=f"Modelled SLAM map ({res.method}, seed {run['seed']})"
    )
    return [paths[0], Path(pgm), *paths[1:]]


def run_deform(job: DeformJob, progress: bool = True) -> list[tuple[Path, dict]]:
    """Run ``map2map deform``; returns (folder, field statistics) per sample."""
    if job.samples < 1:
        raise InputError("samples", f"must be at least 1, got {job.samples}")
    params = load_params(job.params) if job.params else ParametricParams()
    if job.fov is not None:
        params = dataclasses.replace(params, fov_deg=float(job.fov))
    with warnings_unless_error():  # a refused plan: the error alone
        plan = load_plan(job.plan, job.resolution, job.read_options)
        if not plan.free.any():
            raise InputError(job.plan, "the plan has no free space")
    waypoints = read_waypoints(job.waypoints) if job.waypoints else None
    recorded = None
    if job.trajectory:
        recorded = read_trajectory(job.trajectory, v_max=params.v_max, omega_max=params.omega_max)
        _check_trajectory(plan, recorded, job.trajectory)
    # plan every sample's trajectory first: bad start/goal/waypoints fail before writing
    plans: list[tuple[int, Trajectory, np.random.Generator]] = []
    for k in range(job.samples):
        seed = job.seed + k
        traj_rng, model_rng = sample_rngs(seed)
        if recorded is not None:
            traj = recorded
        else:
            try:
                traj, _ = make_trajectory(
                    plan, params, traj_rng, start=job.start, goal=job.goal, waypoints=waypoints
                )
            except InputError as exc:  # name the file the bad point is checked against
                raise InputError(job.waypoints or job.plan, exc.problem) from None
        plans.append((seed, traj, model_rng))
    ensure_output_dir(job.out)
    out: list[tuple[Path, dict]] = []
    bar = tqdm(plans, desc=f"deform ({job.method})", unit="map", disable=not progress)
    for k, (seed, traj, model_rng) in enumerate(bar):
        t0 = time.perf_counter()
        res = deform(plan, traj, job.method, params, model_rng)
        folder = job.out if job.samples == 1 else job.out / f"sample_{k:03d}"
        if job.trajectory:
            source = str(job.trajectory)
        elif job.waypoints:
            source = str(job.waypoints)
        elif job.start:
            source = f"start {list(job.start)} goal {list(job.goal)}"
        else:
            source = "random start and goal"
        run = {
            "map2map_version": __version__,
            "plan": str(job.plan),
            "method": job.method,
            "seed": seed,
            "sample": k,
            "trajectory_source": source,
            "repeat": (
                f"map2map deform {job.plan} --out OUT --method {job.method} --seed {seed} "
                f"--params params.yaml --trajectory trajectory.csv"
            ),
        }
        if job.resolution:
            run["resolution"] = job.resolution
            run["repeat"] += f" --resolution {job.resolution!r}"
        if job.read_options is not None and job.read_options.to_args():
            run["repeat"] += " " + " ".join(job.read_options.to_args())
        write_result(plan, res, folder, run)
        stats = res.field.stats(res.observed)
        stats.update(method=job.method, seconds=time.perf_counter() - t0)
        out.append((folder, stats))
    bar.close()
    return out
