"""SLAM-map hypotheses of a plan mapped from the robot's own scans at drifted poses
(issue #33: ``synthesize --model scans``, a generator with no network).

Model_AB's network draws a 64 px map; upsampled, its walls come out wobbly, its corners
round and its free space in blobs, and a small CNN tells its maps from simulated ones
(docs/synthesize.md). What a SLAM run's map looks like is set by how it was made: a LIDAR's
beams, cropped at the usable range, counted into a grid at poses that err. This module
makes a hypothesis the same way, without a particle filter:

1. **exploration** (:func:`map2map.sim.runner.simulate`, ``oracle`` mapper): the simulator's
   robot explores the plan (frontier exploration on a perfect map, ``duration`` simulated
   seconds, 180 degree LIDAR with its range noise), recording its true poses and scans;
2. **pose error** (:func:`drifted_poses`): every scan's pose is moved by the room-wise
   rigid drift of :mod:`map2map.learn.ab.room_drift` (the transform of the room the robot
   is in: rooms reached late are off the most, and a wall seen from two rooms can be saved
   twice), a rotation of the whole run about its start (``global_deg``), an independent
   jitter per scan (the scan matcher's error: walls a few cm thick and ragged) and, with
   probability ``outlier_share`` per scan, a heading error of ``outlier_deg`` (a scan
   matched wrong: laser streaks through walls);
3. **mapping** (:func:`map_scans`): the scans at those poses counted into GMapping's grid
   exactly as the datasets' ``rbpf`` mapper does (:class:`map2map.slam.gridmap.CountGrid`:
   beams cropped at ``maxUrange``, no-return beams clearing, occupied where hits / visits >
   ``occ_thresh``; one scan every ``temporal_update`` seconds), in the run's own frame,
   then put on the plan's grid at the true start pose, as a run's map is.

A hypothesis costs the exploration (0.1-5 s of CPU a plan) plus the mapping; K hypotheses
differ in start, route, drift and jitter. The settings (:class:`ScanMapParams`) were chosen
on 160 plans of a dev set by the per-plan ranks and the classifier test
(``python -m map2map.experiments.realism.per_plan``; docs/synthesize.md).

Examples
--------
>>> from map2map.maps.floorplan import generate_floorplan
>>> plan = generate_floorplan(3, size=(10, 8))
>>> h = scan_map(plan, 0, 0, ScanMapParams(duration=30.0))
>>> h.map.shape == plan.shape, bool(h.map.free.sum() > 1000), bool(h.map.occupied.sum() > 100)
(True, True, True)
>>> bool((scan_map(plan, 0, 0, ScanMapParams(duration=30.0)).map.data == h.map.data).all())
True
"""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass, field

import numpy as np

from ...core.errors import InputError
from ...core.geometry import compose_pose, relative_pose
from ...core.grid import OccupancyMap
from .room_drift import RoomDrift, RoomDriftParams, room_drift_field

__all__ = ["ScanMapParams", "ScanHypothesis", "scan_rng", "drifted_poses", "map_scans",
           "CountOracle", "walk_transforms", "scan_map"]

#: Stream of :func:`scan_rng` (apart from the exploration's, the drift's and the traces').
_STREAM = 0x5CA75


def _rooms_default() -> RoomDriftParams:
    return RoomDriftParams(rot_deg=1.0, parametric=False)


