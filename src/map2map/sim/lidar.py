"""A 2-D laser scanner: the ROBOTIS LDS-01 of the TurtleBot3 by default.

The true range of every beam comes from exact ray casting
(:mod:`map2map.sim.raycast`) against the solid cells of the world (plan walls plus
furniture) and analytically against moving people (circles). A measurement is
then drawn from the classic beam model (Thrun, Burgard & Fox, *Probabilistic
Robotics*, sec. 6.3): Gaussian noise on a correct return, and with small
probabilities a *short* reading (an unmapped obstacle, uniform between the minimum
range and the true range), a *max-range failure* (no return) or a *random*
reading (uniform over the whole range). Ranges are quantised to 1 mm, as the
LDS-01 reports them.

Conventions of the produced :class:`~map2map.robotlog.base.LaserScan`:

* ``inf`` means *no return* (nothing within ``range_max``; REP 117);
* ``0.0`` means an invalid reading closer than ``range_min``;
* beams are counter-clockwise from ``angle_min`` in the sensor frame
  (0 = straight ahead). A full 360 degree scanner starts at 0 like the ROS
  ``hls_lfcd_lds_driver``; a narrower field of view is centred on the heading and
  includes both ends (180 degrees at 1 degree gives 181 beams, the classic SICK
  layout of CARMEN ``FLASER`` logs).

The scan is taken instantaneously at the pose (no motion distortion during the
200 ms rotation of the real sensor).

Examples
--------
>>> import numpy as np
>>> from map2map.core.grid import OccupancyMap
>>> data = np.full((60, 60), 255, np.uint8); data[:, 50] = 0   # wall at column 50
>>> m = OccupancyMap(data, 0.05)
>>> lidar = Lidar(LidarConfig(noise_sigma=0.0, p_short=0, p_max=0, p_rand=0))
>>> scene = Scene.from_map(m)
>>> scan = lidar.scan(scene, (1.0, 1.5, 0.0), t=0.0, rng=np.random.default_rng(0))
>>> scan.n_beams, round(float(scan.ranges[0]), 3)            # 2.5 m - 1.0 m to the wall face
(360, 1.5)
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np
from numba import njit

from ..core.grid import OccupancyMap
from ..robotlog.base import LaserScan
from .raycast import cast_scan, make_cast_grid

__all__ = ["LidarConfig", "Lidar", "Scene", "LDS01"]


@dataclass(frozen=True)
class LidarConfig:
    """Scanner parameters; defaults are the ROBOTIS LDS-01 (TurtleBot3 Waffle Pi).

    Parameters
    ----------
    fov_deg : float
        Field of view in degrees (360 for the LDS-01; the thesis used 180).
    increment_deg : float
        Angle between beams (1 degree).
    range_min, range_max : float
        Valid range in metres (0.12 - 3.5 m).
    rate_hz : float
        Scans per second (about 5 Hz).
    noise_sigma : float
        Standard deviation of the range noise on correct returns (0.01 m).
    p_short, p_max, p_rand : float
        Per-beam probabilities of a short reading, a max-range failure and a
        random reading (beam-model outliers). All may be 0.
    sensor_offset : (x, y, theta)
        Sensor pose in the robot frame.
    """

    fov_deg: float = 360.0
    increment_deg: float = 1.0
    range_min: float = 0.12
    range_max: float = 3.5
    rate_hz: float = 5.0
    noise_sigma: float = 0.01
    p_short: float = 0.01
    p_max: float = 0.005
    p_rand: float = 0.002
    sensor_offset: tuple[float, float, float] = (0.0, 0.0, 0.0)

    def __post_init__(self) -> None:
        if not 0 < self.fov_deg <= 360:
            raise ValueError(f"fov_deg must be in (0, 360], got {self.fov_deg}")
        if self.increment_deg <= 0:
            raise ValueError("increment_deg must be > 0")
        if not 0 <= self.range_min < self.range_max:
            raise ValueError("need 0 <= range_min < range_max")
        if self.rate_hz <= 0:
            raise ValueError("rate_hz must be > 0")
        if self.noise_sigma < 0 or min(self.p_short, self.p_max, self.p_rand) < 0:
            raise ValueError("noise and outlier probabilities must be >= 0")
        if self.p_short + self.p_max + self.p_rand > 1:
            raise ValueError("outlier probabilities sum to more than 1")

    @property
    def n_beams(self) -> int:
        n = int(round(self.fov_deg / self.increment_deg))
        return n if self.fov_deg >= 360 else n + 1

    @property
    def angle_min(self) -> float:
        return 0.0 if self.fov_deg >= 360 else -math.radians(self.fov_deg) / 2

    @property
    def angle_increment(self) -> float:
        return math.radians(self.increment_deg)

    @property
    def angles(self) -> np.ndarray:
        """Beam angles in the sensor frame (radians, counter-clockwise)."""
        return self.angle_min + self.angle_increment * np.arange(self.n_beams)


#: The TurtleBot3 LDS-01 with its data-sheet values.
LDS01 = LidarConfig()


@dataclass
class Scene:
    """What the scanner sees: static solid cells of a grid plus moving circles.

    Parameters
    ----------
    frame : OccupancyMap
        Gives the metric frame (resolution, origin) of ``solid``.
    solid : (H, W) bool array
        Cells that block beams (walls, furniture).
    circles : (K, 3) float array
        Moving obstacles ``(x, y, radius)`` in metres (people); updated by the world.
    """

    frame: OccupancyMap
    solid: np.ndarray
    circles: np.ndarray = field(default_factory=lambda: np.zeros((0, 3)))

    def __post_init__(self) -> None:
        self.solid = np.asarray(self.solid, bool)
        self._field: np.ndarray | None = None
        self._reach = -1.0

    def _cast_field(self, reach: float) -> np.ndarray:
        """The casting field (:func:`make_cast_grid`), made at the first cast (a world
        whose lidar never casts, such as a furniture trial, never pays for it) over the
        known cells plus more than ``reach`` pixels: rays start in free space, and a cell
        the box leaves out is farther from a ray's path than the ray is long, so the
        ranges are those of the whole grid's field, to the bit."""
        if self._field is None or reach > self._reach:
            within = None
            if math.isfinite(reach):
                known = self.solid | self.frame.free
                rows = np.flatnonzero(known.any(axis=1))
                cols = np.flatnonzero(known.any(axis=0))
                pad = int(math.ceil(reach)) + 8
                if rows.size:
                    within = (rows[0] - pad, rows[-1] + 1 + pad, cols[0] - pad, cols[-1] + 1 + pad)
            self._field = make_cast_grid(self.solid, within)
            self._reach = reach
        return self._field

    @classmethod
    def from_map(cls, m: OccupancyMap) -> Scene:
        """Occupied cells of ``m`` block the beams; free and unknown cells do not.

        Parameters
        ----------
        m : OccupancyMap
            The map.

        Returns
        -------
        Scene
        """
        return cls(m, m.occupied)

    def cast(self, x: float, y: float, theta: float, rel_angles: np.ndarray, max_range: float):
        """Exact true ranges (metres, ``inf`` for nothing within ``max_range``).

        ``(x, y, theta)`` is the sensor pose in the frame of ``self.frame``;
        ``rel_angles`` are beam angles relative to ``theta`` (counter-clockwise).

        Parameters
        ----------
        x, y, theta : float
            Sensor pose, world frame.
        rel_angles : (B,) float array
            Beam angles relative to ``theta``.
        max_range : float
            Metres.

        Returns
        -------
        (B,) float array
            Metres.
        """
        m = self.frame
        row, col = m.world_to_pixel_float(x, y)
        px, py = float(col) + 0.5, float(row) + 0.5
        yaw = m.origin[2]
        # pixel frame has y pointing down: angles flip sign
        heading = -(theta - yaw)
        rel = -np.asarray(rel_angles, float)
        out = np.empty(rel.shape[0])
        cast_scan(
            self._cast_field(max_range / m.resolution),
            px,
            py,
            heading,
            np.cos(rel),
            np.sin(rel),
            max_range / m.resolution,
            out,
        )
        out *= m.resolution
        if len(self.circles):
            _cast_circles(x, y, theta + np.asarray(rel_angles, float), self.circles, out)
        return out


