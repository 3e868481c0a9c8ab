"""Routes for the simulator to drive instead of exploring: waypoints and recorded trajectories.

File formats (those of :mod:`map2map.trajectory`, which reads them):

* **waypoints**: one ``x y`` or ``x,y`` pair per line, metres in the plan's world
  frame; ``#`` comments and a header line ``x,y`` allowed; at least two points.
* **trajectory**: CSV rows ``x,y,theta`` or ``t,x,y,theta`` (a header naming the
  columns is optional); the robot follows the path at its own speed, so the times
  are not used. Poses closer than ``min_spacing`` are thinned out.

:func:`as_waypoints` also accepts any in-memory route: an ``(N, 2|3)`` array, a
list of points, or an object with ``x`` and ``y`` arrays (such as
``map2map.trajectory.Trajectory`` or a PRM path).

Examples
--------
>>> import tempfile, pathlib
>>> p = pathlib.Path(tempfile.mkdtemp()) / "route.csv"
>>> _ = p.write_text("t,x,y,theta\\n0,1.0,2.0,0\\n1,1.01,2.0,0\\n2,2.0,2.0,0\\n")
>>> read_route(p, "trajectory").tolist()
[[1.0, 2.0, 0.0], [2.0, 2.0, 0.0]]
"""

from __future__ import annotations

import os

import numpy as np

__all__ = ["read_route", "as_waypoints"]


def read_route(path: str | os.PathLike, kind: str = "waypoints", min_spacing: float = 0.05):
    """Read a waypoints or trajectory file as an ``(N, 2)`` or ``(N, 3)`` array of points.

    Parsing and validation are :func:`map2map.trajectory.read_waypoints` and
    :func:`map2map.trajectory.read_trajectory`; poses closer than ``min_spacing``
    metres are thinned out.

    Parameters
    ----------
    path : path-like
        The file.
    kind : {"waypoints", "trajectory"}
        How to read it.
    min_spacing : float
        Metres between kept poses.

    Returns
    -------
    (N, 2) or (N, 3) float array
        World metres (and radians).
    """
    from ..trajectory import read_trajectory, read_waypoints

    if kind == "waypoints":
        pts = read_waypoints(path)
    elif kind == "trajectory":
        traj = read_trajectory(path)
        pts = np.column_stack([traj.x, traj.y, traj.theta])
    else:
        raise ValueError(f"unknown route kind {kind!r}")
    return _thin(np.asarray(pts, float), min_spacing)


def _thin(pts: np.ndarray, spacing: float) -> np.ndarray:
    keep = [0]
    for i in range(1, len(pts)):
        if np.hypot(*(pts[i, :2] - pts[keep[-1], :2])) >= spacing:
            keep.append(i)
    if keep[-1] != len(pts) - 1 and np.hypot(*(pts[-1, :2] - pts[keep[-1], :2])) > 0:
        keep.append(len(pts) - 1)
    return pts[keep]


def as_waypoints(route) -> np.ndarray:
    """Any route object as an ``(N, 2|3)`` float array (see module docstring).

    Parameters
    ----------
    route : array-like, Trajectory or roadmap path
        The route.

    Returns
    -------
    (N, 2) or (N, 3) float array

    Examples
    --------
    >>> as_waypoints([(0, 0), (1, 2)]).tolist()
    [[0.0, 0.0], [1.0, 2.0]]
    """
    if hasattr(route, "x") and hasattr(route, "y"):
        cols = [np.asarray(route.x, float), np.asarray(route.y, float)]
        if hasattr(route, "theta"):
            cols.append(np.asarray(route.theta, float))
        return _thin(np.column_stack(cols), 0.05)
    return np.asarray(route, float)
