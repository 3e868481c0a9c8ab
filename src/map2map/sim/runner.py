"""One simulated run: robot + lidar + odometry + mapper + explorer (or a route).

:func:`simulate` drives a TurtleBot3 through a plan and returns a
:class:`SimResult`; :func:`save_run` writes everything a user needs (the map in
the plan's frame, both trajectories, the CARMEN log, a report and figures).

Time advances in control steps of ``1 / control_hz`` seconds (5 Hz): the robot
moves (swept collision checks), the wheel odometry integrates the executed
motion, people walk. Every ``control_hz / rate_hz`` steps (5 Hz for the LDS-01)
the lidar takes a scan at the true pose, the mapper gets ``(odometry, scan)``
(the oracle also the true pose) and is asked for its pose estimate; the explorer
asks for the map when it replans (every 2 s, or when needed).

Frames: the plan frame is the world; the odometry frame and the mapper's frame
both start at the robot's true start pose, so a mapper's map is put into the
plan frame with that pose (:func:`map2map.sim.mapping.resample_to_frame`).

Examples
--------
>>> import numpy as np
>>> from map2map.maps.grid import OccupancyMap
>>> data = np.full((60, 100), 255, np.uint8); data[[0, -1], :] = 0; data[:, [0, -1]] = 0
>>> res = simulate(OccupancyMap(data, 0.05), seed=1, duration=30, progress=False)
>>> res.coverage > 0.9, res.collisions
(True, 0)
"""

from __future__ import annotations

import json
import math
import os
import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from .._io import atomic_path, ensure_output_dir
from ..errors import InputError
from ..maps.grid import OccupancyMap
from ..slam.base import LaserScan, Mapper, OdometryReading
from .explore import ExploreConfig, Explorer, RouteFollower
from .lidar import Lidar, LidarConfig
from .mappers import make_mapper
from .mapping import compose, relative, resample_to_frame
from .odometry import OdometryErrors, WheelOdometry
from .robot import WAFFLE_PI, DiffDriveRobot, RobotParams
from .routes import as_waypoints
from .world import World, check_start

