"""Occupancy-grid mapping with known poses, and the ``oracle`` mapper built on it.

:class:`LogOddsGrid` is the classic inverse-sensor-model grid (Moravec & Elfes;
Thrun, Burgard & Fox, *Probabilistic Robotics*, table 9.1): every cell a beam
crosses gets ``l_free``, the cell of its end point ``l_occ``; a beam with no
return clears its cells up to the maximum range with the weaker ``l_free_far``
(two are needed to mark a cell free, so one max-range failure through a wall does
not make free space behind it).
Cells are traced with the same Amanatides-Woo traversal as the simulated lidar
(numba). The grid grows as the robot explores; a ternary view (0 / 127 / 255) is
kept up to date cell by cell so that asking for the map is cheap.

:class:`OracleMapper` integrates each scan at the **true** pose (given through
:meth:`OracleMapper.observe_truth` before each :meth:`~OracleMapper.update`):
the map a perfect SLAM would make, used to test exploration and as a reference.
Its map frame starts at the first true pose, like every mapper's.

Examples
--------
>>> import numpy as np
>>> from map2map.robotlog.base import LaserScan, OdometryReading
>>> m = OracleMapper(resolution=0.05)
>>> scan = LaserScan(0.0, np.full(360, 1.0, np.float32), 0.0, np.deg2rad(1), 0.12, 3.5)
>>> m.observe_truth((5.0, 5.0, 0.3))
>>> m.update(OdometryReading(0.0, 0.0, 0.0, 0.0), scan)
>>> m.pose().round(6).tolist()
[0.0, 0.0, 0.0]
>>> g = m.get_map(); int(g.occupied.sum()) > 100, int(g.free.sum()) > 1000
(True, True)
"""

from __future__ import annotations

import math

import cv2
import numpy as np
from numba import njit

from ..core.geometry import compose_pose, relative_pose
from ..core.grid import FREE, OCCUPIED, UNKNOWN, OccupancyMap
from ..robotlog.base import LaserScan, OdometryReading

__all__ = ["LogOddsGrid", "OracleMapper", "resample_to_frame"]


@njit(cache=True)
def _set_cell(L, T, r, c, dl, lmin, lmax, occ_thr, free_thr):
    v = L[r, c] + dl
    v = min(max(v, lmin), lmax)
    L[r, c] = v
    if v > occ_thr:
        T[r, c] = 0
    elif v < free_thr:
        T[r, c] = 255
    else:
        T[r, c] = 127


