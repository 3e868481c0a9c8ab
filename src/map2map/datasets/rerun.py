"""A second simulated run of a dataset pair: the same plan, another simulation seed, the
pair's start pose or one of its own (issue #15's realism reference: two independent
simulated SLAM maps of one plan).

:func:`rerun_pair` rebuilds pair ``index`` of a ``map2map dataset build`` dataset exactly
as the build made it (:func:`~map2map.datasets.pair.make_pair`'s plan, simulator, SLAM
backend and build parameters, read from the dataset's manifest and the pair's
``meta.json``), except for the simulation seed (:func:`~map2map.datasets.pair.rerun_seed`
of the pair's ``sim_seed``): new sensor and odometry noise, new SLAM particles, a new
exploration. The start pose is the pair's (``start="pair"``: ``meta.json``'s
``start_pose``, rounded to 1e-6) or drawn from the new seed as the build drew the pair's
(``start="own"``, :func:`~map2map.sim.runner.choose_start`: then the re-run and the pair
are exchangeable, two runs of one plan that each start where their seed put the robot).
With the pair's own ``sim_seed`` the start is drawn from it as the build did, and the
re-run gives the pair's map pixel for pixel. The new SLAM map is cut with the
pair's own crop window (the union of the plan's and the pair's ``B``'s content) and
preprocessed as the pair's ``B`` (thesis 4.1), so it lies on the same pixels as the
dataset's ``A.png``/``B.png``.

:func:`parametric_on_trajectory` drives the parametric model (thesis 3.2) along a
simulation's true trajectory and cuts its map the same way: the parametric map of the
same plan *and the same path* (Fig. 5.14).

Examples
--------
>>> import tempfile
>>> try:
...     rerun_pair(tempfile.mkdtemp(), 0)
... except InputError as exc:
...     print(str(exc).split(": ", 1)[1])
not a map2map dataset (no manifest.sqlite)
"""

from __future__ import annotations

import os
from dataclasses import dataclass

import numpy as np

from ..core.errors import InputError
from .pair import (
    BuildParams,
    PairSpec,
    _simulate,
    crop_box,
    pair_seed,
    preprocess_pair,
    read_pair_meta,
    rerun_seed,
    wall_error,
)
from .plans import PlanSource, load_plan

__all__ = ["STARTS", "RerunResult", "rerun_pair", "parametric_on_trajectory", "parametric_on_run"]


@dataclass
class RerunResult:
    """Run ``run`` of pair ``index``: the preprocessed plan ``a_n`` (identical to the
    pair's ``A.png`` when the plan was rebuilt faithfully, ``a_matches``), the new SLAM
    map ``b_n`` on the same pixels, the run's metadata, the full-resolution ``plan``, the
    crop ``box`` (before the margin) and the simulator's
    :class:`~map2map.sim.runner.SimResult` ``sim`` (true poses, scan times: the run's
    trajectory)."""

    index: int
    run: int
    a_n: np.ndarray
    b_n: np.ndarray
    a_matches: bool
    meta: dict
    plan: object = None
    box: tuple | None = None
    sim: object = None


#: Where a re-run starts: the pair's start pose, or one drawn from the re-run's own seed.
STARTS = ("pair", "own")


