"""Rao-Blackwellized particle-filter SLAM in the style of GMapping (Grisetti et al. 2007).

Each particle carries a robot pose, an importance weight, its own occupancy grid
(:class:`~map2map.slam.gridmap.CountGrid`) and a node in a shared trajectory tree.
One filter step, as in GMapping's ``GridSlamProcessor::processScan``:

1. **Motion** (every odometry reading): each particle's pose is drawn from the
   odometry motion model with GMapping's error coefficients ``srr, srt, str, stt``
   (:func:`sample_motion`).
2. The rest runs only once the robot has travelled ``linear_update`` metres or
   turned ``angular_update`` radians since the last processed scan, or
   ``temporal_update`` seconds have passed.
3. **Improved proposal** (Grisetti 2007, sec. IV): each particle's pose is refined by
   GMapping's hill-climbing scan matcher against the particle's own map
   (:func:`~map2map.slam.gridmap.hill_climb`); if the match scores above
   ``minimum_score``, the proposal is the Gaussian fitted to the scan likelihood on
   a small grid around the matched pose (eqs. 9-12 of the paper) and the new pose
   is drawn from it; otherwise the odometry sample is kept.
4. **Weights** (eq. 13): the weight increment is the log of the likelihood summed
   over those grid points (``eta``), or the likelihood at the odometry pose when
   matching failed. Weights are smoothed as GMapping does (``ogain``).
5. **Adaptive resampling** (sec. V): low-variance resampling when the effective
   sample size ``N_eff = 1 / sum w^2`` falls below ``resample_threshold * N``.
   Particles share the tiles of their common history (copy on write,
   :class:`~map2map.slam.gridmap.CountGrid`): a particle drawn twice gets a grid that
   shares every tile, and a tile is copied only when one of them writes into it.
6. **Map update**: every particle integrates the scan at its pose with GMapping's
   counting rules.

The map and trajectory reported are those of the particle with the highest
accumulated weight (GMapping's ``getBestParticleIndex``). No ground truth is used
anywhere: the filter sees only :class:`OdometryReading` and :class:`LaserScan`.

Defaults are TurtleBot3's ``turtlebot3_slam/config/gmapping_params.yaml`` except
``particles`` (5 instead of 100) and ``lskip`` (1 instead of 0: every second beam
of the 360-beam LDS-01), both for speed; ``benchmarks/bench_slam.py`` and
``map2map.experiments.slam_accuracy.simulated`` measure their effect -- see
:class:`GMappingParams`.

Examples
--------
>>> import numpy as np
>>> from map2map.robotlog.base import LaserScan, OdometryReading
>>> f = GMappingRBPF(GMappingParams(particles=5), seed=0)
>>> ang = np.deg2rad(np.arange(360.0))
>>> r = np.full(360, 1.5)
>>> f.update(OdometryReading(0.0, 0.0, 0.0, 0.0),
...          LaserScan(0.0, r, 0.0, np.deg2rad(1.0), 0.12, 3.5))
>>> f.pose().tolist()
[0.0, 0.0, 0.0]
>>> f.get_map().shape[0] > 0
True
"""

from __future__ import annotations

import math
from dataclasses import dataclass, fields

import numpy as np

from ..core.geometry import compose_pose, relative_pose, wrap_angle
from ..core.grid import OccupancyMap
from ..robotlog.base import LaserScan, OdometryReading
from .gridmap import CountGrid, hill_climb, sample_likelihood

__all__ = [
    "GMappingParams",
    "GMappingRBPF",
    "sample_motion",
    "effective_sample_size",
    "low_variance_resample",
    "normalize_log_weights",
    "absolute_difference",
    "absolute_sum",
    "prepare_scan",
    "make_rbpf",
]