@njit(cache=True)
def integrate_scan(L, T, x0, y0, angles, dists, hits, l_free, l_free_far, l_occ, lims, margin):
    """Trace every beam from ``(x0, y0)`` (pixel coordinates) and update the grid.

    ``angles`` are pixel-frame directions, ``dists`` lengths in pixels, ``hits``
    whether the beam ended on an obstacle (otherwise it only clears, with
    ``l_free_far``). Cells the beam leaves less than ``margin`` pixels before its
    end point are not cleared: a noisy return that overshoots into a thin wall at a
    grazing angle must not erase the wall cell it crossed. A beam that crosses a
    confidently occupied cell (log-odds >= ``block_thr``) weakens it and stops
    there: an outlier reading through a known wall (a random or max-range reading)
    must not carve free space behind it, while a wall that really went away (a
    person who walked off) still fades after a few beams.
    ``lims = (lmin, lmax, occ_thr, free_thr, block_thr)``.

    Parameters
    ----------
    L : (H, W) float32 array
        Log-odds grid, updated in place.
    T : (H, W) array
        Per-cell observation counter, updated in place.
    x0, y0 : float
        Sensor position in pixels.
    angles, dists : float arrays
        Beam directions (pixel frame) and lengths (pixels).
    hits : bool array
        Beam ended on an obstacle.
    l_free, l_free_far, l_occ : float
        Log-odds increments.
    lims : tuple of float
        ``(lmin, lmax, occ_thr, free_thr, block_thr)``.
    margin : float
        Pixels before the end point left uncleared.
    """
    h, w = L.shape
    lmin, lmax, occ_thr, free_thr, block_thr = lims[0], lims[1], lims[2], lims[3], lims[4]
    for i in range(angles.shape[0]):
        dx = math.cos(angles[i])
        dy = math.sin(angles[i])
        d = dists[i]
        lf = l_free if hits[i] else l_free_far
        c = int(math.floor(x0))
        r = int(math.floor(y0))
        if dx > 0.0:
            sc, tx, tdx = 1, (c + 1 - x0) / dx, 1.0 / dx
        elif dx < 0.0:
            sc, tx, tdx = -1, (c - x0) / dx, -1.0 / dx
        else:
            sc, tx, tdx = 0, np.inf, np.inf
        if dy > 0.0:
            sr, ty, tdy = 1, (r + 1 - y0) / dy, 1.0 / dy
        elif dy < 0.0:
            sr, ty, tdy = -1, (r - y0) / dy, -1.0 / dy
        else:
            sr, ty, tdy = 0, np.inf, np.inf
        d_free = d - margin if hits[i] else d
        blocked = False
        while True:
            t_next = tx if tx < ty else ty
            if t_next >= d:
                break
            if t_next < d_free and 0 <= r < h and 0 <= c < w:
                solid = L[r, c] >= block_thr
                _set_cell(L, T, r, c, lf, lmin, lmax, occ_thr, free_thr)
                if solid:  # a confident wall: whatever lies behind it was not seen
                    blocked = True
                    break
            if tx < ty:
                c += sc
                tx += tdx
            elif ty < tx:
                r += sr
                ty += tdy
            else:
                c += sc
                r += sr
                tx += tdx
                ty += tdy
        if not blocked and 0 <= r < h and 0 <= c < w:
            _set_cell(L, T, r, c, l_occ if hits[i] else lf, lmin, lmax, occ_thr, free_thr)


