"""Frontier exploration like ROS ``explore_lite``, and following a given route.

Exploration (Yamauchi 1997; the ``explore_lite`` package of ROS that the thesis
ran, section 4.1) works only on the robot's **own current map** and pose
estimate, in the mapper's frame, never on the plan:

1. **Costmap** (:func:`make_costmap`): the map's occupied cells are inflated. A
   cell is *lethal* when its distance to the nearest occupied cell is below the
   robot radius; within a further ``safety`` margin it is very expensive (paths
   only use it to get out of a tight spot); beyond that the cost decays
   exponentially up to ``inflation_radius`` (like ``costmap_2d``'s inflation
   layer), so paths keep clear of walls. Unknown cells are not traversable.
2. **Global planning**: Dijkstra over the 8-connected costmap from the robot
   (:func:`dijkstra`, numba, binary heap) gives the path cost to every cell.
3. **Frontiers** (:func:`find_frontiers`): free cells next to unknown ones,
   grouped 8-connected; groups shorter than ``min_frontier_size`` metres are
   ignored. A frontier's goal is its reachable cell (within ``goal_reach`` of it)
   with the least path cost; its cost is ``potential_scale * path_length -
   gain_scale * size`` (explore_lite's ranking with the path length as distance).
   Unreachable frontiers are skipped; goals where the robot made no progress for
   ``progress_timeout`` seconds are **blacklisted**.
4. **Path following**: pure pursuit on the planned path with a look-ahead
   distance, turning on the spot when the heading error is large; a local safety
   check sweeps the robot's disc along the commanded arc through the latest scan
   (like DWA's footprint check) and slows down or stops before contact.

Replanning happens every ``replan_period`` seconds (and at once when the goal is
reached or the path is blocked). Exploration ends when no frontier is left.

:class:`RouteFollower` instead drives through given waypoints (a list of
``(x, y)`` or ``(x, y, theta)``, a recorded trajectory or a PRM route) with the
same controller.

Examples
--------
>>> import numpy as np
>>> from map2map.core.grid import OccupancyMap
>>> data = np.full((40, 60), 127, np.uint8); data[5:35, 5:40] = 255
>>> data[5:35, 5] = 0                                   # a wall on the left
>>> m = OccupancyMap(data, 0.05)
>>> cm = make_costmap(m, robot_radius=0.2)
>>> fr = find_frontiers(m, min_size_cells=5)
>>> len(fr.sizes), int(fr.sizes[0]) > 20                # the open right/top/bottom edges
(1, True)
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import cv2
import numpy as np
from numba import njit

from ..core.geometry import wrap_angle
from ..core.grid import OccupancyMap
from ..robotlog.base import LaserScan

__all__ = [
    "ExploreConfig",
    "Costmap",
    "make_costmap",
    "dijkstra",
    "Frontiers",
    "find_frontiers",
    "Explorer",
    "RouteFollower",
    "PathController",
]


@dataclass(frozen=True)
class ExploreConfig:
    """Exploration and control parameters (explore_lite / TurtleBot3 navigation defaults).

    Parameters
    ----------
    robot_radius : float
        Body radius used for the lethal zone (m).
    lethal_margin : float
        Cells closer than ``robot_radius + lethal_margin`` to a mapped wall are not
        traversable: the margin covers the planning grid's coarseness and the local
        safety check's own margin, so that paths are never refused by it.
    safety : float
        Beyond the lethal distance, a further margin of very expensive cells (m).
    inflation_radius : float
        Distance up to which costs are raised near obstacles (m).
    cost_scaling : float
        Exponential decay rate of the inflation cost (1/m).
    inflation_weight : float
        Cost added right at the lethal boundary (a free cell costs 1).
    min_frontier_size : float
        Smallest frontier considered, metres of frontier cells (explore_lite: 0.75).
    potential_scale, gain_scale : float
        Ranking weights of path length and frontier size (explore_lite: 3 and 1).
    goal_reach : float
        Goals may be up to this far from their frontier (m).
    progress_timeout : float
        Seconds without getting 0.1 m closer to the goal before it is blacklisted.
    blacklist_radius : float
        Frontier goals this close to a blacklisted goal are skipped (m).
    blacklist_amnesties : int
        When only blacklisted frontiers are left, the blacklist is cleared and they
        are tried again, at most this many times, before exploration ends.
    replan_period : float
        Seconds between replans (explore_lite's planner_frequency is 0.33 Hz).
    plan_resolution : float
        Cell size of the global planning grid (m); the costmap is min-pooled onto it.
    switch_margin : float
        The robot stays with its current frontier (followed as it shrinks) unless
        another one scores this much better (about a metre of path).
    lookahead : float
        Pure-pursuit look-ahead distance (m).
    goal_tolerance : float
        Distance at which a goal counts as reached (m).
    """

    robot_radius: float = 0.2
    lethal_margin: float = 0.01
    safety: float = 0.05
    inflation_radius: float = 0.6
    cost_scaling: float = 6.0
    inflation_weight: float = 8.0
    min_frontier_size: float = 0.5
    potential_scale: float = 3.0
    gain_scale: float = 1.0
    goal_reach: float = 0.4
    progress_timeout: float = 15.0
    blacklist_radius: float = 0.3
    blacklist_amnesties: int = 2
    replan_period: float = 3.0
    plan_resolution: float = 0.1
    switch_margin: float = 3.0
    lookahead: float = 0.35
    goal_tolerance: float = 0.25


# --------------------------------------------------------------------- costmap
@dataclass
class Costmap:
    """Traversal costs of a map: ``cost`` (float32, ``inf`` where not traversable)."""

    map: OccupancyMap
    cost: np.ndarray
    clearance: np.ndarray  # metres from each cell centre to the nearest occupied cell


def make_costmap(
    m: OccupancyMap,
    *,
    robot_radius: float = 0.2,
    safety: float = 0.03,
    inflation_radius: float = 0.6,
    cost_scaling: float = 6.0,
    inflation_weight: float = 8.0,
) -> Costmap:
    """Inflated costmap of ``m`` (see module docstring).

    Parameters
    ----------
    m : OccupancyMap
        The mapper's current map.
    robot_radius : float
        Radius of the robot, metres.
    safety : float
        Extra clearance, metres, below which a cell is not traversable.
    inflation_radius : float
        Distance, metres, over which costs decay to 1.
    cost_scaling : float
        Exponential decay rate of the inflation.
    inflation_weight : float
        Cost added at the edge of the lethal zone.

    Returns
    -------
    Costmap
    """
    src = np.where(m.occupied, 0, 255).astype(np.uint8)
    d = cv2.distanceTransform(src, cv2.DIST_L2, cv2.DIST_MASK_5)
    clear = (d - np.float32(0.5)) * np.float32(m.resolution)  # to the nearest occupied face
    cost = _inflate(
        clear,
        m.free,
        robot_radius,
        robot_radius + safety,
        inflation_radius,
        cost_scaling,
        inflation_weight,
    )
    return Costmap(m, cost, clear)


@njit(cache=True)
def _inflate(clear, free, radius, lethal_r, inflation_radius, scaling, weight):
    h, w = clear.shape
    out = np.empty((h, w), np.float32)
    for r in range(h):
        for c in range(w):
            d = clear[r, c]
            if not free[r, c] or d < radius:
                out[r, c] = np.inf
            elif d < lethal_r:  # inside the safety margin: only to get out of it
                out[r, c] = 50.0
            elif d > inflation_radius:
                out[r, c] = 1.0
            else:
                out[r, c] = 1.0 + weight * math.exp(-scaling * (d - lethal_r))
    return out


@njit(cache=True)
def _heap_push(hk, hv, n, key, val):
    i = n
    hk[i] = key
    hv[i] = val
    while i > 0:
        p = (i - 1) >> 1
        if hk[p] <= hk[i]:
            break
        hk[p], hk[i] = hk[i], hk[p]
        hv[p], hv[i] = hv[i], hv[p]
        i = p
    return n + 1


@njit(cache=True)
def _heap_pop(hk, hv, n):
    key = hk[0]
    val = hv[0]
    n -= 1
    hk[0] = hk[n]
    hv[0] = hv[n]
    i = 0
    while True:
        lft = 2 * i + 1
        if lft >= n:
            break
        s = lft
        if lft + 1 < n and hk[lft + 1] < hk[lft]:
            s = lft + 1
        if hk[i] <= hk[s]:
            break
        hk[s], hk[i] = hk[i], hk[s]
        hv[s], hv[i] = hv[i], hv[s]
        i = s
    return key, val, n


@njit(cache=True)
def dijkstra(cost, start_r, start_c):
    """Path cost (cells x cost) from one cell to every cell, 8-connected, and parents.

    The edge cost between neighbours is the step length (1 or sqrt 2) times the
    mean of the two cells' costs. Cells with infinite cost are never entered
    (the start cell is always expanded). Returns ``(dist, parent)`` with
    ``parent`` the flat index of the previous cell (-1 at the start / unreached).

    Parameters
    ----------
    cost : (H, W) float array
        Cell costs (``inf``: not traversable).
    start_r, start_c : int
        Start cell.

    Returns
    -------
    dist : (H, W) float64 array
    parent : (H, W) int64 array
    """
    h, w = cost.shape
    n_cells = h * w
    dist = np.full(n_cells, np.inf, np.float32)
    parent = np.full(n_cells, -1, np.int32)
    cap = 8 * n_cells + 1
    hk = np.empty(min(cap, 4 * n_cells + 16), np.float32)
    hv = np.empty(hk.shape[0], np.int32)
    s = start_r * w + start_c
    dist[s] = 0.0
    n = _heap_push(hk, hv, 0, np.float32(0.0), s)
    dr = (-1, -1, -1, 0, 0, 1, 1, 1)
    dc = (-1, 0, 1, -1, 1, -1, 0, 1)
    diag = math.sqrt(2.0)
    flat = cost.ravel()
    while n > 0:
        d, u, n = _heap_pop(hk, hv, n)
        if d > dist[u]:
            continue
        ur = u // w
        uc = u - ur * w
        cu = flat[u]
        if not np.isfinite(cu):
            cu = 1.0  # leaving a lethal start cell
        for k in range(8):
            vr = ur + dr[k]
            vc = uc + dc[k]
            if vr < 0 or vc < 0 or vr >= h or vc >= w:
                continue
            v = vr * w + vc
            cv = flat[v]
            if not np.isfinite(cv):
                continue
            step = diag if (dr[k] != 0 and dc[k] != 0) else 1.0
            nd = d + np.float32(step * 0.5 * (cu + cv))
            if nd < dist[v]:
                dist[v] = nd
                parent[v] = u
                if n >= hk.shape[0]:  # grow the heap (rare)
                    hk2 = np.empty(hk.shape[0] * 2, np.float32)
                    hv2 = np.empty(hk.shape[0] * 2, np.int32)
                    hk2[:n] = hk[:n]
                    hv2[:n] = hv[:n]
                    hk, hv = hk2, hv2
                n = _heap_push(hk, hv, n, nd, v)
    return dist.reshape(h, w), parent


def backtrack(parent: np.ndarray, goal_flat: int, width: int) -> np.ndarray:
    """Cells ``(row, col)`` from the start to ``goal_flat`` following ``parent``.

    Parameters
    ----------
    parent : (H, W) int array
        From :func:`dijkstra`.
    goal_flat : int
        Flat index of the goal cell.
    width : int
        Grid width.

    Returns
    -------
    (P, 2) int array
        ``(row, col)`` from start to goal.

    Examples
    --------
    >>> cost = np.ones((3, 4), np.float32)
    >>> dist, parent = dijkstra(cost, 0, 0)
    >>> backtrack(parent, 2 * 4 + 3, 4).tolist()
    [[0, 0], [1, 1], [2, 2], [2, 3]]
    """
    cells = []
    u = int(goal_flat)
    while u >= 0:
        cells.append(u)
        u = int(parent[u])
    cells.reverse()
    a = np.array(cells, np.int64)
    return np.column_stack([a // width, a % width])


# -------------------------------------------------------------------- frontiers
@dataclass
class Frontiers:
    """Frontier groups of a map: ``labels`` image (0 = none) and per-group ``sizes``."""

    labels: np.ndarray
    sizes: np.ndarray  # cells per group (index k -> label k + 1)


def find_frontiers(m: OccupancyMap, min_size_cells: int = 10) -> Frontiers:
    """Free cells with an unknown 4-neighbour, grouped, small groups dropped.

    Unknown cells with at least 6 free cells among their 8 neighbours (gaps between
    diverging beams far from the robot) and unknown cells touching a wall (the
    fringe beams graze) do not make frontiers. Frontier cells up to one cell apart
    belong to the same group (a ragged boundary is one frontier, not many dashes).

    Parameters
    ----------
    m : OccupancyMap
        The mapper's current map.
    min_size_cells : int
        Smallest group kept.

    Returns
    -------
    Frontiers
    """
    free = m.free.astype(np.uint8)
    k3 = np.ones((3, 3), np.uint8)
    n_free = cv2.filter2D(free, -1, k3, borderType=cv2.BORDER_CONSTANT)
    near_wall = cv2.dilate(m.occupied.astype(np.uint8), k3)
    unk = m.unknown & (n_free < 6) & (near_wall == 0)
    nb = np.zeros_like(unk)
    nb[1:, :] |= unk[:-1, :]
    nb[:-1, :] |= unk[1:, :]
    nb[:, 1:] |= unk[:, :-1]
    nb[:, :-1] |= unk[:, 1:]
    front = m.free & nb
    joined = cv2.dilate(front.astype(np.uint8), k3)
    n, labels = cv2.connectedComponents(joined, connectivity=8)
    labels = np.where(front, labels, 0)
    sizes = np.bincount(labels.ravel(), minlength=n)[1:]
    keep = np.flatnonzero(sizes >= min_size_cells)
    remap = np.zeros(n, np.int32)
    remap[keep + 1] = np.arange(1, len(keep) + 1)
    return Frontiers(remap[labels], sizes[keep].astype(np.int64))


@njit(cache=True)
def _line_of_sight(occ, r0, c0, r1, c1):
    """No occupied cell strictly between two cells (Bresenham)."""
    dr = abs(r1 - r0)
    dc = abs(c1 - c0)
    sr = 1 if r1 > r0 else -1
    sc = 1 if c1 > c0 else -1
    err = dc - dr
    r, c = r0, c0
    while True:
        e2 = 2 * err
        if e2 > -dr:
            err -= dr
            c += sc
        if e2 < dc:
            err += dc
            r += sr
        if r == r1 and c == c1:
            return True
        if occ[r, c]:
            return False


@njit(cache=True)
def frontier_goals(labels, n_groups, dist, occ, reach):
    """A goal per frontier group: near its middle, reachable, in sight of the frontier.

    The middle of a group is its cell nearest to the group's centroid (explore_lite
    drives to the frontier's middle: from there the robot sees past the frontier,
    while the frontier's nearest end is often the edge of a shadow). The goal is the
    reachable cell within ``reach`` cells of the middle with the least path cost and
    a clear line of sight to it; when there is none, the same search around every
    cell of the group. Returns ``(goal_flat, goal_cost)`` per group (-1 / inf if none).

    Parameters
    ----------
    labels : (H, W) int array
        Frontier groups (0 = none, k = group k - 1).
    n_groups : int
        Number of groups.
    dist : (H, W) float array
        Path cost from the robot (:func:`dijkstra`).
    occ : (H, W) bool array
        Cells that block the line of sight.
    reach : int
        Search radius around the middle, cells.

    Returns
    -------
    goal_flat : (n_groups,) int64 array
    goal_cost : (n_groups,) float64 array
    """
    h, w = labels.shape
    sum_r = np.zeros(n_groups)
    sum_c = np.zeros(n_groups)
    cnt = np.zeros(n_groups)
    for r in range(h):
        for c in range(w):
            g = labels[r, c]
            if g > 0:
                sum_r[g - 1] += r
                sum_c[g - 1] += c
                cnt[g - 1] += 1
    mid_d = np.full(n_groups, np.inf)
    mid = np.full(n_groups, -1, np.int64)
    for r in range(h):
        for c in range(w):
            g = labels[r, c] - 1
            if g >= 0:
                d = (r - sum_r[g] / cnt[g]) ** 2 + (c - sum_c[g] / cnt[g]) ** 2
                if d < mid_d[g]:
                    mid_d[g] = d
                    mid[g] = r * w + c
    best = np.full(n_groups, np.inf, np.float32)
    cell = np.full(n_groups, -1, np.int64)
    for g in range(n_groups):
        if mid[g] >= 0:
            _search_goal(dist, occ, mid[g] // w, mid[g] % w, reach, g, best, cell)
    for r in range(h):
        for c in range(w):
            g = labels[r, c] - 1
            if g >= 0 and cell[g] < 0:
                _search_goal(dist, occ, r, c, reach, g, best, cell)
    return cell, best


@njit(cache=True)
def _search_goal(dist, occ, r, c, reach, g, best, cell):
    h, w = dist.shape
    for ddr in range(-reach, reach + 1):
        rr = r + ddr
        if rr < 0 or rr >= h:
            continue
        for ddc in range(-reach, reach + 1):
            if ddr * ddr + ddc * ddc > reach * reach:
                continue
            cc = c + ddc
            if cc < 0 or cc >= w:
                continue
            d = dist[rr, cc]
            if d < best[g] and _line_of_sight(occ, r, c, rr, cc):
                best[g] = d
                cell[g] = rr * w + cc


# ------------------------------------------------------------------ controller
class PathController:
    """Pure pursuit along a polyline (map frame) with turn-on-the-spot and obstacle slowdown."""

    def __init__(self, config: ExploreConfig, max_v: float, max_w: float):
        self.cfg = config
        self.max_v = max_v
        self.max_w = max_w
        self.path = np.zeros((0, 2))
        self._i = 0
        self._scan = None
        self._pts = (np.zeros(0), np.zeros(0))

    def set_path(self, path: np.ndarray) -> None:
        self.path = np.asarray(path, float).reshape(-1, 2)
        self._i = 0

    def remaining(self, pose) -> float:
        if not len(self.path):
            return 0.0
        p = self.path[self._i :]
        d0 = math.hypot(p[0, 0] - pose[0], p[0, 1] - pose[1])
        return d0 + float(np.hypot(*np.diff(p, axis=0).T).sum()) if len(p) > 1 else d0

    def command(self, pose, scan: LaserScan | None) -> tuple[float, float, bool]:
        """``(v, w, blocked)`` to follow the path from ``pose``; ``(0, 0, False)`` at the end.

        Parameters
        ----------
        pose : (x, y, theta)
            Pose estimate, map frame.
        scan : LaserScan or None
            Latest scan (stops the robot before an obstacle).

        Returns
        -------
        v, w : float
        blocked : bool
        """
        if not len(self.path):
            return 0.0, 0.0, False
        x, y, th = pose
        self._i, tx, ty, end = _pursuit_target(self.path, self._i, x, y, self.cfg.lookahead)
        alpha = wrap_angle(math.atan2(ty - y, tx - x) - th)
        w = min(max(2.5 * alpha, -self.max_w), self.max_w)
        if abs(alpha) > math.radians(50):
            return 0.0, w, False
        v = self.max_v * max(0.0, 1.0 - abs(alpha) / math.radians(60))
        v = min(v, max(0.05, end))  # ease into the goal
        if scan is not None:
            # local safety (like DWA's footprint check): sweep the body along the
            # commanded arc through the latest scan's points and slow down or stop
            px, py = self._scan_points(scan)
            t_hit = _time_to_contact(px, py, v, w, self.cfg.robot_radius + 0.005, 1.2, 0.1)
            if t_hit <= 0.2:
                return 0.0, w, True
            if t_hit < 1.2:
                v *= (t_hit - 0.2) / 1.0
        return v, w, False

    def _scan_points(self, scan: LaserScan):
        if scan is not self._scan:
            r = np.asarray(scan.ranges, float)
            ok = np.isfinite(r) & (r >= max(scan.range_min, 1e-3)) & (r < scan.range_max)
            a = scan.angles[ok] + scan.sensor_offset[2]
            ox, oy = scan.sensor_offset[0], scan.sensor_offset[1]
            self._pts = (ox + r[ok] * np.cos(a), oy + r[ok] * np.sin(a))
            self._scan = scan
        return self._pts


@njit(cache=True)
def _pursuit_target(path, i0, x, y, lookahead):
    """Advance the closest path index (never backwards, within 40 points) and return
    ``(index, target_x, target_y, distance_to_end)`` with the target the first point
    at least ``lookahead`` away."""
    n = path.shape[0]
    best = np.inf
    i = i0
    for k in range(i0, min(n, i0 + 40)):
        d = math.hypot(path[k, 0] - x, path[k, 1] - y)
        if d < best:
            best = d
            i = k
    tx, ty = path[n - 1, 0], path[n - 1, 1]
    for k in range(i, n):
        if math.hypot(path[k, 0] - x, path[k, 1] - y) >= lookahead:
            tx, ty = path[k, 0], path[k, 1]
            break
    return i, tx, ty, math.hypot(path[n - 1, 0] - x, path[n - 1, 1] - y)


@njit(cache=True)
def _time_to_contact(px, py, v, w, radius, horizon, dt):
    """First time (s) at which at least two scan points (robot frame) lie inside the
    body moving with ``(v, w)`` and closer than at the start; ``horizon`` if none.
    Two points, so that a single outlier reading does not stop the robot; closer
    than at the start, so that a robot already grazing a wall may move away."""
    r2 = radius * radius
    n = int(horizon / dt + 0.5)
    for k in range(1, n + 1):
        t = k * dt
        if abs(w) < 1e-9:
            cx, cy = v * t, 0.0
        else:
            cx = v / w * math.sin(w * t)
            cy = v / w * (1.0 - math.cos(w * t))
        count = 0
        for i in range(px.shape[0]):
            dx = px[i] - cx
            dy = py[i] - cy
            d2 = dx * dx + dy * dy
            if d2 < r2 and d2 < px[i] * px[i] + py[i] * py[i] - 1e-6:
                count += 1
                if count >= 2:
                    return t - dt
    return horizon



# ------------------------------------------------------------------- explorer
@dataclass
class _Goal:
    xy: tuple[float, float]
    best_dist: float
    since: float
    cost: float


@dataclass
class ExploreStats:
    replans: int = 0
    blacklisted: list[tuple[float, float]] = field(default_factory=list)
    goals: int = 0


class Explorer:
    """explore_lite-style frontier exploration driving one robot (see module docstring).

    Call :meth:`command` at every control step with the current time, the pose
    estimate and map source (the mapper) and the latest scan; it returns
    ``(v, w)``. :attr:`done` becomes True when no frontier is left.
    """

    def __init__(self, config: ExploreConfig, max_v: float, max_w: float, spin_first: bool):
        self.cfg = config
        self.ctrl = PathController(config, max_v, max_w)
        self.max_w = max_w
        self.done = False
        self.stats = ExploreStats()
        self._goal: _Goal | None = None
        self._next_plan = 0.0
        self._spin_left = 2 * math.pi if spin_first else 0.0
        self._last_t: float | None = None
        self._blocked_since: float | None = None
        self._reached: list[tuple[float, float]] = []
        self._empty_plans = 0
        self._blacklist: list[tuple[float, float]] = []
        self._amnesties = 0

    def _blacklist_goal(self, xy) -> None:
        self._blacklist.append(xy)
        self.stats.blacklisted.append(xy)

    # -- planning ----------------------------------------------------------
    def _plan(self, t: float, pose, m: OccupancyMap) -> None:
        cfg = self.cfg
        self.stats.replans += 1
        m_full = m
        bbox = m.content_bbox()
        if bbox is not None:  # plan on the known part only (plus a frontier margin)
            r0, r1, c0, c1 = bbox
            m = m.crop(r0 - 2, r1 + 2, c0 - 2, c1 + 2)
        cm = make_costmap(
            m,
            robot_radius=cfg.robot_radius + cfg.lethal_margin,
            safety=cfg.safety,
            inflation_radius=cfg.inflation_radius,
            cost_scaling=cfg.cost_scaling,
            inflation_weight=cfg.inflation_weight,
        )
        fr = find_frontiers(m, max(1, int(round(cfg.min_frontier_size / m.resolution))))
        n = len(fr.sizes)
        sizes_m = fr.sizes * m.resolution
        # plan on a coarser grid (min-pooled costs keep narrow doors open)
        f = max(1, int(round(cfg.plan_resolution / m.resolution)))
        cost, labels, occ, freec, frame = _coarsen(cm.cost, fr.labels, m, f)
        r, c = (int(v) for v in frame.world_to_pixel(pose[0], pose[1]))
        if not frame.contains(r, c):
            self.ctrl.set_path(np.zeros((0, 2)))
            return
        # the map may put the robot closer to a wall than its radius (map cells are
        # coarse): let it leave through free cells around itself
        k = int(math.ceil(cfg.robot_radius * 1.5 / frame.resolution))
        win = (slice(max(0, r - k), r + k + 1), slice(max(0, c - k), c + k + 1))
        patch = cost[win]
        patch[np.isinf(patch) & freec[win]] = 50.0
        dist, parent = dijkstra(cost, r, c)
        reach = max(1, int(round(cfg.goal_reach / frame.resolution)))
        cells, costs = frontier_goals(labels, n, dist, occ, reach)
        m = frame
        res = m.resolution
        best = None
        candidates = []
        n_blacklisted = 0
        for k in range(n):
            if cells[k] < 0 or not np.isfinite(costs[k]):
                continue
            gr, gc = divmod(int(cells[k]), m.width)
            gx, gy = (float(v[0]) for v in m.pixel_to_world([gr], [gc]))
            if any(
                math.hypot(gx - bx, gy - by) < cfg.blacklist_radius for bx, by in self._blacklist
            ):
                n_blacklisted += 1
                continue
            score = cfg.potential_scale * float(costs[k]) * res - cfg.gain_scale * sizes_m[k]
            candidates.append((score, int(cells[k]), (gx, gy)))
            if best is None or score < best[0]:
                best = (score, int(cells[k]), (gx, gy))
        if best is None and n_blacklisted and self._amnesties < cfg.blacklist_amnesties:
            # only blacklisted frontiers are left: forget the blacklist and retry them
            self._amnesties += 1
            self._blacklist.clear()
            self._plan(t, pose, m_full)
            return
        if best is None:
            # nothing reachable: look around and try again a few times before giving up
            self._empty_plans += 1
            self.done = self._empty_plans >= 3
            self._goal = None
            self.ctrl.set_path(np.zeros((0, 2)))
            return
        self._empty_plans = 0
        score, goal_flat, gxy = best
        g = self._goal
        tracked = None
        if g is not None:
            # the current goal's frontier, followed as it shrinks (its middle moves)
            near = [c for c in candidates if math.hypot(c[2][0] - g.xy[0], c[2][1] - g.xy[1]) < 1.0]
            if near:
                tracked = min(near, key=lambda c: math.hypot(c[2][0] - g.xy[0], c[2][1] - g.xy[1]))
                if score > tracked[0] - cfg.switch_margin:  # commit unless much better
                    score, goal_flat, gxy = tracked
        if any(math.hypot(gxy[0] - x, gxy[1] - y) < 0.3 for x, y in self._reached):
            self._blacklist_goal(gxy)
            self._reached.clear()
            self._plan(t, pose, m_full)
            return
        self._reached.clear()
        if tracked is not None and gxy == tracked[2]:
            g.xy, g.cost = gxy, score  # same frontier: keep its progress timer
        else:
            self._goal = _Goal(gxy, np.inf, t, score)
            self.stats.goals += 1
        cells_rc = backtrack(parent, goal_flat, m.width)
        wx, wy = m.pixel_to_world(cells_rc[:, 0], cells_rc[:, 1])
        self.ctrl.set_path(np.column_stack([wx, wy]))

    # -- control -------------------------------------------------------------
    def command(self, t: float, pose, mapper, scan: LaserScan | None) -> tuple[float, float]:
        """Velocity command at time ``t`` from the mapper's pose estimate ``pose``.

        Parameters
        ----------
        t : float
            Simulated time, seconds.
        pose : (x, y, theta)
            Pose estimate, map frame.
        mapper : Mapper
            Asked for its map when replanning.
        scan : LaserScan or None
            Latest scan.

        Returns
        -------
        v, w : float
        """
        cfg = self.cfg
        dt = 0.0 if self._last_t is None else t - self._last_t
        self._last_t = t
        if self.done:
            return 0.0, 0.0
        if self._spin_left > 0:  # narrow field of view: look around once first
            self._spin_left -= self.max_w * dt
            return 0.0, self.max_w
        g = self._goal
        if g is not None:
            d = self.ctrl.remaining(pose)
            if d < g.best_dist - 0.1:
                g.best_dist = d
                g.since = t
            elif t - g.since > cfg.progress_timeout:
                self._blacklist_goal(g.xy)
                self._goal = None
                self._next_plan = t
            elif math.hypot(pose[0] - g.xy[0], pose[1] - g.xy[1]) < cfg.goal_tolerance:
                # reached: if the same frontier is chosen again, looking from here did
                # not uncover it, so it is blacklisted
                self._reached.append(g.xy)
                self._goal = None
                self._next_plan = t
        if t >= self._next_plan or (not len(self.ctrl.path) and not self._empty_plans):
            self._plan(t, pose, mapper.get_map())
            self._next_plan = t + cfg.replan_period
            if self.done:
                return 0.0, 0.0
        if self._empty_plans:
            return 0.0, 0.5 * self.max_w
        v, w, blocked = self.ctrl.command(pose, scan)
        if blocked:
            if self._blocked_since is None:
                self._blocked_since = t
            elif t - self._blocked_since > 1.0:
                self._next_plan = t  # something in the way: replan now
                self._blocked_since = None
        else:
            self._blocked_since = None
        return v, w


@njit(cache=True)
def _pool(cost, labels, occ, free, f, pad_top):
    """Min-pool ``cost``, max-pool ``labels``, ``occ`` and ``free`` by ``f`` (padded at
    the top/right)."""
    h, w = cost.shape
    h2 = (h + pad_top) // f
    w2 = (w + f - 1) // f
    out_c = np.full((h2, w2), np.inf, np.float32)
    out_l = np.zeros((h2, w2), labels.dtype)
    out_o = np.zeros((h2, w2), np.bool_)
    out_f = np.zeros((h2, w2), np.bool_)
    for r in range(h):
        rr = (r + pad_top) // f
        for c in range(w):
            cc = c // f
            v = cost[r, c]
            if v < out_c[rr, cc]:
                out_c[rr, cc] = v
            lab = labels[r, c]
            if lab > out_l[rr, cc]:
                out_l[rr, cc] = lab
            if occ[r, c]:
                out_o[rr, cc] = True
            if free[r, c]:
                out_f[rr, cc] = True
    return out_c, out_l, out_o, out_f


def _coarsen(cost, labels, m: OccupancyMap, f: int):
    """Min-pool costs, max-pool frontier labels, walls and free cells by ``f``; the frame."""
    h, w = cost.shape
    # pad at the top and the right: the lower-left corner (the origin) stays put
    pad_top = (-h) % f
    cost, labels, occ, free = _pool(cost, labels, m.occupied, m.free, f, pad_top)
    frame = OccupancyMap(np.zeros(cost.shape, np.uint8), m.resolution * f, m.origin)
    return cost, labels, occ, free, frame


class RouteFollower:
    """Drive through waypoints ``(x, y[, theta])`` given in the frame of the pose it is
    handed.

    Consecutive waypoints are joined by straight segments, resampled every 5 cm, and
    followed with :class:`PathController`, one *leg* at a time: the route is cut where
    it turns back by more than 90 degrees (a recorded trajectory's turns on the spot),
    and each leg ends at its last point (within half ``goal_tolerance``). Pure pursuit on
    the whole route would aim, near such a turn, alternately at the points before and
    after it (both within its lookahead) and spin there for ever. If the robot makes no
    progress along its leg (10 cm) for ``skip_after`` seconds (blocked, or crawling at a
    door frame) it skips one metre ahead, or to the next leg. :attr:`done` is set at the
    last waypoint; :meth:`progress` says how far along the route it got.

    Examples
    --------
    >>> f = RouteFollower([(0, 0), (1, 0), (0, 0.05)], ExploreConfig(), 0.26, 1.82)
    >>> [len(leg) for leg in f.legs], round(f.length, 2)
    ([21, 22], 2.0)
    """

    def __init__(
        self, waypoints, config: ExploreConfig, max_v: float, max_w: float, skip_after=10.0
    ):
        wp = np.asarray(waypoints, float)[:, :2]
        seg = [wp[:1]]
        for a, b in zip(wp[:-1], wp[1:], strict=True):
            n = max(1, int(math.ceil(math.hypot(*(b - a)) / 0.05)))
            seg.append(a + (b - a) * (np.arange(1, n + 1) / n)[:, None])
        self.path = np.concatenate(seg)
        # legs: cut at every waypoint where the route turns back (> 90 degrees)
        ends = [0]
        for k in range(1, len(wp) - 1):
            if float(np.dot(wp[k] - wp[k - 1], wp[k + 1] - wp[k])) < 0.0:
                ends.append(sum(len(x) for x in seg[: k + 1]) - 1)
        ends.append(len(self.path) - 1)
        self.legs = [self.path[a : b + 1] for a, b in zip(ends[:-1], ends[1:], strict=True)]
        self._leg_start = ends[:-1]
        steps = np.hypot(*np.diff(self.path, axis=0).T) if len(self.path) > 1 else np.zeros(0)
        self._arc = np.concatenate([[0.0], np.cumsum(steps)])
        #: Length of the route (metres).
        self.length = float(self._arc[-1])
        self.ctrl = PathController(config, max_v, max_w)
        self.cfg = config
        self.done = False
        self.skip_after = skip_after
        self.stats = ExploreStats()
        self._leg = 0
        self._furthest = 0  # index into ``path`` of the furthest point reached
        self._start_leg(0, 0)

    def _start_leg(self, leg: int, skip: int) -> None:
        self._leg = leg
        self._offset = self._leg_start[leg] + skip  # index into ``path`` of ctrl.path[0]
        self.ctrl.set_path(self.legs[leg][skip:])
        self._best = math.inf
        self._since: float | None = None

    def progress(self) -> float:
        """Metres of the route driven so far (to the furthest point reached)."""
        return float(self._arc[self._furthest])

    def command(self, t: float, pose, mapper, scan: LaserScan | None) -> tuple[float, float]:
        if self.done:
            return 0.0, 0.0
        leg = self.legs[self._leg]
        near_end = math.hypot(pose[0] - leg[-1, 0], pose[1] - leg[-1, 1])
        if near_end < self.cfg.goal_tolerance * 0.5:
            self._furthest = max(self._furthest, self._leg_start[self._leg] + len(leg) - 1)
            if self._leg == len(self.legs) - 1:
                self.done = True
                return 0.0, 0.0
            self._start_leg(self._leg + 1, 0)
        v, w, _ = self.ctrl.command(pose, scan)
        self._furthest = max(self._furthest, self._offset + self.ctrl._i)
        left = self.ctrl.remaining(pose)
        if self._since is None or left < self._best - 0.1:
            self._best, self._since = left, t
        elif t - self._since > self.skip_after:  # no progress: skip ahead one metre
            i = self._offset - self._leg_start[self._leg] + self.ctrl._i + 20
            if i < len(self.legs[self._leg]) - 1:
                self._start_leg(self._leg, i)
            elif self._leg < len(self.legs) - 1:
                self._start_leg(self._leg + 1, 0)
            else:
                self._best, self._since = left, t  # the last point: keep trying
        return v, w