__all__ = ["SimResult", "simulate", "save_run", "choose_start", "validate_route", "REACH_MARGIN"]

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
        """The contents of ``report.json``."""
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
    reach keeping :data:`REACH_MARGIN` from walls."""
    from scipy import ndimage

    ok = world.clearance >= radius + 0.15
    if not ok.any():
        ok = world.clearance >= radius
    if not ok.any():
        raise InputError(None, "plan too small for the robot: no place with enough clearance")
    lab, n = ndimage.label(world.clearance >= radius + REACH_MARGIN)
    if n == 0:
        lab, n = ndimage.label(world.clearance >= radius)
    sizes = np.bincount(lab.ravel(), minlength=n + 1)
    sizes[0] = 0
    big = lab == int(np.argmax(sizes))
    cand = np.flatnonzero((ok & big).ravel())
    if not len(cand):
        cand = np.flatnonzero(big.ravel())
    k = int(cand[rng.integers(len(cand))])
    r, c = divmod(k, world.plan.width)
    x, y = world.plan.pixel_to_world([r], [c])
    return float(x[0]), float(y[0]), float(rng.uniform(-math.pi, math.pi))


def validate_route(world: World, waypoints, radius: float, source) -> np.ndarray:
    """Check a route against the plan: finite, >= 1 point, every segment clear of walls."""
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


def simulate(
    plan: OccupancyMap,
    *,
    seed: int = 0,
    duration: float = 420.0,
    fov: float = 360.0,
    mapper: str | Mapper = "oracle",
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
        A registered mapper name (:mod:`map2map.sim.mappers`) or an instance.
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

    Raises
    ------
    InputError
        Plan without free space or too small for the robot, start pose in a wall
        or outside, a route that is malformed or goes through walls, duration <= 0.
    """
    from tqdm.auto import tqdm

    t_wall = time.perf_counter()
    src = source if source is not None else "plan"
    if not (isinstance(duration, int | float) and math.isfinite(duration) and duration > 0):
        raise InputError("--duration", f"duration must be > 0 seconds, got {duration}")
    if not plan.free.any():
        raise InputError(src, "plan has no free space")
    rng = np.random.default_rng(seed)
    rng_world, rng_start, rng_lidar, rng_odo, rng_people = rng.spawn(5)
    lidar_cfg = lidar or LidarConfig(fov_deg=float(fov))
    if lidar is None and fov != 360.0:
        lidar_cfg = LidarConfig(fov_deg=float(fov))
    ecfg = explore or ExploreConfig(robot_radius=robot.radius)
    base = World.build(plan, start=(0.0, 0.0, 0.0), rng=rng_world)
    if not (base.clearance >= robot.radius).any():
        raise InputError(src, "plan too small for the robot: no place with enough clearance")
    wp = None
    if route is not None:
        wp = validate_route(base, as_waypoints(route), robot.radius, route_source or "route")
        if start is None:
            th = float(wp[0, 2]) if wp.shape[1] == 3 else 0.0
            if wp.shape[1] == 2 and len(wp) > 1:
                d = wp[1:, :2] - wp[0, :2]
                k = int(np.argmax(np.hypot(d[:, 0], d[:, 1]) > 0.05))
                th = math.atan2(d[k, 1], d[k, 0])
            start = (float(wp[0, 0]), float(wp[0, 1]), th)
    if start is None:
        start = choose_start(base, robot.radius, rng_start)
    start = tuple(float(v) for v in start)
    check_start(base, start, robot.radius, src)
    world = World.build(
        plan,
        start=start,
        obstacles=obstacles,
        people=people,
        robot_radius=robot.radius,
        rng=rng_world,
    )
    if isinstance(mapper, str):
        mapper_obj = make_mapper(mapper, resolution=plan.resolution, seed=seed)
    else:
        mapper_obj = mapper
    has_truth = hasattr(mapper_obj, "observe_truth")

    bot = DiffDriveRobot(robot, start, world)
    odo = WheelOdometry(odometry or OdometryErrors(), robot, rng=rng_odo)
    sensor = Lidar(lidar_cfg)
    if wp is not None:
        local = np.array([relative(start, (x, y, 0.0))[:2] for x, y in wp[:, :2]])
        driver: Explorer | RouteFollower = RouteFollower(local, ecfg, robot.max_v, robot.max_w)
    else:
        driver = Explorer(ecfg, robot.max_v, robot.max_w, spin_first=lidar_cfg.fov_deg < 360)

    dt = 1.0 / control_hz
    per_scan = max(1, int(round(control_hz / lidar_cfg.rate_hz)))
    n_steps = int(math.floor(duration * control_hz + 1e-9))
    times, true_p, est_p, odo_p, vel = [], [], [], [], []
    scans: list[LaserScan] = []
    readings: list[OdometryReading] = []
    frames = []
    collisions = 0
    contacts: list[tuple[float, float, float, float]] = []
    in_contact = False
    path_len = 0.0
    last_scan = None
    est = (0.0, 0.0, 0.0)
    stop_reason = "time budget"
    next_frame = 0.0
    bar = tqdm(total=int(duration), desc="simulate", unit="sim s", disable=not progress)
    t = 0.0
    for step in range(n_steps + 1):
        t = step * dt
        if step % per_scan == 0:
            if step:
                world.step_people(dt * per_scan, bot.pose[:2], rng_people)
            scan = sensor.scan(world.scene, bot.pose, t, rng_lidar)
            reading = OdometryReading(t, *odo.pose)
            if has_truth:
                mapper_obj.observe_truth(bot.pose)
            mapper_obj.update(reading, scan)
            est = tuple(float(v) for v in mapper_obj.pose())
            scans.append(scan)
            readings.append(reading)
            times.append(t)
            true_p.append(bot.pose)
            est_p.append(compose(start, est))
            odo_p.append(compose(start, odo.pose))
            vel.append((bot.v, bot.w))
            last_scan = scan
            if frame_every > 0 and t >= next_frame:
                frames.append((t, mapper_obj.get_map(), bot.pose))
                next_frame = t + frame_every
            if step:
                bar.update(int(t) - bar.n)
        if step == n_steps:
            break
        v, w = driver.command(t, est, mapper_obj, last_scan)
        if driver.done:
            stop_reason = "route done" if wp is not None else "explored"
            break
        res = bot.step(v, w, dt, world.people.circles if people else None)
        odo.step(res.ds, res.dth)
        path_len += abs(res.ds)
        if res.collided and not in_contact:
            collisions += 1
            contacts.append((t, *bot.pose))
        in_contact = res.collided
    bar.close()

    slam_map = mapper_obj.get_map()
    slam_plan = resample_to_frame(slam_map, start, plan)
    reachable = world.reachable_cells(start, robot.radius, REACH_MARGIN)
    n_reach = int(reachable.sum())
    coverage = float((slam_plan.free & reachable).sum() / n_reach) if n_reach else 0.0
    touchable = world.reachable_cells(start, robot.radius)  # no margin: every squeeze counts
    strict = float((slam_plan.free & touchable).sum() / max(int(touchable.sum()), 1))
    frames = [(ft, resample_to_frame(fm, start, plan), fp) for ft, fm, fp in frames]
    info = {
        "seed": int(seed),
        "mapper": getattr(mapper_obj, "name", type(mapper_obj).__name__),
        "fov_deg": lidar_cfg.fov_deg,
        "obstacles": len(world.furniture),
        "people": int(people),
        "mode": "route" if wp is not None else "explore",
        "replans": driver.stats.replans,
        "blacklisted_goals": len(driver.stats.blacklisted),
        "coverage_strict": round(strict, 6),
        "collision_events": [[round(float(v), 3) for v in c] for c in contacts],
    }
    return SimResult(
        plan=plan,
        world=world,
        start=start,
        times=np.array(times),
        true_poses=np.array(true_p),
        estimated_poses=np.array(est_p),
        odometry_poses=np.array(odo_p),
        scans=scans,
        odometry=readings,
        velocities=np.array(vel),
        slam_map=slam_map,
        slam_map_plan=slam_plan,
        reachable=reachable,
        coverage=coverage,
        path_length=path_len,
        collisions=collisions,
        sim_seconds=float(times[-1]) if times else 0.0,
        wall_seconds=time.perf_counter() - t_wall,
        stop_reason=stop_reason,
        frames=frames,
        info=info,
    )


