"""Synthetic SLAM runs for the tests: a small plan, a driven route, noisy odometry and scans.

Test-only helper: drives straight segments between waypoints (turning in place) and
uses the simulator's lidar and wheel-odometry models; no exploration, so it is fast.
"""

from __future__ import annotations

import numpy as np

from map2map.core.grid import FREE, OCCUPIED, OccupancyMap
from map2map.robotlog.base import OdometryReading
from map2map.sim.lidar import Lidar, LidarConfig, Scene
from map2map.sim.odometry import OdometryErrors, WheelOdometry


def room_plan(resolution: float = 0.05) -> OccupancyMap:
    """A 9 x 6 m flat: outer walls, one interior wall with a door, a pillar."""
    w, h = int(9 / resolution), int(6 / resolution)
    data = np.full((h, w), FREE, np.uint8)
    data[:2, :] = data[-2:, :] = OCCUPIED
    data[:, :2] = data[:, -2:] = OCCUPIED
    c = int(5 / resolution)
    data[:, c : c + 2] = OCCUPIED
    data[int(2.5 / resolution) : int(3.5 / resolution), c : c + 2] = FREE  # door
    data[
        int(1.0 / resolution) : int(1.4 / resolution), int(2 / resolution) : int(2.4 / resolution)
    ] = OCCUPIED
    return OccupancyMap(data, resolution)


def drive(waypoints, speed=0.25, turn=1.0, dt=0.2):
    """True poses at ``dt`` along straight segments between waypoints (turn in place)."""
    poses = []
    x, y = waypoints[0]
    th = np.arctan2(waypoints[1][1] - y, waypoints[1][0] - x)
    poses.append((x, y, th))
    for wx, wy in waypoints[1:]:
        target = np.arctan2(wy - y, wx - x)
        while True:
            d = (target - th + np.pi) % (2 * np.pi) - np.pi
            if abs(d) < 1e-9:
                break
            th += np.clip(d, -turn * dt, turn * dt)
            poses.append((x, y, th))
        dist = np.hypot(wx - x, wy - y)
        n = max(1, int(np.ceil(dist / (speed * dt))))
        for k in range(1, n + 1):
            poses.append((x + (wx - x) * k / n, y + (wy - y) * k / n, th))
        x, y = wx, wy
    return np.asarray(poses)


def synthetic_run(seed=0, waypoints=None, lidar=None, odometry_errors=None):
    """(plan, true poses, list of (OdometryReading, LaserScan)) on :func:`room_plan`.

    Scans come from the simulator's LDS-01 model (exact ray casting, beam-model
    outliers), odometry from its encoder-tick model with UMBmark errors and slip.
    """
    rng = np.random.default_rng(seed)
    plan = room_plan()
    if waypoints is None:
        waypoints = [
            (1.0, 1.0),
            (4.0, 1.0),
            (4.0, 4.8),
            (1.0, 4.8),
            (1.0, 2.8),
            (6.5, 3.0),
            (8.0, 3.0),
            (8.0, 5.0),
            (6.0, 5.0),
            (6.0, 1.0),
            (8.0, 1.0),
        ]
    true = drive(waypoints)
    lid = Lidar(lidar or LidarConfig())
    scene = Scene.from_map(plan)
    odo = WheelOdometry(odometry_errors or OdometryErrors(), rng=rng)
    stream = []
    for k, p in enumerate(true):
        if k:
            q = true[k - 1]
            ds = float(np.hypot(p[0] - q[0], p[1] - q[1]))
            odo.step(ds, float((p[2] - q[2] + np.pi) % (2 * np.pi) - np.pi))
        t = 0.2 * k
        stream.append((OdometryReading(t, *odo.pose), lid.scan(scene, p, t, rng)))
    return plan, true, stream
