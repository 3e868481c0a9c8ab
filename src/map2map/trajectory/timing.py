"""Timed trajectories for a differential-drive robot (thesis section 3.2).

"The orientation, velocity, and acceleration are then calculated using waypoints and
time of arrival information." A path of waypoints becomes a turn-in-place / drive-straight
motion (what a differential-drive TurtleBot3 Waffle Pi does with a global plan): at each
waypoint the robot turns to the next segment's heading, then drives it. Both motions
follow trapezoidal (or triangular) velocity profiles within the robot's limits
(0.26 m/s, 1.82 rad/s; accelerations of the TurtleBot3 DWA planner). Because the robot
never turns and drives at once, the wheel speeds ``v +- omega * b / 2`` stay within
``0.26 m/s`` (``1.82 * 0.287 / 2 = 0.261``). Arrival times at the waypoints are kept
in :attr:`Trajectory.meta`.

All positions are world metres (ROS map frame), ``theta`` radians counter-clockwise
from the world x axis.

Examples
--------
>>> import numpy as np
>>> traj = time_waypoints(np.array([[0.0, 0.0], [1.0, 0.0], [1.0, 1.0]]))
>>> float(traj.v.max()) <= 0.26 + 1e-9, float(np.abs(traj.omega).max()) <= 1.82 + 1e-9
(True, True)
>>> bool(np.allclose([traj.x[-1], traj.y[-1]], [1.0, 1.0]))
True
"""

from __future__ import annotations

import csv
import io
import math
import os
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from ..core._io import atomic_path
from ..core.errors import InputError
from ..core.geometry import wrap_angle

__all__ = [
    "Trajectory",
    "trapezoid",
    "time_waypoints",
    "trajectory_from_poses",
    "read_trajectory",
    "read_waypoints",
]


@dataclass
class Trajectory:
    """A timed robot trajectory, world metres and radians.

    Attributes
    ----------
    t, x, y, theta, v, omega : (N,) float arrays
        Time [s], position [m], heading [rad], forward speed [m/s], turn rate [rad/s].
    meta : dict
        Extras such as the waypoint arrival times.
    """

    t: np.ndarray
    x: np.ndarray
    y: np.ndarray
    theta: np.ndarray
    v: np.ndarray
    omega: np.ndarray
    meta: dict[str, Any] = field(default_factory=dict)

    def __post_init__(self) -> None:
        arrays = [
            np.asarray(getattr(self, k), float) for k in ("t", "x", "y", "theta", "v", "omega")
        ]
        n = arrays[0].shape
        if any(a.shape != n or a.ndim != 1 for a in arrays):
            raise ValueError("trajectory arrays must be 1-D and of equal length")
        self.t, self.x, self.y, self.theta, self.v, self.omega = arrays

    def __len__(self) -> int:
        return self.t.size

    @property
    def acceleration(self) -> np.ndarray:
        """Forward acceleration [m/s^2] (finite differences of ``v``)."""
        return np.gradient(self.v, self.t) if len(self) > 1 else np.zeros_like(self.v)

    @property
    def angular_acceleration(self) -> np.ndarray:
        """Angular acceleration [rad/s^2]."""
        return np.gradient(self.omega, self.t) if len(self) > 1 else np.zeros_like(self.v)

    @property
    def length(self) -> float:
        """Distance travelled [m]."""
        return float(np.hypot(np.diff(self.x), np.diff(self.y)).sum())

    def to_csv(self, path: str | os.PathLike) -> None:
        """Write ``t,x,y,theta,v,omega`` (header line, one row per sample, full precision so
        that reading it back gives the same numbers) atomically.

        Parameters
        ----------
        path : path-like
            Output file.
        """
        buf = io.StringIO()
        buf.write("t,x,y,theta,v,omega\n")
        np.savetxt(
            buf,
            np.column_stack([self.t, self.x, self.y, self.theta, self.v, self.omega]),
            delimiter=",",
            fmt="%.17g",
        )
        with atomic_path(path) as tmp:
            tmp.write_text(buf.getvalue(), encoding="utf-8")


