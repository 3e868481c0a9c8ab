"""Coverage from the robot's own exploration for synthesized SLAM maps (issue #15: realism
of Model_AB's maps; beyond the thesis, a hybrid like :mod:`map2map.learn.ab.drift`).

Model_AB's network maps every room of a plan; a simulated 7-minute exploration does not
(gen6300's val plans: free mapped 0.95 against 0.82, unknown share 0.12 against 0.21).
What a run leaves unseen depends on where it starts and how its frontier exploration
goes, which the network cannot know. This module lets the simulator's robot explore the
plan itself, with the ``oracle`` mapper (true poses, no particle filter: the exploration
``explore_lite`` would make with a perfect map, about 0.5-3 s of CPU a plan against
10-60 s for the dataset's ``rbpf`` runs), and hands two things to
:func:`map2map.learn.ab.synthesize.synthesize`:

(a) **what was seen** (``coverage="explore"``): every generated pixel farther than
    ``margin_px`` from a cell the exploration's map knows (free or occupied) becomes
    unknown (:func:`hide_unseen`). The band is there because the oracle marks a wall's
    *face* (where the rays ended) while the generated map draws its walls ``wall_px``
    thick behind the face and may place them up to half a network cell off: without it
    the walls of every seen room would be thinned or cut. The default band is the
    rendered wall thickness rounded up (3 px of a 256 px square for the shipped weights),
    fixed before any measurement;
(b) **the route** (``drift_route="explore"``): the exploration's true trajectory (its
    poses at the scan times) drives the parametric drift
    (:func:`map2map.learn.ab.drift.drift_field` ``trajectory=``) instead of the 12-node
    roadmap tour.

The two are separable; both come from one exploration per hypothesis. Hypothesis (or
plan) ``k`` of seed ``s`` explores with the simulation seed drawn from its own generator
:func:`explore_rng` ``(s, k)`` (start pose, sensor noise), a stream apart from the drift's
:func:`~map2map.learn.ab.drift.drift_rng` ``(s, k)``, so (a) alone leaves the drift field
exactly as without it, and the same seed gives the same bytes.

Examples
--------
>>> from map2map.maps.floorplan import generate_floorplan
>>> plan = generate_floorplan(3, size=(10, 8))
>>> ex = explore_plan(plan, explore_rng(0, 0), ExploreParams(duration=20.0))
>>> ex.seen.shape == plan.shape, bool(0.0 < ex.seen.mean() < 1.0), len(ex.trajectory.t) > 10
(True, True, True)
>>> out = hide_unseen(plan.data, ex.seen, 2)
>>> bool((out[~ex.seen] == UNKNOWN).mean() > 0.5), bool((out[ex.seen] == plan.data[ex.seen]).all())
(True, True)
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from scipy import ndimage

from ...core.errors import InputError
from ...core.grid import FREE, OCCUPIED, UNKNOWN, OccupancyMap
from ...trajectory.timing import Trajectory

__all__ = ["COVERAGES", "DRIFT_ROUTES", "ExploreParams", "Exploration", "explore_rng",
           "explore_plan", "hide_unseen", "free_from_rays", "coverage_options"]

#: ``coverage`` choices of :func:`map2map.learn.ab.synthesize.synthesize`: the network's own
#: extent, or only what the hypothesis's exploration saw.
COVERAGES = ("none", "explore", "rays")
#: ``drift_route`` choices: the drift's 12-node roadmap tour, or the exploration's path.
DRIFT_ROUTES = ("tour", "explore")
#: Stream of :func:`explore_rng` (apart from the drift's and the dropout's uses of a seed).
_STREAM = 0xE4B10


@dataclass(frozen=True)
class ExploreParams:
    """How a hypothesis's exploration runs (module doc).

    Parameters
    ----------
    duration : float
        Simulated seconds. 275, not the dataset build's 420 (7 minutes, thesis 4.1): this
        robot plans on a perfect map, the build's on its own rbpf SLAM map, which errs,
        and it maps the same share in less time. 275 s gave the simulated runs' free
        mapped and unknown shares on gen900's val plans explored at their own resolution
        (session 13, docs/synthesize.md; 420 s: ratios 5.02 unknown, 3.55 free mapped).
    fov : float
        LIDAR field of view [deg] (the dataset build's 180).
    mapper : str
        The simulator's mapper (``"oracle"``: true poses; ``"rbpf"`` would add SLAM's
        own errors at 10-20x the cost).
    margin_px : float or None
        Band [px of the output frame] around the exploration's known cells kept as the
        network drew it; ``None``: the rendered wall thickness rounded up.
    reach_px : int
        ``coverage="rays"`` (:func:`free_from_rays`): the network's free pixels kept up to
        this far (chessboard) from a cell the rays crossed.
    hits_px : float or None
        ``coverage="rays"``: a cell where the rays ended (a face the LIDAR hit) is drawn
        occupied when the network draws no wall within this distance [px]; ``None`` (the
        default): never. On 120 dev plans (2026-11-27, docs/synthesize.md) 2 and 4 px
        doubled the walls the network draws off their faces (``bend`` extreme on 90 % and
        78 % of plans, against 66 % without).
    """

    duration: float = 275.0
    fov: float = 180.0
    mapper: str = "oracle"
    margin_px: float | None = None
    reach_px: int = 2
    hits_px: float | None = None

    def __post_init__(self):
        if not (math.isfinite(self.duration) and self.duration > 0):
            raise InputError("duration", f"must be > 0 seconds, got {self.duration}")
        if self.fov not in (180.0, 360.0):
            raise InputError("fov", f"must be 180 or 360, got {self.fov}")
        if self.margin_px is not None and not self.margin_px >= 0:
            raise InputError("margin_px", f"must be >= 0, got {self.margin_px}")

    def margin(self, wall_px: float) -> int:
        """The band in whole pixels for maps whose walls are ``wall_px`` thick.

        Examples
        --------
        >>> ExploreParams().margin(2.06), ExploreParams(margin_px=1).margin(2.06)
        (3, 1)
        """
        if self.margin_px is not None:
            return int(math.ceil(self.margin_px))
        return int(math.ceil(max(1.0, float(wall_px)) - 1e-9))


@dataclass
class Exploration:
    """One exploration of a plan (module doc).

    Attributes
    ----------
    seen : (H, W) bool
        Cells of the plan's grid that the exploration's map knows (free or occupied).
    free : (H, W) bool
        Cells its rays crossed (the map's free cells).
    trajectory : Trajectory
        The robot's true poses at the scan times (plan frame).
    start : (x, y, theta)
    coverage : float
        Share of the reachable free space mapped free (:class:`~map2map.sim.runner.
        SimResult`'s).
    sim_seconds, wall_seconds : float
    stop_reason : str
    seed : int
        The simulation seed drawn from the generator.
    """

    seen: np.ndarray
    free: np.ndarray
    trajectory: Trajectory
    start: tuple
    coverage: float
    sim_seconds: float
    wall_seconds: float
    stop_reason: str
    seed: int

    def stats(self) -> dict:
        """Numbers for a summary (seen share, coverage, seconds, seed)."""
        return {"seen_share": round(float(self.seen.mean()), 4),
                "coverage": round(self.coverage, 4), "sim_seconds": round(self.sim_seconds, 1),
                "stop_reason": self.stop_reason, "seed": self.seed}


def explore_rng(seed: int, k: int) -> np.random.Generator:
    """The exploration generator of hypothesis (or plan) ``k`` under ``seed``.

    Examples
    --------
    >>> from map2map.learn.ab.drift import drift_rng
    >>> int(explore_rng(0, 1).integers(1 << 30)) == int(explore_rng(0, 1).integers(1 << 30))
    True
    >>> int(explore_rng(0, 1).integers(1 << 30)) == int(drift_rng(0, 1).integers(1 << 30))
    False
    """
    return np.random.default_rng(np.random.SeedSequence(int(seed), spawn_key=(_STREAM, int(k))))


def explore_plan(plan: OccupancyMap, rng: np.random.Generator,
                 params: ExploreParams | None = None) -> Exploration:
    """Let the simulator's robot explore ``plan`` (module doc).

    Parameters
    ----------
    plan : OccupancyMap
        The plan at its metric resolution (free cells drivable, occupied walls).
    rng : numpy.random.Generator
        Draws the simulation seed (:func:`explore_rng`).
    params : ExploreParams, optional

    Returns
    -------
    Exploration

    Raises
    ------
    InputError
        A plan without free space or too small for the robot.
    """
    from ...sim.runner import simulate
    from ...trajectory.timing import trajectory_from_poses

    ep = params or ExploreParams()
    seed = int(rng.integers(1 << 32))
    res = simulate(plan, seed=seed, duration=ep.duration, fov=ep.fov, mapper=ep.mapper,
                   progress=False)
    p = res.true_poses
    if len(p) >= 2:
        traj = trajectory_from_poses(p[:, 0], p[:, 1], p[:, 2], t=res.times)
    else:                                 # one scan: a standing robot, one pose twice
        traj = trajectory_from_poses(np.repeat(p[:, 0], 2), np.repeat(p[:, 1], 2),
                                     np.repeat(p[:, 2], 2), t=[0.0, 1.0])
    seen = res.slam_map_plan.data != UNKNOWN
    return Exploration(seen, res.slam_map_plan.data == FREE, traj, res.start,
                       float(res.coverage), float(res.sim_seconds), float(res.wall_seconds),
                       res.stop_reason, seed)


def hide_unseen(m: np.ndarray, seen: np.ndarray, margin_px: int) -> np.ndarray:
    """Map ``m`` with every pixel farther than ``margin_px`` (chessboard distance) from
    a ``seen`` cell set unknown (module doc, (a)); the rest as it was.

    Parameters
    ----------
    m : (H, W) uint8
        Ternary map (plan frame).
    seen : (H, W) bool
        :attr:`Exploration.seen`.
    margin_px : int

    Returns
    -------
    (H, W) uint8

    Examples
    --------
    >>> m = np.full((1, 8), 255, np.uint8); seen = np.zeros((1, 8), bool); seen[0, :2] = True
    >>> hide_unseen(m, seen, 2).tolist()
    [[255, 255, 255, 255, 127, 127, 127, 127]]
    """
    m = np.asarray(m, np.uint8)
    seen = np.asarray(seen, bool)
    if m.shape != seen.shape:
        raise ValueError(f"map {m.shape} and seen cells {seen.shape} differ in shape")
    keep = seen
    if margin_px > 0 and seen.any():
        keep = ndimage.binary_dilation(seen, np.ones((3, 3), bool), iterations=int(margin_px))
    out = m.copy()
    out[~keep] = UNKNOWN
    return out


def free_from_rays(m: np.ndarray, seen: np.ndarray, free: np.ndarray, margin_px: int,
                   reach_px: int = 2, hits_px: float | None = None) -> np.ndarray:
    """Map ``m`` with its free space replaced by what the exploration's rays crossed
    (``coverage="rays"``): free where a ray crossed and ``m`` draws no wall, and where
    ``m`` is free within ``reach_px`` of such a cell; ``m``'s walls where within
    ``margin_px`` of a ``seen`` cell (as :func:`hide_unseen`); the faces the rays hit
    (``seen`` and not ``free``) occupied where ``m`` draws no wall within ``hits_px``;
    unknown elsewhere.

    A SLAM map's free space ends where its rays did: at walls, in ray fans through doors
    and gaps (laser streaks) and in arcs at the LIDAR's range. The network's own free
    space ends in blurred blobs (issue #33: rougher open frontiers than a SLAM run's on
    84 % of plans); here it only closes the gap between a face and a wall the network
    drew a little behind it.

    Parameters
    ----------
    m : (H, W) uint8
        Ternary map (plan frame).
    seen, free : (H, W) bool
        :attr:`Exploration.seen` and :attr:`Exploration.free`.
    margin_px, reach_px : int
    hits_px : float or None

    Returns
    -------
    (H, W) uint8

    Examples
    --------
    A room the network drew with a rounded corner; the rays crossed all of it and hit its
    walls:

    >>> m = np.full((7, 7), 127, np.uint8); m[1:6, 1:6] = 255; m[1, 1] = 127; m[:, 6] = 0
    >>> free = np.zeros((7, 7), bool); free[1:6, 1:6] = True
    >>> seen = free.copy(); seen[0, :] = seen[:, 0] = seen[6, :] = seen[:, 6] = True
    >>> out = free_from_rays(m, seen, free, 1, hits_px=2.0)
    >>> int(out[1, 1]), int(out[0, 3]), int(out[3, 6])
    (255, 0, 0)
    >>> int(free_from_rays(m, seen, free, 1)[0, 3])     # hits not drawn by default
    127
    """
    m = np.asarray(m, np.uint8)
    seen, free = np.asarray(seen, bool), np.asarray(free, bool)
    if not m.shape == seen.shape == free.shape:
        raise ValueError(f"map {m.shape}, seen {seen.shape} and free {free.shape} differ "
                         "in shape")
    square = np.ones((3, 3), bool)
    occ = m == OCCUPIED
    near = seen
    if margin_px > 0 and seen.any():
        near = ndimage.binary_dilation(seen, square, iterations=int(margin_px))
    out = np.full(m.shape, UNKNOWN, np.uint8)
    out[occ & near] = OCCUPIED
    f = free.copy()
    if reach_px > 0 and free.any():
        f |= (m == FREE) & ndimage.binary_dilation(free, square, iterations=int(reach_px))
    out[f & ~occ] = FREE
    if hits_px is not None:
        hit = seen & ~free
        if occ.any():
            hit &= ndimage.distance_transform_edt(~occ) > hits_px
        out[hit] = OCCUPIED
    return out


def coverage_options(coverage: str, drift_route: str) -> tuple[bool, bool]:
    """Check ``coverage`` and ``drift_route``; ``(hide unseen, drift along the
    exploration)``.

    Examples
    --------
    >>> coverage_options("explore", "tour"), coverage_options("none", "explore")
    ((True, False), (False, True))
    >>> try:
    ...     coverage_options("all", "tour")
    ... except InputError as exc:
    ...     print(exc)
    coverage: must be one of none, explore, rays, got 'all'
    """
    if coverage not in COVERAGES:
        raise InputError("coverage", f"must be one of {', '.join(COVERAGES)}, got {coverage!r}")
    if drift_route not in DRIFT_ROUTES:
        raise InputError("drift_route",
                         f"must be one of {', '.join(DRIFT_ROUTES)}, got {drift_route!r}")
    return coverage in ("explore", "rays"), drift_route == "explore"