class LogOddsGrid:
    """A growing log-odds occupancy grid in a metric frame (image order, yaw 0).

    Parameters
    ----------
    resolution : float
        Metres per cell.
    l_occ, l_free, l_free_far : float
        Log-odds increments for a hit cell, a crossed cell and a cell crossed by a
        beam without return. Defaults 1.0, -0.33, -0.15: with the occupied
        threshold at 0 a cell is occupied when more than about a quarter of the
        beams reaching it end in it, like GMapping's ``occ_thresh`` of 0.25.
    l_min, l_max : float
        Clamping bounds (-2, 3.5).
    occ_threshold, free_threshold : float
        Log-odds above which a cell is occupied (0.0) and below which it is free
        (-0.3, one crossing beam); cells never observed stay unknown.
    block_threshold : float
        Log-odds from which a cell stops the beams crossing it (2.0: hit at least
        twice more than missed); see :func:`integrate_scan`.
    margin : float
        Extra metres added on each side whenever the grid has to grow.
    """

    def __init__(
        self,
        resolution: float = 0.05,
        *,
        l_occ: float = 1.0,
        l_free: float = -0.33,
        l_free_far: float = -0.15,
        l_min: float = -2.0,
        l_max: float = 3.5,
        occ_threshold: float = 0.0,
        free_threshold: float = -0.3,
        block_threshold: float = 2.0,
        margin: float = 3.0,
    ):
        self.resolution = float(resolution)
        self.l_occ, self.l_free, self.l_free_far = l_occ, l_free, l_free_far
        self._lims = np.array([l_min, l_max, occ_threshold, free_threshold, block_threshold])
        self.margin = margin
        self.L = np.zeros((0, 0), np.float32)
        self.T = np.zeros((0, 0), np.uint8)
        self.ox = self.oy = 0.0  # world position of the lower-left corner

    def _ensure(self, xmin, xmax, ymin, ymax) -> None:
        res = self.resolution
        h, w = self.L.shape
        if h and (
            xmin >= self.ox
            and ymin >= self.oy
            and xmax < self.ox + w * res
            and ymax < self.oy + h * res
        ):
            return
        if not h:
            nx0 = math.floor((xmin - self.margin) / res)
            ny0 = math.floor((ymin - self.margin) / res)
            nx1 = math.ceil((xmax + self.margin) / res)
            ny1 = math.ceil((ymax + self.margin) / res)
            self.ox, self.oy = nx0 * res, ny0 * res
            self.L = np.zeros((ny1 - ny0, nx1 - nx0), np.float32)
            self.T = np.full(self.L.shape, UNKNOWN, np.uint8)
            return
        cx0 = round(self.ox / res)
        cy0 = round(self.oy / res)
        nx0 = min(cx0, math.floor((xmin - self.margin) / res))
        ny0 = min(cy0, math.floor((ymin - self.margin) / res))
        nx1 = max(cx0 + w, math.ceil((xmax + self.margin) / res))
        ny1 = max(cy0 + h, math.ceil((ymax + self.margin) / res))
        left, bottom = cx0 - nx0, cy0 - ny0
        right, top = nx1 - (cx0 + w), ny1 - (cy0 + h)
        pads = ((top, bottom), (left, right))
        self.L = np.pad(self.L, pads)
        self.T = np.pad(self.T, pads, constant_values=UNKNOWN)
        self.ox, self.oy = nx0 * res, ny0 * res

    def integrate(self, sensor_pose, scan: LaserScan) -> None:
        """Add one scan taken from ``sensor_pose`` (x, y, theta) in this grid's frame.

        Parameters
        ----------
        sensor_pose : (x, y, theta)
            Sensor pose, this grid's frame.
        scan : LaserScan
            The scan.
        """
        x, y, th = (float(v) for v in sensor_pose)
        rmax = float(scan.range_max)
        self._ensure(x - rmax, x + rmax, y - rmax, y + rmax)
        r = np.asarray(scan.ranges, np.float64)
        hits = np.isfinite(r) & (r >= scan.range_min) & (r < rmax)
        far = np.isinf(r) & (r > 0)
        use = hits | far
        if not use.any():
            return
        res = self.resolution
        h = self.L.shape[0]
        px = (x - self.ox) / res
        py = h - (y - self.oy) / res
        ang = -(th + scan.angles[use])
        dist = np.where(hits[use], r[use], rmax) / res
        integrate_scan(
            self.L,
            self.T,
            px,
            py,
            ang,
            dist,
            hits[use],
            self.l_free,
            self.l_free_far,
            self.l_occ,
            self._lims,
            0.5,
        )

    def to_map(self) -> OccupancyMap:
        """The ternary map (a copy) with its frame.

        Returns
        -------
        OccupancyMap
        """
        if not self.T.size:
            return OccupancyMap(np.full((1, 1), UNKNOWN, np.uint8), self.resolution)
        return OccupancyMap(self.T.copy(), self.resolution, (self.ox, self.oy, 0.0))