@dataclass(frozen=True)
class GMappingParams:
    """GMapping parameters (names as in ``slam_gmapping``); defaults from TurtleBot3.

    TurtleBot3's ``gmapping_params.yaml`` sets: maxUrange 3.0, sigma 0.05,
    kernelSize 1, lstep 0.05, astep 0.05, iterations 5, lsigma 0.075, ogain 3.0,
    lskip 0, minimumScore 50, srr 0.1, srt 0.2, str 0.1, stt 0.2, linearUpdate 1.0,
    angularUpdate 0.2, temporalUpdate 0.5, resampleThreshold 0.5, particles 100,
    delta 0.05, llsamplerange 0.01, llsamplestep 0.01, lasamplerange 0.005,
    lasamplestep 0.005. ``occ_thresh`` 0.25 is slam_gmapping's default.

    Deviations, for speed (a 7-minute simulated run should take a few seconds):
    ``particles`` 5 (not 100) and ``lskip`` 1 (not 0; the matcher uses every second
    of the LDS-01's 360 beams). Measured (before ``motion_prior``) on 10 simulated
    explorations (procedural apartments and offices, 7 minutes, realistic odometry):
    mean map error 7.1 cm with 5 particles, 6.4 cm with 10, 6.7 cm with 30 -- within
    run-to-run spread -- while time grows linearly (about 6, 8 and 22 CPU seconds per run); see
    ``benchmarks/bench_slam.py`` and ``map2map.experiments.slam_accuracy.simulated``.

    Three switches that are not GMapping parameters. ``sigma_is_std`` (default True)
    reads ``sigma`` and ``lsigma`` as the standard deviations the ROS documentation
    describes ("the sigma used by the greedy endpoint matching"): the endpoint terms
    are ``exp(-d^2 / (2 sigma^2))`` and ``-d^2 / (2 lsigma^2)``. GMapping's code
    divides by ``sigma`` itself (False), which with 0.05 is a Gaussian of 16 cm
    standard deviation: flat within the 3x3 kernel, so the hill climber wanders
    inside a cell at every update and the map random-walks (measured: 38 cm drift in
    two simulated minutes with perfect odometry and no motion noise, 10 cm with
    True; see ``map2map.experiments.slam_accuracy.simulated``). ``sample_proposal``
    draws each particle's new pose from the Gaussian fitted around its scan match
    (Grisetti 2007, eq. 12; GMapping's code keeps the matched pose itself, ``False``), and
    ``no_return_free`` clears free space along beams without a return up to
    ``max_urange`` (GMapping's documented set-up for drivers reporting no-returns at
    the maximum range; the simulator's LDS-01 reports ``inf``).

    ``motion_prior`` (default 4; 0 is GMapping's code) keeps the motion-model factor
    of the improved proposal (Grisetti 2007, eq. 9: scan likelihood *times* odometry
    motion model) in the scan matcher: the hill climb maximises the score minus
    ``motion_prior`` times half the squared Mahalanobis distance to the particle's
    noise-free odometry prediction, with the standard deviations of the motion model
    (``srr`` ... ``stt``) for the odometry since the last processed scan. Near its
    optimum the score ``sum exp(-d^2 / 2 sigma^2)`` behaves like a log-likelihood, so
    1 weighs the two as the paper's product does; but the beams are not independent
    (the score over-counts a wall seen by many beams), so the default 4 tempers the
    scan term, as is usual for beam models (Thrun et al., Probabilistic Robotics 6.3).
    Without it the match slides along corridors where the score is flat, and the
    filter drifts even with perfect odometry (offices 13 / 17 of the quality set,
    perfect odometry: ATE 18 / 17 cm without, 19 / 8 cm with ``motion_prior`` 1).
    On the 20 plans of ``map2map.experiments.slam_accuracy.simulated``, motion_prior
    0 / 1 / 4: ATE mean 13.4 / 9.5 / 5.1 cm, map error mean 10.3 / 8.9 / 7.2 cm,
    coverage 0.75 / 0.71 / 0.76.

    ``close_loops`` (default False; ``map2map slam`` turns it on for a recorded log)
    keeps every processed scan and the odometry at it, and :meth:`GMappingRBPF.optimize`
    (called by :func:`map2map.slam.offline.run_slam` at the end of the log) closes the
    loops of the best particle's trajectory with a pose graph and draws the map again
    from the corrected poses (:mod:`map2map.slam.loops`).
    """

    particles: int = 5
    max_urange: float = 3.0
    sigma: float = 0.05
    kernel_size: int = 1
    lstep: float = 0.05
    astep: float = 0.05
    iterations: int = 5
    lsigma: float = 0.075
    ogain: float = 3.0
    lskip: int = 1
    minimum_score: float = 50.0
    srr: float = 0.1
    srt: float = 0.2
    str: float = 0.1
    stt: float = 0.2
    linear_update: float = 1.0
    angular_update: float = 0.2
    temporal_update: float = 0.5
    resample_threshold: float = 0.5
    delta: float = 0.05
    llsamplerange: float = 0.01
    llsamplestep: float = 0.01
    lasamplerange: float = 0.005
    lasamplestep: float = 0.005
    occ_thresh: float = 0.25
    initial_size: float = 20.0
    sample_proposal: bool = True
    motion_prior: float = 4.0
    no_return_free: bool = True
    sigma_is_std: bool = True
    close_loops: bool = False

    def __post_init__(self) -> None:
        if self.particles < 1:
            raise ValueError(f"particles must be >= 1, got {self.particles}")
        if self.delta <= 0 or self.max_urange <= 0:
            raise ValueError("delta and max_urange must be > 0")
        for f in fields(self):
            v = getattr(self, f.name)
            if isinstance(v, float) and not math.isfinite(v):
                raise ValueError(f"{f.name} must be finite, got {v}")

    def due(self, moved: float, turned: float, elapsed: float) -> bool:
        """Whether a scan is processed: ``moved`` metres / ``turned`` radians travelled
        since the last processed scan reach ``linear_update`` / ``angular_update``, or
        ``elapsed`` seconds exceed ``temporal_update`` (when that is >= 0).

        Examples
        --------
        >>> p = GMappingParams()
        >>> p.due(0.2, 0.05, 0.4), p.due(1.0, 0.0, 0.0), p.due(0.0, 0.0, 0.6)
        (False, True, True)
        """
        return (moved >= self.linear_update or turned >= self.angular_update
                or (self.temporal_update >= 0 and elapsed > self.temporal_update))


