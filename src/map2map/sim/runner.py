"""One simulated run: robot + lidar + odometry + mapper + explorer (or a route).

:func:`simulate` drives a TurtleBot3 through a plan and returns a
:class:`SimResult` (arrays, no files); :func:`map2map.jobs.simulate.save_run` writes
everything a user needs (the map in the plan's frame, both trajectories, the CARMEN
log, a report and figures).

Time advances in control steps of ``1 / control_hz`` seconds (5 Hz): the robot
moves (swept collision checks), the wheel odometry integrates the executed
motion, people walk. Every ``control_hz / rate_hz`` steps (5 Hz for the LDS-01)
the lidar takes a scan at the true pose, the mapper gets ``(odometry, scan)``
(the oracle also the true pose) and is asked for its pose estimate; the explorer
steers by that estimate and asks for the map when it replans (every 2 s, or when
needed). A route (``--waypoints``, ``--trajectory``) is in the plan frame, so its
follower steers by the true pose, as a robot localized in the known plan would: steered
by the SLAM estimate, a robot replaying its own true path drifted with the estimate
(0.3 m in a door of a generated apartment) and stuck in door frames.

Frames: the plan frame is the world; the odometry frame and the mapper's frame
both start at the robot's true start pose, so a mapper's map is put into the
plan frame with that pose (:func:`map2map.sim.mapping.resample_to_frame`).

Examples
--------
>>> import numpy as np
>>> from map2map.core.grid import OccupancyMap
>>> data = np.full((60, 100), 255, np.uint8); data[[0, -1], :] = 0; data[:, [0, -1]] = 0
>>> res = simulate(OccupancyMap(data, 0.05), mapper="oracle", seed=1, duration=30, progress=False)
>>> res.coverage > 0.9, res.collisions
(True, 0)
"""

from __future__ import annotations

import math
import os
import time
import warnings
from dataclasses import dataclass, field, fields, replace
from typing import Any

import numpy as np

from ..core.errors import InputError, MapWarning
from ..core.geometry import compose_pose, relative_pose
from ..core.grid import OccupancyMap
from ..robotlog.base import LaserScan, Mapper, OdometryReading
from ..robotlog.mappers import make_mapper
from .explore import ExploreConfig, Explorer, RouteFollower
from .lidar import Lidar, LidarConfig
from .mapping import resample_to_frame
from .odometry import OdometryErrors, WheelOdometry
from .robot import WAFFLE_PI, DiffDriveRobot, RobotParams
from .routes import as_waypoints
from .world import World, check_start

__all__ = ["SimConfig", "SimResult", "simulate", "choose_start", "validate_route", "REACH_MARGIN"]

#: Clearance (m) beyond the robot radius that "reachable" free space requires: the
#: coverage reference is what a navigation stack keeping 5 cm from walls can reach.
REACH_MARGIN = 0.05


