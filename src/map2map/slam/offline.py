"""Run a SLAM backend over a recorded log and write its map, trajectory and figure.

This is what ``map2map slam LOG --out DIR`` does:

1. :func:`run_slam` feeds every ``(odometry, scan)`` pair of a log to a backend
   chosen by name from the mapper registry (:mod:`map2map.robotlog.mappers`), with a
   tqdm progress bar, and returns the final map and estimated trajectory;
2. :func:`map2map.jobs.slam.write_slam_outputs` writes ``map.yaml`` + ``map.pgm``
   (ROS map_saver
   format), ``trajectory.csv`` (``t, x, y, theta`` in the map frame) and
   ``figure.png`` (the map with the estimated trajectory and the raw odometry).

Examples
--------
>>> import numpy as np
>>> from map2map.robotlog.carmen import CarmenLog
>>> from map2map.robotlog.base import LaserScan, OdometryReading
>>> ang = np.deg2rad(1.0)
>>> log = CarmenLog([OdometryReading(0.2 * k, 0.1 * k, 0.0, 0.0) for k in range(5)],
...                 [LaserScan(0.2 * k, np.full(360, 1.5, np.float32), 0.0, ang, 0.1, 3.5)
...                  for k in range(5)])
>>> res = run_slam(log, "graph")
>>> res.trajectory.shape[1], res.map.resolution
(4, 0.05)
"""

from __future__ import annotations

import math
import os
from dataclasses import dataclass

import numpy as np

from ..core.errors import InputError
from ..core.grid import OccupancyMap
from ..core.limits import DEFAULT_BUDGET_BYTES
from ..robotlog.base import Mapper
from ..robotlog.carmen import CarmenLog

__all__ = [
    "SlamResult",
    "check_options",
    "run_slam",
    "odometry_in_map_frame",
    "default_usable_range",
    "backend_options",
    "default_particles",
    "default_close_loops",
    "RECORDED_LOG_PARTICLES",
    "map_tiles_estimate",
    "memory_estimate",
    "check_memory",
    "default_memory_limit",
]

#: Peak memory of ``map2map slam`` besides the map tiles and the map image: interpreter,
#: numba kernels, log reader, figure (measured: 0.25-0.45 GiB on the Radish logs and the
#: campus of ``benchmarks/slam_memory.py``).
BASE_BYTES = 500 * 2**20
#: What the graph backend holds besides: the likelihood lookup tables of its scan
#: matcher (measured: 0.3-0.45 GiB more than the particle filter on aces and the campus).
GRAPH_TABLES_BYTES = 300 * 2**20
#: Tiles a particle holds on its own beyond the map it shares (its copies of the tiles
#: written since its last common ancestor), in discs of the usable range: measured 0.4-0.7
#: of a disc on aces (5 particles) and the benchmark's campus (5 and 30 particles).
PARTICLE_DISCS = 1.5
#: Bytes per pixel of the map image over the path's extent at the end: the map, its
#: crop, the figure's reduction (measured: about 9 on the campus).
IMAGE_BYTES_PER_PIXEL = 12
#: Particle count of ``rbpf`` for a recorded log (a real robot's: one without the start
#: pose ``map2map simulate`` writes), where the simulator's speed default of 5 particles
#: (:class:`map2map.slam.rbpf.GMappingParams`) leaves the Radish maps bent and doubled.
#: The filter is followed by loop closure (:func:`default_close_loops`,
#: :mod:`map2map.slam.loops`); 10 particles + closure meet issue #35's target on seeds
#: 0-7 of both shared Radish logs within the time bound, where 20 + closure does not fit
#: it. See docs/slam.md "Defaults for a recorded log" and
#: ``python -m map2map.experiments.slam_accuracy carmen``.
RECORDED_LOG_PARTICLES = 10


@dataclass
class SlamResult:
    """Outcome of :func:`run_slam`."""

    map: OccupancyMap
    trajectory: np.ndarray  # (T, 4): t, x, y, theta in the map frame
    odometry: np.ndarray  # (N, 4): t, x, y, theta, raw odometry in the map frame
    mapper: Mapper
    backend: str


