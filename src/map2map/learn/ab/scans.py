"""SLAM-map hypotheses of a plan mapped from the robot's own scans at its particle filter's
or at drifted poses (issue #33: ``synthesize --model scans``, a generator with no network).

Model_AB's network draws a 64 px map; upsampled, its walls come out wobbly, its corners
round and its free space in blobs, and a small CNN tells its maps from simulated ones
(docs/synthesize.md). What a SLAM run's map looks like is set by how it was made: a LIDAR's
beams, cropped at the usable range, counted into a grid at poses that err. This module
makes a hypothesis the same way. By default (``pose_error="filter"``, since session 31)
the scans are mapped at the exploring particle filter's own estimate, so each hypothesis
is the map of a simulated ``rbpf`` run of the plan; with ``pose_error="drawn"`` (the
default until then) its pose error is drawn, not estimated (step 2):

1. **exploration** (:func:`explore`, :func:`map2map.sim.runner.simulate`): the
   simulator's robot explores the plan (frontier exploration, ``duration`` simulated
   seconds, 180 degree LIDAR with its range noise) on the map of the datasets' ``rbpf``
   particle filter, steered by its pose estimate, exactly as a run's robot explores
   (``explore_map="rbpf"``, the default since session 26), recording its true poses, its
   scans, which of them the filter processed and the filter's estimate of their poses
   (its map is not used). ``"grid"`` (:class:`GridOracle`, the default in session 25) explores on
   GMapping's grid at the true poses instead: its walls are one cell thick, so the
   no-return beams that cross them open frontiers behind them, and its robot turns back
   at doors to chase those (it finished 28 % of 40 dev plans within 420 s, the particle
   filter's robot 55 %), leaving too many laser streaks and too much open frontier in
   its maps. ``"oracle"`` (the default until session 25) explores on the simulator's
   perfect map out to the full range and leaves walls seen only from 3 to 3.5 m away
   unmapped, free space ending in range arcs in front of them (docs/synthesize.md);
2. **pose error**: the particle filter's best trajectory (``"filter"``), drawn by a model
   learned from it (``"learned"``, :mod:`map2map.learn.ab.pose_error`), or drawn
   (``"drawn"``, :func:`drifted_poses`): every scan's pose is moved by the room-wise
   rigid drift of :mod:`map2map.learn.ab.room_drift` (the transform of the room the robot
   is in, chained along its route: the start room is where the map is anchored, each
   room steps from the one the robot entered it from, so rooms reached late are off the
   most and a wall seen from two rooms can be saved twice), a rotation of the whole run
   about its start (``global_deg``), a jitter per scan correlated over about a second
   (the scan matcher's error: walls a few cm thick and ragged; independent per scan until
   session 27, which drew walls thicker than a run's) and, with probability
   ``outlier_share`` per scan, a heading error of ``outlier_deg`` (a scan matched wrong:
   laser streaks through walls; 2 % of scans until session 28, none since: the runs'
   streaks come from the exploration's own scans);
3. **mapping** (:func:`map_scans`): the scans at those poses counted into GMapping's grid
   exactly as the datasets' ``rbpf`` mapper does (:class:`map2map.slam.gridmap.CountGrid`:
   beams cropped at ``maxUrange``, no-return beams clearing, occupied where hits / visits >
   ``occ_thresh``; the scans GMapping would process), in the run's own frame, then put
   on the plan's grid at the true start pose, as a run's map is.

A hypothesis costs the exploration (about 1-3 s of CPU a plan with the particle filter,
half that on the grid) plus the mapping; K hypotheses
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
from ...sim.mapping import OracleMapper
from .config import POSE_ERRORS
from .room_drift import RoomDrift, RoomDriftParams, room_drift_field

__all__ = ["ScanMapParams", "ScanHypothesis", "GridOracle", "Exploration", "explore",
           "scan_rng", "correlated", "drifted_poses", "map_scans", "drawn_hypothesis", "scan_map"]

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
        Simulated seconds of exploration (the datasets' runs: 420 with ``rbpf``).
    fov : float
        LIDAR field of view [deg] (the datasets': 180).
    jitter_m, jitter_deg : float
        Standard deviation of each scan's position (per axis) and heading error.
    jitter_s : float
        Correlation time of that error, seconds (0: independent per scan, the default
        until session 27; > 0: a Gauss-Markov process along the run, :func:`correlated`,
        so that scans taken close in time err alike, as a scan matcher's estimate does).
    global_deg : float
        Standard deviation of the rotation of the whole run about its start pose.
    outlier_share, outlier_deg : float
        Share of scans given an extra heading error, and its standard deviation (0.02
        until session 28; 0 leaves the random stream as it was, only the extra error
        goes).
    rooms : RoomDriftParams
        The room-wise rigid drift (its ``parametric`` field is not used here; 1 degree a
        step, 0.02 of the step's length).
    room_order : {"random", "visits"}
        How the room drift chains the rooms: a random walk from a random room
        (``"random"``), or along the robot's route (``"visits"``: the start room is not
        moved, each room steps from the one the robot came from when it first entered it).
    explore_map : {"rbpf", "grid", "oracle"}
        The map the robot explores on (module doc, step 1): the ``rbpf`` particle
        filter's, as a run's robot (the default since session 26; the scans it processed
        are the ones mapped); GMapping's count grid of the scans it would process at the
        true poses (``"grid"``, :class:`GridOracle`, the default in session 25; about
        half the particle filter's CPU time); or the simulator's log-odds oracle out to
        the full range (``"oracle"``; one scan every ``temporal_update`` seconds is
        mapped).
    pose_error : {"filter", "drawn", "learned"} or None
        Where the poses the scans are mapped at come from: the exploring particle filter's
        own estimate (``"filter"``, needs ``explore_map="rbpf"``: the best particle's
        trajectory, so the hypothesis is the map of a simulated ``rbpf`` run of the plan,
        as the datasets' pairs are; the drift settings are not used), drawn (step 2 of
        the module doc: room drift, whole-run turn, jitter) or drawn by the pose-error
        model learned from the filter (``"learned"``,
        :func:`~map2map.learn.ab.pose_error.errors_along`; needs the scans a mapper processed:
        ``explore_map`` ``"rbpf"`` or ``"grid"``). None (the default):
        ``"filter"`` when exploring on ``"rbpf"``, else ``"drawn"``. How each passes for
        a simulated run: docs/synthesize.md.
    pose_model : str or None
        With ``pose_error="learned"``: the model file (None: the shipped one).

    The defaults were chosen on 160 plans of the seed-20261127 dev set among eight
    settings by the per-plan ranks and the classifier AUC; ``room_order="visits"`` on
    160 plans of each of two other dev sets (seeds 20261130 and 20261129), against the
    random walk and three other candidates; ``explore_map="grid"`` with 420 s on 320 plans
    of the seed-20261201 dev set by the converged classifier, and ``"rbpf"`` on 320 plans
    of the seed-20261203 dev set (classifier AUC 0.77 / 0.82 / 0.78 against 0.80 / 0.86 /
    0.83 with three classifier seeds; its streaks and open frontier as the runs'; the
    diversity ratio 1.16 against 1.29; docs/synthesize.md); ``jitter_s=1.0`` on 320
    plans of the seed-20261205 dev set (AUC 0.723 / 0.716 against 0.777 / 0.830 with two
    classifier seeds; walls as thin as the runs', saved twice and bent a little more);
    ``outlier_share=0`` on the same dev set (AUC 0.706 / 0.680 against 0.723 / 0.716; the
    streaks as the runs'; frozen in session 28 before its test set was built).
    """

    duration: float = 420.0
    fov: float = 180.0
    jitter_m: float = 0.0175
    jitter_deg: float = 0.45
    global_deg: float = 2.5
    outlier_share: float = 0.0
    outlier_deg: float = 3.0
    rooms: RoomDriftParams = field(default_factory=_rooms_default)
    room_order: str = "visits"
    explore_map: str = "rbpf"
    jitter_s: float = 1.0
    pose_error: str | None = None
    pose_model: str | None = None

    def __post_init__(self):
        for name in ("duration", "fov", "jitter_m", "jitter_deg", "global_deg",
                     "outlier_deg", "jitter_s"):
            v = getattr(self, name)
            if not (math.isfinite(v) and v >= 0):
                raise InputError(name, f"must be finite and >= 0, got {v!r}")
        if not 0.0 <= self.outlier_share <= 1.0:
            raise InputError("outlier_share", f"must be in [0, 1], got {self.outlier_share!r}")
        if self.duration <= 0:
            raise InputError("duration", f"must be > 0, got {self.duration!r}")
        if self.explore_map not in ("grid", "oracle", "rbpf"):
            raise InputError("explore_map",
                             f"must be 'grid', 'oracle' or 'rbpf', got {self.explore_map!r}")
        if self.pose_error is None:                 # frozen: set the resolved default
            object.__setattr__(self, "pose_error",
                               "filter" if self.explore_map == "rbpf" else "drawn")
        if self.pose_error not in POSE_ERRORS:
            raise InputError("pose_error", f"must be one of {', '.join(POSE_ERRORS)}, "
                             f"got {self.pose_error!r}")
        if self.pose_error == "learned" and self.explore_map == "oracle":
            raise InputError("pose_error", "'learned' needs explore_map 'rbpf' or 'grid'")
        if self.pose_error == "filter" and self.explore_map != "rbpf":
            raise InputError("pose_error", "'filter' takes the exploring particle filter's "
                             f"poses: it needs explore_map 'rbpf', not {self.explore_map!r}")
        if self.room_order not in ("random", "visits"):
            raise InputError("room_order",
                             f"must be 'random' or 'visits', got {self.room_order!r}")

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
        The poses the scans were mapped at (plan frame): drifted, or with ``pose_error
        "filter"`` the particle filter's at the scans it processed (true elsewhere).
    true_poses : (N, 3) float
        Their true poses.
    drift : RoomDrift or None
        None with ``pose_error "filter"``.
    info : dict
        Exploration and drift figures for a summary.
    """

    map: OccupancyMap
    poses: np.ndarray
    true_poses: np.ndarray
    drift: RoomDrift | None
    info: dict


class GridOracle(OracleMapper):
    """A mapper (the :class:`~map2map.robotlog.base.Mapper` protocol) that counts the
    scans GMapping would process into GMapping's grid at the **true** poses: the map the
    run's robot explores on, without its pose error (module doc, step 1).

    A scan is processed as :class:`~map2map.slam.rbpf.GMappingRBPF` processes one
    (:meth:`~map2map.slam.rbpf.GMappingParams.due`): the first, then whenever the robot has
    moved ``linear_update`` metres or turned ``angular_update`` radians since the last
    processed scan (the true motion stands for the odometry), or ``temporal_update``
    seconds have passed. Each is registered in a
    :class:`~map2map.slam.gridmap.CountGrid` (beams cropped at ``max_urange``, no-return
    beams clearing), and the map is occupied where hits / visits > ``occ_thresh``: the
    cells the robot plans on are the cells :func:`map_scans` draws. The
    :class:`~map2map.sim.mapping.OracleMapper` instead integrates every scan in a
    log-odds grid out to the full 3.5 m range, so a robot exploring on it may leave a
    room whose GMapping map is not complete; ``ScanMapParams(explore_map="grid")``
    explores on this one instead (docs/synthesize.md, session 23, "Exploring on GMapping's
    grid").

    Parameters
    ----------
    resolution : float
        Cell size (metres; the plan's).

    Attributes
    ----------
    processed : list of int
        The indices (in the order :meth:`update` was called) of the scans registered.

    Examples
    --------
    >>> from map2map.robotlog.base import LaserScan, OdometryReading
    >>> m = GridOracle(0.05)
    >>> for t, x in [(0.0, 2.0), (0.2, 2.01), (0.6, 2.02), (0.7, 3.1)]:
    ...     scan = LaserScan(t, np.full(180, 1.0, np.float32), -math.pi / 2, math.pi / 179,
    ...                      0.12, 3.5)
    ...     m.observe_truth((x, 2.0, 0.0))
    ...     m.update(OdometryReading(t, 0.0, 0.0, 0.0), scan)
    >>> m.processed, m.pose().round(2).tolist()
    ([0, 2, 3], [1.1, 0.0, 0.0])
    >>> bool(m.get_map().occupied.sum() > 10)
    True
    """

    name = "grid-oracle"

    def __init__(self, resolution: float = 0.05):
        from ...slam.gridmap import CountGrid
        from ...slam.rbpf import GMappingParams

        self.params = GMappingParams()
        self.grid = CountGrid.around(0.0, 0.0, self.params.initial_size / 2, float(resolution))
        self.processed: list[int] = []
        self._truth = self._start = None
        self._pose = (0.0, 0.0, 0.0)
        self._last = None                  # time of the last processed scan
        self._lin = self._ang = 0.0
        self._prev = None                  # the previous true pose (map frame)
        self._n = 0
        self._map = None

    def update(self, odom, scan) -> None:
        """Register ``scan`` at the pose given to :meth:`observe_truth` if it is due
        (class doc); ``odom`` is not used.

        Raises
        ------
        RuntimeError
            No :meth:`observe_truth` since the last update.
        """
        from ...slam.rbpf import prepare_scan

        self._advance()
        i, self._n = self._n, self._n + 1
        p = self.params
        if self._prev is not None:
            step = relative_pose(self._prev, self._pose)
            self._lin += math.hypot(step[0], step[1])
            self._ang += abs(step[2])
        self._prev = self._pose
        t = float(scan.t)
        if self._last is not None and not p.due(self._lin, self._ang, t - self._last):
            return
        self._lin = self._ang = 0.0
        self._last = t
        r, a = prepare_scan(scan)
        self.grid.register_scan(compose_pose(self._pose, scan.sensor_offset), r, a,
                                p.max_urange, float(scan.range_max), p.no_return_free)
        self.processed.append(i)
        self._map = None

    def get_map(self) -> OccupancyMap:
        """GMapping's map of the scans processed so far (cached between them)."""
        if self._map is None:
            self._map = self.grid.to_occupancy_map(self.params.occ_thresh)
        return self._map


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


def correlated(z: np.ndarray, dt: float, tau: float) -> np.ndarray:
    """Independent standard normal rows ``z`` (one per scan, ``dt`` seconds apart) made a
    stationary Gauss-Markov process of correlation time ``tau`` seconds (AR(1), ``rho =
    exp(-dt / tau)``): each row still standard normal, neighbours alike.

    Examples
    --------
    >>> z = np.random.default_rng(0).standard_normal((20000, 1))
    >>> y = correlated(z, 0.2, 2.0)
    >>> round(float(y.std()), 1), round(float(np.corrcoef(y[1:, 0], y[:-1, 0])[0, 1]), 1)
    (1.0, 0.9)
    """
    from scipy.signal import lfilter

    rho = math.exp(-float(dt) / float(tau))
    gain = math.sqrt(1.0 - rho * rho)
    x = np.array(z, float)
    x[0] /= max(gain, 1e-12)                 # the first row keeps unit variance
    return lfilter([gain], [1.0, -rho], x, axis=0)


def _scan_period(times) -> float:
    """Median seconds between scans (``times`` None: the LIDAR's 5 Hz)."""
    if times is None or len(times) < 2:
        return 0.2
    return float(np.median(np.diff(np.asarray(times, float)))) or 0.2


def drifted_poses(plan: OccupancyMap, poses: np.ndarray, start, drift: RoomDrift,
                  rng: np.random.Generator, params: ScanMapParams,
                  times=None) -> np.ndarray:
    """Poses ``(N, 3)`` (plan frame, metres and radians) moved by the pose error of the
    module doc, step 2: each by the rigid transform of the room it lies in, then the
    whole run turned about ``start``, then per-scan jitter and outliers (drawn from
    ``rng`` in that order). With ``params.jitter_s`` > 0 the jitter is correlated in time
    (:func:`correlated`; ``times``, the scans' seconds, give its step).

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
    if len(T):
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
    if params.jitter_s > 0 and n > 1:
        z = correlated(z, _scan_period(times), params.jitter_s)
    out[:, :2] += params.jitter_m * z[:, :2]
    out[:, 2] += math.radians(params.jitter_deg) * z[:, 2]
    hit = rng.random(n) < params.outlier_share
    out[:, 2] += np.where(hit, math.radians(params.outlier_deg) * rng.standard_normal(n), 0.0)
    return out


def map_scans(scans, times, poses, start, plan: OccupancyMap, keep=None) -> OccupancyMap:
    """Count ``scans`` taken at ``poses`` (plan frame) into GMapping's grid as the datasets'
    ``rbpf`` mapper does (module doc, step 3; :class:`~map2map.slam.rbpf.GMappingParams`
    defaults: ``max_urange``, ``occ_thresh``, ``temporal_update``, ``no_return_free``),
    in the run's frame (``start`` at the origin), and put the map on ``plan``'s grid.

    ``keep`` (indices, optional) names the scans to map, e.g. the ones a
    :class:`GridOracle` processed; by default one every ``temporal_update`` seconds.

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
    from ...slam.gridmap import CountGrid
    from ...slam.rbpf import GMappingParams, prepare_scan

    gp = GMappingParams()
    grid = CountGrid.around(0.0, 0.0, gp.initial_size / 2, plan.resolution)
    last = -math.inf
    use = None if keep is None else set(int(i) for i in keep)
    for i, (scan, t, pose) in enumerate(zip(scans, times, poses, strict=True)):
        if use is None:
            if float(t) - last < gp.temporal_update:
                continue
            last = float(t)
        elif i not in use:
            continue
        r, a = prepare_scan(scan)
        laser = compose_pose(relative_pose(start, pose), scan.sensor_offset)
        grid.register_scan(laser, r, a, gp.max_urange, float(scan.range_max),
                           gp.no_return_free)
    return resample_to_frame(grid.to_occupancy_map(gp.occ_thresh), start, plan)


def _explore_mapper(kind: str, resolution: float, sim_seed: int):
    """The mapper the robot explores on (:class:`ScanMapParams` ``explore_map``)."""
    if kind == "grid":
        return GridOracle(resolution)
    if kind == "rbpf":
        from ...robotlog.mappers import make_mapper

        return make_mapper("rbpf", resolution=resolution, seed=sim_seed)
    return "oracle"


def _processed(mapper, times) -> np.ndarray | None:
    """Indices of the scans the exploring ``mapper`` registered (None: the oracle's, one
    every ``temporal_update`` seconds is mapped instead)."""
    if isinstance(mapper, GridOracle):
        return np.asarray(mapper.processed, int)
    if hasattr(mapper, "trajectory"):          # the particle filter: its nodes' times
        return np.searchsorted(np.asarray(times, float), mapper.trajectory()[:, 0])
    return None


@dataclass
class Exploration:
    """What :func:`explore` recorded of one robot's run: its true ``poses`` (N, 3), the
    ``scans`` and their ``times``, the ``start`` pose, the indices ``keep`` of the scans
    the exploring mapper processed (None: the oracle's, one every ``temporal_update`` s is
    drawn), and the run's ``seed``, ``coverage`` and ``sim_seconds``; ``filter_poses``:
    the particle filter's estimate at the scans ``keep`` names (plan frame; the best
    particle's trajectory at the end of the run), None unless it explored on ``rbpf``."""

    poses: np.ndarray
    scans: list
    times: np.ndarray
    start: tuple
    keep: np.ndarray | None
    seed: int
    coverage: float
    sim_seconds: float
    filter_poses: np.ndarray | None = None


def explore(plan: OccupancyMap, seed: int, k: int, params: ScanMapParams | None = None,
            start=None) -> Exploration:
    """Step 1 of the module doc for hypothesis ``k`` of ``plan`` under ``seed``: the
    simulator's robot explores with the simulation seed of
    :func:`~map2map.learn.ab.coverage.explore_rng` ``(seed, k)`` on the map of
    ``params.explore_map``. It does not depend on the pose-error settings.

    Examples
    --------
    >>> from map2map.maps.floorplan import generate_floorplan
    >>> plan = generate_floorplan(3, size=(10, 8))
    >>> e = explore(plan, 0, 0, ScanMapParams(duration=20.0))
    >>> len(e.scans) == len(e.poses) == len(e.times), bool(0 < len(e.keep) < len(e.scans))
    (True, True)
    """
    from ...sim.runner import simulate
    from .coverage import explore_rng

    sp = params or ScanMapParams()
    sim_seed = int(explore_rng(seed, k).integers(1 << 32))
    mapper = _explore_mapper(sp.explore_map, plan.resolution, sim_seed)
    res = simulate(plan, seed=sim_seed, duration=sp.duration, fov=sp.fov, mapper=mapper,
                   start=None if start is None else tuple(float(v) for v in start),
                   progress=False)
    filt = None
    if hasattr(mapper, "trajectory"):           # the particle filter: its own poses too
        traj = mapper.trajectory()
        filt = compose_pose(np.asarray(res.start, float), traj[:, 1:4]).reshape(-1, 3)
    return Exploration(res.true_poses, res.scans, res.times, res.start,
                       _processed(mapper, res.times), sim_seed, float(res.coverage),
                       float(res.sim_seconds), filt)


def scan_map(plan: OccupancyMap, seed: int, k: int,
             params: ScanMapParams | None = None, start=None) -> ScanHypothesis:
    """Hypothesis ``k`` of ``plan`` under ``seed`` (module doc): its exploration
    (:func:`explore`), its pose error drawn from :func:`scan_rng` ``(seed, k)``.

    ``start`` (x, y, yaw; metres and radians in the plan's frame, optional) is where the
    robot starts, as ``map2map simulate --start``; by default the simulation seed draws
    it in the free space.

    Raises
    ------
    InputError
        A plan without free space or too small for the robot.
    """
    sp = params or ScanMapParams()
    return drawn_hypothesis(plan, explore(plan, seed, k, sp, start), seed, k, sp)


def drawn_hypothesis(plan: OccupancyMap, ex: Exploration, seed: int, k: int,
                     params: ScanMapParams | None = None) -> ScanHypothesis:
    """Steps 2 and 3 of the module doc for a recorded exploration ``ex`` (of
    :func:`explore`): hypothesis ``k``'s scans mapped at the particle filter's poses
    (``pose_error "filter"``, the default) or at a pose error drawn from
    :func:`scan_rng` ``(seed, k)`` (``"drawn"``). ``scan_map(plan, seed, k, params)`` is
    ``drawn_hypothesis(plan, explore(plan, seed, k, params), seed, k, params)``, so one
    exploration serves any pose-error settings (``params.duration``, ``fov`` and
    ``explore_map`` are the exploration's and not read here): tuning the pose error
    need not explore again.

    Examples
    --------
    >>> from map2map.maps.floorplan import generate_floorplan
    >>> plan = generate_floorplan(3, size=(10, 8))
    >>> sp = ScanMapParams(duration=20.0)
    >>> ex = explore(plan, 0, 0, sp)
    >>> h = drawn_hypothesis(plan, ex, 0, 0, sp)
    >>> bool((h.map.data == scan_map(plan, 0, 0, sp).map.data).all())
    True
    """
    sp = params or ScanMapParams()
    if sp.pose_error in ("filter", "learned"):
        if ex.keep is None or (sp.pose_error == "filter" and ex.filter_poses is None):
            raise InputError("pose_error", f"{sp.pose_error!r} needs the scans the exploring "
                             "mapper processed (explore_map 'rbpf'"
                             f"{'' if sp.pose_error == 'filter' else ' or grid'})")
        from .pose_error import errors_along

        drift, used = None, np.asarray(ex.keep, int)
        poses = np.array(ex.poses, float, copy=True)
        poses[used] = ex.filter_poses if sp.pose_error == "filter" else \
            poses[used] + errors_along(ex, sp.pose_model, scan_rng(seed, k))
    else:
        rng = scan_rng(seed, k)
        path = plan.world_to_pixel_float(ex.poses[:, 0], ex.poses[:, 1]) \
            if sp.room_order == "visits" else None
        drift = room_drift_field(plan.data, rng, sp.rooms, path)
        poses = drifted_poses(plan, ex.poses, ex.start, drift, rng, sp, ex.times)
        used = np.arange(len(poses))
    m = map_scans(ex.scans, ex.times, poses, ex.start, plan, ex.keep)
    err = np.hypot(*(poses[used, :2] - ex.poses[used, :2]).T)
    info = {"seed": ex.seed, "coverage": round(ex.coverage, 4),
            "sim_seconds": round(ex.sim_seconds, 1), "scans": len(ex.scans),
            "pose_error": sp.pose_error,
            "pose_error_m": {"mean": round(float(err.mean()), 4) if len(err) else 0.0,
                             "max": round(float(err.max()), 4) if len(err) else 0.0},
            "drift": {} if drift is None else
            {k2: round(float(v), 3) for k2, v in drift.stats().items()}}
    return ScanHypothesis(m, poses, ex.poses, drift, info)