@dataclass
class SimResult:
    """Everything a run produced.

    Attributes
    ----------
    plan : OccupancyMap
        The input plan.
    world : World
        Plan plus furniture and people.
    start : (x, y, theta)
        True start pose (plan frame) = origin of the odometry and map frames.
    times : (N,) array
        Scan times (s).
    true_poses, estimated_poses, odometry_poses : (N, 3) arrays
        Per scan, in the plan frame (odometry and estimates transformed with ``start``).
    scans : list of LaserScan
    odometry : list of OdometryReading
        Raw odometry readings (odometry frame) as the mapper received them.
    velocities : (N, 2) array
        ``(v, w)`` of the robot at each scan.
    slam_map : OccupancyMap
        The mapper's final map in its own frame.
    slam_map_plan : OccupancyMap
        The same map resampled onto the plan's grid.
    reachable : (H, W) bool
        Plan cells the robot's body can reach keeping :data:`REACH_MARGIN` from
        walls (the coverage reference, see :meth:`World.reachable_cells`).
    coverage : float
        Fraction of ``reachable`` the final map marks free.
    path_length : float
        Metres driven (true).
    collisions : int
        Contact events with walls or furniture (times and poses in
        ``info["collision_events"]``).
    sim_seconds, wall_seconds : float
    stop_reason : str
        ``"explored"``, ``"route done"`` or ``"time budget"``.
    frames : list
        ``(t, map in plan frame, true pose)`` snapshots for the animation.
    info : dict
        Parameters and counters for the report.
    """

    plan: OccupancyMap
    world: World
    start: tuple[float, float, float]
    times: np.ndarray
    true_poses: np.ndarray
    estimated_poses: np.ndarray
    odometry_poses: np.ndarray
    scans: list[LaserScan]
    odometry: list[OdometryReading]
    velocities: np.ndarray
    slam_map: OccupancyMap
    slam_map_plan: OccupancyMap
    reachable: np.ndarray
    coverage: float
    path_length: float
    collisions: int
    sim_seconds: float
    wall_seconds: float
    stop_reason: str
    frames: list = field(default_factory=list)
    info: dict[str, Any] = field(default_factory=dict)

    def report(self) -> dict[str, Any]:
        """The contents of ``report.json``.

        Returns
        -------
        dict
        """
        err = self.estimated_poses[:, :2] - self.true_poses[:, :2]
        return {
            "coverage": round(self.coverage, 6),
            "path_length_m": round(self.path_length, 4),
            "collisions": self.collisions,
            "simulated_seconds": round(self.sim_seconds, 3),
            "wall_seconds": round(self.wall_seconds, 3),
            "stop_reason": self.stop_reason,
            "scans": len(self.scans),
            "ate_rmse_m": round(float(np.sqrt((err**2).sum(axis=1).mean())), 6),
            "reachable_free_m2": round(float(self.reachable.sum()) * self.plan.resolution**2, 3),
            "start_pose": [round(v, 6) for v in self.start],
            **self.info,
        }


def choose_start(world: World, radius: float, rng: np.random.Generator):
    """A random start pose with room around it, in the largest region the robot can
    reach keeping :data:`REACH_MARGIN` from walls.

    Parameters
    ----------
    world : World
        The plan with its clearance.
    radius : float
        Robot radius, metres.
    rng : numpy.random.Generator
        Source of the draw.

    Returns
    -------
    (x, y, theta)
        Plan frame.

    Raises
    ------
    InputError
        No place with enough clearance.
    """
    from scipy import ndimage

    room = world.clearance >= radius
    rows, cols = np.flatnonzero(room.any(axis=1)), np.flatnonzero(room.any(axis=0))
    if rows.size == 0:
        raise InputError(None, "plan too small for the robot: no place with enough clearance")
    # every set below lies within `room`: its bounding box keeps their cells in the same
    # (row-major) order, the labels in the same order, so the same draw picks the same cell
    r0, c0 = int(rows[0]), int(cols[0])
    clear = world.clearance[r0 : int(rows[-1]) + 1, c0 : int(cols[-1]) + 1]
    ok = clear >= radius + 0.15
    if not ok.any():
        ok = clear >= radius
    lab, n = ndimage.label(clear >= radius + REACH_MARGIN)
    if n == 0:
        lab, n = ndimage.label(clear >= radius)
    sizes = np.bincount(lab.ravel(), minlength=n + 1)
    sizes[0] = 0
    big = lab == int(np.argmax(sizes))
    cand = np.flatnonzero((ok & big).ravel())
    if not len(cand):
        cand = np.flatnonzero(big.ravel())
    k = int(cand[rng.integers(len(cand))])
    r, c = divmod(k, clear.shape[1])
    r, c = r + r0, c + c0
    x, y = world.plan.pixel_to_world([r], [c])
    return float(x[0]), float(y[0]), float(rng.uniform(-math.pi, math.pi))