@dataclass(frozen=True)
class ScanMapParams:
    """How a hypothesis is explored, drifted and mapped (module doc).

    Parameters
    ----------
    duration : float
        Simulated seconds of exploration (the datasets' runs: 420 with ``rbpf``; this
        robot plans on a perfect map).
    fov : float
        LIDAR field of view [deg] (the datasets': 180).
    jitter_m, jitter_deg : float
        Standard deviation of each scan's independent position (per axis) and heading
        error.
    global_deg : float
        Standard deviation of the rotation of the whole run about its start pose.
    outlier_share, outlier_deg : float
        Share of scans given an extra heading error, and its standard deviation.
    rooms : RoomDriftParams
        The room-wise rigid drift (its ``parametric`` field is not used here; 1 degree a
        step, 0.02 of the step's length).
    error : {"rooms", "walk"}
        The slow pose error: the room-wise rigid drift (``rooms``, ``room_order``), or a
        random walk along the route that grows only where the robot had not been
        (:func:`walk_transforms`: ``walk_deg`` and ``walk_m`` per square-root metre of new
        ground, a per-map amplitude of log-normal spread ``walk_spread``; within
        ``lock_m`` of where it was more than ``lock_s`` seconds before, the error is the one
        it had there, as a scan matcher keeps a mapped place where it was mapped).
    walk_deg, walk_m, walk_spread, lock_m, lock_s : float
        The walk's settings (``error="walk"``).
    match_m, match_deg : float
        Each scan is matched to the map counted so far, kept near its erring pose by a
        prior of these standard deviations (:func:`map_scans` ``match``); 0: not matched.
    room_order : {"random", "visits"}
        How the room drift chains the rooms: a random walk from a random room
        (``"random"``), or along the robot's route (``"visits"``: the start room is not
        moved, each room steps from the one the robot came from when it first entered it).
    explore_map : {"oracle", "gmapping"}
        The map the robot explores on: the simulator's oracle (log-odds, the LIDAR's whole
        range) or GMapping's count grid at the true poses (beams cropped at ``maxUrange``,
        one scan every ``temporalUpdate``), which is what a run's robot sees of the plan:
        it goes on until the cropped map has no frontier left.

    The defaults were chosen on 160 plans of the seed-20261127 dev set among eight
    settings by the per-plan ranks and the classifier AUC (docs/synthesize.md).
    """

    duration: float = 400.0
    fov: float = 180.0
    jitter_m: float = 0.0175
    jitter_deg: float = 0.45
    global_deg: float = 2.5
    outlier_share: float = 0.02
    outlier_deg: float = 3.0
    rooms: RoomDriftParams = field(default_factory=_rooms_default)
    error: str = "rooms"
    walk_deg: float = 0.5
    walk_m: float = 0.04
    walk_spread: float = 0.8
    lock_m: float = 1.0
    lock_s: float = 10.0
    match_m: float = 0.0
    match_deg: float = 0.0
    room_order: str = "random"
    explore_map: str = "oracle"

    def __post_init__(self):
        for name in ("duration", "fov", "jitter_m", "jitter_deg", "global_deg",
                     "outlier_deg"):
            v = getattr(self, name)
            if not (math.isfinite(v) and v >= 0):
                raise InputError(name, f"must be finite and >= 0, got {v!r}")
        if not 0.0 <= self.outlier_share <= 1.0:
            raise InputError("outlier_share", f"must be in [0, 1], got {self.outlier_share!r}")
        if self.duration <= 0:
            raise InputError("duration", f"must be > 0, got {self.duration!r}")
        for name, allowed in (("error", ("rooms", "walk")), ("room_order", ("random", "visits")),
                              ("explore_map", ("oracle", "gmapping"))):
            if getattr(self, name) not in allowed:
                raise InputError(name, f"must be one of {', '.join(allowed)}, "
                                 f"got {getattr(self, name)!r}")
        for name in ("walk_deg", "walk_m", "walk_spread", "lock_m", "lock_s", "match_m",
                     "match_deg"):
            v = getattr(self, name)
            if not (math.isfinite(v) and v >= 0):
                raise InputError(name, f"must be finite and >= 0, got {v!r}")

    def to_dict(self) -> dict:
        """The settings as plain JSON values."""
        return asdict(self)


@dataclass
class ScanHypothesis:
    """One hypothesis of :func:`scan_map`.

    Attributes
    ----------
    map : OccupancyMap
        In the plan's grid (shape, resolution, origin).
    poses : (N, 3) float
        The drifted poses of the scans mapped (plan frame).
    true_poses : (N, 3) float
        Their true poses.
    drift : RoomDrift
    info : dict
        Exploration and drift figures for a summary.
    """

    map: OccupancyMap
    poses: np.ndarray
    true_poses: np.ndarray
    drift: RoomDrift
    info: dict