def trapezoid(tau: np.ndarray, distance: float, v_max: float, a_max: float):
    """Position and speed at times ``tau`` of a rest-to-rest trapezoidal profile.

    Returns ``(s, v, duration)``; triangular when ``distance`` is too short to reach
    ``v_max``.

    Parameters
    ----------
    tau : ndarray
        Times since the start, seconds (clipped to the profile's duration).
    distance : float
        Distance (or angle) to cover, >= 0.
    v_max : float
        Speed limit.
    a_max : float
        Acceleration limit.

    Returns
    -------
    s, v : ndarray
        Position and speed at ``tau``.
    duration : float
        Time the profile takes.

    Examples
    --------
    >>> s, v, T = trapezoid(np.array([0.0, 10.0]), 1.0, 0.5, 1.0)
    >>> round(T, 3), s.tolist()
    (2.5, [0.0, 1.0])
    """
    tau = np.asarray(tau, float)
    d = abs(float(distance))
    if d == 0:
        return np.zeros_like(tau), np.zeros_like(tau), 0.0
    t_acc = v_max / a_max
    if a_max * t_acc * t_acc >= d:  # triangular
        t_acc = math.sqrt(d / a_max)
        peak = a_max * t_acc
        t_flat = 0.0
    else:
        peak = v_max
        t_flat = (d - a_max * t_acc * t_acc) / v_max
    total = 2 * t_acc + t_flat
    tc = np.clip(tau, 0.0, total)
    s1 = 0.5 * a_max * np.minimum(tc, t_acc) ** 2
    s2 = peak * np.clip(tc - t_acc, 0.0, t_flat)
    t3 = np.clip(tc - t_acc - t_flat, 0.0, t_acc)
    s3 = peak * t3 - 0.5 * a_max * t3**2
    v = np.where(tc < t_acc, a_max * tc, np.where(tc < t_acc + t_flat, peak, peak - a_max * t3))
    v = np.where((tau <= 0) | (tau >= total), 0.0, v)
    sign = 1.0 if distance >= 0 else -1.0
    return sign * (s1 + s2 + s3), sign * v, total


def time_waypoints(
    waypoints: np.ndarray,
    *,
    v_max: float = 0.26,
    omega_max: float = 1.82,
    acc_lin: float = 2.5,
    acc_ang: float = 3.2,
    dt: float = 0.1,
    theta0: float | None = None,
) -> Trajectory:
    """Turn-then-drive timed trajectory through world waypoints (W, 2) [m].

    The robot starts at rest facing the first segment (or ``theta0``), and stops at the
    last waypoint. Samples every ``dt`` seconds plus the final instant.

    Parameters
    ----------
    waypoints : (W, 2) array-like
        World positions in metres, W >= 2.
    v_max, omega_max : float
        Linear (m/s) and angular (rad/s) speed limits (TurtleBot3 Waffle Pi defaults).
    acc_lin, acc_ang : float
        Linear (m/s^2) and angular (rad/s^2) acceleration limits.
    dt : float
        Sampling period, seconds.
    theta0 : float, optional
        Initial heading (radians); default: facing the first segment.

    Returns
    -------
    Trajectory
        Poses and speeds sampled every ``dt`` seconds.

    Examples
    --------
    >>> tr = time_waypoints(np.array([[0.0, 0.0], [1.0, 0.0]]), dt=0.5)
    >>> round(float(tr.x[-1]), 6), round(float(tr.t[-1]), 2)
    (1.0, 3.95)
    """
    wp = np.asarray(waypoints, float)
    keep = np.concatenate([[True], np.hypot(*np.diff(wp, axis=0).T) > 1e-9])
    wp = wp[keep]
    if wp.shape[0] < 2:
        return Trajectory(
            np.array([0.0]), wp[:1, 0], wp[:1, 1], np.array([theta0 or 0.0]), [0.0], [0.0]
        )
    seg = np.diff(wp, axis=0)
    headings = np.arctan2(seg[:, 1], seg[:, 0])
    heading = headings[0] if theta0 is None else float(theta0)
    prims = []  # (kind, t0, T, x0, y0, th0, amount)
    t = 0.0
    arrivals = [0.0]
    for i in range(seg.shape[0]):
        turn = float(wrap_angle(headings[i] - heading, keep_in_range=True))
        if abs(turn) > 1e-9:
            T = trapezoid(np.zeros(1), turn, omega_max, acc_ang)[2]
            prims.append(("turn", t, T, wp[i, 0], wp[i, 1], heading, turn))
            t += T
            heading = headings[i]
        dist = float(np.hypot(*seg[i]))
        T = trapezoid(np.zeros(1), dist, v_max, acc_lin)[2]
        prims.append(("drive", t, T, wp[i, 0], wp[i, 1], heading, dist))
        t += T
        arrivals.append(t)
    times = np.arange(0.0, t, dt)
    times = np.append(times, t) if times[-1] < t - 1e-9 else times
    x = np.empty_like(times)
    y = np.empty_like(times)
    th = np.empty_like(times)
    v = np.zeros_like(times)
    om = np.zeros_like(times)
    starts = np.array([p[1] for p in prims])
    which = np.clip(np.searchsorted(starts, times, side="right") - 1, 0, len(prims) - 1)
    for k, (kind, t0, _dur, x0, y0, th0, amount) in enumerate(prims):
        sel = which == k
        if not sel.any():
            continue
        tau = times[sel] - t0
        if kind == "turn":
            s, rate, _ = trapezoid(tau, amount, omega_max, acc_ang)
            x[sel], y[sel], th[sel], om[sel] = x0, y0, wrap_angle(th0 + s, keep_in_range=True), rate
        else:
            s, speed, _ = trapezoid(tau, amount, v_max, acc_lin)
            x[sel] = x0 + s * math.cos(th0)
            y[sel] = y0 + s * math.sin(th0)
            th[sel], v[sel] = th0, speed
    return Trajectory(times, x, y, th, v, om, meta={"waypoint_times": arrivals})