def validate_route(world: World, waypoints, radius: float, source) -> np.ndarray:
    """Check a route against the plan: finite, >= 1 point, every segment clear of walls.

    Parameters
    ----------
    world : World
        The plan with its clearance.
    waypoints : array-like
        ``(N, 2)`` or ``(N, 3)`` points, plan frame.
    radius : float
        Clearance the robot needs, metres.
    source : path-like or str
        Named in errors.

    Returns
    -------
    (N, 2) or (N, 3) float array

    Raises
    ------
    InputError
        Malformed route, a point or segment outside the plan or through a wall.
    """
    try:
        wp = np.asarray(waypoints, float)
    except (TypeError, ValueError):
        raise InputError(source, "route must be a list of (x, y) or (x, y, theta)") from None
    if wp.ndim != 2 or wp.shape[0] < 1 or wp.shape[1] not in (2, 3):
        raise InputError(source, "route must be a list of (x, y) or (x, y, theta) points")
    if not np.isfinite(wp).all():
        raise InputError(source, "route has non-finite coordinates")
    res = world.plan.resolution
    for i in range(len(wp)):
        a = wp[i, :2]
        b = wp[min(i + 1, len(wp) - 1), :2]
        n = max(1, int(math.ceil(np.hypot(*(b - a)) / (res / 2))))
        f = np.linspace(0, 1, n + 1)
        pts = a + (b - a) * f[:, None]
        r, c = world.plan.world_to_pixel(pts[:, 0], pts[:, 1])
        if not world.plan.contains(r, c).all():
            raise InputError(source, f"route point {i + 1} or its segment leaves the plan")
        bad = world.clearance_at(pts[:, 0], pts[:, 1]) < radius
        if bad.any():
            k = int(np.argmax(bad))
            raise InputError(
                source,
                f"route goes through a wall near ({pts[k, 0]:.2f}, {pts[k, 1]:.2f}) "
                f"(segment {i + 1}; the robot needs {radius:.2f} m of clearance)",
            )
    return wp


@dataclass(frozen=True)
class SimConfig:
    """The knobs of :func:`simulate` in one value (a dataset builder keeps one per split).

    Every field is a keyword argument of :func:`simulate` with the same default;
    ``simulate(plan, config=cfg)`` runs with ``cfg`` and ``simulate(plan, seed=3)``
    builds one. See :func:`simulate` for the meaning of each field.

    Examples
    --------
    >>> cfg = SimConfig(mapper="oracle", duration=30.0, progress=False)
    >>> cfg.seed, cfg.control_hz, cfg.lidar_config().fov_deg
    (0, 5.0, 360.0)
    >>> SimConfig(fov=180.0).lidar_config().fov_deg
    180.0
    """

    seed: int = 0
    duration: float = 420.0
    fov: float = 360.0
    mapper: str | Mapper = "rbpf"
    obstacles: int = 0
    people: int = 0
    lidar: LidarConfig | None = None
    odometry: OdometryErrors | None = None
    robot: RobotParams = WAFFLE_PI
    explore: ExploreConfig | None = None
    control_hz: float = 5.0
    frame_every: float = 0.0
    progress: bool = True

    def lidar_config(self) -> LidarConfig:
        """``lidar``, or the LDS-01 defaults with the field of view ``fov``.

        Returns
        -------
        LidarConfig
        """
        return self.lidar or LidarConfig(fov_deg=float(self.fov))


_KNOBS = tuple(f.name for f in fields(SimConfig))