def scan_rng(seed: int, k: int) -> np.random.Generator:
    """The generator of hypothesis ``k``'s pose error under ``seed`` (its own stream).

    Examples
    --------
    >>> float(scan_rng(0, 1).random()) == float(scan_rng(0, 1).random())
    True
    >>> float(scan_rng(0, 1).random()) == float(scan_rng(0, 2).random())
    False
    """
    return np.random.default_rng(np.random.SeedSequence(int(seed), spawn_key=(_STREAM, int(k))))


def walk_transforms(poses: np.ndarray, times: np.ndarray, rng: np.random.Generator,
                    params: ScanMapParams) -> np.ndarray:
    """World transforms ``(phi, tx, ty)`` per scan of the walk pose error
    (``ScanMapParams.error="walk"``): an estimated position is ``R(phi) p + t``.

    The first scan's is the identity. Going on, the error takes a random step about the
    robot's position per scan, of standard deviation ``walk_deg`` and ``walk_m`` (per axis)
    times ``sqrt(ds)`` (``ds``: metres driven plus 0.1 m per radian turned) times the
    map's amplitude; but within ``lock_m`` of a position it held more than ``lock_s``
    seconds before, the error is the one it had at the first such time (the place is
    mapped: a scan matcher keeps it there) and no step is taken.

    Examples
    --------
    >>> p = np.column_stack([np.linspace(0, 10, 101), np.zeros(101), np.zeros(101)])
    >>> sp = ScanMapParams(error="walk")
    >>> E = walk_transforms(p, np.arange(101.0), np.random.default_rng(0), sp)
    >>> E.shape, bool(np.allclose(E[0], 0)), bool(np.abs(E[-1]).max() > 0)
    ((101, 3), True, True)
    >>> back = np.vstack([p, p[::-1]])                   # there and back: locked on return
    >>> E2 = walk_transforms(back, np.arange(202.0), np.random.default_rng(0), sp)
    >>> bool(np.allclose(E2[-1], E2[0]))
    True
    """
    from scipy.spatial import cKDTree

    P = np.asarray(poses, float).reshape(-1, 3)
    t = np.asarray(times, float)
    n = len(P)
    E = np.zeros((n, 3))
    if n == 0:
        return E
    amp = math.exp(params.walk_spread * float(rng.standard_normal()))
    z = rng.standard_normal((n, 3))
    ds = np.r_[0.0, np.hypot(*np.diff(P[:, :2], axis=0).T)
               + 0.1 * np.abs(np.angle(np.exp(1j * np.diff(P[:, 2]))))]
    sd = np.sqrt(ds) * amp
    dphi = math.radians(params.walk_deg) * sd * z[:, 0]
    dt = params.walk_m * sd[:, None] * z[:, 1:]
    near = cKDTree(P[:, :2]).query_ball_point(P[:, :2], params.lock_m)
    for i in range(1, n):
        old = [j for j in near[i] if t[j] < t[i] - params.lock_s]
        if old:
            E[i] = E[min(old)]
            continue
        phi, tx, ty = E[i - 1]
        cx = math.cos(phi) * P[i, 0] - math.sin(phi) * P[i, 1] + tx
        cy = math.sin(phi) * P[i, 0] + math.cos(phi) * P[i, 1] + ty
        c, s_ = math.cos(dphi[i]), math.sin(dphi[i])
        E[i] = (phi + dphi[i],
                c * (tx - cx) - s_ * (ty - cy) + cx + dt[i, 0],
                s_ * (tx - cx) + c * (ty - cy) + cy + dt[i, 1])
    return E