class OracleMapper:
    """Mapping at the true poses (see module docstring); implements the Mapper protocol.

    Parameters
    ----------
    resolution : float
        Map resolution in metres per cell.
    seed : int, optional
        Unused (the oracle is deterministic); accepted like every registered mapper.
    **grid_options
        Passed to :class:`LogOddsGrid`.
    """

    name = "oracle"

    def __init__(self, resolution: float = 0.05, seed: int | None = None, **grid_options):
        self.grid = LogOddsGrid(resolution, **grid_options)
        self._truth: tuple[float, float, float] | None = None
        self._start: tuple[float, float, float] | None = None
        self._pose = (0.0, 0.0, 0.0)

    def observe_truth(self, pose) -> None:
        """The true pose (any fixed world frame) at the next scan.

        Parameters
        ----------
        pose : (x, y, theta)
            True pose.
        """
        self._truth = tuple(float(v) for v in pose)

    def update(self, odom: OdometryReading, scan: LaserScan) -> None:
        """Integrate ``scan`` at the pose given to :meth:`observe_truth`.

        Parameters
        ----------
        odom : OdometryReading
            Ignored (the oracle uses the true pose).
        scan : LaserScan
            Integrated at the true pose.

        Raises
        ------
        RuntimeError
            No :meth:`observe_truth` since the last update.
        """
        sensor = compose_pose(self._advance(), scan.sensor_offset)
        self.grid.integrate(sensor, scan)

    def _advance(self) -> tuple[float, float, float]:
        """Take the pose given to :meth:`observe_truth` as the current one (map frame: the
        first such pose at the origin) and return it."""
        if self._truth is None:
            raise RuntimeError(f"{type(self).__name__} needs observe_truth(pose) before "
                               "each update")
        if self._start is None:
            self._start = self._truth
        self._pose = relative_pose(self._start, self._truth)
        self._truth = None
        return self._pose

    def pose(self) -> np.ndarray:
        """The current pose in the map frame (exact).

        Returns
        -------
        (3,) ndarray
            The last true pose relative to the first one (the map frame).
        """
        return np.array(self._pose)

    def get_map(self) -> OccupancyMap:
        """The map built from the true poses.

        Returns
        -------
        OccupancyMap
        """
        return self.grid.to_map()


def resample_to_frame(m: OccupancyMap, frame_pose, target: OccupancyMap) -> OccupancyMap:
    """Resample map ``m`` onto the grid of ``target`` (same shape, resolution, origin).

    ``frame_pose`` is the pose of ``m``'s world frame in ``target``'s world frame
    (for a SLAM map: the robot's true start pose in the plan). Nearest-neighbour,
    cells outside ``m`` are unknown.

    Parameters
    ----------
    m : OccupancyMap
        The map to move.
    frame_pose : (x, y, theta)
        Pose of ``m``'s world frame in ``target``'s.
    target : OccupancyMap
        The grid to resample onto.

    Returns
    -------
    OccupancyMap
        ``target``'s shape, resolution and origin, ``m``'s content.

    Examples
    --------
    >>> import numpy as np
    >>> src = OccupancyMap(np.full((4, 4), 255, np.uint8), 1.0, (-2.0, -2.0, 0.0))
    >>> dst = OccupancyMap(np.full((10, 10), 127, np.uint8), 1.0)
    >>> out = resample_to_frame(src, (5.0, 5.0, 0.0), dst)
    >>> int(out.free.sum()), bool(out.free[3:7, 3:7].all())
    (16, True)
    """
    # plan pixel (col, row) -> plan world -> m's frame -> m pixel (col, row)
    pts = np.array([[0.0, 0.0], [1.0, 0.0], [0.0, 1.0]])
    wx, wy = target.pixel_to_world(pts[:, 1], pts[:, 0])
    fx, fy, fth = (float(v) for v in frame_pose)
    c, s = math.cos(fth), math.sin(fth)
    lx = c * (wx - fx) + s * (wy - fy)
    ly = -s * (wx - fx) + c * (wy - fy)
    rr, cc = m.world_to_pixel_float(lx, ly)
    src = np.column_stack([cc, rr])
    a = np.column_stack([src[1] - src[0], src[2] - src[0], src[0]])  # 2x3: dst -> src
    data = cv2.warpAffine(
        m.data,
        a,
        (target.width, target.height),
        flags=cv2.INTER_NEAREST | cv2.WARP_INVERSE_MAP,
        borderMode=cv2.BORDER_CONSTANT,
        borderValue=UNKNOWN,
    )
    # guard against interpolation artefacts: keep only the three values (in place: a
    # plan of 12 MP made two int64 copies)
    data[(data != OCCUPIED) & (data != FREE)] = UNKNOWN
    return OccupancyMap(data, target.resolution, target.origin)