def simulate(
    plan: OccupancyMap,
    *,
    seed: int = 0,
    duration: float = 420.0,
    fov: float = 360.0,
    mapper: str | Mapper = "rbpf",
    route=None,
    obstacles: int = 0,
    people: int = 0,
    start=None,
    lidar: LidarConfig | None = None,
    odometry: OdometryErrors | None = None,
    robot: RobotParams = WAFFLE_PI,
    explore: ExploreConfig | None = None,
    control_hz: float = 5.0,
    frame_every: float = 0.0,
    progress: bool = True,
    source: str | os.PathLike | None = None,
    route_source: str | os.PathLike | None = None,
    config: SimConfig | None = None,
) -> SimResult:
    """Simulate one run of a TurtleBot3 exploring ``plan`` (or following ``route``).

    Parameters
    ----------
    plan : OccupancyMap
        Free cells are where the robot may drive; occupied cells are walls.
    seed : int
        Seeds every random step (start pose, furniture, people, noise, SLAM).
    duration : float
        Simulated time budget in seconds (thesis: 7 minutes).
    fov : float
        Lidar field of view in degrees (360 for the LDS-01, 180 in the thesis).
    mapper : str or Mapper
        A registered mapper name (:mod:`map2map.robotlog.mappers`) or an instance;
        default ``"rbpf"``, the GMapping-style particle filter (as ``map2map simulate``).
    route : array-like or trajectory, optional
        Waypoints ``(x, y[, theta])`` in the plan frame to drive instead of exploring
        (anything :func:`map2map.sim.routes.as_waypoints` accepts, e.g. a PRM route).
    obstacles, people : int
        Random furniture boxes and walking people (seeded).
    start : (x, y, theta), optional
        True start pose in the plan frame; default: the route's first point, else
        a random pose with room around it.
    lidar, odometry, robot, explore : optional
        Sensor, odometry error, robot and exploration parameters (defaults:
        LDS-01, :class:`OdometryErrors` defaults, Waffle Pi, explore_lite).
    control_hz : float
        Physics and control rate (default 5 Hz, the scan rate: at most 5 cm of
        motion per step, swept collision checks make larger steps safe).
    frame_every : float
        Simulated seconds between animation frames (0: none).
    progress : bool
        Show a tqdm progress bar (simulated seconds).
    source, route_source : path, optional
        Names used in error messages (the plan file, the route file).
    config : SimConfig, optional
        All the knobs above (``seed`` to ``progress``) in one value; a knob also
        given as a keyword with a value other than its default overrides ``config``.

    Returns
    -------
    SimResult
        Trajectories (true, estimated, odometry), scans, odometry readings, the
        mapper's map (own frame and resampled onto the plan), coverage of the
        reachable free space, collisions and the report's counters.

    Raises
    ------
    InputError
        Plan without free space or too small for the robot, start pose in a wall
        or outside, a route that is malformed or goes through walls, duration <= 0.

    Examples
    --------
    >>> import numpy as np
    >>> data = np.full((60, 100), 255, np.uint8); data[[0, -1], :] = 0; data[:, [0, -1]] = 0
    >>> cfg = SimConfig(mapper="oracle", seed=2, duration=10, progress=False)
    >>> res = simulate(OccupancyMap(data, 0.05), config=cfg)
    >>> res.info["mapper"], len(res.scans)
    ('oracle', 46)
    """
    t_wall = time.perf_counter()
    given = locals()
    cfg = _config(config, {k: given[k] for k in _KNOBS})
    src = source if source is not None else "plan"
    duration = cfg.duration
    if not (isinstance(duration, int | float) and math.isfinite(duration) and duration > 0):
        raise InputError("duration", f"duration must be > 0 seconds, got {duration}")
    if not plan.free.any():
        raise InputError(src, "plan has no free space")
    setup = _set_up(plan, cfg, route, start, src, route_source)
    trace = _drive(setup, cfg)
    res = _result(plan, setup, trace, cfg, t_wall)
    if res.stop_reason == "time budget" and setup.waypoints is not None:
        drv = setup.driver
        warnings.warn(
            f"{route_source or 'route'}: not completed within the time budget (`duration` "
            f"{duration:g} s): the robot got {drv.progress():.1f} m along its "
            f"{drv.length:.1f} m ({100 * drv.progress() / max(drv.length, 1e-9):.0f} %); "
            "a longer `duration` lets it finish",
            MapWarning,
            stacklevel=2,
        )
    return res


def _config(config: SimConfig | None, knobs: dict[str, Any]) -> SimConfig:
    """``config`` with the knobs given as keywords (non-default values) applied."""
    if config is None:
        return SimConfig(**knobs)
    defaults = SimConfig()
    changed = {k: v for k, v in knobs.items() if not _same(v, getattr(defaults, k))}
    return replace(config, **changed) if changed else config


def _same(a, b) -> bool:
    """``a`` is the default ``b`` (same type, equal)."""
    if a is b:
        return True
    try:
        return bool(a == b) and type(a) is type(b)
    except Exception:  # noqa: BLE001 - arrays, odd objects: not the default
        return False


@dataclass
class _Setup:
    """What a run starts from: the world, the start pose, the robot and its parts."""

    world: World
    start: tuple[float, float, float]
    waypoints: np.ndarray | None
    mapper: Mapper
    bot: DiffDriveRobot
    odo: WheelOdometry
    sensor: Lidar
    lidar: LidarConfig
    driver: Explorer | RouteFollower
    rng_lidar: np.random.Generator
    rng_people: np.random.Generator


