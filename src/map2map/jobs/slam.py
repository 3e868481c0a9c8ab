"""``map2map slam`` as a job: read a recorded log, run a SLAM backend, write map and figure.

:func:`slam` takes a :class:`SlamSpec` and returns a :class:`SlamRun` (``written`` and the
in-memory :class:`~map2map.slam.offline.SlamResult`); :func:`write_slam_outputs`
writes ``map.yaml`` + ``map.pgm`` (ROS map_saver format, cropped to what was seen),
``trajectory.csv`` (``t, x, y, theta`` in the map frame) and ``figure.png`` (the map
with the estimated trajectory and the raw odometry).

The map frame is the robot's first pose (x = its initial heading): a recorded log says
nothing about how the building lies in it, and the figure says so in its title. A
``map2map simulate`` log carries the true start pose in the plan (PARAM
``map2map_start_*``, :meth:`~map2map.robotlog.carmen.CarmenLog.plan_start_pose`): its
figure is drawn in the plan frame, as the plan is drawn (the files stay in the map frame).

Examples
--------
>>> import numpy as np, tempfile, pathlib
>>> from map2map.robotlog.base import LaserScan, OdometryReading
>>> from map2map.robotlog.carmen import CarmenLog
>>> from map2map.slam.offline import run_slam
>>> ang = np.deg2rad(1.0)
>>> log = CarmenLog([OdometryReading(0.2 * k, 0.1 * k, 0.0, 0.0) for k in range(5)],
...                 [LaserScan(0.2 * k, np.full(360, 1.5, np.float32), 0.0, ang, 0.1, 3.5)
...                  for k in range(5)])
>>> out = pathlib.Path(tempfile.mkdtemp())
>>> sorted(p.name for p in write_slam_outputs(run_slam(log, "graph"), out))
['figure.png', 'map.pgm', 'map.yaml', 'trajectory.csv']
"""

from __future__ import annotations

import os
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from ..core._io import atomic_dir, atomic_path, check_output_dir, ensure_output_dir
from ..core.grid import OccupancyMap
from ..slam.offline import SlamResult, check_options, run_slam
from ._common import check_seed, final_paths

__all__ = ["SlamSpec", "SlamRun", "slam", "write_slam_outputs", "plan_frame_grid", "figure_frame"]


@dataclass
class SlamSpec:
    """What ``map2map slam`` is asked to do (see :func:`map2map.slam.offline.run_slam`)."""

    log: str | os.PathLike
    out: str | os.PathLike
    backend: str = "rbpf"
    particles: int | None = None
    #: rbpf: close the loops after the filter (None: on for a recorded log).
    close_loops: bool | None = None
    resolution: float = 0.05
    max_range: float | None = None
    seed: int = 0
    format: str = "auto"
    #: A ROS bag's LaserScan and odometry topics (``/tf`` for the odom -> base transform).
    scan_topic: str | None = None
    odom_topic: str | None = None
    figures: bool = True
    progress: bool = True
    #: Largest peak memory to plan for, GiB (None: 4; 0: no limit).
    max_memory: float | None = None


@dataclass
class SlamRun:
    """What :func:`slam` wrote (name -> path) and the SLAM result itself."""

    written: dict[str, Path]
    result: SlamResult
    #: What the log reader said once (message types skipped, odometry rebuilt, ...).
    notes: list[str] = field(default_factory=list)


