"""Figures of the parametric model: thesis Fig. 3.3 (roadmap and path) and Fig. 5.15
(plan with trajectory, displacement field, deformed map).

Examples
--------
>>> import numpy as np, tempfile, pathlib
>>> from map2map.core.grid import OccupancyMap
>>> from map2map.parametric import ParametricParams, deform, make_trajectory
>>> data = np.zeros((64, 64), np.uint8); data[2:62, 2:62] = 255
>>> plan = OccupancyMap(data, resolution=0.1)
>>> rng = np.random.default_rng(0)
>>> traj, rm = make_trajectory(plan, ParametricParams(), rng, start=(1.0, 1.0), goal=(5.0, 5.0))
>>> out = pathlib.Path(tempfile.mkdtemp())
>>> roadmap_figure(plan, rm, traj, out / "roadmap.png")
>>> deform_figure(plan, deform(plan, traj, "additive", ParametricParams(), rng), out / "f.png")
>>> sorted(p.name for p in out.iterdir())
['f.png', 'roadmap.png']
"""

from __future__ import annotations

import os

import numpy as np
from matplotlib.collections import LineCollection

from ..core.grid import OccupancyMap
from ..core.viz import draw_map, new_figure, save_figure
from ..trajectory.prm import Roadmap
from ..trajectory.timing import Trajectory
from .pipeline import DeformResult, trajectory_to_pixels

__all__ = ["roadmap_figure", "deform_figure", "draw_trajectory"]


def draw_trajectory(ax, plan: OccupancyMap, traj: Trajectory, colour: str = "tab:orange") -> None:
    """Trajectory in the plan's pixel coordinates, start (circle) and goal (star) marked.

    Parameters
    ----------
    ax : matplotlib.axes.Axes
        Axes showing the plan in pixel coordinates.
    plan : OccupancyMap
        The plan.
    traj : Trajectory
        World poses.
    colour : str
        Line colour.
    """
    px = trajectory_to_pixels(plan, traj.x, traj.y, traj.theta)
    ax.plot(px[:, 0], px[:, 1], "-", color=colour, lw=2, label="trajectory")
    ax.plot(px[0, 0], px[0, 1], "o", color=colour, ms=7, mec="k")
    ax.plot(px[-1, 0], px[-1, 1], "*", color=colour, ms=12, mec="k")


def roadmap_figure(
    plan: OccupancyMap, rm: Roadmap, traj: Trajectory, path: str | os.PathLike
) -> None:
    """Thesis Fig. 3.3: the probabilistic roadmap (blue) and the chosen trajectory (orange).

    Parameters
    ----------
    plan : OccupancyMap
        The plan.
    rm : Roadmap
        The roadmap.
    traj : Trajectory
        The trajectory.
    path : path-like
        Output figure (atomic).
    """
    fig, ax = new_figure(plan)
    draw_map(ax, plan, title=f"Probabilistic roadmap ({rm.nodes.shape[0]} nodes) and trajectory")
    seg = np.stack([rm.nodes[rm.edges[:, 0]], rm.nodes[rm.edges[:, 1]]], 1)
    ax.add_collection(LineCollection(seg, colors="tab:blue", linewidths=0.5, alpha=0.6))
    ax.plot(rm.nodes[:, 0], rm.nodes[:, 1], ".", color="tab:blue", ms=2)
    draw_trajectory(ax, plan, traj)
    save_figure(fig, path)


def deform_figure(
    plan: OccupancyMap, result: DeformResult, path: str | os.PathLike, title: str | None = None
) -> None:
    """Thesis Fig. 5.15: plan with trajectory, displacement field (|d| and arrows), and the
    modelled SLAM map.

    Parameters
    ----------
    plan : OccupancyMap
        The plan.
    result : DeformResult
        From :func:`map2map.parametric.pipeline.deform`.
    path : path-like
        Output figure (atomic).
    title : str, optional
        Figure title.
    """
    fig, axes = new_figure(plan, ncols=3)
    draw_map(axes[0], plan, title="Plan and trajectory")
    draw_trajectory(axes[0], plan, result.trajectory)
    f = result.field
    mag = np.where(result.observed, f.magnitude, np.nan)
    stats = f.stats(result.observed)
    im = axes[1].imshow(mag, cmap="viridis", interpolation="nearest")
    axes[1].set_xticks([])
    axes[1].set_yticks([])
    h, w = plan.shape
    step = max(1, int(max(h, w) / 24))
    yy, xx = np.mgrid[step // 2 : h : step, step // 2 : w : step]
    sel = result.observed[yy, xx]
    axes[1].quiver(
        xx[sel], yy[sel], f.dx[yy, xx][sel], f.dy[yy, xx][sel],
        color="white", angles="xy", scale_units="xy", scale=None, width=0.004,
    )  # fmt: skip
    axes[1].set_title(
        f"Displacement |d| [px] ({result.method}): "
        f"mean {stats['mean']:.2f}, max {stats['max']:.2f}",
        fontsize=9,
    )
    fig.colorbar(im, ax=axes[1], fraction=0.046, pad=0.02)
    draw_map(axes[2], result.map, title=title or "Modelled SLAM map")
    save_figure(fig, path)
