"""Differential-drive robot: the TurtleBot3 Waffle Pi, with acceleration limits and collisions.

The body is a disc of radius ``radius`` (the Waffle Pi footprint is 281 x 306 mm;
its circumscribed radius is about 0.21 m). Commands ``(v, w)`` are limited by the
maximum speeds, by each wheel's speed (``|v +- w b / 2| <= v_max``, keeping the
curvature) and by the acceleration limits; the pose then follows the exact arc of
constant ``(v, w)`` over the step.

Collisions are checked on the swept path: the arc is sampled at most half a cell
apart and every sample must keep the body clear of all blocked cells (walls,
furniture, everything outside the free space of the plan), using the clearance
map of :class:`~map2map.sim.world.World` (Euclidean distance from each cell centre
to the nearest blocked cell centre, accurate to half a cell). On contact the
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
        """Scale ``(v, w)`` so that no wheel exceeds ``max_v`` (same curvature)."""
        v = float(np.clip(v, -self.max_v, self.max_v))
        w = float(np.clip(w, -self.max_w, self.max_w))
        fastest = abs(v) + abs(w) * self.wheelbase / 2
        if fastest > self.max_v:
            s = self.max_v / fastest
            v, w = v * s, w * s
        return v, w


WAFFLE_PI = RobotParams()


def arc_step(pose, ds: float, dth: float) -> tuple[float, float, float]:
    """Pose after moving ``ds`` along an arc turning by ``dth`` (exact integration)."""
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
    clearance : callable
        ``clearance(xs, ys) -> distances`` (metres from each point to the nearest
        blocked cell), e.g. :meth:`map2map.sim.world.World.clearance_at`.
    sample_step : float
        Maximum spacing of the collision samples along the path (metres).
    """

    def __init__(self, params: RobotParams, pose, clearance, sample_step: float):
        self.params = params
        self.pose = tuple(float(v) for v in pose)
        self.v = 0.0
        self.w = 0.0
        self._clearance = clearance
        self._sample_step = float(sample_step)

    def step(self, v_cmd: float, w_cmd: float, dt: float, people=None) -> StepResult:
        """Apply a velocity command for ``dt`` seconds; returns what was executed.

        ``people`` is an optional ``(K, 3)`` array of ``(x, y, radius)``; the robot
        halts rather than drive into a person (not a collision).
        """
        p = self.params
        v_cmd, w_cmd = p.wheel_speed_limit(v_cmd, w_cmd)
        v = float(np.clip(v_cmd, self.v - p.max_acc * dt, self.v + p.max_acc * dt))
        w = float(np.clip(w_cmd, self.w - p.max_alpha * dt, self.w + p.max_alpha * dt))
        v, w = p.wheel_speed_limit(v, w)
        ds, dth = v * dt, w * dt
        if ds == 0.0 and dth == 0.0:
            self.v = self.w = 0.0
            return StepResult(0.0, 0.0, False, False)
        n = max(1, int(math.ceil(abs(ds) / self._sample_step)))
        fr = np.arange(1, n + 1) / n
        xs, ys, ths = _arc_samples(self.pose, ds, dth, fr)
        clear = self._clearance(xs, ys) >= p.radius
        blocked = np.zeros(n, bool)
        if people is not None and len(people):
            d = np.hypot(xs[:, None] - people[None, :, 0], ys[:, None] - people[None, :, 1])
            near = (d < p.radius + people[None, :, 2]).any(axis=1)
            # only block motion that gets closer to a person
            d0 = np.hypot(self.pose[0] - people[:, 0], self.pose[1] - people[:, 1])
            closer = (d < d0[None, :]).any(axis=1)
            blocked = near & closer
        ok = clear & ~blocked
        if ok.all():
            self.pose = (float(xs[-1]), float(ys[-1]), _wrap(float(ths[-1])))
            self.v, self.w = v, w
            return StepResult(ds, dth, False, False)
        k = int(np.argmin(ok))  # first bad sample
        f = fr[k - 1] if k > 0 else 0.0
        if k > 0:
            self.pose = (float(xs[k - 1]), float(ys[k - 1]), _wrap(float(ths[k - 1])))
        self.v = self.w = 0.0
        return StepResult(ds * f, dth * f, not clear[k], bool(blocked[k] and clear[k]))


def _arc_samples(pose, ds, dth, fractions):
    x, y, th = pose
    d = ds * fractions
    a = dth * fractions
    if abs(dth) < 1e-9:
        mid = th + a / 2
        return x + d * np.cos(mid), y + d * np.sin(mid), th + a
    r = ds / dth
    return x + r * (np.sin(th + a) - math.sin(th)), y - r * (np.cos(th + a) - math.cos(th)), th + a


def _wrap(a: float) -> float:
    return (a + math.pi) % (2 * math.pi) - math.pi
