"""Synthetic SLAM runs for the tests: a small plan, a driven route, noisy odometry and scans.

Test-only helper (the real simulator lives in :mod:`map2map.sim`). Ray casting here is
a plain numpy march along each beam in 1 cm steps -- slow but obviously correct.
"""

from __future__ import annotations

import numpy as np

from map2map.maps.grid import FREE, OCCUPIED, OccupancyMap
from map2map.slam.base import LaserScan, OdometryReading


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


def raycast(m: OccupancyMap, x: float, y: float, theta: float, angles: np.ndarray, rmax: float):
    """Ranges from world pose ``(x, y, theta)`` to the first occupied cell (inf if none)."""
    steps = np.arange(0.0, rmax, 0.01)
    a = theta + angles
    px = x + np.cos(a)[:, None] * steps[None, :]
    py = y + np.sin(a)[:, None] * steps[None, :]
    r, c = m.world_to_pixel(px, py)
    inside = m.contains(r, c)
    occ = np.ones(r.shape, bool)
    occ[inside] = m.data[r[inside], c[inside]] == OCCUPIED
    first = np.where(occ.any(axis=1), occ.argmax(axis=1), -1)
    out = np.where(first >= 0, steps[np.maximum(first, 0)], np.inf)
    return out


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


def odometry(true: np.ndarray, rng, scale=1.01, rot_scale=1.02, sigma_t=0.01, sigma_r=0.01):
    """Integrate the true increments with systematic scale error and random noise per step."""
    out = [np.zeros(3)]
    for k in range(1, len(true)):
        p0, p1 = true[k - 1], true[k]
        c, s = np.cos(p0[2]), np.sin(p0[2])
        dx, dy = p1[0] - p0[0], p1[1] - p0[1]
        lx, ly = c * dx + s * dy, -s * dx + c * dy
        dt = (p1[2] - p0[2] + np.pi) % (2 * np.pi) - np.pi
        d = np.hypot(lx, ly)
        lx = lx * scale + rng.normal(0, sigma_t * d + 1e-4)
        ly = ly * scale + rng.normal(0, sigma_t * d * 0.3 + 1e-4)
        dt = dt * rot_scale + rng.normal(0, sigma_r * abs(dt) + 0.002 * d + 1e-4)
        q = out[-1]
        cq, sq = np.cos(q[2]), np.sin(q[2])
        out.append(np.array([q[0] + cq * lx - sq * ly, q[1] + sq * lx + cq * ly, q[2] + dt]))
    return np.asarray(out)


def synthetic_run(seed=0, waypoints=None, n_beams=360, rmax=3.5, noise=0.01):
    """(plan, true poses, list of (OdometryReading, LaserScan)) on :func:`room_plan`."""
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
    odo = odometry(true, rng)
    inc = 2 * np.pi / n_beams
    angles = np.arange(n_beams) * inc
    stream = []
    for k, (p, o) in enumerate(zip(true, odo, strict=True)):
        r = raycast(plan, p[0], p[1], p[2], angles, rmax)
        r = r + rng.normal(0, noise, r.shape)
        r = np.where(np.isfinite(r), r, np.inf).astype(np.float32)
        t = 0.2 * k
        stream.append((OdometryReading(t, *o), LaserScan(t, r, 0.0, inc, 0.12, rmax)))
    return plan, true, stream
