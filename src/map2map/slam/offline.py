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

from dataclasses import dataclass

import numpy as np

from ..core.errors import InputError
from ..core.grid import OccupancyMap
from ..core.limits import check_map_size
from ..robotlog.base import Mapper
from ..robotlog.carmen import CarmenLog

__all__ = [
    "SlamResult",
    "check_options",
    "run_slam",
    "odometry_in_map_frame",
    "default_usable_range",
]


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


def map_shape_estimate(log: CarmenLog, resolution: float, reach: float) -> tuple[int, int]:
    """Rows and columns of the map ``log`` would build: odometry extent +- ``reach`` metres.

    The odometry's bounding box (the SLAM map frame differs from it only by the drift
    the filter corrects), widened by the usable range on every side, at
    ``resolution`` metres per pixel: what :func:`run_slam` checks against the memory
    budget (:func:`map2map.core.limits.check_map_size`) before building anything.

    >>> from map2map.robotlog.base import OdometryReading
    >>> log = CarmenLog([OdometryReading(0, 0, 0, 0), OdometryReading(1, 9, 4, 0)], [])
    >>> map_shape_estimate(log, 0.05, 3.0)
    (200, 300)
    """
    xy = np.array([(r.x, r.y) for r in log.odometry], float).reshape(-1, 2)
    span = (xy.max(0) - xy.min(0)) if len(xy) else np.zeros(2)
    w, h = (np.ceil((span + 2 * reach) / resolution)).astype(int)
    return int(h), int(w)


def farthest_reading(log: CarmenLog) -> float:
    """The longest valid range reading of ``log`` (metres; 0 if none).

    A map reaches no farther from the path than this, whatever range the backend is
    allowed: the graph backend defaults to the sensor maximum (50 m on the Radish logs,
    whose no-returns read as invalid), which as a margin would inflate
    :func:`map_shape_estimate` several times over.

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
    **options,
) -> SlamResult:
    """Replay ``log`` through the backend registered as ``backend``; no ground truth is used.

    ``max_range`` is the usable laser range: GMapping's ``maxUrange`` for ``rbpf``,
    default :func:`default_usable_range` (3 m for TurtleBot3's 3.5 m LDS-01, as its
    configuration; 10 m for a long-range scanner such as the 50 m SICK of the
    Radish logs); the graph backend's ``max_range``, default the sensor maximum.
    ``rbpf`` matches every beam of a scanner of at most 200 beams (``lskip`` 0:
    the default ``lskip`` 1 is for the LDS-01's 360). Other keyword options go to
    the backend's parameters. A map too large for the memory budget (its extent
    from :func:`map_shape_estimate`) is refused before any grid is allocated, naming
    ``source`` (the log file).

    Parameters
    ----------
    log : CarmenLog
        The recorded run (odometry and scans).
    backend : str
        Registered mapper name (``"rbpf"``, ``"graph"``).
    particles : int, optional
        Particle count of ``rbpf``.
    resolution : float
        Map cell size, metres.
    seed : int
        Seed of the backend's random steps.
    max_range : float, optional
        Usable laser range (above).
    progress : bool
        Show a tqdm progress bar.
    source : str or path, optional
        The log file, named in a size refusal.
    **options
        Backend parameters.

    Returns
    -------
    SlamResult
        Map, estimated trajectory and raw odometry in the map frame, the mapper.

    Raises
    ------
    InputError
        Options refused by :func:`check_options`, or a log without scans.

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

    check_options(backend, particles=particles, resolution=resolution, max_range=max_range)
    if len(log) == 0:
        raise InputError(None, "log holds no scans")
    sensor_max = float(log.scans[0].range_max)
    if backend == "rbpf":
        options.setdefault("particles", particles)
        options.setdefault("max_urange", max_range or default_usable_range(sensor_max))
        if log.scans[0].n_beams <= 200:
            options.setdefault("lskip", 0)
    elif backend == "graph":
        options.setdefault("max_range", max_range or sensor_max)
    reach = min(
        float(options.get("max_urange", options.get("max_range", sensor_max))),
        farthest_reading(log),
    )
    check_map_size(
        map_shape_estimate(log, resolution, float(reach)),
        source if source is not None else "log",
        "slam",
        way_out="give a coarser `resolution`",
    )
    mapper = make_mapper(backend, resolution=resolution, seed=seed, **options)
    for odo, scan in tqdm(
        log, total=len(log), desc=f"slam ({backend})", unit="scan", disable=not progress
    ):
        mapper.update(odo, scan)
    if hasattr(mapper, "optimize"):
        mapper.optimize()
    traj = mapper.trajectory() if hasattr(mapper, "trajectory") else np.zeros((0, 4))
    return SlamResult(mapper.get_map(), traj, odometry_in_map_frame(log), mapper, backend)
