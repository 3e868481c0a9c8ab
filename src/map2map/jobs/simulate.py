"""``map2map simulate`` as a job: read the plan and route, simulate, write the run's files.

:func:`simulate` takes a :class:`SimulateSpec` and returns a :class:`SimulateRun`: the
files written (``written``) and the in-memory :class:`~map2map.sim.runner.SimResult`.
:func:`save_run` writes a result: ``slam_map.yaml``/``.pgm`` (plan frame),
``trajectory_true.csv``, ``trajectory_estimated.csv`` (``t,x,y,theta``), ``run.log``
(CARMEN), ``report.json``, ``figure.png``, optionally ``exploration.gif`` and the log as a
ROS bag (``run.bag`` or the ROS 2 folder ``run_bag``, :mod:`map2map.robotlog.rosbag`).

Examples
--------
>>> import numpy as np, tempfile, pathlib
>>> from map2map.core.grid import OccupancyMap
>>> data = np.full((60, 100), 255, np.uint8); data[[0, -1], :] = 0; data[:, [0, -1]] = 0
>>> out = pathlib.Path(tempfile.mkdtemp())
>>> run = simulate(SimulateSpec(OccupancyMap(data, 0.05), out, duration=5, mapper="oracle",
...                             figures=False, progress=False))
>>> sorted(run.written), run.result.collisions
(['log', 'report', 'slam_map', 'trajectory_estimated', 'trajectory_true'], 0)
"""

from __future__ import annotations

import json
import math
import os
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from ..core._io import atomic_dir, atomic_path, check_output_dir, ensure_output_dir
from ..core.errors import InputError
from ..core.grid import OccupancyMap
from ..maps.formats import save_map
from ..robotlog.carmen import write_carmen
from ..sim.runner import SimResult
from ..sim.runner import simulate as run_simulation
from ._common import check_seed, final_paths

__all__ = ["SimulateSpec", "SimulateRun", "simulate", "save_run", "save_figure_png", "save_gif"]


@dataclass
class SimulateSpec:
    """What ``map2map simulate`` is asked to do.

    ``plan`` is a file (any format :func:`map2map.maps.formats.load_map` reads, with
    ``load_options``) or an :class:`OccupancyMap`. Route and start coordinates are in
    the plan's own world frame (for a HouseExpo JSON plan: HouseExpo's x, y, theta,
    converted by :func:`map2map.maps.houseexpo.houseexpo_to_world`). ``figures=False``
    skips ``figure.png`` and the gif (a dataset builder's choice). ``plan_name`` names
    an in-memory plan in error messages. ``bag`` (a format of
    :data:`~map2map.robotlog.rosbag.BAG_FORMATS`) also writes the log as a ROS bag.
    """

    plan: str | os.PathLike | OccupancyMap
    out: str | os.PathLike
    plan_name: str | os.PathLike | None = None
    seed: int = 0
    duration: float = 420.0
    fov: float = 360.0
    mapper: str = "rbpf"
    waypoints: str | os.PathLike | None = None
    trajectory: str | os.PathLike | None = None
    start: tuple[float, float, float] | None = None
    obstacles: int = 0
    people: int = 0
    gif: bool = False
    figures: bool = True
    progress: bool = True
    load_options: dict = field(default_factory=dict)
    #: Also write the log as a ROS bag: "ros1" (run.bag), "ros2" or "mcap" (run_bag/).
    bag: str | None = None


@dataclass
class SimulateRun:
    """What :func:`simulate` wrote (name -> path) and the simulated run itself."""

    written: dict[str, Path]
    result: SimResult