# ----------------------------------------------------------------------------- motion
def absolute_difference(p1: np.ndarray, p2: np.ndarray) -> np.ndarray:
    """Pose of ``p1`` in the frame of ``p2`` (GMapping ``absoluteDifference``), row-wise.

    :func:`map2map.core.geometry.relative_pose` ``(p2, p1)`` on arrays.

    Parameters
    ----------
    p1, p2 : (N, 3) float arrays
        Poses.

    Returns
    -------
    (N, 3) float array

    Examples
    --------
    >>> d = absolute_difference(np.array([1.0, 1.0, np.pi / 2]), np.array([0.0, 1.0, np.pi / 2]))
    >>> np.round(d, 9) + 0.0
    array([ 0., -1.,  0.])
    """
    return relative_pose(np.asarray(p2, float), np.asarray(p1, float))


class StartFrame:
    """Odometry in the map frame (which starts at the first reading) for a scan stream.

    Shared by the backends: it also refuses a scan whose beam count differs from
    the first scan's (``ValueError``).

    Examples
    --------
    >>> sf = StartFrame()
    >>> scan = LaserScan(0.0, np.ones(4), 0.0, np.pi / 2, 0.1, 5.0)
    >>> sf.accept(OdometryReading(0.0, 2.0, 1.0, np.pi / 2), scan).tolist()
    [0.0, 0.0, 0.0]
    >>> np.round(sf.accept(OdometryReading(1.0, 2.0, 2.0, np.pi / 2), scan), 9).tolist()
    [1.0, 0.0, 0.0]
    """

    def __init__(self) -> None:
        self.origin: np.ndarray | None = None
        self.n_beams: int | None = None

    def accept(self, odom: OdometryReading, scan: LaserScan) -> np.ndarray:
        if self.n_beams is None:
            self.n_beams = scan.n_beams
        elif scan.n_beams != self.n_beams:
            raise ValueError(f"scan has {scan.n_beams} beams, earlier scans had {self.n_beams}")
        raw = np.array([odom.x, odom.y, odom.theta], float)
        if self.origin is None:
            self.origin = raw
        return absolute_difference(raw, self.origin)


