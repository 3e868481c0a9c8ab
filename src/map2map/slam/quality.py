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

__all__ = ["ate_rmse", "wall_error", "map_to_plan_points"]


def ate_rmse(est: np.ndarray, true: np.ndarray, align: bool = True) -> float:
    """RMSE (m) of matched positions ``est[:, :2]`` vs ``true[:, :2]``, rigidly aligned first."""
    est = np.asarray(est, float)[:, :2]
    true = np.asarray(true, float)[:, :2]
    if align and len(est) >= 2:
        est = apply(fit_rigid(est, true), est)
    return float(np.sqrt(np.mean(np.sum((est - true) ** 2, axis=1))))


def map_to_plan_points(slam_map: OccupancyMap, start_pose) -> np.ndarray:
    """World (plan-frame) coordinates ``(K, 2)`` of the occupied cells of a SLAM map."""
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
    pts = map_to_plan_points(slam_map, start_pose)
    if len(pts) == 0:
        return float("nan")
    dist = ndimage.distance_transform_edt(~plan.occupied) * plan.resolution

    def lookup(q):
        r, c = plan.world_to_pixel_float(q[:, 0], q[:, 1])
        # bilinear; outside the plan counts as the distance at the nearest border
        return ndimage.map_coordinates(dist, [r, c], order=1, mode="nearest")

    if not align:
        return float(np.mean(lookup(pts)))
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
    return float(min(np.mean(lookup(moved(sol.x))), np.mean(lookup(pts))))