def slam(spec: SlamSpec) -> SlamRun:
    """Run ``map2map slam``: every parameter, the output folder and the log checked first.

    Parameters
    ----------
    spec : SlamSpec
        Log, backend and its options, output folder.

    Returns
    -------
    SlamRun
        ``written`` (name -> path), the :class:`~map2map.slam.offline.SlamResult` and
        the reader's notes.

    Raises
    ------
    InputError
        A bad parameter, log or output folder (nothing is written). The outputs go
        to a temporary folder renamed whole at the end
        (:func:`map2map.core._io.atomic_dir`: an existing folder is replaced).
    """
    from ..robotlog.logs import load_log

    check_seed(spec.seed)
    kw = dict(particles=spec.particles, resolution=spec.resolution, max_range=spec.max_range,
              max_memory=spec.max_memory)  # fmt: skip
    check_options(spec.backend, **kw)  # before reading the log: fail fast
    out = check_output_dir(spec.out, protect=(spec.log,))
    # every format problem is raised here, before output
    log = load_log(spec.log, spec.format, scan_topic=spec.scan_topic, odom_topic=spec.odom_topic)
    res = run_slam(
        log,
        spec.backend,
        particles=spec.particles,
        resolution=spec.resolution,
        seed=spec.seed,
        close_loops=spec.close_loops,
        max_range=spec.max_range,
        progress=spec.progress,
        source=spec.log,
        max_memory=spec.max_memory,
    )
    with atomic_dir(out, protect=(spec.log,)) as tmp:
        paths = write_slam_outputs(
            res,
            tmp,
            title=f"{Path(spec.log).name}: {spec.backend}",
            figures=spec.figures,
            frame=log.plan_start_pose(),
        )
    names = ["map", "map_pgm", "trajectory", "figure"]
    written = final_paths(dict(zip(names, paths, strict=False)), tmp, out)
    return SlamRun(written, res, list(log.notes))


def plan_frame_grid(m: OccupancyMap, frame) -> OccupancyMap:
    """An all-unknown grid, axis-aligned in the plan frame, holding map ``m`` placed at ``frame``.

    ``frame`` is the pose ``(x, y, theta)`` of ``m``'s world frame in the plan frame;
    the grid has ``m``'s resolution and a zero-yaw origin.

    Examples
    --------
    >>> import numpy as np
    >>> m = OccupancyMap(np.full((10, 20), 255, np.uint8), 0.1)
    >>> g = plan_frame_grid(m, (5.0, 1.0, np.pi / 2))
    >>> g.shape, g.origin
    ((20, 10), (4.0, 1.0, 0.0))
    """
    from ..core.geometry import compose_pose

    rows = np.array([-0.5, -0.5, m.height - 0.5, m.height - 0.5])
    cols = np.array([-0.5, m.width - 0.5, -0.5, m.width - 0.5])
    x, y = m.pixel_to_world(rows, cols)
    p = compose_pose(np.asarray(frame, float), np.column_stack([x, y, np.zeros(4)]))
    res = m.resolution
    x0, y0 = (np.round(p[:, :2].min(0) / res, 6)) * res
    w, h = np.ceil(np.round((p[:, :2].max(0) - (x0, y0)) / res, 6)).astype(int)
    return OccupancyMap(np.full((max(h, 1), max(w, 1)), 127, np.uint8), res, (x0, y0, 0.0))


def figure_frame(res: SlamResult, frame=None, plan: OccupancyMap | None = None):
    """The map, path and odometry a SLAM figure draws, in the frame it names.

    Without ``frame`` everything stays in the map frame (the robot's first pose).
    With ``frame`` (pose of the map frame in the plan frame) the map is resampled
    into the plan frame, onto ``plan``'s grid when given, and the paths moved with it.

    Returns
    -------
    map : OccupancyMap
    trajectory, odometry : (T, 3), (N, 3) arrays
        ``x, y, theta`` in that frame.
    frame_text : str
        What the frame is, for the figure's title.

    Examples
    --------
    >>> import numpy as np
    >>> from map2map.slam.offline import SlamResult
    >>> m = OccupancyMap(np.full((10, 20), 255, np.uint8), 0.1)
    >>> res = SlamResult(m, np.array([[0.0, 1.0, 0.0, 0.0]]), np.zeros((1, 4)), None, "x")
    >>> figure_frame(res)[3]
    "map frame = first pose (x right = robot's initial heading)"
    >>> shown, traj, _, text = figure_frame(res, (5.0, 1.0, np.pi / 2))
    >>> shown.shape, np.round(traj, 6).tolist(), text.split(" (")[0]
    ((20, 10), [[5.0, 2.0, 1.570796]], 'plan frame')
    """
    from ..core.geometry import compose_pose

    m, traj, odom = res.map, res.trajectory[:, 1:4], res.odometry[:, 1:4]
    if frame is None:
        return m, traj, odom, "map frame = first pose (x right = robot's initial heading)"
    from ..sim.mapping import resample_to_frame

    target = plan if plan is not None else plan_frame_grid(m, frame)
    m = resample_to_frame(m, frame, target)
    f = np.asarray(frame, float)
    traj = compose_pose(f, traj) if len(traj) else traj
    odom = compose_pose(f, odom) if len(odom) else odom
    return m, traj, odom, "plan frame (map placed at the simulator's true start pose)"