def trajectory_from_poses(
    x, y, theta, t=None, *, v_max: float = 0.26, omega_max: float = 1.82
) -> Trajectory:
    """A trajectory from recorded poses; times (if absent) from the speed limits.

    Without ``t`` each step takes ``max(distance / v_max, |turn| / omega_max)`` (at least
    1 ms). Speeds are finite differences: ``v`` is the displacement projected on the
    heading per second, ``omega`` the wrapped heading change per second.

    Parameters
    ----------
    x, y, theta : array-like
        Poses in world metres and radians (N >= 2).
    t : array-like, optional
        Times in seconds, strictly increasing.
    v_max, omega_max : float
        Speed limits used to time the steps when ``t`` is absent.

    Returns
    -------
    Trajectory

    Examples
    --------
    >>> tr = trajectory_from_poses([0.0, 0.26], [0.0, 0.0], [0.0, 0.0])
    >>> tr.t.tolist(), tr.v.round(3).tolist()
    ([0.0, 1.0], [0.26, 0.0])
    """
    x, y, theta = (np.asarray(a, float) for a in (x, y, theta))
    dist = np.hypot(np.diff(x), np.diff(y))
    dth = wrap_angle(np.diff(theta), keep_in_range=True)
    if t is None:
        dts = np.maximum(np.maximum(dist / v_max, np.abs(dth) / omega_max), 1e-3)
        t = np.concatenate([[0.0], np.cumsum(dts)])
    t = np.asarray(t, float)
    dt = np.diff(t)
    fwd = np.diff(x) * np.cos(theta[:-1]) + np.diff(y) * np.sin(theta[:-1])
    v = np.concatenate([fwd / dt, [0.0]]) if t.size > 1 else np.zeros(1)
    om = np.concatenate([dth / dt, [0.0]]) if t.size > 1 else np.zeros(1)
    return Trajectory(t, x, y, wrap_angle(theta, keep_in_range=True), v, om)