def _route_start(wp: np.ndarray) -> tuple[float, float, float]:
    """Start pose of a route: its first point, heading to the first point 5 cm away."""
    th = float(wp[0, 2]) if wp.shape[1] == 3 else 0.0
    if wp.shape[1] == 2 and len(wp) > 1:
        d = wp[1:, :2] - wp[0, :2]
        k = int(np.argmax(np.hypot(d[:, 0], d[:, 1]) > 0.05))
        th = math.atan2(d[k, 1], d[k, 0])
    return float(wp[0, 0]), float(wp[0, 1]), th


def _set_up(plan, cfg: SimConfig, route, start, src, route_source) -> _Setup:
    """World, start pose, mapper, robot, odometry, lidar and driver (explorer or route).

    The random streams are spawned from ``cfg.seed`` in a fixed order (world, start,
    lidar, odometry, people), so the same seed gives the same run bit for bit.
    """
    robot = cfg.robot
    rng = np.random.default_rng(cfg.seed)
    rng_world, rng_start, rng_lidar, rng_odo, rng_people = rng.spawn(5)
    lidar_cfg = cfg.lidar_config()
    ecfg = cfg.explore or ExploreConfig(robot_radius=robot.radius)
    base = World.build(plan, start=(0.0, 0.0, 0.0), rng=rng_world)
    if not (base.clearance >= robot.radius).any():
        raise InputError(src, "plan too small for the robot: no place with enough clearance")
    wp = None
    if route is not None:
        wp = validate_route(base, as_waypoints(route), robot.radius, route_source or "route")
        if start is None:
            start = _route_start(wp)
    if start is None:
        start = choose_start(base, robot.radius, rng_start)
    start = tuple(float(v) for v in start)
    check_start(base, start, robot.radius, src)
    world = base  # nothing to add: the same world (its build drew nothing from rng_world)
    if cfg.obstacles or cfg.people:
        world = World.build(
            plan,
            start=start,
            obstacles=cfg.obstacles,
            people=cfg.people,
            robot_radius=robot.radius,
            rng=rng_world,
        )
    mapper = cfg.mapper
    if isinstance(mapper, str):
        mapper = make_mapper(mapper, resolution=plan.resolution, seed=cfg.seed)
    if wp is not None:
        local = np.array([relative_pose(start, (x, y, 0.0))[:2] for x, y in wp[:, :2]])
        driver: Explorer | RouteFollower = RouteFollower(local, ecfg, robot.max_v, robot.max_w)
    else:
        driver = Explorer(ecfg, robot.max_v, robot.max_w, spin_first=lidar_cfg.fov_deg < 360)
    return _Setup(
        world=world,
        start=start,
        waypoints=wp,
        mapper=mapper,
        bot=DiffDriveRobot(robot, start, world),
        odo=WheelOdometry(cfg.odometry or OdometryErrors(), robot, rng=rng_odo),
        sensor=Lidar(lidar_cfg),
        lidar=lidar_cfg,
        driver=driver,
        rng_lidar=rng_lidar,
        rng_people=rng_people,
    )


@dataclass
class _Trace:
    """What the control loop recorded, per scan and per contact."""

    times: list = field(default_factory=list)
    true_p: list = field(default_factory=list)
    est_p: list = field(default_factory=list)
    odo_p: list = field(default_factory=list)
    vel: list = field(default_factory=list)
    scans: list[LaserScan] = field(default_factory=list)
    readings: list[OdometryReading] = field(default_factory=list)
    frames: list = field(default_factory=list)
    collisions: int = 0
    contacts: list[tuple[float, float, float, float]] = field(default_factory=list)
    path_len: float = 0.0
    stop_reason: str = "time budget"