def simulate(spec: SimulateSpec) -> SimulateRun:
    """Run ``map2map simulate``: every input and the output folder checked before any work.

    Parameters
    ----------
    spec : SimulateSpec
        Plan, route, robot and mapper settings, output folder.

    Returns
    -------
    SimulateRun
        ``written`` (name -> path under ``spec.out``) and the
        :class:`~map2map.sim.runner.SimResult`.

    Raises
    ------
    InputError
        A bad parameter, plan, route or output folder (nothing is written). The
        outputs go to a temporary folder renamed whole at the end
        (:func:`map2map.core._io.atomic_dir`: an existing folder is replaced).
    """
    from ..maps.formats import load_map
    from ..maps.houseexpo import is_houseexpo, plan_poses_to_world
    from ..sim.routes import read_route

    check_seed(spec.seed)
    if spec.waypoints is not None and spec.trajectory is not None:
        raise InputError(None, "use only one of waypoints, trajectory")
    inputs = (spec.plan_name if isinstance(spec.plan, OccupancyMap) else spec.plan,
              spec.waypoints, spec.trajectory)  # fmt: skip
    check_output_dir(spec.out, protect=inputs)
    if spec.bag is not None:
        from ..robotlog.rosbag import check_bag_format

        check_bag_format(spec.bag, "bag")
    if not (math.isfinite(spec.duration) and spec.duration > 0):
        raise InputError("duration", f"duration must be > 0 seconds, got {spec.duration:g}")
    if spec.obstacles < 0 or spec.people < 0:
        raise InputError("obstacles/people", "counts must be >= 0")
    if isinstance(spec.plan, OccupancyMap):
        plan, source = spec.plan, spec.plan_name
    else:
        plan, source = load_map(spec.plan, **spec.load_options), spec.plan
    route, route_file = None, None
    if spec.waypoints or spec.trajectory:
        route_file = spec.waypoints or spec.trajectory
        route = read_route(route_file, "waypoints" if spec.waypoints else "trajectory")
    start = tuple(spec.start) if spec.start is not None else None
    if is_houseexpo(plan):  # HouseExpo's frame has y down: route and start to the ROS frame
        route = None if route is None else plan_poses_to_world(route)
        start = None if start is None else tuple(plan_poses_to_world(np.array([start]))[0])
    res = run_simulation(
        plan,
        seed=spec.seed,
        duration=spec.duration,
        fov=spec.fov,
        mapper=spec.mapper,
        route=route,
        obstacles=spec.obstacles,
        people=spec.people,
        start=start,
        frame_every=2.0 if (spec.gif and spec.figures) else 0.0,
        progress=spec.progress,
        source=source,
        route_source=route_file,
    )
    with atomic_dir(spec.out, protect=inputs) as tmp:
        written = save_run(res, tmp, gif=spec.gif, figures=spec.figures, bag=spec.bag)
    return SimulateRun(final_paths(written, tmp, spec.out), res)


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
    """Three panels: the plan with both paths, the map in the plan frame, the overlay.

    Drawn with OpenCV and Pillow (:mod:`map2map.core.viz_raster`), not matplotlib: a
    ``map2map simulate`` process spends about 0.6 CPU seconds less (imports and
    drawing), which counts when thousands of runs build a data set.
    """
    from ..core.viz_raster import Panel, map_to_rgb8, rgb8, save_panels

    plan = plan_with_world(res)
    tr, tc = res.plan.world_to_pixel_float(res.true_poses[:, 0], res.true_poses[:, 1])
    er, ec = res.plan.world_to_pixel_float(res.estimated_poses[:, 0], res.estimated_poses[:, 1])
    green, red = (0.17, 0.63, 0.17), (0.84, 0.15, 0.16)  # matplotlib's tab:green, tab:red
    p0 = Panel(
        map_to_rgb8(plan),
        title="plan (+furniture): true and estimated path",
        resolution=plan.resolution,
    )
    p0.line(tr, tc, colour=green, width=2)
    p0.line(er, ec, colour=red, width=1, dashed=True)
    p0.markers(tr[:1], tc[:1], colour=green, size=9)
    legend = [("true", green, "-"), ("estimated", red, "--")]
    hits = np.array(res.info.get("collision_events") or np.zeros((0, 4)), float).reshape(-1, 4)
    if len(hits):
        hr, hc = res.plan.world_to_pixel_float(hits[:, 1], hits[:, 2])
        p0.markers(hr, hc, colour=(1.0, 0.0, 0.0), marker="x", size=11)
        legend.append(("collision", (1.0, 0.0, 0.0), "x"))
    p0.legend(legend)
    p1 = Panel(
        map_to_rgb8(res.slam_map_plan),
        title=f"{res.info.get('mapper', '')} map, coverage {100 * res.coverage:.1f} %",
        resolution=res.slam_map_plan.resolution,
    )
    p1.line(tr, tc, colour=green, width=1, alpha=0.7)
    # uint8 colours as the Panel would round them: no float image of a 12 MP plan
    rgb = np.full((*plan.shape, 3), 255, np.uint8)
    rgb[res.reachable & ~res.slam_map_plan.free] = rgb8((1.0, 0.75, 0.3))
    rgb[res.reachable & res.slam_map_plan.free] = rgb8((0.75, 0.9, 0.75))
    rgb[plan.occupied] = rgb8((0.2, 0.2, 0.2))
    rgb[res.slam_map_plan.occupied] = rgb8((0.85, 0.1, 0.1))
    p2 = Panel(rgb, title="reachable: mapped (green) / missed (orange); map walls red")
    save_panels(
        [p0, p1, p2],
        path,
        title=f"{res.info.get('mode')} {res.sim_seconds:.0f} s simulated, "
        f"{res.path_length:.1f} m, {res.collisions} collisions, stop: {res.stop_reason}",
    )


