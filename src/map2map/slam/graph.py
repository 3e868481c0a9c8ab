"""Graph SLAM in the style of Karto / slam_toolbox: correlative matching, loop closure, pose graph.

The front end turns the odometry + scan stream into **keyframes** (a new one after
``min_travel_distance`` metres, ``min_travel_heading`` radians or
``min_time_interval`` seconds, as Karto's ``HasMovedEnough``) linked by
constraints; the back end optimises the keyframe poses; the map is rendered from
the keyframe scans at their optimised poses.

* **Sequential constraints**: each keyframe's scan is matched against a *running
  submap* made of the last ``scan_buffer_size`` keyframes by correlative scan
  matching (Olson 2009; Karto's ``ScanMatcher::MatchScan``): an exhaustive
  search over a window of ``(dx, dy, dtheta)`` around the odometry prediction,
  scoring each pose by the mean of a likelihood-field lookup table at the scan
  endpoints. Coarse-to-fine: a coarse pass (step ``coarse_resolution``, angle
  ``coarse_angle_step``, wide smear) and a fine pass around the coarse optimum
  (step ``fine_resolution``, angle ``fine_angle_step``, narrow smear), responses
  penalised for leaving the odometry guess as Karto does (:func:`_penalty`). The
  response spread gives the covariance of the match (Karto's
  ``ComputePositionalCovariance``), whose inverse weights the constraint.
* **Loop closure** (Karto ``TryCloseLoop``): candidate keyframes lie within
  ``loop_search_distance`` of the new keyframe's estimate but at least
  ``loop_min_graph_distance`` metres away along the graph's constraints (shortest
  path, so places already tied by a closure are near); they are grouped into chains
  of consecutive keyframes (at least ``loop_min_chain_size``); the new scan is
  matched against each chain's submap with a wide window. A closure is accepted
  when the coarse response exceeds ``loop_min_response_coarse``, its positional
  variance is below ``loop_max_variance_coarse`` and the fine response exceeds
  ``loop_min_response_fine``, the match is unambiguous (``loop_max_ambiguity``) and
  the correction it implies is plausible: at most ``loop_max_correction`` plus
  ``loop_max_drift_rate`` times the path length between the two places along the
  graph (rejects aliasing with a look-alike room further away).
* **Back end**: ``scipy.optimize.least_squares`` over all keyframe poses (the first
  fixed) with whitened SE(2) residuals, an analytic sparse Jacobian and a robust
  ``huber`` loss, after every accepted loop closure.

Defaults follow slam_toolbox's ``mapper_params_online_async.yaml`` where they carry
over (minimum_travel_distance 0.5, minimum_travel_heading 0.5, scan_buffer_size 10,
correlation_search_space_dimension 0.5, coarse angle resolution 0.0349 over
+-0.349 rad, loop_search_maximum_distance 3.0, loop_match_minimum_chain_size 10,
loop_match_maximum_variance_coarse 3.0, loop_match_minimum_response_coarse 0.35,
loop_match_minimum_response_fine 0.45, link_match_minimum_response_fine 0.1).
Deviations for speed: minimum_time_interval 1.0 s (not 0.5), a fine translation step
of 0.025 m (not 0.01), loop searches on a 0.1 m coarse grid, scans thinned to
``max_points`` endpoints. Loop closures must also be unambiguous: the best
coarse response more than 4 coarse steps away from the optimum must stay below
``loop_max_ambiguity`` times the optimum (rejects corridor aliasing).

Examples
--------
>>> import numpy as np
>>> from map2map.robotlog.base import LaserScan, OdometryReading
>>> g = GraphSLAM()
>>> r = np.full(360, 1.5)
>>> g.update(OdometryReading(0.0, 0.0, 0.0, 0.0),
...          LaserScan(0.0, r, 0.0, np.deg2rad(1.0), 0.12, 3.5))
>>> len(g.keyframes), g.pose().tolist()
(1, [0.0, 0.0, 0.0])
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from scipy.sparse import coo_matrix
from scipy.sparse.csgraph import dijkstra

from ..core.grid import OccupancyMap
from ..robotlog.base import LaserScan, OdometryReading
from .gridmap import CountGrid
from .posegraph import (
    LookupTable,
    MatchResult,
    _sqrt_info,
    correlative_match,
    optimize_pose_graph,
)
from .rbpf import StartFrame, absolute_difference, absolute_sum, prepare_scan

__all__ = [
    "GraphSLAMParams",
    "GraphSLAM",
    "Keyframe",
    "MatchResult",
    "LookupTable",
    "correlative_match",
    "optimize_pose_graph",
    "make_graph",
]


@dataclass(frozen=True)
class GraphSLAMParams:
    """Parameters of :class:`GraphSLAM` (slam_toolbox names in the module docstring)."""

    resolution: float = 0.05
    max_range: float = 3.5
    min_travel_distance: float = 0.5
    min_travel_heading: float = 0.5
    min_time_interval: float = 1.0
    scan_buffer_size: int = 10
    search_half_width: float = 0.25
    search_half_angle: float = 0.349
    coarse_resolution: float = 0.05
    coarse_angle_step: float = 0.0349
    fine_resolution: float = 0.025
    fine_angle_step: float = 0.00349
    coarse_smear: float = 0.1
    fine_smear: float = 0.04
    link_min_response: float = 0.1
    loop_search_distance: float = 3.0
    loop_min_graph_distance: float = 5.0
    loop_min_chain_size: int = 10
    loop_search_half_width: float = 1.5
    loop_attempt_travel: float = 0.5
    loop_coarse_resolution: float = 0.1
    loop_max_variance_coarse: float = 3.0
    loop_min_response_coarse: float = 0.35
    loop_min_response_fine: float = 0.45
    loop_max_ambiguity: float = 0.9
    loop_max_correction: float = 0.3
    loop_max_drift_rate: float = 0.05
    odom_sigma_xy: float = 0.05
    odom_sigma_theta: float = 0.05
    huber_scale: float = 3.0
    occ_thresh: float = 0.25
    max_points: int = 120
    no_return_free: bool = True


@dataclass
class Keyframe:
    """A node of the pose graph: its scan endpoints in the robot frame and its pose."""

    t: float
    pose: np.ndarray
    odom: np.ndarray
    points: np.ndarray  # (K, 2) endpoints in the robot frame (for matching)
    ranges: np.ndarray  # full scan, for map rendering
    angles: np.ndarray
    offset: np.ndarray
    range_max: float


# ----------------------------------------------------------------------------- mapper
class GraphSLAM:
    """Karto-style graph SLAM mapper (implements :class:`map2map.robotlog.base.Mapper`)."""

    name = "graph"

    def __init__(self, params: GraphSLAMParams | None = None):
        self.params = params or GraphSLAMParams()
        self.keyframes: list[Keyframe] = []
        self.edges: list[tuple[int, int, np.ndarray, np.ndarray]] = []
        self.loop_closures: list[tuple[int, int]] = []
        self._frame = StartFrame()
        self._odom: np.ndarray | None = None
        self._grid: CountGrid | None = None
        self._rendered = 0
        self._map_cache: OccupancyMap | None = None
        self.n_link_failures = 0
        self._travel = 0.0

    # ---------------------------------------------------------------- Mapper API
    def update(self, odom: OdometryReading, scan: LaserScan) -> None:
        p = self.params
        o = self._frame.accept(odom, scan)  # odometry in the map frame
        self._odom = o
        if self.keyframes:
            last = self.keyframes[-1]
            d = absolute_difference(o, last.odom)
            moved = math.hypot(d[0], d[1]) >= p.min_travel_distance
            turned = abs(d[2]) >= p.min_travel_heading
            waited = p.min_time_interval >= 0 and scan.t - last.t >= p.min_time_interval
            if not (moved or turned or waited):
                return
        self._add_keyframe(o, scan)

    def pose(self) -> np.ndarray:
        if not self.keyframes:
            return np.zeros(3)
        last = self.keyframes[-1]
        return absolute_sum(last.pose, absolute_difference(self._odom, last.odom))

    def get_map(self) -> OccupancyMap:
        if self._map_cache is None:
            self._render()
            self._map_cache = self._grid.to_occupancy_map(
                self.params.occ_thresh, {"mapper": "graph"}
            )
        return self._map_cache

    def trajectory(self) -> np.ndarray:
        """``(K, 4)`` rows ``t, x, y, theta`` of the optimised keyframes.

        Returns
        -------
        (K, 4) ndarray
        """
        return np.array([(k.t, *k.pose) for k in self.keyframes], float).reshape(-1, 4)

    # ---------------------------------------------------------------- internals
    def _add_keyframe(self, o: np.ndarray, scan: LaserScan) -> None:
        p = self.params
        ranges, angles = prepare_scan(scan)
        off = np.asarray(scan.sensor_offset, float)
        ok = np.isfinite(ranges) & (ranges <= p.max_range)
        idx = np.flatnonzero(ok)
        if idx.size > p.max_points:
            idx = idx[np.linspace(0, idx.size - 1, p.max_points).round().astype(int)]
        a = off[2] + angles[idx]
        r = ranges[idx]
        pts = np.stack([off[0] + r * np.cos(a), off[1] + r * np.sin(a)], axis=1)
        if not self.keyframes:
            kf = Keyframe(scan.t, np.zeros(3), o, pts, ranges, angles, off, scan.range_max)
            self.keyframes.append(kf)
            self._map_cache = None
            return
        prev = self.keyframes[-1]
        k = len(self.keyframes)
        odo_rel = absolute_difference(o, prev.odom)
        guess = absolute_sum(prev.pose, odo_rel)
        pose, rel, sqrt_info = guess, odo_rel, self._odom_sqrt_info(odo_rel)
        if len(pts) >= 10:
            buf = self.keyframes[-p.scan_buffer_size :]
            sub = np.concatenate([self._world_points(b) for b in buf])
            coarse = LookupTable(sub, p.coarse_resolution, p.coarse_smear, 1.0)
            fine = LookupTable(sub, p.fine_resolution, p.fine_smear, 1.0)
            res, _ = correlative_match(
                pts,
                guess,
                coarse,
                fine,
                p.search_half_width,
                p.search_half_angle,
                p.coarse_resolution,
                p.coarse_angle_step,
                p.fine_resolution,
                p.fine_angle_step,
                penalize=True,
            )
            if res.response >= p.link_min_response:
                pose = res.pose
                rel = absolute_difference(pose, prev.pose)
                sqrt_info = _sqrt_info(res.covariance)
            else:
                self.n_link_failures += 1
        kf = Keyframe(scan.t, np.asarray(pose, float), o, pts, ranges, angles, off, scan.range_max)
        self.keyframes.append(kf)
        self.edges.append((k - 1, k, rel, sqrt_info))
        self._travel += math.hypot(odo_rel[0], odo_rel[1])
        if self._travel >= p.loop_attempt_travel and self._try_close_loop(k):
            self._optimize()
        if self._travel >= p.loop_attempt_travel:
            self._travel = 0.0
        self._map_cache = None

    def _odom_sqrt_info(self, rel: np.ndarray) -> np.ndarray:
        p = self.params
        d = math.hypot(rel[0], rel[1])
        sxy = p.odom_sigma_xy * max(d, 0.1)
        st = p.odom_sigma_theta * max(abs(rel[2]) + d, 0.1)
        return np.diag([1 / sxy, 1 / sxy, 1 / st])

    def _world_points(self, kf: Keyframe) -> np.ndarray:
        c, s = math.cos(kf.pose[2]), math.sin(kf.pose[2])
        pts = kf.points
        return np.stack(
            [
                kf.pose[0] + c * pts[:, 0] - s * pts[:, 1],
                kf.pose[1] + s * pts[:, 0] + c * pts[:, 1],
            ],
            axis=1,
        )

    def _graph_distance(self, k: int) -> np.ndarray:
        """Distance (m) from node ``k`` to every node along the constraints of the graph.

        Each edge weighs the length of its measured translation, so a stretch of
        keyframes already tied together by a loop closure counts as near.
        """
        n = len(self.keyframes)
        ii = np.array([e[0] for e in self.edges])
        jj = np.array([e[1] for e in self.edges])
        w = np.array([math.hypot(e[2][0], e[2][1]) for e in self.edges]) + 1e-3
        g = coo_matrix((w, (ii, jj)), shape=(n, n)).tocsr()
        return dijkstra(g, directed=False, indices=k)

    def _try_close_loop(self, k: int) -> bool:
        p = self.params
        kf = self.keyframes[k]
        if len(kf.points) < 10:
            return False
        poses = np.array([f.pose for f in self.keyframes[:k]])
        near = np.hypot(poses[:, 0] - kf.pose[0], poses[:, 1] - kf.pose[1]) < p.loop_search_distance
        gdist = self._graph_distance(k)
        far_in_graph = gdist[:k] > p.loop_min_graph_distance
        cand = np.flatnonzero(near & far_in_graph)
        if cand.size == 0:
            return False
        # chains of consecutive candidate keyframes
        chains = np.split(cand, np.flatnonzero(np.diff(cand) > 1) + 1)
        chains = [c for c in chains if c.size >= p.loop_min_chain_size]
        closed = False
        for chain in chains:
            sub = np.concatenate([self._world_points(self.keyframes[i]) for i in chain])
            coarse = LookupTable(
                sub, p.loop_coarse_resolution, p.coarse_smear, p.loop_search_half_width
            )
            fine = LookupTable(sub, p.fine_resolution, p.fine_smear, 1.0)
            res, coarse_resp = correlative_match(
                kf.points,
                kf.pose,
                coarse,
                fine,
                p.loop_search_half_width,
                p.search_half_angle,
                p.loop_coarse_resolution,
                p.coarse_angle_step,
                p.fine_resolution,
                p.fine_angle_step,
            )
            var = res.coarse_covariance  # type: ignore[attr-defined]
            if coarse_resp < p.loop_min_response_coarse:
                continue
            if var[0, 0] + var[1, 1] > p.loop_max_variance_coarse:
                continue
            if res.response < p.loop_min_response_fine:
                continue
            if res.ambiguity > p.loop_max_ambiguity:  # type: ignore[attr-defined]
                continue
            # drift gate: the correction must be plausible for the path length between
            # the two places along the graph (odometry + matching drift is bounded)
            correction = math.hypot(res.pose[0] - kf.pose[0], res.pose[1] - kf.pose[1])
            path = float(np.min(gdist[chain]))
            if correction > p.loop_max_correction + p.loop_max_drift_rate * path:
                continue
            # constraint to the chain keyframe closest to the matched pose
            cp = np.array([self.keyframes[i].pose for i in chain])
            j = int(chain[np.argmin(np.hypot(cp[:, 0] - res.pose[0], cp[:, 1] - res.pose[1]))])
            rel = absolute_difference(res.pose, self.keyframes[j].pose)
            self.edges.append((j, k, rel, _sqrt_info(res.covariance)))
            self.loop_closures.append((j, k))
            closed = True
        return closed

    def _optimize(self) -> None:
        poses = np.array([k.pose for k in self.keyframes])
        new = optimize_pose_graph(poses, self.edges, "huber", self.params.huber_scale)
        for kf, q in zip(self.keyframes, new, strict=True):
            kf.pose = q
        self._rendered = 0  # poses moved: render the map again from scratch

    def memory_bytes(self) -> int:
        """Bytes of the map's tiles (0 before the map is first drawn).

        Returns
        -------
        int
        """
        return self._grid.pool.nbytes() if self._grid is not None else 0

    def optimize(self) -> None:
        """Run the back end once more (e.g. at the end of a log)."""
        if self.loop_closures:
            self._optimize()
            self._map_cache = None

    def _render(self) -> None:
        """Integrate the keyframe scans at their optimised poses (GMapping counting rules)."""
        p = self.params
        if self._rendered == 0 or self._grid is None:
            poses = np.array([k.pose for k in self.keyframes])
            lo = poses[:, :2].min(0) - p.max_range - 1
            hi = poses[:, :2].max(0) + p.max_range + 1
            nx = int(math.ceil((hi[0] - lo[0]) / p.resolution))
            ny = int(math.ceil((hi[1] - lo[1]) / p.resolution))
            self._grid = CountGrid((ny, nx), lo[0], lo[1], p.resolution)
            self._rendered = 0
        for kf in self.keyframes[self._rendered :]:
            lp = absolute_sum(kf.pose, kf.offset)
            self._grid.register_scan(
                lp, kf.ranges, kf.angles, p.max_range, kf.range_max, p.no_return_free
            )
        self._rendered = len(self.keyframes)


def make_graph(resolution: float = 0.05, seed: int | None = 0, **options) -> GraphSLAM:
    """Registry factory (``map2map simulate --mapper graph``); graph SLAM is deterministic,
    ``seed`` is accepted for a uniform interface. Keyword options are
    :class:`GraphSLAMParams` fields (``None`` keeps the default); ``particles`` is ignored.

    Parameters
    ----------
    resolution : float
        Cell size of the map, metres.
    seed : int, optional
        Ignored (the backend is deterministic).
    **options
        :class:`GraphSLAMParams` fields.

    Returns
    -------
    GraphSLAM

    Examples
    --------
    >>> make_graph(0.1).params.resolution
    0.1
    """
    opts = {k: v for k, v in options.items() if v is not None and k != "particles"}
    return GraphSLAM(GraphSLAMParams(resolution=float(resolution), **opts))