def odometry_in_map_frame(log: CarmenLog) -> np.ndarray:
    """``(N, 4)`` raw odometry ``t, x, y, theta`` relative to the first reading (the map frame).

    Parameters
    ----------
    log : CarmenLog
        A recorded run.

    Returns
    -------
    (N, 4) float array
    """
    from .rbpf import absolute_difference

    o = np.array([(r.x, r.y, r.theta) for r in log.odometry], float)
    rel = absolute_difference(o, o[0][None, :].repeat(len(o), 0))
    t = np.array([r.t for r in log.odometry], float)
    return np.column_stack([t, rel])


def check_options(
    backend: str = "rbpf",
    *,
    particles: int | None = None,
    resolution: float = 0.05,
    max_range: float | None = None,
    max_memory: float | None = None,
) -> None:
    """Raise :class:`InputError` (naming the parameter) for options :func:`run_slam` refuses.

    Parameters
    ----------
    backend : str
        Registered mapper name.
    particles : int, optional
        Particle count (``rbpf`` only).
    resolution : float
        Map cell size, metres.
    max_range : float, optional
        Usable laser range, metres.
    max_memory : float, optional
        Memory limit, GiB (0: none).

    Raises
    ------
    InputError
        A value out of range, or an option the backend does not take.

    Examples
    --------
    >>> check_options("graph", resolution=0.05)
    >>> check_options("rbpf", particles=0)
    Traceback (most recent call last):
    ...
    map2map.core.errors.InputError: particles: must be >= 1, got 0
    """
    if backend == "oracle":
        raise InputError("backend", "the oracle mapper needs true poses; use rbpf or graph")
    if particles is not None and particles < 1:
        raise InputError("particles", f"must be >= 1, got {particles}")
    if not resolution > 0:
        raise InputError("resolution", f"must be > 0, got {resolution}")
    if max_range is not None and not max_range > 0:
        raise InputError("max_range", f"must be > 0, got {max_range}")
    if max_memory is not None and not max_memory >= 0:
        raise InputError("max_memory", f"must be >= 0 GiB (0: no limit), got {max_memory}")


def default_usable_range(sensor_max: float) -> float:
    """GMapping's ``maxUrange`` for a scanner of maximum range ``sensor_max`` (metres).

    TurtleBot3 uses 3.0 m with its 3.5 m LDS-01 (86 %); a long-range scanner keeps
    80 % of its range up to 10 m. On the Radish logs (50 m SICK, scans about 1 m
    apart) the TurtleBot3 value of 3 m left the matcher too little to match and
    the map fell apart (``map2map.experiments.slam_accuracy.carmen``: 2.8 m mean error
    on aces).

    Parameters
    ----------
    sensor_max : float
        The scanner's maximum range, metres.

    Returns
    -------
    float

    Examples
    --------
    >>> default_usable_range(3.5), default_usable_range(7.5), default_usable_range(50.0)
    (3.0, 6.0, 10.0)
    """
    return float(min(sensor_max, max(3.0, min(10.0, 0.8 * sensor_max))))