# ------------------------------------------------------------------- outputs
def _write_csv(path: Path, times, poses) -> None:
    with atomic_path(path) as tmp:
        with open(tmp, "w", encoding="ascii") as f:
            f.write("t,x,y,theta\n")
            for t, (x, y, th) in zip(times, poses, strict=True):
                # float(): a numpy scalar's repr is "np.float64(0.0)", not a CSV number
                f.write(f"{float(t)!r},{float(x)!r},{float(y)!r},{float(th)!r}\n")


def plan_with_world(res: SimResult) -> OccupancyMap:
    """The plan with the furniture drawn in (what the robot actually drove through)."""
    data = res.plan.data.copy()
    for r0, r1, c0, c1 in res.world.furniture:
        data[r0:r1, c0:c1] = 0
    return res.plan.copy(data=data)


def save_figure_png(res: SimResult, path: Path) -> None:
    """Three panels: the plan with both paths, the map in the plan frame, the overlay."""
    from ..viz import draw_map, new_figure, save_figure

    plan = plan_with_world(res)
    fig, axes = new_figure(plan, ncols=3, panel_inches=4.5)
    tr, tc = res.plan.world_to_pixel_float(res.true_poses[:, 0], res.true_poses[:, 1])
    er, ec = res.plan.world_to_pixel_float(res.estimated_poses[:, 0], res.estimated_poses[:, 1])
    draw_map(axes[0], plan, title="plan (+furniture): true and estimated path")
    axes[0].plot(tc, tr, "-", color="tab:green", lw=1.2, label="true")
    axes[0].plot(ec, er, "--", color="tab:red", lw=1.0, label="estimated")
    axes[0].plot(tc[:1], tr[:1], "o", color="tab:green", ms=5)
    hits = np.array(res.info.get("collision_events") or np.zeros((0, 4)), float).reshape(-1, 4)
    if len(hits):
        hr, hc = res.plan.world_to_pixel_float(hits[:, 1], hits[:, 2])
        axes[0].plot(hc, hr, "x", color="red", ms=7, mew=2, label="collision")
    axes[0].legend(loc="upper right", fontsize=7)
    draw_map(
        axes[1],
        res.slam_map_plan,
        title=f"{res.info.get('mapper', '')} map, coverage {100 * res.coverage:.1f} %",
    )
    axes[1].plot(tc, tr, "-", color="tab:green", lw=0.8, alpha=0.7)
    rgb = np.ones((*plan.shape, 3))
    rgb[res.reachable & ~res.slam_map_plan.free] = (1.0, 0.75, 0.3)
    rgb[res.reachable & res.slam_map_plan.free] = (0.75, 0.9, 0.75)
    rgb[plan.occupied] = (0.2, 0.2, 0.2)
    rgb[res.slam_map_plan.occupied] = (0.85, 0.1, 0.1)
    axes[2].imshow(rgb, interpolation="nearest")
    axes[2].set_xticks([])
    axes[2].set_yticks([])
    axes[2].set_title("reachable: mapped (green) / missed (orange); map walls red", fontsize=9)
    fig.suptitle(
        f"{res.info.get('mode')} {res.sim_seconds:.0f} s simulated, "
        f"{res.path_length:.1f} m, {res.collisions} collisions, stop: {res.stop_reason}",
        fontsize=10,
    )
    save_figure(fig, path)