def rerun_pair(ds: str | os.PathLike, index: int, run: int = 2, *,
               sim_seed: int | None = None, start: str = "pair") -> RerunResult:
    """Simulate pair ``index`` of dataset ``ds`` again with seed ``rerun_seed(sim_seed, run)``.

    Parameters
    ----------
    ds : path
        A ``map2map dataset build`` folder (read only).
    index : int
        Pair index (a simulated pair).
    run : int
        Run number (>= 2; run 1 is the dataset's own map).
    sim_seed : int, optional
        Use this simulation seed instead (the pair's own ``sim_seed`` rebuilds run 1,
        with its trajectory).
    start : {"pair", "own"}
        ``"pair"``: start at the pair's start pose (``meta.json``); ``"own"``: at a start
        drawn from the run's seed, as the build drew the pair's.

    Returns
    -------
    RerunResult

    Raises
    ------
    InputError
        Not a dataset, the pair is missing, parametric, or has no ``sim_seed``.
    """
    from ..maps.formats import load_map
    from .build import open_dataset
    from .pairfolder import PLAN_PNG, SLAM_YAML, pair_dir, read_picture

    if start not in STARTS:
        raise InputError("start", f"must be one of {', '.join(STARTS)}, got {start!r}")
    if run < 2 and sim_seed is None:
        raise InputError("run", f"must be >= 2 (run 1 is the dataset's map), got {run}")
    with open_dataset(ds) as man:
        ident = man.get_info("identity")
    folder = pair_dir(ds, index)
    meta = read_pair_meta(folder)
    if meta.get("kind") != "simulate" or "sim_seed" not in meta:
        raise InputError(folder, "not a simulated pair (no sim_seed): nothing to re-run")
    params = BuildParams(**ident["params"])
    src = PlanSource.from_arg(ident["plans"], ident["resolution"], ident.get("plan_resolution"))
    plan_id, plan = load_plan(src, int(ident["seed"]), int(meta["plan_index"]))
    if plan_id != meta["plan_id"]:
        raise InputError(folder, f"the dataset's plan {plan_id} is not the pair's "
                                 f"{meta['plan_id']} (plan folder changed?)")
    spec = PairSpec(int(index), int(ident["seed"]), src, params)
    seed = rerun_seed(int(meta["sim_seed"]), run) if sim_seed is None else int(sim_seed)
    keep: list = []
    # the pair's own seed draws the pair's start exactly; meta.json's start_pose is
    # rounded to 1e-6, and an exploration started 1e-7 rad off goes another way
    at = (None if start == "own" or seed == int(meta["sim_seed"])
          else tuple(meta["start_pose"]))
    b2, _, info = _simulate(spec, plan, pair_seed(spec.seed, spec.index), sim_seed=seed,
                            start=at, keep=keep)
    b1 = load_map(folder / SLAM_YAML)
    box = crop_box(plan, b1)
    a_n, b_n = preprocess_pair(plan, b2, params.size, params.thicken, box=box)
    a_file = read_picture(folder / PLAN_PNG)
    err, err95 = wall_error(plan, b2)
    info.update(run=int(run), index=int(index), plan_id=plan_id, start_from=start,
                wall_error_m=err, wall_error_p95_m=err95, size=params.size, thicken=params.thicken,
                fov=params.fov)
    return RerunResult(int(index), int(run), a_n, b_n, bool(np.array_equal(a_n, a_file)),
                       info, plan, box, keep[0])


def parametric_on_trajectory(plan, sim, box, size: int, thicken: int, fov: float,
                             rng: np.random.Generator, method: str = "additive"
                             ) -> np.ndarray:
    """The parametric model (thesis 3.2, :func:`map2map.parametric.pipeline.deform`)
    driven along simulation ``sim``'s true trajectory (its poses at the scan times) through
    ``plan``, cut with the pair window ``box`` and preprocessed as a pair's ``B``:
    ``(size, size)`` uint8 on the pair's pixels. The model draws its own odometry and
    LIDAR errors (``rng``); only the path is shared with the simulation."""
    from ..parametric.params import ParametricParams
    from ..parametric.pipeline import deform
    from ..trajectory.timing import trajectory_from_poses

    p = sim.true_poses
    traj = trajectory_from_poses(p[:, 0], p[:, 1], p[:, 2], t=sim.times)
    res = deform(plan, traj, method, ParametricParams(fov_deg=float(fov)), rng)
    return preprocess_pair(plan, res.map, int(size), int(thicken), box=box)[1]


def parametric_on_run(rr, method: str = "additive", seed: int = 0) -> np.ndarray:
    """:func:`parametric_on_trajectory` along re-run ``rr``'s trajectory
    (:class:`~map2map.datasets.rerun.RerunResult`), seeded by ``(seed, index, run)``."""
    return parametric_on_trajectory(
        rr.plan, rr.sim, rr.box, rr.meta["size"], rr.meta["thicken"], rr.meta["fov"],
        np.random.default_rng([int(seed), int(rr.index), int(rr.run)]), method)
