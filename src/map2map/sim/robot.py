"""Differential-drive robot: the TurtleBot3 Waffle Pi, with acceleration limits and collisions.

The body is a disc of radius ``radius`` (the Waffle Pi footprint is 281 x 306 mm;
its circumscribed radius is about 0.21 m). Commands ``(v, w)`` are limited by the
maximum speeds, by each wheel's speed (``|v +- w b / 2| <= v_max``, keeping the
curvature) and by the acceleration limits; the pose then follows the exact arc of
constant ``(v, w)`` over the step.

Collisions are checked on the swept path (numba): the arc is sampled at most half
a cell apart and every sample must keep the body clear of all blocked cells
(walls, furniture, everything outside the free space of the plan), using the
clearance map of :class:`~map2map.sim.world.World` to skip samples far from any
wall and an exact disc-square overlap test against the blocked cells near walls. On contact the
robot stops at the last clear sample, its speed drops to zero and the step
reports the collision: it never tunnels through a wall.

Examples
--------
>>> import numpy as np
>>> p = RobotParams()
>>> round(p.wheel_speed_limit(0.26, 1.0)[0], 3)   # a turn slows the forward speed
0.168
>>> [round(v, 4) for v in arc_step((0.0, 0.0, 0.0), 1.0, np.pi / 2)]  # quarter circle
[0.6366, 0.6366, 1.5708]
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numba import njit

from ..core.geometry import wrap_angle

__all__ = ["RobotParams", "WAFFLE_PI", "DiffDriveRobot", "StepResult", "arc_step"]


@dataclass(frozen=True)
class RobotParams:
    """TurtleBot3 Waffle Pi defaults (ROBOTIS e-manual; DWA limits of turtlebot3_navigation).

    Parameters
    ----------
    wheel_radius : float
        0.033 m.
    wheelbase : float
        Distance between the wheels, 0.287 m.
    max_v, max_w : float
        0.26 m/s and 1.82 rad/s.
    radius : float
        Body radius for collisions, 0.2 m.
    max_acc, max_alpha : float
        Linear (2.5 m/s^2) and angular (3.2 rad/s^2) acceleration limits.
    """

    wheel_radius: float = 0.033
    wheelbase: float = 0.287
    max_v: float = 0.26
    max_w: float = 1.82
    radius: float = 0.2
    max_acc: float = 2.5
    max_alpha: float = 3.2

    def wheel_speed_limit(self, v: float, w: float) -> tuple[float, float]:
        """Scale ``(v, w)`` so that no wheel exceeds ``max_v`` (same curvature).

        Parameters
        ----------
        v, w : float
            Linear (m/s) and angular (rad/s) command.

        Returns
        -------
        v, w : float
        """
        v = min(max(float(v), -self.max_v), self.max_v)
        w = min(max(float(w), -self.max_w), self.max_w)
        fastest = abs(v) + abs(w) * self.wheelbase / 2
        if fastest > self.max_v:
            s = self.max_v / fastest
            v, w = v * s, w * s
        return v, w


WAFFLE_PI = RobotParams()


def arc_step(pose, ds: float, dth: float) -> tuple[float, float, float]:
    """Pose after moving ``ds`` along an arc turning by ``dth`` (exact integration).

    Parameters
    ----------
    pose : (x, y, theta)
        Start pose.
    ds : float
        Arc length, metres.
    dth : float
        Heading change, radians.

    Returns
    -------
    (x, y, theta)

    Examples
    --------
    >>> [round(v, 6) for v in arc_step((0.0, 0.0, 0.0), 1.0, 0.0)]
    [1.0, 0.0, 0.0]
    """
    x, y, th = pose
    if abs(dth) < 1e-9:
        mid = th + dth / 2
        return x + ds * math.cos(mid), y + ds * math.sin(mid), th + dth
    r = ds / dth
    return (
        x + r * (math.sin(th + dth) - math.sin(th)),
        y - r * (math.cos(th + dth) - math.cos(th)),
        th + dth,
    )


@dataclass
class StepResult:
    """What happened during one physics step."""

    ds: float  # distance actually travelled (m)
    dth: float  # rotation actually made (rad)
    collided: bool
    blocked_by_person: bool


class DiffDriveRobot:
    """The true robot: pose, velocities and swept collision checks against a world.

    Parameters
    ----------
    params : RobotParams
    pose : (x, y, theta)
        True start pose in the plan frame.
    world : World
        Gives ``clearance`` (metres from each cell to the nearest blocked cell)
        and its frame ``plan`` (:class:`map2map.sim.world.World`).
    """

    def __init__(self, params: RobotParams, pose, world):
        self.params = params
        self.pose = tuple(float(v) for v in pose)
        self.v = 0.0
        self.w = 0.0
        self._clear = world.clearance
        self._blocked = world.blocked
        m = world.plan
        self._frame = (m.origin[0], m.origin[1], m.origin[2], m.resolution, m.height)
        self._sample_step = m.resolution / 2

    def step(self, v_cmd: float, w_cmd: float, dt: float, people=None) -> StepResult:
        """Apply a velocity command for ``dt`` seconds; returns what was executed.

        ``people`` is an optional ``(K, 3)`` array of ``(x, y, radius)``; the robot
        halts rather than drive into a person (not a collision).

        Parameters
        ----------
        v_cmd, w_cmd : float
            Command.
        dt : float
            Seconds.
        people : array, optional
            Circles ``(x, y, r)`` of the people.

        Returns
        -------
        StepResult
            Executed motion ``ds``, ``dth``, ``collided``, ``blocked_by_person``.
        """
        p = self.params
        v_cmd, w_cmd = p.wheel_speed_limit(v_cmd, w_cmd)
        v = min(max(v_cmd, self.v - p.max_acc * dt), self.v + p.max_acc * dt)
        w = min(max(w_cmd, self.w - p.max_alpha * dt), self.w + p.max_alpha * dt)
        v, w = p.wheel_speed_limit(v, w)
        ds, dth = v * dt, w * dt
        if ds == 0.0 and dth == 0.0:
            self.v = self.w = 0.0
            return StepResult(0.0, 0.0, False, False)
        n = max(1, int(math.ceil(abs(ds) / self._sample_step)))
        x, y, th = self.pose
        k, is_person = _sweep(
            self._clear,
            self._blocked,
            *self._frame,
            x,
            y,
            th,
            ds,
            dth,
            n,
            p.radius,
            people if people is not None else _NO_PEOPLE,
        )
        if k == n:
            self.pose = _wrap_pose(arc_step(self.pose, ds, dth))
            self.v, self.w = v, w
            return StepResult(ds, dth, False, False)
        f = k / n  # the last clear sample
        self.pose = _wrap_pose(arc_step(self.pose, ds * f, dth * f))
        self.v = self.w = 0.0
        return StepResult(ds * f, dth * f, not is_person, is_person)


_NO_PEOPLE = np.zeros((0, 3))


def _wrap_pose(p):
    return (p[0], p[1], wrap_angle(p[2]))


@njit(cache=True)
def _sweep(clear, blocked, ox, oy, yaw, res, height, x, y, th, ds, dth, n, radius, people):
    """Index (0..n) of the first sample along the arc that is not clear, and whether
    a person (rather than a wall) stopped it; ``n`` when the whole arc is clear."""
    h, w = clear.shape
    cy, sy = math.cos(yaw), math.sin(yaw)
    for i in range(1, n + 1):
        f = i / n
        a = dth * f
        d = ds * f
        if abs(dth) < 1e-9:
            px = x + d * math.cos(th + a / 2)
            py = y + d * math.sin(th + a / 2)
        else:
            rr = ds / dth
            px = x + rr * (math.sin(th + a) - math.sin(th))
            py = y - rr * (math.cos(th + a) - math.cos(th))
        lx = cy * (px - ox) + sy * (py - oy)
        ly = -sy * (px - ox) + cy * (py - oy)
        col = int(math.floor(lx / res))
        row = int(math.floor(height - ly / res))
        if row < 0 or col < 0 or row >= h or col >= w:
            return i - 1, False
        if clear[row, col] < radius + res and _disc_hits(
            blocked, lx / res, height - ly / res, radius / res
        ):
            return i - 1, False
        for k in range(people.shape[0]):
            dd = math.hypot(px - people[k, 0], py - people[k, 1])
            if dd < radius + people[k, 2]:
                d0 = math.hypot(x - people[k, 0], y - people[k, 1])
                if dd < d0:  # only motion towards a person is blocked
                    return i - 1, True
    return n, False


@njit(cache=True)
def _disc_hits(blocked, px, py, rad):
    """Whether a disc (pixel units, centre in continuous pixel coordinates) overlaps
    any blocked cell square: the exact test, used near walls."""
    h, w = blocked.shape
    r0 = max(0, int(math.floor(py - rad)))
    r1 = min(h - 1, int(math.floor(py + rad)))
    c0 = max(0, int(math.floor(px - rad)))
    c1 = min(w - 1, int(math.floor(px + rad)))
    if py - rad < 0 or px - rad < 0 or py + rad >= h or px + rad >= w:
        return True  # leaves the plan
    r2 = rad * rad
    for r in range(r0, r1 + 1):
        dy = 0.0 if r <= py <= r + 1 else min(abs(py - r), abs(py - r - 1))
        for c in range(c0, c1 + 1):
            if blocked[r, c]:
                dx = 0.0 if c <= px <= c + 1 else min(abs(px - c), abs(px - c - 1))
                if dx * dx + dy * dy < r2:
                    return True
    return False