def drifted_poses(plan: OccupancyMap, poses: np.ndarray, start, drift: RoomDrift,
                  rng: np.random.Generator, params: ScanMapParams,
                  walk: np.ndarray | None = None) -> np.ndarray:
    """Poses ``(N, 3)`` (plan frame, metres and radians) moved by the pose error of the
    module doc, step 2: each by the rigid transform of the room it lies in (or, given
    ``walk``, by its own world transform ``(phi, tx, ty)`` of :func:`walk_transforms`), then
    the whole run turned about ``start``, then per-scan jitter and outliers (drawn from
    ``rng`` in that order).

    The room transforms act on pixel coordinates ``(column, row)``, rows pointing down,
    so a room turned by ``phi`` there turns the poses in it by ``-phi`` in the world.

    Examples
    --------
    >>> from map2map.maps.floorplan import generate_floorplan
    >>> plan = generate_floorplan(3, size=(10, 8))
    >>> d = room_drift_field(plan.data, np.random.default_rng(0), RoomDriftParams(scale=0))
    >>> p = np.array([[3.0, 2.0, 0.5], [6.0, 4.0, -1.0]])
    >>> still = ScanMapParams(jitter_m=0, jitter_deg=0, global_deg=0, outlier_share=0)
    >>> bool(np.allclose(drifted_poses(plan, p, p[0], d, np.random.default_rng(0), still), p))
    True
    """
    P = np.asarray(poses, float).reshape(-1, 3)
    out = P.copy()
    H, W = plan.shape
    rows, cols = plan.world_to_pixel_float(P[:, 0], P[:, 1])
    T = drift.transforms
    if walk is not None:
        phi = walk[:, 0]
        out[:, 0] = np.cos(phi) * P[:, 0] - np.sin(phi) * P[:, 1] + walk[:, 1]
        out[:, 1] = np.sin(phi) * P[:, 0] + np.cos(phi) * P[:, 1] + walk[:, 2]
        out[:, 2] = P[:, 2] + phi
    elif len(T):
        lab = drift.rooms[np.clip(np.rint(rows).astype(int), 0, H - 1),
                          np.clip(np.rint(cols).astype(int), 0, W - 1)]
        A = np.where((lab >= 1)[:, None, None], T[np.maximum(lab, 1) - 1],
                     np.array([[1.0, 0.0, 0.0], [0.0, 1.0, 0.0]]))
        qc = A[:, 0, 0] * cols + A[:, 0, 1] * rows + A[:, 0, 2]
        qr = A[:, 1, 0] * cols + A[:, 1, 1] * rows + A[:, 1, 2]
        out[:, 0], out[:, 1] = plan.pixel_to_world(qr, qc)
        out[:, 2] = P[:, 2] - np.arctan2(A[:, 1, 0], A[:, 0, 0])
    n = len(P)
    g = math.radians(params.global_deg) * float(rng.standard_normal())
    sx, sy = float(start[0]), float(start[1])
    c, s = math.cos(g), math.sin(g)
    dx, dy = out[:, 0] - sx, out[:, 1] - sy
    out[:, 0], out[:, 1] = sx + c * dx - s * dy, sy + s * dx + c * dy
    out[:, 2] += g
    z = rng.standard_normal((n, 3))
    out[:, :2] += params.jitter_m * z[:, :2]
    out[:, 2] += math.radians(params.jitter_deg) * z[:, 2]
    hit = rng.random(n) < params.outlier_share
    out[:, 2] += np.where(hit, math.radians(params.outlier_deg) * rng.standard_normal(n), 0.0)
    return out