def map_tiles_estimate(
    log: CarmenLog, resolution: float, reach: float, no_return_free: bool = True
) -> int:
    """Map tiles (:data:`~map2map.slam.gridmap.TILE` cells square) the log's beams cross.

    The grids grow as the robot goes (:class:`~map2map.slam.gridmap.CountGrid`): a
    tile is allocated when a beam first reaches it. Here every beam of a scan taken
    every quarter tile of travel (or 0.1 rad of turn) is followed from the odometry
    pose, at quarter-tile steps, up to its reading or ``reach`` metres (a beam
    without a return up to ``reach`` when ``no_return_free``, as the map update
    does), and the tiles it passes are counted. Odometry drift moves the beams a
    little, not the area they sweep; a tenth more is added for the tiles a beam only
    clips.

    Parameters
    ----------
    log : CarmenLog
        The recorded run.
    resolution : float
        Cell size, metres.
    reach : float
        How far from the robot the map is written, metres.
    no_return_free : bool
        Count beams without a return up to ``reach``.

    Returns
    -------
    int

    Examples
    --------
    >>> from map2map.robotlog.base import LaserScan, OdometryReading
    >>> scan = LaserScan(0.0, np.full(360, 3.0), -np.pi, np.pi / 180, 0.1, 3.5)
    >>> log = CarmenLog([OdometryReading(0, 0, 0, 0)], [scan])
    >>> map_tiles_estimate(log, 0.05, 10.0)  # a 3 m disc across 4 tiles of 3.2 m, + 10 %
    5
    """
    from .gridmap import TILE

    tile_m = TILE * resolution
    step = tile_m / 4
    keys = []
    last = None
    batch: list[tuple[np.ndarray, np.ndarray]] = []

    def flush() -> None:
        if not batch:
            return
        pts = np.concatenate([p for p, _ in batch])
        keys.append(np.unique(np.floor(pts / tile_m).astype(np.int64) @ np.array([1, 1 << 32])))
        batch.clear()

    n_points = 0
    for odo, scan in log:
        pose = np.array([odo.x, odo.y, odo.theta], float)
        if last is not None:
            moved = math.hypot(*(pose[:2] - last[:2]))
            turned = abs((pose[2] - last[2] + math.pi) % (2 * math.pi) - math.pi)
            if moved < step and turned < 0.1:
                continue
        last = pose
        r = np.asarray(scan.ranges, float)
        no_return = ~np.isfinite(r) | (r >= scan.range_max)
        ok = (r > 0) & ~no_return if not no_return_free else (r > 0) | no_return
        r = np.minimum(np.where(no_return, reach, r), reach)[ok]
        ang = np.asarray(scan.angles, float)[ok]
        off = scan.sensor_offset
        c, s = math.cos(pose[2]), math.sin(pose[2])
        lx = pose[0] + c * off[0] - s * off[1]
        ly = pose[1] + s * off[0] + c * off[1]
        a = pose[2] + off[2] + ang
        t = np.arange(0.0, reach + step, step)
        tt = np.minimum(t[None, :], r[:, None])  # samples along each beam, up to its end
        pts = np.stack([lx + tt * np.cos(a)[:, None], ly + tt * np.sin(a)[:, None]], -1)
        batch.append((pts.reshape(-1, 2), r))
        n_points += pts.shape[0] * pts.shape[1]
        if n_points > 2_000_000:
            flush()
            keys = [np.unique(np.concatenate(keys))]
            n_points = 0
    flush()
    if not keys:
        return 0
    return int(math.ceil(1.1 * np.unique(np.concatenate(keys)).size))


def farthest_reading(log: CarmenLog) -> float:
    """The longest valid range reading of ``log`` (metres; 0 if none).

    A map reaches no farther from the path than this, whatever range the backend is
    allowed: the graph backend defaults to the sensor maximum (50 m on the Radish logs,
    whose no-returns read as invalid), which as a margin would inflate
    :func:`map_tiles_estimate` several times over.

    >>> from map2map.robotlog.base import LaserScan
    >>> s = LaserScan(0.0, np.array([1.0, 7.5, np.inf]), 0.0, 0.1, 0.1, 50.0)
    >>> farthest_reading(CarmenLog([], [s]))
    7.5
    """
    far = 0.0
    for scan in log.scans:
        r = np.asarray(scan.ranges, float)[scan.valid]
        if r.size:
            far = max(far, float(r.max()))
    return far


def _has_no_returns(log: CarmenLog) -> bool:
    """Whether some beam of ``log`` has no return (a reading at or past the maximum)."""
    for scan in log.scans:
        r = np.asarray(scan.ranges, float)
        if (np.isinf(r) | (r >= scan.range_max)).any():
            return True
    return False


def default_particles(log: CarmenLog, backend: str = "rbpf") -> int | None:
    """Particle count :func:`run_slam` uses for ``log`` when none is given.

    A simulator run (a log carrying ``map2map simulate``'s start pose,
    :meth:`~map2map.robotlog.carmen.CarmenLog.plan_start_pose`) keeps the simulator's
    speed default (5, :class:`~map2map.slam.rbpf.GMappingParams`), so that a map built
    from it is the one ``simulate`` and the datasets build; a recorded log (CARMEN,
    BreezySLAM, ROS bag) gets :data:`RECORDED_LOG_PARTICLES`. None for a backend
    without particles.

    Parameters
    ----------
    log : CarmenLog
        The run to map.
    backend : str
        Registered mapper name.

    Returns
    -------
    int or None

    Examples
    --------
    >>> from map2map.robotlog.carmen import CarmenLog
    >>> default_particles(CarmenLog([], [])) == RECORDED_LOG_PARTICLES
    True
    >>> sim = CarmenLog([], [], params={"map2map_start_x": "0", "map2map_start_y": "0",
    ...                                 "map2map_start_theta": "0"})
    >>> default_particles(sim), default_particles(sim, "graph")
    (5, None)
    """
    from .rbpf import GMappingParams

    if backend != "rbpf":
        return None
    if log.plan_start_pose() is not None:
        return GMappingParams().particles
    return RECORDED_LOG_PARTICLES