def absolute_sum(p: np.ndarray, d: np.ndarray) -> np.ndarray:
    """Compose pose ``p`` with the relative motion ``d`` (GMapping ``absoluteSum``), row-wise.

    :func:`map2map.core.geometry.compose_pose` on arrays.

    Parameters
    ----------
    p : (N, 3) float array
        Poses.
    d : (N, 3) or (3,) float array
        Motions in the frames of ``p``.

    Returns
    -------
    (N, 3) float array

    Examples
    --------
    >>> absolute_sum(np.array([[0.0, 0.0, np.pi / 2]]), np.array([1.0, 0.0, 0.0])).round(6).tolist()
    [[0.0, 1.0, 1.570796]]
    """
    return compose_pose(np.asarray(p, float), np.asarray(d, float))


def sample_motion(
    poses: np.ndarray,
    odom_new: np.ndarray,
    odom_old: np.ndarray,
    srr: float,
    srt: float,
    str_: float,
    stt: float,
    rng: np.random.Generator,
) -> np.ndarray:
    """Draw new particle poses from GMapping's odometry motion model (``drawFromMotion``).

    The odometry increment ``delta = odom_new - odom_old`` (in the frame of
    ``odom_old``) is perturbed per particle with standard deviations::

        sigma_x     = srr |dx| + str |dtheta| + 0.3 srr |dy|
        sigma_y     = srr |dy| + str |dtheta| + 0.3 srr |dx|
        sigma_theta = stt |dtheta| + srt sqrt(dx^2 + dy^2)

    (GMapping's ``srr``: translation error from translation, ``srt``: translation
    from rotation in the ROS wiki's wording, applied here exactly as the GMapping
    source does) and composed with each particle's pose.

    Parameters
    ----------
    poses : (N, 3) float array
        Particle poses.
    odom_new, odom_old : (3,) float arrays
        Odometry now and at the previous update.
    srr, srt, str_, stt : float
        GMapping's motion-model noise parameters.
    rng : numpy.random.Generator
        Source of the noise.

    Returns
    -------
    (N, 3) float array

    Examples
    --------
    >>> rng = np.random.default_rng(0)
    >>> p = sample_motion(np.zeros((1000, 3)), np.array([1.0, 0, 0]), np.zeros(3),
    ...                   0.1, 0.2, 0.1, 0.2, rng)
    >>> round(float(p[:, 0].mean()), 1), round(float(p[:, 0].std()), 2)
    (1.0, 0.1)
    """
    poses = np.asarray(poses, float)
    d = absolute_difference(np.asarray(odom_new, float), np.asarray(odom_old, float))
    dx, dy, dt = abs(d[0]), abs(d[1]), abs(d[2])
    sxy = 0.3 * srr
    sig = np.array(
        [
            srr * dx + str_ * dt + sxy * dy,
            srr * dy + str_ * dt + sxy * dx,
            stt * dt + srt * math.hypot(d[0], d[1]),
        ]
    )
    noisy = d[None, :] + rng.standard_normal((poses.shape[0], 3)) * sig[None, :]
    return absolute_sum(poses, noisy)


# -------------------------------------------------------------------------- weights
def normalize_log_weights(log_w: np.ndarray, gain: float = 1.0) -> np.ndarray:
    """Normalised weights ``exp(gain (l - max l)) / sum`` (GMapping ``normalize``).

    GMapping smooths the likelihood with ``gain = 1 / (ogain * N)``.

    Parameters
    ----------
    log_w : (N,) float array
        Log-weights.
    gain : float
        Smoothing gain.

    Returns
    -------
    (N,) float array
        Weights summing to 1.

    Examples
    --------
    >>> normalize_log_weights(np.array([0.0, 0.0, np.log(2.0)])).round(2).tolist()
    [0.25, 0.25, 0.5]
    """
    lw = np.asarray(log_w, float)
    w = np.exp(gain * (lw - lw.max()))
    return w / w.sum()


def effective_sample_size(weights: np.ndarray) -> float:
    """``N_eff = 1 / sum(w_i^2)`` of normalised weights (Grisetti 2007, eq. 14).

    Parameters
    ----------
    weights : (N,) float array
        Normalised weights.

    Returns
    -------
    float

    Examples
    --------
    >>> round(effective_sample_size(np.full(10, 0.1)), 9)
    10.0
    >>> effective_sample_size(np.array([1.0, 0, 0]))
    1.0
    """
    w = np.asarray(weights, float)
    return float(1.0 / np.sum(w * w))