def map_scans(scans, times, poses, start, plan: OccupancyMap, match=None,
              rng: np.random.Generator | None = None) -> OccupancyMap:
    """Count ``scans`` taken at ``poses`` (plan frame) into GMapping's grid as the datasets'
    ``rbpf`` mapper does (module doc, step 3; :class:`~map2map.slam.rbpf.GMappingParams`
    defaults: ``max_urange``, ``occ_thresh``, ``temporal_update``, ``no_return_free``),
    in the run's frame (``start`` at the origin), and put the map on ``plan``'s grid.

    ``match`` ``(metres, degrees)``: before it is counted, each scan after the first is
    matched to the grid counted so far as GMapping's filter matches a particle's scan
    (:func:`~map2map.slam.gridmap.hill_climb` from the given pose, kept near it by a
    Gaussian prior of those standard deviations, times ``motion_prior``), and its pose is
    drawn (``rng``) from the Gaussian fitted around the match
    (:func:`~map2map.slam.gridmap.sample_likelihood`): a scan matcher takes out a small
    error against what is mapped, not a large one.

    Examples
    --------
    >>> from map2map.robotlog.base import LaserScan
    >>> plan = OccupancyMap(np.full((80, 80), 255, np.uint8), 0.05)
    >>> scan = LaserScan(0.0, np.full(180, 1.0, np.float32), -math.pi / 2, math.pi / 179, 0.12, 3.5)
    >>> m = map_scans([scan], [0.0], [(2.0, 2.0, 0.0)], (2.0, 2.0, 0.0), plan)
    >>> m.shape, bool(m.free[40, 45]), bool(m.occupied[40, 59]), int(m.data[40, 61])
    ((80, 80), True, True, 127)
    """
    from ...sim.mapping import resample_to_frame
    from ...slam.gridmap import CountGrid, hill_climb, sample_likelihood
    from ...slam.rbpf import GMappingParams, _matching_beams, prepare_scan

    gp = GMappingParams()
    grid = CountGrid.around(0.0, 0.0, gp.initial_size / 2, plan.resolution)
    sig, lsig = 2 * gp.sigma**2, 2 * gp.lsigma**2
    if match is not None:
        w_xy = gp.motion_prior / max(float(match[0]), 1e-4) ** 2
        w_t = gp.motion_prior / max(math.radians(float(match[1])), 1e-5) ** 2
        rng = rng if rng is not None else np.random.default_rng(0)
    last = -math.inf
    counted = 0
    for scan, t, pose in zip(scans, times, poses, strict=True):
        if float(t) - last < gp.temporal_update:
            continue
        last = float(t)
        r, a = prepare_scan(scan)
        robot = np.asarray(relative_pose(start, pose), float)
        off = np.asarray(scan.sensor_offset, float)
        if match is not None and counted:
            mr, ma = _matching_beams(r, a, gp.max_urange, gp.lskip)
            if mr.size:
                prior = np.array([*robot, w_xy, w_xy, w_t])
                mx, my, mt, score = hill_climb(*grid.match_arrays(), *robot, off, mr, ma,
                                               gp.kernel_size, sig, gp.lstep, gp.astep,
                                               gp.iterations, prior)
                if score > gp.minimum_score:
                    _, mean, cov = sample_likelihood(
                        *grid.match_arrays(), mx, my, mt, off, mr, ma, gp.kernel_size, sig,
                        lsig, gp.llsamplerange, gp.llsamplestep, gp.lasamplerange,
                        gp.lasamplestep)
                    chol = np.linalg.cholesky(cov + np.diag([1e-10, 1e-10, 1e-12]))
                    robot = mean + chol @ rng.standard_normal(3)
        grid.register_scan(compose_pose(robot, off), r, a, gp.max_urange,
                           float(scan.range_max), gp.no_return_free)
        counted += 1
    return resample_to_frame(grid.to_occupancy_map(gp.occ_thresh), start, plan)


