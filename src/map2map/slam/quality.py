"""How good is a SLAM run: trajectory error (ATE) and map error against the plan.

These use ground truth and are for *evaluation only* -- no mapper imports them.

* :func:`ate_rmse` -- absolute trajectory error (Sturm et al. 2012): RMSE of the
  position differences after the least-squares rigid alignment (Umeyama 1991,
  no scale; :func:`map2map.core.geometry.fit_rigid`) of the estimated to the true positions.
* :func:`wall_error` -- the mean distance (metres) from each occupied cell of the
  SLAM map to the nearest wall of the plan, with the SLAM map placed in the plan
  by the robot's true start pose (the map frame starts there). With ``align=True``
  the placement is first refined by the rigid transform that minimises the
  (Huber-robust) distances -- the appendix paper's ``E_rigid,opt``, the figure its
  "about 4 cm for real GMapping maps" refers to (sec. 5.2).

Examples
--------
>>> import numpy as np
>>> t = np.array([[0, 0], [1, 0], [1, 1.0]])
>>> round(ate_rmse(t + 5.0, t), 9)
0.0
"""

from __future__ import annotations

import numpy as np
from scipy import ndimage

from ..core.geometry import apply, fit_rigid
from ..core.grid import OccupancyMap

__all__ = [
    "ate_rmse",
    "wall_error",
    "wall_distances",
    "map_to_plan_points",
    "scan_endpoint_map",
]


def ate_rmse(est: np.ndarray, true: np.ndarray, align: bool = True) -> float:
    """RMSE (m) of matched positions ``est[:, :2]`` vs ``true[:, :2]``, rigidly aligned first.

    Parameters
    ----------
    est, true : (N, >=2) float arrays
        Matched estimated and true poses.
    align : bool
        Fit a rigid transform ``est -> true`` first.

    Returns
    -------
    float

    Examples
    --------
    >>> true = np.array([[0.0, 0.0], [1.0, 0.0], [2.0, 0.0]])
    >>> ate_rmse(true + [0.5, 0.0], true), round(ate_rmse(true + [0.5, 0.0], true, align=False), 3)
    (0.0, 0.5)
    """
    est = np.asarray(est, float)[:, :2]
    true = np.asarray(true, float)[:, :2]
    if align and len(est) >= 2:
        est = apply(fit_rigid(est, true), est)
    return float(np.sqrt(np.mean(np.sum((est - true) ** 2, axis=1))))


def map_to_plan_points(slam_map: OccupancyMap, start_pose) -> np.ndarray:
    """World (plan-frame) coordinates ``(K, 2)`` of the occupied cells of a SLAM map.

    Parameters
    ----------
    slam_map : OccupancyMap
        The SLAM map in its own frame.
    start_pose : (x, y, theta)
        Pose of that frame in the plan (the robot's true start pose).

    Returns
    -------
    (K, 2) float array
    """
    rows, cols = np.nonzero(slam_map.occupied)
    x, y = slam_map.pixel_to_world(rows, cols)
    x0, y0, th = (float(v) for v in start_pose)
    c, s = np.cos(th), np.sin(th)
    return np.stack([x0 + c * x - s * y, y0 + s * x + c * y], axis=1)


def wall_error(
    slam_map: OccupancyMap, plan: OccupancyMap, start_pose, align: bool = False
) -> float:
    """Mean distance (m) of mapped wall cells to the nearest plan wall (``nan`` if none).

    With ``align`` the SLAM map's placement (the true start pose) is refined by the
    rigid transform (rotation about the points' centroid, translation) minimising the
    distances with a Huber loss (scale 10 cm), so that a global offset or rotation of
    an otherwise good map is not counted -- as in the appendix paper's rigid alignment.

    Parameters
    ----------
    slam_map : OccupancyMap
        The SLAM map in its own frame.
    plan : OccupancyMap
        The plan.
    start_pose : (x, y, theta)
        Pose of the SLAM map's frame in the plan.
    align : bool
        Refine the placement first.

    Returns
    -------
    float

    Examples
    --------
    >>> from map2map.core.grid import OccupancyMap
    >>> d = np.full((40, 40), 255, np.uint8); d[20, 5:35] = 0
    >>> plan = OccupancyMap(d, 0.05)
    >>> wall_error(plan, plan, (0.0, 0.0, 0.0))
    0.0
    >>> round(wall_error(plan, plan, (0.0, 0.1, 0.0)), 3)      # shifted 10 cm
    0.1
    >>> round(wall_error(plan, plan, (0.0, 0.1, 0.0), align=True), 3)
    0.0
    """
    d = wall_distances(slam_map, plan, start_pose, align=align)
    return float(np.mean(d)) if len(d) else float("nan")