def default_close_loops(log: CarmenLog, backend: str = "rbpf") -> bool | None:
    """Whether :func:`run_slam` closes the loops of ``rbpf`` after the filter for ``log``.

    On for a recorded log (CARMEN, BreezySLAM, ROS bag): the filter's best particle is
    corrected by a pose graph with loop closures (:mod:`map2map.slam.loops`); off for
    a simulator run (a log carrying ``map2map simulate``'s start pose), so that its
    map is the one ``simulate`` and the datasets build. None for another backend.

    Parameters
    ----------
    log : CarmenLog
        The run to map.
    backend : str
        Registered mapper name.

    Returns
    -------
    bool or None

    Examples
    --------
    >>> from map2map.robotlog.carmen import CarmenLog
    >>> sim = CarmenLog([], [], params={"map2map_start_x": "0", "map2map_start_y": "0",
    ...                                 "map2map_start_theta": "0"})
    >>> default_close_loops(CarmenLog([], [])), default_close_loops(sim)
    (True, False)
    >>> default_close_loops(sim, "graph") is None
    True
    """
    if backend != "rbpf":
        return None
    return log.plan_start_pose() is None


def backend_options(
    log: CarmenLog,
    backend: str = "rbpf",
    *,
    particles: int | None = None,
    max_range: float | None = None,
    **options,
) -> dict:
    """The backend's options :func:`run_slam` uses for ``log`` (usable range, beams, particles).

    ``particles`` defaults to :func:`default_particles` (more for a recorded log than
    for a simulator run), ``close_loops`` to :func:`default_close_loops` (on for a
    recorded log); given values are kept.

    Parameters
    ----------
    log : CarmenLog
        The recorded run (its first scan names the sensor).
    backend : str
        Registered mapper name.
    particles : int, optional
        Particle count of ``rbpf``.
    max_range : float, optional
        Usable laser range, metres.
    **options
        Backend parameters given, kept.

    Returns
    -------
    dict
    """
    sensor_max = float(log.scans[0].range_max)
    if backend == "rbpf":
        if particles is None:
            particles = default_particles(log, backend)
        options.setdefault("particles", particles)
        if options.get("close_loops") is None:
            options["close_loops"] = default_close_loops(log, backend)
        options.setdefault("max_urange", max_range or default_usable_range(sensor_max))
        if log.scans[0].n_beams <= 200:
            options.setdefault("lskip", 0)
    else:
        if options.pop("close_loops", None):
            raise InputError("close_loops", f"is an rbpf option; {backend} does not take it")
        if backend == "graph":
            options.setdefault("max_range", max_range or sensor_max)
    return options