#: Largest side (px) of the map a figure draws; a larger map is reduced by whole blocks,
#: walls kept (:func:`map2map.maps.render.display_map`). The figure is about 1000 px wide.
FIGURE_MAX_PIXELS = 2400


def _figure(
    res: SlamResult,
    path: Path,
    title: str,
    frame=None,
    plan: OccupancyMap | None = None,
) -> None:
    """The map, its estimated trajectory and the raw odometry, titled with the frame drawn.

    See :func:`figure_frame`; ``plan``'s walls are drawn faintly beneath the map.
    """
    from ..core.viz import draw_map, map_to_rgb, new_figure, save_figure
    from ..maps.render import display_map

    m, traj, odom, frame_text = figure_frame(res, frame, plan)
    if plan is None:  # a campus map (6000 px) drawn whole took 3.5 GB in matplotlib
        m = display_map(m, FIGURE_MAX_PIXELS)
    fig, ax = new_figure(m, 1, panel_inches=7.0)
    draw_map(ax, m, title=f"{title}\n{frame_text}")
    if plan is not None:  # the plan's walls the map did not mark, faintly beneath
        rgb = map_to_rgb(m)
        ghost = plan.occupied & ~m.occupied
        rgb[ghost] = (0.62, 0.72, 0.92)
        ax.images[0].set_data(rgb)
        ax.plot([], [], "s", color=(0.62, 0.72, 0.92), label="plan walls")
    if len(odom):
        r, c = m.world_to_pixel_float(odom[:, 0], odom[:, 1])
        ax.plot(c + 0.5, r + 0.5, color="0.55", lw=1.0, ls="--", label="raw odometry")
    if len(traj):
        r, c = m.world_to_pixel_float(traj[:, 0], traj[:, 1])
        ax.plot(c + 0.5, r + 0.5, color="tab:red", lw=1.4, label=f"{res.backend} estimate")
        ax.plot(c[:1] + 0.5, r[:1] + 0.5, "o", color="tab:green", ms=5, label="start")
    ax.set_xlim(-0.5, m.width - 0.5)
    ax.set_ylim(m.height - 0.5, -0.5)
    ax.legend(loc="upper right", fontsize=8, framealpha=0.8)
    save_figure(fig, path)


def write_slam_outputs(
    res: SlamResult,
    out: str | os.PathLike,
    *,
    title: str | None = None,
    figures: bool = True,
    frame=None,
    plan: OccupancyMap | None = None,
) -> list[Path]:
    """Write ``map.yaml``/``map.pgm``, ``trajectory.csv`` and ``figure.png`` under ``out``.

    The files are in the map frame (the first pose). ``frame`` (the pose of the map
    frame in the plan frame, e.g. a simulated run's true start pose) draws the figure
    in the plan frame, over ``plan``'s walls when given; otherwise the figure is in the
    map frame and its title says so.
    """
    from ..maps.ros import save_ros_map

    out = ensure_output_dir(out)
    m = res.map
    bbox = m.content_bbox()
    if bbox is not None:  # crop to what was seen, with a small unknown border
        r0, r1, c0, c1 = bbox
        m = m.crop(r0 - 10, r1 + 10, c0 - 10, c1 + 10)
        res = SlamResult(m, res.trajectory, res.odometry, res.mapper, res.backend)
    pgm = save_ros_map(m, out / "map.yaml")
    csv = out / "trajectory.csv"
    with atomic_path(csv) as tmp:
        np.savetxt(
            tmp, res.trajectory, fmt="%.6f", delimiter=",", header="t,x,y,theta", comments=""
        )
    if not figures:
        return [out / "map.yaml", Path(pgm), csv]
    fig = out / "figure.png"
    _figure(res, fig, title or f"{res.backend} map and trajectory", frame=frame, plan=plan)
    return [out / "map.yaml", Path(pgm), csv, fig]