def _read_table(path: str | os.PathLike, what: str) -> tuple[list[str] | None, np.ndarray]:
    source = os.fspath(path)
    try:
        with open(path, encoding="utf-8") as fh:
            text = fh.read()
    except OSError as exc:
        raise InputError(source, f"cannot read {what} ({exc.strerror})") from None
    except UnicodeDecodeError:
        raise InputError(source, f"{what} is not a text file") from None
    lines = [ln.split("#", 1)[0].strip() for ln in text.splitlines()]
    numbered = [(i + 1, ln) for i, ln in enumerate(lines) if ln]
    if not numbered:
        raise InputError(source, f"{what} is empty")
    header = None
    rows = []
    for k, (lineno, ln) in enumerate(numbered):
        cells = [c for c in next(csv.reader([ln.replace("\t", ",")])) if c.strip() != ""]
        if len(cells) == 1:
            cells = ln.split()
        try:
            vals = [float(c) for c in cells]
        except ValueError:
            if k == 0:
                header = [c.strip().lower() for c in cells]
                continue
            raise InputError(source, f"line {lineno}: not numbers: {ln!r}") from None
        if not all(math.isfinite(v) for v in vals):
            raise InputError(source, f"line {lineno}: non-finite value: {ln!r}")
        if rows and len(vals) != len(rows[0][1]):
            raise InputError(
                source, f"line {lineno}: {len(vals)} columns, expected {len(rows[0][1])}"
            )
        rows.append((lineno, vals))
    if not rows:
        raise InputError(source, f"{what} has no data rows")
    return header, np.array([r[1] for r in rows], float)


def read_waypoints(path: str | os.PathLike) -> np.ndarray:
    """Waypoints file: one ``x y`` (or ``x,y``) pair per line in world metres, ``#`` comments,
    optional header ``x,y``. At least two waypoints. Returns (W, 2).

    Parameters
    ----------
    path : path-like
        The text file.

    Returns
    -------
    (W, 2) float array
        World metres.

    Raises
    ------
    InputError
        Missing file, a malformed line (with its number), fewer than two waypoints.
    """
    header, arr = _read_table(path, "waypoints file")
    if header is not None and header[:2] != ["x", "y"]:
        raise InputError(path, f"waypoints header must be 'x,y', got {','.join(header)!r}")
    if arr.shape[1] != 2:
        raise InputError(path, f"waypoints need 2 columns (x y), found {arr.shape[1]}")
    if arr.shape[0] < 2:
        raise InputError(path, "at least two waypoints are needed")
    return arr


def read_trajectory(
    path: str | os.PathLike, *, v_max: float = 0.26, omega_max: float = 1.82
) -> Trajectory:
    """Read a trajectory CSV: columns ``x,y,theta``, ``t,x,y,theta`` or ``t,x,y,theta,v,omega``.

    A header line naming the columns is optional (with it, columns may come in any order
    and extra ones are ignored). World metres and radians. ``v`` and ``omega`` are
    recomputed from the poses unless both are given; missing times come from the speed
    limits (:func:`trajectory_from_poses`).

    Parameters
    ----------
    path : path-like
        The CSV file.
    v_max, omega_max : float
        Speed limits that time the poses when the file has no ``t`` column.

    Returns
    -------
    Trajectory

    Raises
    ------
    InputError
        Missing file, unknown columns, malformed numbers, fewer than two poses.
    """
    header, arr = _read_table(path, "trajectory file")
    if header is not None:
        need = {"x", "y", "theta"}
        if not need <= set(header):
            raise InputError(path, f"trajectory header must name x, y, theta; got {header}")
        col = {name: header.index(name) for name in header}
        if arr.shape[1] != len(header):
            raise InputError(path, "header and data have different column counts")
        get = {k: arr[:, col[k]] for k in col}
    else:
        names = {3: ["x", "y", "theta"], 4: ["t", "x", "y", "theta"],
                 6: ["t", "x", "y", "theta", "v", "omega"]}.get(arr.shape[1])  # fmt: skip
        if names is None:
            raise InputError(
                path, f"expected 3 (x,y,theta), 4 (t,x,y,theta) or 6 columns, got {arr.shape[1]}"
            )
        get = {k: arr[:, i] for i, k in enumerate(names)}
    if arr.shape[0] < 2:
        raise InputError(path, "a trajectory needs at least two poses")
    t = get.get("t")
    if t is not None and not np.all(np.diff(t) > 0):
        raise InputError(path, "times must increase strictly")
    traj = trajectory_from_poses(
        get["x"], get["y"], get["theta"], t, v_max=v_max, omega_max=omega_max
    )
    if "v" in get and "omega" in get:
        traj.v, traj.omega = get["v"].copy(), get["omega"].copy()
    return traj