class CountOracle:
    """A :class:`~map2map.robotlog.base.Mapper` that counts scans into GMapping's grid at
    the true poses (:func:`map_scans`'s rules): what a SLAM run's robot sees of the plan
    when its poses are right, for the exploration (``ScanMapParams.explore_map``).

    Examples
    --------
    >>> from map2map.maps.floorplan import generate_floorplan
    >>> from map2map.sim.runner import simulate
    >>> plan = generate_floorplan(3, size=(10, 8))
    >>> r = simulate(plan, seed=1, duration=20.0, mapper=CountOracle(plan.resolution),
    ...              progress=False)
    >>> r.info["mapper"], bool(r.slam_map_plan.free.sum() > 100)
    ('gmapping-oracle', True)
    """

    name = "gmapping-oracle"

    def __init__(self, resolution: float = 0.05):
        from ...slam.gridmap import CountGrid
        from ...slam.rbpf import GMappingParams

        self.params = GMappingParams()
        self.grid = CountGrid.around(0.0, 0.0, self.params.initial_size / 2, float(resolution))
        self._truth = self._start = None
        self._pose = np.zeros(3)
        self._last = -math.inf
        self._map = None

    def observe_truth(self, pose) -> None:
        """The true pose (any fixed world frame) at the next scan."""
        self._truth = tuple(float(v) for v in pose)

    def update(self, odom, scan) -> None:
        """Count ``scan`` at the true pose given to :meth:`observe_truth` (every
        ``temporal_update`` seconds, as :func:`map_scans`)."""
        from ...slam.rbpf import prepare_scan

        if self._truth is None:
            raise RuntimeError("CountOracle needs observe_truth(pose) before each update")
        if self._start is None:
            self._start = self._truth
        self._pose = np.asarray(relative_pose(self._start, self._truth), float)
        self._truth = None
        if float(scan.t) - self._last < self.params.temporal_update:
            return
        self._last = float(scan.t)
        r, a = prepare_scan(scan)
        p = self.params
        self.grid.register_scan(compose_pose(self._pose, scan.sensor_offset), r, a,
                                p.max_urange, float(scan.range_max), p.no_return_free)
        self._map = None

    def pose(self) -> np.ndarray:
        """The last true pose relative to the first (the map frame)."""
        return self._pose.copy()

    def get_map(self) -> OccupancyMap:
        """The grid's ternary map (cached until the next scan counted)."""
        if self._map is None:
            self._map = self.grid.to_occupancy_map(self.params.occ_thresh)
        return self._map


def scan_map(plan: OccupancyMap, seed: int, k: int,
             params: ScanMapParams | None = None, start=None) -> ScanHypothesis:
    """Hypothesis ``k`` of ``plan`` under ``seed`` (module doc): explored with the
    simulation seed of :func:`~map2map.learn.ab.coverage.explore_rng` ``(seed, k)``, its
    pose error drawn from :func:`scan_rng` ``(seed, k)``.

    ``start`` (x, y, yaw; metres and radians in the plan's frame, optional) is where the
    robot starts, as ``map2map simulate --start``; by default the simulation seed draws
    it in the free space.

    Raises
    ------
    InputError
        A plan without free space or too small for the robot.
    """
    from ...sim.runner import simulate
    from .coverage import explore_rng

    sp = params or ScanMapParams()
    sim_seed = int(explore_rng(seed, k).integers(1 << 32))
    mapper = CountOracle(plan.resolution) if sp.explore_map == "gmapping" else "oracle"
    res = simulate(plan, seed=sim_seed, duration=sp.duration, fov=sp.fov, mapper=mapper,
                   start=None if start is None else tuple(float(v) for v in start),
                   progress=False)
    rng = scan_rng(seed, k)
    path = plan.world_to_pixel_float(res.true_poses[:, 0], res.true_poses[:, 1]) \
        if sp.room_order == "visits" else None
    drift = room_drift_field(plan.data, rng, sp.rooms, path)
    walk = None
    if sp.error == "walk":
        walk = walk_transforms(res.true_poses, res.times, rng, sp)
    poses = drifted_poses(plan, res.true_poses, res.start, drift, rng, sp, walk)
    match = (sp.match_m, sp.match_deg) if sp.match_m > 0 and sp.match_deg > 0 else None
    m = map_scans(res.scans, res.times, poses, res.start, plan, match, rng)
    err = np.hypot(*(poses[:, :2] - res.true_poses[:, :2]).T)
    info = {"seed": sim_seed, "coverage": round(float(res.coverage), 4),
            "sim_seconds": round(float(res.sim_seconds), 1), "scans": len(res.scans),
            "pose_error_m": {"mean": round(float(err.mean()), 4) if len(err) else 0.0,
                             "max": round(float(err.max()), 4) if len(err) else 0.0},
            "drift": {k2: round(float(v), 3) for k2, v in drift.stats().items()}}
    return ScanHypothesis(m, poses, res.true_poses, drift, info)