def save_gif(res: SimResult, path: Path, max_frames: int = 80) -> None:
    """An animation of the map growing over the plan (faint), with the true path so far."""
    from PIL import Image, ImageDraw

    from ..core.viz_raster import map_to_rgb

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


def save_run(
    res: SimResult,
    out: str | os.PathLike,
    *,
    gif: bool = False,
    figures: bool = True,
    bag: str | None = None,
) -> dict[str, Path]:
    """Write the run's outputs into folder ``out``; returns name -> path.

    ``slam_map.yaml``/``.pgm`` (plan frame), ``trajectory_true.csv``,
    ``trajectory_estimated.csv`` (plan frame, columns ``t,x,y,theta``), ``run.log``
    (CARMEN, odometry frame, with ``TRUEPOS`` in the plan frame), ``report.json``,
    ``figure.png`` (unless ``figures`` is false), optionally ``exploration.gif`` and,
    with ``bag`` (``"ros1"``, ``"ros2"``, ``"mcap"``), the odometry and scans of the log
    as a ROS bag (``run.bag`` or ``run_bag/``, :func:`map2map.robotlog.rosbag.write_bag`;
    the true start pose in a ROS 2 bag's ``custom_data``, no ``TRUEPOS``).
    """

    out = ensure_output_dir(out)
    paths = {
        "slam_map": out / "slam_map.yaml",
        "trajectory_true": out / "trajectory_true.csv",
        "trajectory_estimated": out / "trajectory_estimated.csv",
        "log": out / "run.log",
        "report": out / "report.json",
    }
    if figures:
        paths["figure"] = out / "figure.png"
    save_map(res.slam_map_plan, paths["slam_map"])
    _write_csv(paths["trajectory_true"], res.times, res.true_poses)
    _write_csv(paths["trajectory_estimated"], res.times, res.estimated_poses)
    start = {
        "map2map_start_x": res.start[0],
        "map2map_start_y": res.start[1],
        "map2map_start_theta": res.start[2],
    }
    write_carmen(
        paths["log"],
        zip(res.odometry, res.scans, [tuple(p) for p in res.true_poses], strict=True),
        velocities=[tuple(v) for v in res.velocities],
        params=start,
    )
    if bag is not None:
        from ..robotlog.carmen import CarmenLog
        from ..robotlog.rosbag import bag_name, write_bag

        paths["bag"] = out / bag_name("run", bag)
        params = {k: repr(float(v)) for k, v in start.items()}
        write_bag(CarmenLog(list(res.odometry), list(res.scans), params=params), paths["bag"],
                  format=bag)  # fmt: skip
    if figures:
        save_figure_png(res, paths["figure"])
    if figures and gif and res.frames:
        paths["gif"] = out / "exploration.gif"
        save_gif(res, paths["gif"])
    with atomic_path(paths["report"]) as tmp:
        tmp.write_text(json.dumps(res.report(), indent=2) + "\n")
    return paths
