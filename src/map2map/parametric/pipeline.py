"""The parametric CAD->SLAM model end to end (thesis Fig. 3.2).

``plan + trajectory -> key poses -> visibility -> LIDAR field (3.8-3.30) + odometry errors
(3.31-3.53) -> odometry field (additive 3.81-3.90 or EKF 3.54-3.80) -> d = d_L + d_O ->
deformed map``.

Examples
--------
>>> import numpy as np
>>> from map2map.core.grid import OccupancyMap
>>> data = np.zeros((64, 64), np.uint8); data[2:62, 2:62] = 255
>>> plan = OccupancyMap(data, resolution=0.1)
>>> rng = np.random.default_rng(0)
>>> traj, _ = make_trajectory(plan, ParametricParams(), rng, start=(1.0, 1.0), goal=(5.0, 5.0))
>>> res = deform(plan, traj, "additive", ParametricParams(), rng)
>>> res.map.shape, res.field.dx.dtype
((64, 64), dtype('float32'))
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass, field

import numpy as np
from scipy import ndimage

from ..core.errors import InputError
from ..core.geometry import wrap_angle
from ..core.grid import FREE, OCCUPIED, OccupancyMap
from ..trajectory.prm import (
    Roadmap,
    build_roadmap,
    path_through,
    random_start_goal,
    random_tour,
)
from ..trajectory.timing import Trajectory, time_waypoints
from .additive import additive_field
from .ekf import ekf_field
from .field import DisplacementField, warp_map
from .lidar import draw_lidar_coefficients, lidar_field, random_range_angle
from .odometry import draw_odometry_coefficients, odometry_errors, straight_run_length
from .params import ParametricParams
from .visibility import Visibility, visible_pixels

__all__ = [
    "METHODS",
    "DeformResult",
    "keyframe_indices",
    "trajectory_to_pixels",
    "check_point",
    "make_trajectory",
    "deform",
]

METHODS = ("additive", "ekf")


@dataclass
class DeformResult:
    """A modelled SLAM map and the ground-truth field that made it.

    ``field`` is the total displacement ``d = d_L + d_O`` [px], zero on pixels never
    observed; ``map`` has the plan's resolution and origin.
    """

    map: OccupancyMap
    field: DisplacementField
    lidar: DisplacementField
    odometry: DisplacementField
    observed: np.ndarray
    trajectory: Trajectory
    keyposes_px: np.ndarray
    method: str
    params: ParametricParams
    drawn: dict = field(default_factory=dict)
    timings: dict = field(default_factory=dict)


def keyframe_indices(
    traj: Trajectory, distance: float, angle: float, smooth: int = 15
) -> np.ndarray:
    """Indices of key poses: the first, then whenever the robot has moved ``distance``
    metres or turned ``angle`` radians since the last key pose, and the last.

    The turn is measured on the (unwrapped) heading averaged over ``smooth`` samples, so
    that the jitter of recorded grid paths (headings jumping by pi/4 at every stair step)
    does not make every sample a key pose; a real, lasting turn passes the filter.

    Parameters
    ----------
    traj : Trajectory
        The trajectory.
    distance : float
        Metres between key poses.
    angle : float
        Radians between key poses.
    smooth : int
        Samples averaged for the heading.

    Returns
    -------
    (K,) int array
    """
    keep = [0]
    x, y = traj.x, traj.y
    th = np.unwrap(traj.theta)
    if smooth > 1 and th.size > smooth:
        th = ndimage.uniform_filter1d(th, size=smooth, mode="nearest")
    for i in range(1, len(traj)):
        j = keep[-1]
        if (
            math.hypot(x[i] - x[j], y[i] - y[j]) >= distance
            or abs(float(wrap_angle(th[i] - th[j], keep_in_range=True))) >= angle
        ):
            keep.append(i)
    if keep[-1] != len(traj) - 1:
        keep.append(len(traj) - 1)
    return np.asarray(keep)


def trajectory_to_pixels(plan: OccupancyMap, x, y, theta) -> np.ndarray:
    """World poses -> pixel poses ``(x = column, y = row, angle)``, the angle in the image
    frame (y down, so a world heading ``theta`` becomes ``-(theta - yaw)``).

    Parameters
    ----------
    plan : OccupancyMap
        The plan whose grid is used.
    x, y, theta : array-like
        World poses.

    Returns
    -------
    (N, 3) float array
    """
    rows, cols = plan.world_to_pixel_float(x, y)
    ang = wrap_angle(-(np.asarray(theta, float) - plan.origin[2]), keep_in_range=True)
    return np.stack([cols, rows, ang], 1)


def check_point(plan: OccupancyMap, x: float, y: float, what: str) -> np.ndarray:
    """Pixel ``(x, y)`` of a world point that must lie in the plan's free space.

    Parameters
    ----------
    plan : OccupancyMap
        The plan.
    x, y : float
        World point, metres.
    what : str
        Name of the point in errors (``"start"``, ``"goal"``...).

    Returns
    -------
    (2,) float array

    Raises
    ------
    InputError
        Outside the plan or not on free space.
    """
    r, c = plan.world_to_pixel([x], [y])
    name = f"{what} ({x:g}, {y:g}) m"
    if not plan.contains(r, c)[0]:
        w, h = plan.size_m
        raise InputError(what, f"{name} is outside the map ({w:g} x {h:g} m)")
    v = int(plan.data[r[0], c[0]])
    if v != FREE:
        kind = "in a wall" if v == OCCUPIED else "in unknown space"
        raise InputError(what, f"{name} is {kind}, not in free space")
    rr, cc = plan.world_to_pixel_float([x], [y])
    return np.array([cc[0], rr[0]])


def make_trajectory(
    plan: OccupancyMap,
    p: ParametricParams,
    rng: np.random.Generator,
    *,
    start: tuple[float, float] | None = None,
    goal: tuple[float, float] | None = None,
    waypoints: np.ndarray | None = None,
    tour: int = 0,
) -> tuple[Trajectory, Roadmap]:
    """A timed trajectory over the plan's roadmap (thesis 3.2, Fig. 3.3).

    With ``waypoints`` (W, 2, world metres) the path visits them in order; with ``start``
    and ``goal`` (world metres) it joins them; otherwise it joins two random roadmap
    nodes, or, with ``tour`` > 2, tours that many roadmap nodes spread over the plan.
    Raises :class:`InputError` for points outside the free space or not connected.

    Parameters
    ----------
    plan : OccupancyMap
        The plan.
    p : ParametricParams
        Roadmap and robot parameters.
    rng : numpy.random.Generator
        Source of the roadmap and the random ends.
    start, goal : (x, y), optional
        World metres.
    waypoints : (W, 2) array, optional
        World metres.
    tour : int
        Number of spread-out nodes to tour.

    Returns
    -------
    trajectory : Trajectory
    roadmap : Roadmap
    """
    if not plan.free.any():
        raise InputError(None, "the plan has no free space")
    if waypoints is None and (start is None) != (goal is None):
        raise InputError(None, "give both `start` and `goal`, or neither")
    pts = None
    names = None
    if waypoints is not None:
        pts = np.stack(
            [check_point(plan, float(x), float(y), "waypoints") for x, y in np.asarray(waypoints)]
        )
        names = [f"waypoint ({x:g}, {y:g}) m" for x, y in np.asarray(waypoints)]
    elif start is not None:
        pts = np.stack(
            [
                check_point(plan, *map(float, start), "start"),
                check_point(plan, *map(float, goal), "goal"),
            ]
        )
        names = [f"start ({start[0]:g}, {start[1]:g}) m", f"goal ({goal[0]:g}, {goal[1]:g}) m"]
    rm = build_roadmap(
        plan,
        robot_radius=p.robot_radius,
        nodes_per_m2=p.prm_nodes_per_m2,
        k=p.prm_k,
        skeleton_step=p.prm_skeleton_step,
        rng=rng,
    )
    if pts is None:
        pts = random_tour(rm, rng, tour) if tour > 2 else np.stack(random_start_goal(rm, rng))
    path_px = path_through(rm, pts, names)
    wx, wy = plan.pixel_to_world(path_px[:, 1], path_px[:, 0])
    traj = time_waypoints(
        np.stack([wx, wy], 1),
        v_max=p.v_max,
        omega_max=p.omega_max,
        acc_lin=p.acc_lin,
        acc_ang=p.acc_ang,
        dt=p.dt,
    )
    traj.meta["path_px"] = path_px
    return traj, rm


def deform(
    plan: OccupancyMap,
    trajectory: Trajectory,
    method: str = "additive",
    params: ParametricParams | None = None,
    rng: np.random.Generator | None = None,
) -> DeformResult:
    """Model the SLAM map the robot would build driving ``trajectory`` through ``plan``.

    Parameters
    ----------
    plan : OccupancyMap
        The CAD floor plan.
    trajectory : Trajectory
        Robot trajectory in the plan's world frame.
    method : {"additive", "ekf"}
        Conversion of odometry error to map error: ref. [58] (thesis eqs. 3.81-3.90) or EKF-SLAM
        (thesis eqs. 3.54-3.80).
    params : ParametricParams
        Model parameters (defaults if None).
    rng : numpy.random.Generator
        All random draws; the same generator state gives the same bytes.

    Returns
    -------
    DeformResult
        The modelled map, the total, LIDAR and odometry fields, the observed pixels
        and the trajectory.

    Examples
    --------
    >>> from map2map.maps.floorplan import generate_floorplan
    >>> plan = generate_floorplan(1, size=(6, 5), resolution=0.1)
    >>> rng = np.random.default_rng(0)
    >>> traj, _ = make_trajectory(plan, ParametricParams(), rng)
    >>> res = deform(plan, traj, rng=rng)
    >>> res.map.shape == plan.shape
    True
    """
    if method not in METHODS:
        raise InputError("method", f"unknown method {method!r} (use additive or ekf)")
    p = params or ParametricParams()
    rng = rng if rng is not None else np.random.default_rng()
    if not plan.free.any():
        raise InputError(None, "the plan has no free space")
    timings: dict[str, float] = {}
    t0 = time.perf_counter()
    res = plan.resolution
    pm = 1.0 / res
    key = keyframe_indices(trajectory, p.keyframe_distance, p.keyframe_angle)
    poses_px = trajectory_to_pixels(
        plan, trajectory.x[key], trajectory.y[key], trajectory.theta[key]
    )
    # sensor poses and visibility
    vis: Visibility = visible_pixels(
        plan.occupied,
        poses_px,
        p.range_min * pm,
        p.range_max * pm,
        math.radians(p.fov_deg),
        unknown=plan.unknown,
    )
    observed = vis.observed_mask()
    timings["visibility"] = time.perf_counter() - t0
    # LIDAR model (thesis eqs. 3.8-3.30)
    t1 = time.perf_counter()
    lcoef = draw_lidar_coefficients(p, rng)
    ocoef = draw_odometry_coefficients(p, rng)
    if p.lidar_geometry == "random":
        D, alpha = random_range_angle(plan.shape, p.range_min, p.range_max, p.median_size, rng)
        heading: np.ndarray | float = 0.0
    else:
        D, alpha, heading = _geometry_range_angle(vis, poses_px, res, p.range_max)
    lf = lidar_field(D, alpha, lcoef, p, pm, rng, heading)
    timings["lidar"] = time.perf_counter() - t1
    # odometry model (thesis eqs. 3.31-3.53) on metric image-frame key poses
    t2 = time.perf_counter()
    metric = poses_px.copy()
    metric[:, :2] *= res
    L = straight_run_length(trajectory)
    odo = odometry_errors(metric, ocoef, p, L)
    if method == "additive":
        dxo, dyo = additive_field(vis, poses_px, lf.z_meas, lf.D, odo, p, pm, rng)
        extra = {}
    else:
        er = ekf_field(vis, observed & plan.occupied, poses_px, odo, lcoef, p, res)
        dxo, dyo = er.dx, er.dy
        extra = {
            "ekf_landmarks": int(er.landmarks.size),
            "ekf_final_robot_error_px": [float(v) for v in er.robot_error[-1, :2] / res],
        }
    timings["odometry"] = time.perf_counter() - t2
    # total field and deformed map (item 6)
    t3 = time.perf_counter()
    total = DisplacementField(lf.dx + dxo, lf.dy + dyo)
    data = warp_map(plan.data, total, observed)
    timings["warp"] = time.perf_counter() - t3
    out = plan.copy(data=data)
    out.meta = {**plan.meta, "source": "map2map.parametric", "method": method}
    drawn = {
        "lidar": lcoef.as_dict(),
        "odometry": ocoef.as_dict(),
        "E_b": float(odo.e_b),
        "E_d": float(odo.e_d),
        "straight_run_L_m": float(L),
        "key_poses": int(key.size),
        **extra,
    }
    return DeformResult(
        map=out,
        field=total.masked(observed),
        lidar=DisplacementField(lf.dx, lf.dy).masked(observed),
        odometry=DisplacementField(dxo, dyo).masked(observed),
        observed=observed,
        trajectory=trajectory,
        keyposes_px=poses_px,
        method=method,
        params=p,
        drawn=drawn,
        timings=timings,
    )


def _geometry_range_angle(vis: Visibility, poses_px: np.ndarray, res: float, range_max: float):
    """Range [m], sensor-frame bearing and sensor heading of each pixel from the first
    key pose that saw it (unobserved pixels: ``range_max``, 0, 0)."""
    h, w = vis.shape
    first = vis.first_seen()
    rows, cols = np.nonzero(first >= 0)
    k = first[rows, cols]
    D = np.full((h, w), range_max)
    alpha = np.zeros((h, w))
    heading = np.zeros((h, w))
    dx = cols - poses_px[k, 0]
    dy = rows - poses_px[k, 1]
    D[rows, cols] = np.maximum(np.hypot(dx, dy) * res, 1e-3)
    alpha[rows, cols] = wrap_angle(np.arctan2(dy, dx) - poses_px[k, 2], keep_in_range=True)
    heading[rows, cols] = poses_px[k, 2]
    return D, alpha, heading