@njit(cache=True)
def _cast_circles(x, y, angles, circles, out):
    """Lower ``out`` to the first intersection of each ray with any circle."""
    for j in range(angles.shape[0]):
        dx = math.cos(angles[j])
        dy = math.sin(angles[j])
        for k in range(circles.shape[0]):
            fx = x - circles[k, 0]
            fy = y - circles[k, 1]
            b = fx * dx + fy * dy
            c = fx * fx + fy * fy - circles[k, 2] ** 2
            disc = b * b - c
            if disc < 0.0:
                continue
            if c < 0.0:  # sensor inside the circle: blocked at once
                t = 0.0
            else:
                t = -b - math.sqrt(disc)
            if 0.0 <= t < out[j]:
                out[j] = t


class Lidar:
    """Turns true geometry into noisy :class:`LaserScan` s (see module docstring)."""

    def __init__(self, config: LidarConfig = LDS01):
        self.config = config
        self._angles = config.angles

    def true_ranges(self, scene: Scene, pose) -> np.ndarray:
        """Exact ranges (metres) from robot ``pose``; ``inf`` beyond ``range_max``.

        Parameters
        ----------
        scene : Scene
            What the beams hit.
        pose : (x, y, theta)
            Robot pose (the sensor offset is applied).

        Returns
        -------
        (B,) float array
        """
        cfg = self.config
        x, y, th = (float(v) for v in pose)
        ox, oy, oth = cfg.sensor_offset
        sx = x + math.cos(th) * ox - math.sin(th) * oy
        sy = y + math.sin(th) * ox + math.cos(th) * oy
        d = scene.cast(sx, sy, th + oth, self._angles, cfg.range_max)
        d[d > cfg.range_max] = np.inf
        return d

    def measure(self, true: np.ndarray, rng: np.random.Generator) -> np.ndarray:
        """Apply the beam model and 1 mm quantisation to exact ranges (float32).

        Parameters
        ----------
        true : (B,) float array
            Exact ranges.
        rng : numpy.random.Generator
            Source of the noise.

        Returns
        -------
        (B,) float32 array
        """
        cfg = self.config
        n = true.shape[0]
        kind = rng.random(n)
        noise = rng.standard_normal(n)
        u = rng.random(n)
        hit = np.isfinite(true)
        z = np.where(hit, true + cfg.noise_sigma * noise, np.inf)
        lo, hi = cfg.range_min, cfg.range_max
        c1 = cfg.p_short
        c2 = c1 + cfg.p_max
        c3 = c2 + cfg.p_rand
        short_hi = np.where(hit, np.minimum(true, hi), hi)
        z = np.where(kind < c1, lo + u * np.maximum(short_hi - lo, 0.0), z)
        z = np.where((kind >= c1) & (kind < c2), np.inf, z)
        z = np.where((kind >= c2) & (kind < c3), lo + u * (hi - lo), z)
        z = np.where(z >= hi, np.inf, z)
        z = np.where(z < lo, 0.0, z)
        return (np.round(z * 1000.0) / 1000.0).astype(np.float32)

    def scan(self, scene: Scene, pose, t: float, rng: np.random.Generator) -> LaserScan:
        """A noisy scan taken at robot ``pose`` (plan frame) at time ``t``.

        Parameters
        ----------
        scene : Scene
            What the beams hit.
        pose : (x, y, theta)
            Robot pose, plan frame.
        t : float
            Time stamp, seconds.
        rng : numpy.random.Generator
            Source of the noise.

        Returns
        -------
        LaserScan
        """
        cfg = self.config
        ranges = self.measure(self.true_ranges(scene, pose), rng)
        return LaserScan(
            t=float(t),
            ranges=ranges,
            angle_min=cfg.angle_min,
            angle_increment=cfg.angle_increment,
            range_min=cfg.range_min,
            range_max=cfg.range_max,
            sensor_offset=tuple(float(v) for v in cfg.sensor_offset),
        )
