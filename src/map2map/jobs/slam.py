"""``map2map slam`` as a job: read a recorded log, run a SLAM backend, write map and figure.

:func:`slam` takes a :class:`SlamSpec` and returns a :class:`SlamRun` (``written`` and the
in-memory :class:`~map2map.slam.offline.SlamResult`); :func:`write_slam_outputs`
writes ``map.yaml`` + ``map.pgm`` (ROS map_saver format, cropped to what was seen),
``trajectory.csv`` (``t, x, y, theta`` in the map frame) and ``figure.png`` (the map
with the estimated trajectory and the raw odometry).

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

from ..core._io import atomic_path, ensure_output_dir
from ..core.errors import InputError
from ..slam.offline import SlamResult, check_options, run_slam

__all__ = ["SlamSpec", "SlamRun", "slam", "write_slam_outputs"]


@dataclass
class SlamSpec:
    """What ``map2map slam`` is asked to do (see :func:`map2map.slam.offline.run_slam`)."""

    log: str | os.PathLike
    out: str | os.PathLike
    backend: str = "rbpf"
    particles: int | None = None
    resolution: float = 0.05
    max_range: float | None = None
    seed: int = 0
    format: str = "auto"
    figures: bool = True
    progress: bool = True


@dataclass
class SlamRun:
    """What :func:`slam` wrote (name -> path) and the SLAM result itself."""

    written: dict[str, Path]
    result: SlamResult
    #: What the log reader said once (message types skipped, odometry rebuilt, ...).
    notes: list[str] = field(default_factory=list)


def slam(spec: SlamSpec) -> SlamRun:
    """Run ``map2map slam``: the log and every parameter are checked before writing."""
    from ..robotlog.logs import load_log

    kw = dict(particles=spec.particles, resolution=spec.resolution, max_range=spec.max_range)
    check_options(spec.backend, **kw)  # before reading the log: fail fast
    out = Path(spec.out)
    if out.exists() and not out.is_dir():
        raise InputError(out, "output path exists and is not a directory")
    log = load_log(spec.log, spec.format)  # every format problem is raised here, before output
    res = run_slam(
        log,
        spec.backend,
        particles=spec.particles,
        resolution=spec.resolution,
        seed=spec.seed,
        max_range=spec.max_range,
        progress=spec.progress,
        source=spec.log,
    )
    paths = write_slam_outputs(
        res, out, title=f"{Path(spec.log).name}: {spec.backend}", figures=spec.figures
    )
    names = ["map", "map_pgm", "trajectory", "figure"]
    return SlamRun(dict(zip(names, paths, strict=False)), res, list(log.notes))


def _figure(res: SlamResult, path: Path, title: str) -> None:
    from ..core.viz import draw_map, new_figure, save_figure

    m = res.map
    fig, ax = new_figure(m, 1, panel_inches=7.0)
    draw_map(ax, m, title=title)
    if len(res.odometry):
        r, c = m.world_to_pixel_float(res.odometry[:, 1], res.odometry[:, 2])
        ax.plot(c + 0.5, r + 0.5, color="0.55", lw=1.0, ls="--", label="raw odometry")
    if len(res.trajectory):
        r, c = m.world_to_pixel_float(res.trajectory[:, 1], res.trajectory[:, 2])
        ax.plot(c + 0.5, r + 0.5, color="tab:red", lw=1.4, label=f"{res.backend} estimate")
        ax.plot(c[:1] + 0.5, r[:1] + 0.5, "o", color="tab:green", ms=5, label="start")
    ax.set_xlim(-0.5, m.width - 0.5)
    ax.set_ylim(m.height - 0.5, -0.5)
    ax.legend(loc="upper right", fontsize=8, framealpha=0.8)
    save_figure(fig, path)


def write_slam_outputs(
    res: SlamResult, out: str | os.PathLike, *, title: str | None = None, figures: bool = True
) -> list[Path]:
    """Write ``map.yaml``/``map.pgm``, ``trajectory.csv`` and ``figure.png`` under ``out``."""
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
    _figure(res, fig, title or f"{res.backend} map and trajectory")
    return [out / "map.yaml", Path(pgm), csv, fig]