def low_variance_resample(weights: np.ndarray, rng: np.random.Generator) -> np.ndarray:
    """Indices drawn by low-variance (systematic) resampling (Thrun et al., table 4.4).

    One random offset ``u ~ U[0, 1/N)``; particle ``i`` is picked once for each of
    the ``N`` equally spaced pointers ``u + k/N`` that fall in its slice of the
    cumulative weight. A particle of weight ``w`` is drawn ``floor(N w)`` or
    ``ceil(N w)`` times.

    Parameters
    ----------
    weights : (N,) float array
        Normalised weights.
    rng : numpy.random.Generator
        Draws the offset.

    Returns
    -------
    (N,) int array
        Sorted particle indices.

    Examples
    --------
    >>> low_variance_resample(np.array([0.5, 0.0, 0.5, 0.0]), np.random.default_rng(1)).tolist()
    [0, 0, 2, 2]
    """
    w = np.asarray(weights, float)
    n = w.size
    c = np.cumsum(w)
    c /= c[-1]
    pointers = (rng.random() + np.arange(n)) / n
    return np.minimum(np.searchsorted(c, pointers, side="right"), n - 1)


# ----------------------------------------------------------------------------- scans
def prepare_scan(scan: LaserScan) -> tuple[np.ndarray, np.ndarray]:
    """``(ranges, angles)`` as float64: no return (``>= range_max``, ``inf``) becomes ``inf``,
    an invalid reading (``nan``, below ``range_min``) becomes ``nan``.

    Parameters
    ----------
    scan : LaserScan

    Returns
    -------
    ranges, angles : (B,) float64 arrays
        Angles in the laser frame.

    Examples
    --------
    >>> from map2map.robotlog.base import LaserScan
    >>> r, a = prepare_scan(LaserScan(0.0, np.array([1.0, 3.5, 0.01]), 0.0, 0.1, 0.12, 3.5))
    >>> r.tolist()
    [1.0, inf, nan]
    """
    r = np.asarray(scan.ranges, np.float64).copy()
    r[np.isnan(r) | (r < scan.range_min)] = np.nan
    r[r >= scan.range_max] = np.inf
    return r, scan.angles.astype(np.float64)


def _matching_beams(r: np.ndarray, a: np.ndarray, usable: float, lskip: int):
    """Beams the matcher uses: finite, below ``usable``, every ``lskip + 1``-th."""
    keep = np.isfinite(r) & (r < usable)
    if lskip > 0:
        keep &= (np.arange(r.size) % (lskip + 1)) == lskip
    return np.ascontiguousarray(r[keep]), np.ascontiguousarray(a[keep])