def memory_estimate(
    log: CarmenLog, backend: str = "rbpf", *, resolution: float = 0.05, **options
) -> int:
    """Peak memory (bytes) :func:`run_slam` plans for: the map tiles the path can reach.

    ``BASE_BYTES`` (and ``GRAPH_TABLES_BYTES`` for ``graph``), plus
    :data:`~map2map.slam.gridmap.TILE_BYTES` per tile of :func:`map_tiles_estimate`
    (the tiles the beams cross, up to the backend's usable range) and, for ``rbpf``,
    ``PARTICLE_DISCS`` discs of the usable range per particle beyond the first
    (particles share the tiles of their common history), a quarter more for the tile
    pool's growth, plus
    ``IMAGE_BYTES_PER_PIXEL`` per pixel of the path's extent widened by the range (the
    map image written at the end is dense over the tiles' extent).

    Parameters
    ----------
    log : CarmenLog
        The recorded run.
    backend : str
        Registered mapper name.
    resolution : float
        Cell size, metres.
    **options
        The backend's options (:func:`backend_options`).

    Returns
    -------
    int

    Examples
    --------
    >>> from map2map.robotlog.base import LaserScan, OdometryReading
    >>> scans = [LaserScan(float(t), np.full(180, 8.0), -1.5, 0.017, 0.1, 50.0) for t in range(3)]
    >>> log = CarmenLog([OdometryReading(float(t), 20.0 * t, 0.0, 0.0) for t in range(3)], scans)
    >>> memory_estimate(log, "rbpf", **backend_options(log, "rbpf")) < 2**30
    True
    """
    from .gridmap import TILE, TILE_BYTES
    from .rbpf import GMappingParams

    if not len(log):
        return BASE_BYTES
    opts = dict(options)
    if backend == "rbpf":
        reach = opts.get("max_urange") or default_usable_range(float(log.scans[0].range_max))
    else:
        reach = opts.get("max_range") or float(log.scans[0].range_max)
    if opts.get("no_return_free", True) and _has_no_returns(log):
        reach = float(reach)  # no-return beams clear free space up to the usable range
    else:
        reach = min(float(reach), farthest_reading(log))
    reach += 2 * resolution
    tiles = float(map_tiles_estimate(log, resolution, reach, opts.get("no_return_free", True)))
    if backend == "rbpf":
        n = opts.get("particles") or GMappingParams().particles
        disc = math.pi * (reach / (TILE * resolution) + 1) ** 2
        tiles += PARTICLE_DISCS * disc * (int(n) - 1)
    xy = np.array([(r.x, r.y) for r in log.odometry], float).reshape(-1, 2)
    span = (xy.max(0) - xy.min(0) + 2 * reach) / resolution + 2 * TILE
    fixed = BASE_BYTES + (GRAPH_TABLES_BYTES if backend == "graph" else 0)
    return int(fixed + 1.25 * tiles * TILE_BYTES + IMAGE_BYTES_PER_PIXEL * span.prod())


def default_memory_limit() -> int:
    """The memory a ``slam`` run may plan for by default: 4 GiB, or the machine's RAM if less.

    Returns
    -------
    int
        Bytes.

    Examples
    --------
    >>> default_memory_limit() <= 4 * 2**30
    True
    """
    try:
        ram = os.sysconf("SC_PAGE_SIZE") * os.sysconf("SC_PHYS_PAGES")
    except (AttributeError, ValueError, OSError):
        ram = DEFAULT_BUDGET_BYTES
    return int(min(DEFAULT_BUDGET_BYTES, ram if ram > 0 else DEFAULT_BUDGET_BYTES))


def check_memory(need: float, max_memory: float | None, source, backend: str) -> None:
    """Refuse a run whose estimated peak memory ``need`` (bytes) exceeds ``max_memory`` GiB.

    Parameters
    ----------
    need : float
        Estimated peak memory, bytes (:func:`memory_estimate`).
    max_memory : float, optional
        Limit in GiB; None: :func:`default_memory_limit` (4 GiB, or the machine's RAM
        if less); 0: no limit.
    source : str or path
        The log, named in the message.
    backend : str
        The backend, named in the message.

    Raises
    ------
    InputError
        One line: the estimate, the limit and the ways out.

    Examples
    --------
    >>> check_memory(2**30, None, "a.log", "rbpf")
    >>> check_memory(5 * 2**30, None, "a.log", "rbpf")  # doctest: +ELLIPSIS
    Traceback (most recent call last):
    ...
    map2map.core.errors.InputError: a.log: mapping it (rbpf) would need about 5.0 GiB, ...
    """
    limit = default_memory_limit() if max_memory is None else max_memory * 2**30
    if not limit or need <= limit:
        return
    ways = "a coarser `resolution`"
    ways += ", fewer `particles` or `backend=graph`" if backend == "rbpf" else ""
    ways += " or a shorter `max_range`" if backend == "graph" else ""
    ask = math.ceil(need / 2**30 * 1.1 * 10) / 10
    raise InputError(
        source,
        f"mapping it ({backend}) would need about {need / 2**30:.1f} GiB, over the "
        f"{limit / 2**30:.1f} GiB `max_memory`; give {ways}, or pass `max_memory={ask}` "
        "to try anyway",
    )