def wall_distances(
    slam_map: OccupancyMap, plan: OccupancyMap, start_pose, align: bool = False
) -> np.ndarray:
    """Distance (m) of every occupied cell of ``slam_map`` to the nearest wall of ``plan``.

    The placement and the optional rigid refinement are those of :func:`wall_error`
    (which is the mean of this array); with ``align`` the refinement is kept only if
    it lowers the mean.

    Parameters
    ----------
    slam_map : OccupancyMap
        The SLAM map in its own frame.
    plan : OccupancyMap
        The plan.
    start_pose : (x, y, theta)
        Pose of the SLAM map's frame in the plan.
    align : bool
        Refine the placement first.

    Returns
    -------
    (K,) float array

    Examples
    --------
    >>> from map2map.core.grid import OccupancyMap
    >>> d = np.full((40, 40), 255, np.uint8); d[20, 5:35] = 0
    >>> plan = OccupancyMap(d, 0.05)
    >>> round(float(np.median(wall_distances(plan, plan, (0.0, 0.1, 0.0)))), 6)
    0.1
    """
    pts = map_to_plan_points(slam_map, start_pose)
    if len(pts) == 0:
        return np.zeros(0)
    dist = ndimage.distance_transform_edt(~plan.occupied) * plan.resolution

    def lookup(q):
        r, c = plan.world_to_pixel_float(q[:, 0], q[:, 1])
        # bilinear; outside the plan counts as the distance at the nearest border
        return ndimage.map_coordinates(dist, [r, c], order=1, mode="nearest")

    placed = lookup(pts)
    if not align:
        return placed
    from scipy.optimize import least_squares

    centre = pts.mean(0)
    rel = pts - centre

    def moved(v):
        c, s = np.cos(v[2]), np.sin(v[2])
        return np.stack([c * rel[:, 0] - s * rel[:, 1], s * rel[:, 0] + c * rel[:, 1]], 1) + (
            centre + v[:2]
        )

    sol = least_squares(
        lambda v: lookup(moved(v)),
        np.zeros(3),
        loss="huber",
        f_scale=0.1,
        diff_step=[1e-3, 1e-3, 1e-4],
        x_scale=[0.05, 0.05, 0.01],
    )
    aligned = lookup(moved(sol.x))
    return aligned if np.mean(aligned) < np.mean(placed) else placed


def scan_endpoint_map(
    scans, poses, resolution: float = 0.05, *, max_range: float | None = None, min_hits: int = 1
) -> OccupancyMap:
    """Raster of the scan endpoints at given poses: the reference map of a corrected log.

    Every valid reading (:attr:`~map2map.robotlog.base.LaserScan.valid`, and below
    ``max_range`` when given) of scan ``k`` is placed at ``poses[k]`` composed with
    the scan's sensor offset; a cell hit at least ``min_hits`` times is occupied,
    every other cell unknown (no free space: the endpoints say nothing about it).

    Parameters
    ----------
    scans : sequence of LaserScan
    poses : (N, 3) array
        Robot poses ``x, y, theta`` (world metres, radians), one per scan.
    resolution : float
        Metres per pixel.
    max_range : float, optional
        Leave out readings at or beyond this range.
    min_hits : int
        Hits a cell needs to count as a wall.

    Returns
    -------
    OccupancyMap
        Occupied (0) endpoint cells, the rest unknown (127), in the poses' frame.

    Examples
    --------
    >>> from map2map.robotlog.base import LaserScan
    >>> s = LaserScan(0.0, np.full(90, 1.0, np.float32), 0.0, np.deg2rad(1.0), 0.1, 5.0)
    >>> m = scan_endpoint_map([s], np.zeros((1, 3)))
    >>> int(m.occupied.sum()) > 10, m.resolution
    (True, 0.05)
    """
    poses = np.asarray(poses, float)
    xs, ys = [], []
    for scan, (px, py, pth) in zip(scans, poses, strict=True):
        ok = scan.valid
        if max_range is not None:
            ok &= np.asarray(scan.ranges, float) < max_range
        r = np.asarray(scan.ranges, float)[ok]
        ox, oy, oth = scan.sensor_offset
        sx = px + np.cos(pth) * ox - np.sin(pth) * oy
        sy = py + np.sin(pth) * ox + np.cos(pth) * oy
        a = pth + oth + scan.angles[ok]
        xs.append(sx + r * np.cos(a))
        ys.append(sy + r * np.sin(a))
    x = np.concatenate(xs) if xs else np.zeros(0)
    y = np.concatenate(ys) if ys else np.zeros(0)
    if len(x) == 0:
        return OccupancyMap(np.full((1, 1), 127, np.uint8), resolution)
    x0, y0 = x.min() - 5 * resolution, y.min() - 5 * resolution
    w = int(np.ceil((x.max() - x0) / resolution)) + 5
    h = int(np.ceil((y.max() - y0) / resolution)) + 5
    col = ((x - x0) / resolution).astype(np.int64)
    row = h - 1 - ((y - y0) / resolution).astype(np.int64)
    hits = np.bincount(row * w + col, minlength=h * w).reshape(h, w)
    data = np.where(hits >= min_hits, 0, 127).astype(np.uint8)
    return OccupancyMap(data, resolution, (float(x0), float(y0), 0.0))