# ----------------------------------------------------------------------------- filter
class GMappingRBPF:
    """GMapping-style RBPF mapper (implements :class:`map2map.robotlog.base.Mapper`).

    Parameters
    ----------
    params : GMappingParams
    seed : int or numpy.random.Generator
        All sampling (motion model, proposal, resampling) draws from it.
    """

    name = "rbpf"

    def __init__(
        self, params: GMappingParams | None = None, seed: int | np.random.Generator | None = 0
    ):
        self.params = params or GMappingParams()
        self.rng = seed if isinstance(seed, np.random.Generator) else np.random.default_rng(seed)
        n = self.params.particles
        self.poses = np.zeros((n, 3))
        self.log_w = np.zeros(n)
        self.log_w_sum = np.zeros(n)
        self.grids: list[CountGrid] = []
        # trajectory tree: node poses / parents / times; particles point at leaves
        self._node_pose: list[np.ndarray] = []
        self._node_parent: list[np.ndarray] = []
        self._node_time: list[float] = []
        self._n_nodes = 0
        self.leaf = np.full(n, -1, np.int64)
        self._frame = StartFrame()
        # particle poses and odometry at the last processed scan (motion prior anchor)
        self._upd_pose = np.zeros((n, 3))
        self._upd_odom = np.zeros(3)
        self._last_odom: np.ndarray | None = None
        self._lin = 0.0
        self._ang = 0.0
        self._last_t = -np.inf
        self._map_cache: OccupancyMap | None = None
        self.n_updates = 0
        self.n_resamples = 0
        self.n_match_failures = 0
        self.neff_history: list[float] = []
        # close_loops: every processed scan (ranges, angles, laser offset, range_max) and
        # the odometry at it, in the order of the trajectory's nodes
        self._scans: list[tuple[np.ndarray, np.ndarray, np.ndarray, float]] = []
        self._odoms: list[np.ndarray] = []
        self._closed: tuple[np.ndarray, OccupancyMap] | None = None
        self.loop_closures: list[tuple[int, int]] = []
        # denominators of the endpoint Gaussians exp(-d^2 / den), see GMappingParams
        p = self.params
        self._sig = 2 * p.sigma**2 if p.sigma_is_std else p.sigma
        self._lsig = 2 * p.lsigma**2 if p.sigma_is_std else p.lsigma

    # ---------------------------------------------------------------- Mapper API
    def update(self, odom: OdometryReading, scan: LaserScan) -> None:
        """Feed one odometry reading and its scan (see module docstring for the steps).

        Parameters
        ----------
        odom : OdometryReading
            Raw odometry at the scan's time.
        scan : LaserScan
            The scan.
        """
        p = self.params
        if self._closed is not None:
            raise RuntimeError("optimize() has closed the loops: the filter has ended")
        o = self._frame.accept(odom, scan)  # odometry in the map frame
        ranges, angles = prepare_scan(scan)
        if self._last_odom is None:
            self._last_odom = o
            self._upd_odom = o
            self._last_t = scan.t
            # every particle starts at the origin: one grid, shared (copy on write)
            first = CountGrid.around(0.0, 0.0, p.initial_size / 2, p.delta)
            self.grids = [first]
            self._register_all(ranges, angles, scan)
            self.grids += [first.copy() for _ in range(p.particles - 1)]
            self._keep_scan(ranges, angles, scan, o)
            self._add_nodes(scan.t)
            self._map_cache = None
            self.n_updates += 1
            return
        step = absolute_difference(o, self._last_odom)
        self.poses = sample_motion(
            self.poses, o, self._last_odom, p.srr, p.srt, p.str, p.stt, self.rng
        )
        self._lin += math.hypot(step[0], step[1])
        self._ang += abs(step[2])
        self._last_odom = o
        if not p.due(self._lin, self._ang, scan.t - self._last_t):
            return
        self._lin = self._ang = 0.0
        self._last_t = scan.t
        self._process(ranges, angles, scan, o)
        self._keep_scan(ranges, angles, scan, o)
        self._add_nodes(scan.t)
        self._map_cache = None
        self.n_updates += 1

    def pose(self) -> np.ndarray:
        """Pose of the best particle (highest accumulated log weight); after
        :meth:`optimize`, the last corrected pose.

        Returns
        -------
        (3,) ndarray
        """
        if self._closed is not None:
            return self._closed[0][-1, 1:4].copy()
        return self.poses[self.best_index()].copy()

    def get_map(self) -> OccupancyMap:
        """The best particle's occupancy map (cached between filter updates).

        Returns
        -------
        OccupancyMap
        """
        if self._closed is not None:
            return self._closed[1]
        if self._map_cache is None:
            if not self.grids:
                raise RuntimeError("no scan integrated yet")
            g = self.grids[self.best_index()]
            self._map_cache = g.to_occupancy_map(self.params.occ_thresh, {"mapper": self.name})
        return self._map_cache

    # ------------------------------------------------------------------- extras
    def best_index(self) -> int:
        return int(np.argmax(self.log_w_sum))

    def trajectory(self) -> np.ndarray:
        """``(T, 4)`` rows ``t, x, y, theta`` of the best particle at each processed scan.

        Returns
        -------
        (T, 4) ndarray
        """
        if self._closed is not None:
            return self._closed[0].copy()
        if not self._node_pose:
            return np.zeros((0, 4))
        poses = np.concatenate(self._node_pose)
        parents = np.concatenate(self._node_parent)
        times = np.repeat(np.asarray(self._node_time), [len(a) for a in self._node_pose])
        rows = []
        k = int(self.leaf[self.best_index()])
        while k >= 0:
            rows.append((times[k], *poses[k]))
            k = int(parents[k])
        return np.asarray(rows[::-1], float)

    def optimize(self) -> None:
        """With ``close_loops``: close the loops of the best particle's trajectory and draw
        its map again from the corrected poses (:func:`map2map.slam.loops.close_loops`);
        otherwise nothing.

        The particles' grids are given back first (the peak memory stays that of the
        filter); :meth:`get_map`, :meth:`trajectory` and :meth:`pose` give the corrected
        map and poses afterwards, and the filter takes no more scans. Deterministic.
        """
        if not self.params.close_loops or self._closed is not None or not self._scans:
            return
        from .loops import LoopClosureParams, close_loops, scan_points

        p = self.params
        traj = self.trajectory()
        lc = LoopClosureParams()
        pts = [scan_points(r, a, off, p.max_urange, lc.max_points) for r, a, off, _ in self._scans]
        poses, self.loop_closures = close_loops(traj[:, 1:4], pts, lc, np.array(self._odoms))
        for g in self.grids:
            g.release()
        grid = CountGrid.around(0.0, 0.0, p.initial_size / 2, p.delta)
        laser = absolute_sum(poses, np.array([off for _, _, off, _ in self._scans]))
        for q, (r, a, _, rmax) in zip(laser, self._scans, strict=True):
            grid.register_scan(q, r, a, p.max_urange, rmax, p.no_return_free)
        out = np.column_stack([traj[:, 0], poses])
        self._closed = (out, grid.to_occupancy_map(p.occ_thresh, {"mapper": self.name}))
        self._scans = []

    # ---------------------------------------------------------------- internals
    def _keep_scan(self, ranges, angles, scan: LaserScan, o: np.ndarray) -> None:
        if self.params.close_loops:
            self._scans.append((ranges, angles, self._laser_offset(scan), float(scan.range_max)))
            self._odoms.append(np.asarray(o, float).copy())

    def _laser_offset(self, scan: LaserScan) -> np.ndarray:
        return np.asarray(scan.sensor_offset, np.float64)

    def _register_all(self, ranges, angles, scan: LaserScan) -> None:
        off = self._laser_offset(scan)
        poses = self.poses[: len(self.grids)]  # one grid (shared) at the first scan
        lp = absolute_sum(poses, np.broadcast_to(off, poses.shape))
        for g, q in zip(self.grids, lp, strict=True):
            g.register_scan(
                q,
                ranges,
                angles,
                self.params.max_urange,
                scan.range_max,
                self.params.no_return_free,
            )

    def _add_nodes(self, t: float) -> None:
        base = self._n_nodes  # nodes so far (a running count: summing the lists is O(T^2))
        self._node_pose.append(self.poses.copy())
        self._node_parent.append(self.leaf.copy())
        self._node_time.append(float(t))
        self._n_nodes += self.poses.shape[0]
        self.leaf = base + np.arange(self.poses.shape[0])

    def _motion_priors(self, o: np.ndarray) -> np.ndarray:
        """``(N, 6)`` motion priors ``(mx, my, mt, wx, wy, wt)`` for :func:`hill_climb`.

        The mean is each particle's pose at the previous processed scan moved by the
        odometry since then, without noise; the weights are ``motion_prior / s^2`` with
        ``s`` the standard deviations of GMapping's motion model
        (:func:`sample_motion`) for that odometry increment, expressed in the world
        frame along the particle's heading (floored at 5 mm and 0.005 rad).
        """
        p = self.params
        n = p.particles
        out = np.zeros((n, 6))
        if p.motion_prior <= 0:
            return out
        d = absolute_difference(o, self._upd_odom)
        dx, dy, dt = abs(d[0]), abs(d[1]), abs(d[2])
        sl = max(p.srr * dx + p.str * dt + 0.3 * p.srr * dy, 0.005)  # along the heading
        sc = max(p.srr * dy + p.str * dt + 0.3 * p.srr * dx, 0.005)  # across
        st = max(p.stt * dt + p.srt * math.hypot(d[0], d[1]), 0.005)
        mean = absolute_sum(self._upd_pose, np.broadcast_to(d, self._upd_pose.shape))
        out[:, :3] = mean
        # isotropic in x, y (the larger of the two): the climb moves along world axes
        s_xy = max(sl, sc)
        out[:, 3] = out[:, 4] = p.motion_prior / s_xy**2
        out[:, 5] = p.motion_prior / st**2
        return out

    def _process(self, ranges, angles, scan: LaserScan, o: np.ndarray) -> None:
        p = self.params
        off = self._laser_offset(scan)
        mr, ma = _matching_beams(ranges, angles, p.max_urange, p.lskip)
        n = p.particles
        priors = self._motion_priors(o)
        for i in range(n):
            g = self.grids[i]
            x, y, t = self.poses[i]
            if mr.size == 0:
                continue
            mx, my, mt, score = hill_climb(
                *g.match_arrays(),
                x,
                y,
                t,
                off,
                mr,
                ma,
                p.kernel_size,
                self._sig,
                p.lstep,
                p.astep,
                p.iterations,
                priors[i],
            )
            if score > p.minimum_score:
                cx, cy, ct = mx, my, mt
            else:
                cx, cy, ct = x, y, t
                self.n_match_failures += 1
            log_eta, mean, cov = sample_likelihood(
                *g.match_arrays(),
                cx,
                cy,
                ct,
                off,
                mr,
                ma,
                p.kernel_size,
                self._sig,
                self._lsig,
                p.llsamplerange if score > p.minimum_score else 0.0,
                p.llsamplestep,
                p.lasamplerange if score > p.minimum_score else 0.0,
                p.lasamplestep,
            )
            if score > p.minimum_score:
                if p.sample_proposal:
                    # draw from the Gaussian proposal fitted around the match (eq. 12)
                    chol = np.linalg.cholesky(cov + np.diag([1e-10, 1e-10, 1e-12]))
                    new = mean + chol @ self.rng.standard_normal(3)
                else:
                    new = np.array([cx, cy, ct])
                self.poses[i] = (new[0], new[1], wrap_angle(new[2]))
            self.log_w[i] += log_eta
            self.log_w_sum[i] += log_eta
        w = normalize_log_weights(self.log_w, 1.0 / (p.ogain * n))
        neff = effective_sample_size(w)
        self.neff_history.append(neff)
        if neff < p.resample_threshold * n:
            idx = low_variance_resample(w, self.rng)
            self._resample(idx)
        self._upd_pose = self.poses.copy()
        self._upd_odom = o
        self._register_all(ranges, angles, scan)

    def _resample(self, idx: np.ndarray) -> None:
        """Keep particles ``idx``: a particle drawn again gets a copy of the grid that
        shares every tile (copy on write), a particle not drawn gives its tiles back.
        """
        drawn = [int(j) for j in idx]
        kept = set(drawn)
        for j, g in enumerate(self.grids):
            if j not in kept:
                g.release()
        taken: set[int] = set()
        grids = []
        for j in drawn:
            grids.append(self.grids[j] if j not in taken else self.grids[j].copy())
            taken.add(j)
        self.grids = grids
        self.poses = self.poses[idx].copy()
        self.leaf = self.leaf[idx].copy()
        self.log_w_sum = self.log_w_sum[idx].copy()
        self.log_w = np.zeros_like(self.log_w)
        self.n_resamples += 1

    def memory_bytes(self) -> int:
        """Bytes of the particles' map tiles (the pool they share).

        Returns
        -------
        int
        """
        return self.grids[0].pool.nbytes() if self.grids else 0


def make_rbpf(
    resolution: float = 0.05, seed: int | np.random.Generator | None = 0, **options
) -> GMappingRBPF:
    """Registry factory (``map2map simulate --mapper rbpf``): ``resolution`` is GMapping's
    ``delta``; other keyword options are :class:`GMappingParams` fields (``None`` keeps the
    default).

    Parameters
    ----------
    resolution : float
        Map cell size, metres.
    seed : int or numpy.random.Generator, optional
        Seed of the filter's random steps.
    **options
        :class:`GMappingParams` fields.

    Returns
    -------
    GMappingRBPF

    Examples
    --------
    >>> make_rbpf(0.05, seed=1, particles=8).params.particles
    8
    """
    opts = {k: v for k, v in options.items() if v is not None}
    return GMappingRBPF(GMappingParams(delta=float(resolution), **opts), seed=seed)
