"""Loop closure after a particle filter: a pose graph over the best particle's trajectory.

The particle filter (:mod:`map2map.slam.rbpf`) is accurate from scan to scan but can
lose a loop: the particle that would have matched the old map where the robot comes
back may have been resampled away, and the survivors lay the corridor down a second
time beside the first (a doubled wall). This post-step keeps the filter as the front
end and closes the loops afterwards, in the manner of graph SLAM (Karto, slam_toolbox,
:mod:`map2map.slam.graph`):

1. **Nodes**: the best particle's pose at every processed scan, with that scan's
   endpoints (thinned to ``max_points``) and the odometry there.
2. **Steps checked against the odometry**: a filter step whose heading differs from
   the odometry's by more than ``jump_angle``, or whose translation by more than
   ``jump_distance``, is matched again -- the scan against the last ``link_buffer``
   scans at their corrected poses, by correlative matching
   (:func:`map2map.slam.graph.correlative_match`, Karto's penalty for leaving the
   odometry's prediction) -- or replaced by the odometry's step if that match is weak.
   On the Radish fhw log the filter's best particle makes single wrong turns of
   0.3-0.7 rad where the odometry is off by at most 0.16 rad.
3. **Sequential edges**: the (checked) steps, with a standard deviation that grows with
   the step (``seq_sigma_xy`` + ``seq_sigma_per_m`` times its length; likewise for the
   heading).
4. **Loop closures**, node by node in time order (Karto's ``TryCloseLoop``, as
   :meth:`map2map.slam.graph.GraphSLAM._try_close_loop`): earlier nodes within
   ``search_distance`` of the node's current estimate but at least
   ``min_graph_distance`` away along the graph (shortest path, so a stretch already
   tied by a closure is near) form chains of consecutive nodes; the node's scan is
   matched against each chain's endpoints by coarse-to-fine correlative matching in a
   window no wider than the drift gate (``max_correction`` + ``max_drift_rate`` times
   the path between the two places along the graph, at most ``half_width``) and
   accepted on the graph backend's tests (responses, coarse variance, ambiguity).
5. **Optimisation** (:func:`gauss_newton_pose_graph`: Gauss-Newton with Huber weights
   and a sparse direct solve) when a closure moves its node by more than
   ``reoptimize_distance`` or ``reoptimize_angle``, and once at the end; later nodes
   follow the corrected one by their (checked) steps.

The map is then drawn again from every processed scan at its corrected pose with the
filter's counting rules (:class:`~map2map.slam.gridmap.CountGrid`). Deterministic: no
random step.

Examples
--------
>>> import numpy as np
>>> poses = np.array([[0.0, 0.0, 0.0], [1.0, 0.0, 0.0]])
>>> pts = [np.array([[2.0, y] for y in np.linspace(-1, 1, 21)])] * 2
>>> out, closures = close_loops(poses, pts)
>>> np.allclose(out, poses), closures
(True, [])
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from scipy.sparse import coo_matrix
from scipy.sparse.csgraph import dijkstra

from ..core.geometry import compose_pose, relative_pose, wrap_angle
from .posegraph import LookupTable, _sqrt_info, correlative_match, gauss_newton_pose_graph

__all__ = ["LoopClosureParams", "close_loops", "scan_points", "gauss_newton_pose_graph"]


@dataclass(frozen=True)
class LoopClosureParams:
    """Parameters of :func:`close_loops` (names of :class:`~map2map.slam.graph.GraphSLAMParams`
    where they mean the same)."""

    max_points: int = 120
    search_distance: float = 4.0
    min_graph_distance: float = 5.0
    min_chain_size: int = 5
    half_width: float = 3.0
    half_angle: float = 0.349
    coarse_resolution: float = 0.1
    coarse_angle_step: float = 0.0349
    fine_resolution: float = 0.025
    fine_angle_step: float = 0.00349
    coarse_smear: float = 0.1
    fine_smear: float = 0.04
    min_response_coarse: float = 0.35
    min_response_fine: float = 0.45
    max_variance_coarse: float = 3.0
    max_ambiguity: float = 0.9
    max_correction: float = 0.5
    max_drift_rate: float = 0.1
    attempt_travel: float = 0.5
    seq_sigma_xy: float = 0.02
    seq_sigma_per_m: float = 0.02
    seq_sigma_theta: float = 0.005
    seq_sigma_theta_per_rad: float = 0.05
    huber_scale: float = 3.0
    jump_angle: float = 0.1
    jump_distance: float = 0.2
    link_buffer: int = 10
    link_half_width: float = 0.25
    link_half_angle: float = 0.349
    link_coarse_resolution: float = 0.05
    link_min_response: float = 0.1
    reoptimize_distance: float = 0.05
    reoptimize_angle: float = 0.01


def scan_points(ranges, angles, offset, usable_range: float, max_points: int) -> np.ndarray:
    """``(K, 2)`` endpoints in the robot frame of the finite readings below ``usable_range``,
    thinned evenly to at most ``max_points``.

    Examples
    --------
    >>> p = scan_points(np.array([1.0, np.inf, 2.0]), np.array([0.0, 0.5, np.pi / 2]),
    ...                 np.zeros(3), 10.0, 100)
    >>> np.round(p, 6).tolist()
    [[1.0, 0.0], [0.0, 2.0]]
    """
    r = np.asarray(ranges, float)
    a = np.asarray(angles, float)
    idx = np.flatnonzero(np.isfinite(r) & (r < usable_range))
    if idx.size > max_points:
        idx = idx[np.linspace(0, idx.size - 1, max_points).round().astype(int)]
    off = np.asarray(offset, float)
    ang = off[2] + a[idx]
    return np.stack([off[0] + r[idx] * np.cos(ang), off[1] + r[idx] * np.sin(ang)], axis=1)


def _world(pose: np.ndarray, pts: np.ndarray) -> np.ndarray:
    c, s = math.cos(pose[2]), math.sin(pose[2])
    return np.stack(
        [pose[0] + c * pts[:, 0] - s * pts[:, 1], pose[1] + s * pts[:, 0] + c * pts[:, 1]], 1
    )


def _near(points: np.ndarray, scan: np.ndarray, margin: float) -> np.ndarray:
    """``points`` inside the bounding box of ``scan`` widened by ``margin`` (all if none)."""
    lo = scan.min(0) - margin
    hi = scan.max(0) + margin
    keep = np.all((points >= lo) & (points <= hi), axis=1)
    return points[keep] if keep.any() else points


def close_loops(
    poses: np.ndarray,
    points: list[np.ndarray],
    params: LoopClosureParams | None = None,
    odometry: np.ndarray | None = None,
) -> tuple[np.ndarray, list[tuple[int, int]]]:
    """Close the loops of a trajectory (module docstring); returns the corrected poses and
    the accepted closures ``(earlier node, later node)``.

    Parameters
    ----------
    poses : (T, 3) float array
        The front end's poses ``x, y, theta``, one per scan.
    points : list of (K, 2) float arrays
        Each scan's endpoints in the robot frame (:func:`scan_points`).
    params : LoopClosureParams, optional
    odometry : (T, 3) float array, optional
        The odometry at each node (any fixed frame): steps of the front end that
        disagree with it are matched again (module docstring, step 2); None: no check.

    Returns
    -------
    poses : (T, 3) float array
    closures : list of (int, int)
    """
    p = params or LoopClosureParams()
    front = np.asarray(poses, float)
    n = len(front)
    if n < 2:
        return front.copy(), []
    rel = relative_pose(front[:-1], front[1:])  # node k+1 in the frame of node k
    step = np.hypot(rel[:, 0], rel[:, 1])
    sxy = p.seq_sigma_xy + p.seq_sigma_per_m * step
    sth = (
        p.seq_sigma_theta + p.seq_sigma_per_m * step + p.seq_sigma_theta_per_rad * np.abs(rel[:, 2])
    )
    edges = [
        (k, k + 1, rel[k], np.diag([1 / sxy[k], 1 / sxy[k], 1 / sth[k]])) for k in range(n - 1)
    ]
    # graph adjacency for the graph distance (edge weight: its translation)
    ei = list(range(n - 1))
    ej = list(range(1, n))
    ew = list(step + 1e-3)
    est = front.copy()
    closures: list[tuple[int, int]] = []
    travel = 0.0
    rel = rel.copy()
    odo = None if odometry is None else np.asarray(odometry, float)

    def attempt(k: int) -> bool:
        """Try to close a loop at node ``k``; True if the graph should be re-optimised."""
        near = np.hypot(est[:k, 0] - est[k, 0], est[:k, 1] - est[k, 1]) < p.search_distance
        if not near.any():
            return False
        g = coo_matrix((ew, (ei, ej)), shape=(n, n)).tocsr()
        gdist = dijkstra(g, directed=False, indices=k)
        cand = np.flatnonzero(near & (gdist[:k] > p.min_graph_distance))
        if cand.size == 0:
            return False
        chains = np.split(cand, np.flatnonzero(np.diff(cand) > 1) + 1)
        closed = False
        for chain in chains:
            if chain.size < p.min_chain_size:
                continue
            # a correction beyond the drift gate (below) would be refused: search no wider
            path = float(np.min(gdist[chain]))
            gate = p.max_correction + p.max_drift_rate * path
            half = min(p.half_width, math.ceil(gate / p.coarse_resolution) * p.coarse_resolution)
            sub = np.concatenate([_world(est[i], points[i]) for i in chain])
            if len(sub) < 10:  # scans without returns in range: nothing to match
                continue
            coarse = LookupTable(sub, p.coarse_resolution, p.coarse_smear, half)
            fine = LookupTable(
                _near(sub, _world(est[k], points[k]), half + 0.5),
                p.fine_resolution,
                p.fine_smear,
                1.0,
            )
            res, coarse_resp = correlative_match(
                points[k],
                est[k],
                coarse,
                fine,
                half,
                p.half_angle,
                p.coarse_resolution,
                p.coarse_angle_step,
                p.fine_resolution,
                p.fine_angle_step,
            )
            var = res.coarse_covariance  # type: ignore[attr-defined]
            if (
                coarse_resp < p.min_response_coarse
                or var[0, 0] + var[1, 1] > p.max_variance_coarse
                or res.response < p.min_response_fine
                or res.ambiguity > p.max_ambiguity  # type: ignore[attr-defined]
            ):
                continue
            correction = math.hypot(res.pose[0] - est[k, 0], res.pose[1] - est[k, 1])
            if correction > gate:
                continue
            cp = est[chain]
            j = int(chain[np.argmin(np.hypot(cp[:, 0] - res.pose[0], cp[:, 1] - res.pose[1]))])
            z = relative_pose(est[j], res.pose)
            edge = (j, k, z, _sqrt_info(res.covariance))
            turn = abs(wrap_angle(res.pose[2] - est[k, 2]))
            edges.append(edge)
            ei.append(j)
            ej.append(k)
            ew.append(math.hypot(z[0], z[1]) + 1e-3)
            closures.append((j, k))
            # optimise now only if the closure moves this node: a closure that agrees
            # with the estimate waits for the next one, or the end
            closed |= correction > p.reoptimize_distance or turn > p.reoptimize_angle
        return closed

    for k in range(1, n):
        if odo is not None and len(points[k]) >= 10:
            ro = relative_pose(odo[k - 1], odo[k])
            if (
                abs(wrap_angle(rel[k - 1, 2] - ro[2])) > p.jump_angle
                or math.hypot(rel[k - 1, 0] - ro[0], rel[k - 1, 1] - ro[1]) > p.jump_distance
            ):
                guess = compose_pose(est[k - 1], ro)
                lo = max(0, k - p.link_buffer)
                sub = np.concatenate([_world(est[i], points[i]) for i in range(lo, k)])
                new = guess  # the odometry's step, unless the scan matches
                if len(sub) >= 10:
                    coarse = LookupTable(sub, p.link_coarse_resolution, p.coarse_smear, 1.0)
                    fine = LookupTable(sub, p.fine_resolution, p.fine_smear, 1.0)
                    res, _ = correlative_match(
                        points[k],
                        guess,
                        coarse,
                        fine,
                        p.link_half_width,
                        p.link_half_angle,
                        p.link_coarse_resolution,
                        p.coarse_angle_step,
                        p.fine_resolution,
                        p.fine_angle_step,
                        penalize=True,
                    )
                    if res.response >= p.link_min_response:
                        new = res.pose
                rel[k - 1] = relative_pose(est[k - 1], new)
                i, j, _, info = edges[k - 1]
                edges[k - 1] = (i, j, rel[k - 1], info)
        est[k] = compose_pose(est[k - 1], rel[k - 1])
        travel += step[k - 1]
        if travel < p.attempt_travel or len(points[k]) < 10:
            continue
        travel = 0.0
        if attempt(k):
            sub_edges = [e for e in edges if e[1] <= k]
            est[: k + 1] = gauss_newton_pose_graph(est[: k + 1], sub_edges, p.huber_scale)
    if closures:
        est = gauss_newton_pose_graph(est, edges, p.huber_scale)
    return est, closures