def save_gif(res: SimResult, path: Path, max_frames: int = 80) -> None:
    """An animation of the map growing over the plan (faint), with the true path so far."""
    from PIL import Image, ImageDraw

    from ..viz import map_to_rgb

    frames = res.frames
    if not frames:
        return
    step = max(1, int(math.ceil(len(frames) / max_frames)))
    frames = frames[::step]
    plan = plan_with_world(res)
    scale = max(2, int(math.ceil(480 / max(plan.width, plan.height))))
    rad = 0.2 / res.plan.resolution * scale
    tr, tc = res.plan.world_to_pixel_float(res.true_poses[:, 0], res.true_poses[:, 1])
    trail = np.column_stack([(tc + 0.5) * scale, (tr + 0.5) * scale])
    images = []
    for ft, m, pose in frames:
        rgb = map_to_rgb(m)
        ghost = m.unknown & plan.occupied  # walls not mapped yet, faintly
        rgb[ghost] = (0.55, 0.6, 0.68)
        img = Image.fromarray((rgb * 255).astype(np.uint8)).resize(
            (m.width * scale, m.height * scale), Image.NEAREST
        )
        d = ImageDraw.Draw(img)
        k = int(np.searchsorted(res.times, ft, side="right"))
        if k > 1:
            d.line([tuple(p) for p in trail[:k]], fill=(40, 150, 40), width=max(1, scale // 2))
        r, c = res.plan.world_to_pixel_float(pose[0], pose[1])
        x, y = (float(c) + 0.5) * scale, (float(r) + 0.5) * scale
        d.ellipse([x - rad, y - rad, x + rad, y + rad], outline=(200, 40, 40), width=2)
        d.line(
            [x, y, x + rad * math.cos(pose[2]), y - rad * math.sin(pose[2])],
            fill=(200, 40, 40),
            width=2,
        )
        d.text((4, 4), f"t = {ft:.0f} s", fill=(0, 0, 0))
        images.append(img)
    with atomic_path(path) as tmp:
        images[0].save(
            tmp, format="GIF", save_all=True, append_images=images[1:], duration=120, loop=0
        )


def save_run(res: SimResult, out: str | os.PathLike, *, gif: bool = False) -> dict[str, Path]:
    """Write the run's outputs into folder ``out``; returns name -> path.

    ``slam_map.yaml``/``.pgm`` (plan frame), ``trajectory_true.csv``,
    ``trajectory_estimated.csv`` (plan frame, columns ``t,x,y,theta``), ``run.log``
    (CARMEN, odometry frame, with ``TRUEPOS`` in the plan frame), ``report.json``,
    ``figure.png`` and optionally ``exploration.gif``.
    """
    from ..maps.formats import save_map
    from .carmen import write_carmen

    out = ensure_output_dir(out)
    paths = {
        "slam_map": out / "slam_map.yaml",
        "trajectory_true": out / "trajectory_true.csv",
        "trajectory_estimated": out / "trajectory_estimated.csv",
        "log": out / "run.log",
        "report": out / "report.json",
        "figure": out / "figure.png",
    }
    save_map(res.slam_map_plan, paths["slam_map"])
    _write_csv(paths["trajectory_true"], res.times, res.true_poses)
    _write_csv(paths["trajectory_estimated"], res.times, res.estimated_poses)
    write_carmen(
        paths["log"],
        zip(res.odometry, res.scans, [tuple(p) for p in res.true_poses], strict=True),
        velocities=[tuple(v) for v in res.velocities],
        params={
            "map2map_start_x": res.start[0],
            "map2map_start_y": res.start[1],
            "map2map_start_theta": res.start[2],
        },
    )
    save_figure_png(res, paths["figure"])
    if gif and res.frames:
        paths["gif"] = out / "exploration.gif"
        save_gif(res, paths["gif"])
    with atomic_path(paths["report"]) as tmp:
        tmp.write_text(json.dumps(res.report(), indent=2) + "\n")
    return paths