def _drive(s: _Setup, cfg: SimConfig) -> _Trace:
    """The control loop (module docstring): move, integrate odometry, scan, map, replan."""
    from tqdm.auto import tqdm

    world, bot, odo, mapper, driver, start = s.world, s.bot, s.odo, s.mapper, s.driver, s.start
    has_truth = hasattr(mapper, "observe_truth")
    control_hz, duration = cfg.control_hz, cfg.duration
    dt = 1.0 / control_hz
    per_scan = max(1, int(round(control_hz / s.lidar.rate_hz)))
    n_steps = int(math.floor(duration * control_hz + 1e-9))
    tr = _Trace()
    in_contact = False
    last_scan = None
    est = (0.0, 0.0, 0.0)
    next_frame = 0.0
    bar = tqdm(total=int(duration), desc="simulate", unit="sim s", disable=not cfg.progress)
    t = 0.0
    for step in range(n_steps + 1):
        t = step * dt
        if step % per_scan == 0:
            if step:
                world.step_people(dt * per_scan, bot.pose[:2], s.rng_people)
            scan = s.sensor.scan(world.scene, bot.pose, t, s.rng_lidar)
            reading = OdometryReading(t, *odo.pose)
            if has_truth:
                mapper.observe_truth(bot.pose)
            mapper.update(reading, scan)
            est = tuple(float(v) for v in mapper.pose())
            tr.scans.append(scan)
            tr.readings.append(reading)
            tr.times.append(t)
            tr.true_p.append(bot.pose)
            tr.est_p.append(compose_pose(start, est))
            tr.odo_p.append(compose_pose(start, odo.pose))
            tr.vel.append((bot.v, bot.w))
            last_scan = scan
            if cfg.frame_every > 0 and t >= next_frame:
                tr.frames.append((t, mapper.get_map(), bot.pose))
                next_frame = t + cfg.frame_every
            if step:
                bar.update(int(t) - bar.n)
        if step == n_steps:
            break
        # a route is in the plan frame: its follower is localized there (the true pose, as
        # a robot localized in the known plan), the explorer in its own map (the estimate)
        here = relative_pose(start, bot.pose) if s.waypoints is not None else est
        v, w = driver.command(t, here, mapper, last_scan)
        if driver.done:
            tr.stop_reason = "route done" if s.waypoints is not None else "explored"
            break
        res = bot.step(v, w, dt, world.people.circles if cfg.people else None)
        odo.step(res.ds, res.dth)
        tr.path_len += abs(res.ds)
        if res.collided and not in_contact:
            tr.collisions += 1
            tr.contacts.append((t, *bot.pose))
        in_contact = res.collided
    bar.close()
    return tr


def _result(plan, s: _Setup, tr: _Trace, cfg: SimConfig, t_wall: float) -> SimResult:
    """The :class:`SimResult`: final map in the plan frame, coverage, report counters."""
    world, start, mapper, driver = s.world, s.start, s.mapper, s.driver
    radius = cfg.robot.radius
    slam_map = mapper.get_map()
    slam_plan = resample_to_frame(slam_map, start, plan)
    reachable = world.reachable_cells(start, radius, REACH_MARGIN)
    n_reach = int(reachable.sum())
    coverage = float((slam_plan.free & reachable).sum() / n_reach) if n_reach else 0.0
    touchable = world.reachable_cells(start, radius)  # no margin: every squeeze counts
    strict = float((slam_plan.free & touchable).sum() / max(int(touchable.sum()), 1))
    frames = [(ft, resample_to_frame(fm, start, plan), fp) for ft, fm, fp in tr.frames]
    info = {
        "seed": int(cfg.seed),
        "mapper": getattr(mapper, "name", type(mapper).__name__),
        "fov_deg": s.lidar.fov_deg,
        "obstacles": len(world.furniture),
        "people": int(cfg.people),
        "mode": "route" if s.waypoints is not None else "explore",
        **({"route_length_m": round(driver.length, 4),
            "route_driven_m": round(driver.progress(), 4)} if s.waypoints is not None else {}),
        "replans": driver.stats.replans,
        "blacklisted_goals": len(driver.stats.blacklisted),
        "coverage_strict": round(strict, 6),
        "collision_events": [[round(float(v), 3) for v in c] for c in tr.contacts],
    }
    return SimResult(
        plan=plan,
        world=world,
        start=start,
        times=np.array(tr.times),
        true_poses=np.array(tr.true_p),
        estimated_poses=np.array(tr.est_p),
        odometry_poses=np.array(tr.odo_p),
        scans=tr.scans,
        odometry=tr.readings,
        velocities=np.array(tr.vel),
        slam_map=slam_map,
        slam_map_plan=slam_plan,
        reachable=reachable,
        coverage=coverage,
        path_length=tr.path_len,
        collisions=tr.collisions,
        sim_seconds=float(tr.times[-1]) if tr.times else 0.0,
        wall_seconds=time.perf_counter() - t_wall,
        stop_reason=tr.stop_reason,
        frames=frames,
        info=info,
    )