def run_slam(
    log: CarmenLog,
    backend: str = "rbpf",
    *,
    particles: int | None = None,
    resolution: float = 0.05,
    seed: int = 0,
    max_range: float | None = None,
    progress: bool = False,
    source=None,
    max_memory: float | None = None,
    **options,
) -> SlamResult:
    """Replay ``log`` through the backend registered as ``backend``; no ground truth is used.

    ``max_range`` is the usable laser range: GMapping's ``maxUrange`` for ``rbpf``,
    default :func:`default_usable_range` (3 m for TurtleBot3's 3.5 m LDS-01, as its
    configuration; 10 m for a long-range scanner such as the 50 m SICK of the
    Radish logs); the graph backend's ``max_range``, default the sensor maximum.
    ``rbpf`` matches every beam of a scanner of at most 200 beams (``lskip`` 0:
    the default ``lskip`` 1 is for the LDS-01's 360). Other keyword options go to
    the backend's parameters. The grids grow as the robot goes (tiles allocated on
    first touch, shared between particles until written); a run whose
    :func:`memory_estimate` exceeds ``max_memory`` is refused before any grid is
    allocated, naming ``source`` (the log file) and the way out.

    Parameters
    ----------
    log : CarmenLog
        The recorded run (odometry and scans).
    backend : str
        Registered mapper name (``"rbpf"``, ``"graph"``).
    particles : int, optional
        Particle count of ``rbpf`` (default :func:`default_particles`:
        :data:`RECORDED_LOG_PARTICLES` for a recorded log, 5 for a simulator run).
    resolution : float
        Map cell size, metres.
    seed : int
        Seed of the backend's random steps.
    max_range : float, optional
        Usable laser range (above).
    progress : bool
        Show a tqdm progress bar.
    source : str or path, optional
        The log file, named in a memory refusal.
    max_memory : float, optional
        Largest peak memory to plan for, GiB (default 4, the memory budget of
        :mod:`map2map.core.limits`, or the machine's RAM if less; 0: no limit).
    **options
        Backend parameters.

    Returns
    -------
    SlamResult
        Map, estimated trajectory and raw odometry in the map frame, the mapper.

    Raises
    ------
    InputError
        Options refused by :func:`check_options`, a log without scans, or a run
        whose memory estimate exceeds ``max_memory``.

    Examples
    --------
    >>> from map2map.robotlog.base import LaserScan, OdometryReading
    >>> from map2map.robotlog.carmen import CarmenLog
    >>> scans = [LaserScan(float(t), np.full(90, 2.0), -np.pi, np.pi / 45, 0.1, 3.5)
    ...          for t in range(3)]
    >>> odo = [OdometryReading(float(t), 0.0, 0.0, 0.0) for t in range(3)]
    >>> res = run_slam(CarmenLog(odometry=odo, scans=scans), "graph")
    >>> res.trajectory.shape[1], bool(res.map.occupied.any())
    (4, True)
    """
    from tqdm.auto import tqdm

    from ..robotlog.mappers import make_mapper

    check_options(
        backend,
        particles=particles,
        resolution=resolution,
        max_range=max_range,
        max_memory=max_memory,
    )
    if len(log) == 0:
        raise InputError(None, "log holds no scans")
    options = backend_options(log, backend, particles=particles, max_range=max_range, **options)
    need = memory_estimate(log, backend, resolution=resolution, **options)
    check_memory(need, max_memory, source if source is not None else "log", backend)
    mapper = make_mapper(backend, resolution=resolution, seed=seed, **options)
    bar = tqdm(log, total=len(log), desc=f"slam ({backend})", unit="scan", disable=not progress)
    for k, (odo, scan) in enumerate(bar):
        mapper.update(odo, scan)
        if progress and k % 100 == 0 and getattr(mapper, "memory_bytes", lambda: 0)():
            bar.set_postfix_str(f"map {mapper.memory_bytes() / 2**20:.0f} MiB", refresh=False)
    if hasattr(mapper, "optimize"):
        mapper.optimize()
    traj = mapper.trajectory() if hasattr(mapper, "trajectory") else np.zeros((0, 4))
    return SlamResult(mapper.get_map(), traj, odometry_in_map_frame(log), mapper, backend)
