"""Correlative scan matching (Olson 2009; Karto's ``ScanMatcher::MatchScan``) and SE(2)
pose-graph optimisation: the parts of the ``graph`` backend (:mod:`map2map.slam.graph`)
that the particle filter's loop closure (:mod:`map2map.slam.loops`) uses too, kept apart
from both mappers so that neither imports the other.

Examples
--------
>>> import numpy as np
>>> r = _se2_residual(np.zeros((1, 3)), np.array([[1.0, 0.0, 0.0]]),
...                   np.array([[1.0, 0.0, 0.0]]))
>>> bool(np.abs(r).max() < 1e-12)
True
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numba as nb
import numpy as np
from scipy.optimize import least_squares
from scipy.sparse import coo_matrix, csr_matrix
from scipy.sparse.linalg import spsolve

from ..core.geometry import relative_pose, wrap_angle
from .gridmap import likelihood_field

__all__ = ["MatchResult", "LookupTable", "correlative_match", "optimize_pose_graph",
           "gauss_newton_pose_graph"]


@dataclass
class MatchResult:
    """Outcome of a correlative match."""

    pose: np.ndarray
    response: float
    covariance: np.ndarray = field(default_factory=lambda: np.eye(3))


# ----------------------------------------------------------------------------- kernels
@nb.njit(cache=True)
def _correlate(table, tx0, ty0, res, pts, cx, cy, dxs, dys, thetas):
    """Mean lookup response for every ``(theta, dx, dy)``: shape ``(nth, ndx, ndy)``.

    Points ``pts`` (robot frame) are rotated by each ``theta`` then shifted to
    ``(cx + dx, cy + dy)``; a point outside the table scores 0. The cell indices of
    each shift are computed once per angle (the same arithmetic, so the same cells).
    """
    ny, nx = table.shape
    nth, ndx, ndy = thetas.shape[0], dxs.shape[0], dys.shape[0]
    k = pts.shape[0]
    out = np.zeros((nth, ndx, ndy))
    wx = np.empty(k)
    wy = np.empty(k)
    ix = np.empty(k, np.int64)
    iy = np.empty((ndy, k), np.int64)
    for a in range(nth):
        c, s = math.cos(thetas[a]), math.sin(thetas[a])
        for p in range(k):
            wx[p] = c * pts[p, 0] - s * pts[p, 1] + cx
            wy[p] = s * pts[p, 0] + c * pts[p, 1] + cy
        for j in range(ndy):
            for p in range(k):
                iy[j, p] = int(math.floor((wy[p] + dys[j] - ty0) / res))
        for i in range(ndx):
            for p in range(k):
                ix[p] = int(math.floor((wx[p] + dxs[i] - tx0) / res))
            for j in range(ndy):
                acc = 0.0
                for p in range(k):
                    xi = ix[p]
                    yi = iy[j, p]
                    if 0 <= xi < nx and 0 <= yi < ny:
                        acc += table[yi, xi]
                out[a, i, j] = acc / max(k, 1)
    return out


class LookupTable:
    """A likelihood-field lookup table built from world points (Olson 2009).

    Parameters
    ----------
    points : (K, 2) world endpoints of the submap
    resolution : cell size (m)
    smear : sigma (m) of the Gaussian smear around each endpoint
    margin : extra border (m) beyond the points' bounding box
    """

    def __init__(self, points: np.ndarray, resolution: float, smear: float, margin: float):
        pts = np.asarray(points, float)
        lo = pts.min(axis=0) - margin
        hi = pts.max(axis=0) + margin
        shape = (int(math.ceil((hi[1] - lo[1]) / resolution)) + 1,) + (
            int(math.ceil((hi[0] - lo[0]) / resolution)) + 1,
        )
        occ = np.zeros(shape, bool)
        ix = np.floor((pts[:, 0] - lo[0]) / resolution).astype(int)
        iy = np.floor((pts[:, 1] - lo[1]) / resolution).astype(int)
        occ[iy, ix] = True
        self.table = likelihood_field(occ, resolution, smear)
        self.x0, self.y0 = float(lo[0]), float(lo[1])
        self.resolution = float(resolution)

    def correlate(self, pts, cx, cy, dxs, dys, thetas) -> np.ndarray:
        return _correlate(
            self.table,
            self.x0,
            self.y0,
            self.resolution,
            np.ascontiguousarray(pts, np.float64),
            float(cx),
            float(cy),
            np.asarray(dxs, np.float64),
            np.asarray(dys, np.float64),
            np.asarray(thetas, np.float64),
        )


def _grid(half: float, step: float) -> np.ndarray:
    n = int(round(half / step))
    return np.arange(-n, n + 1) * step


def _covariance(resp: np.ndarray, dxs, dys, thetas, best, fine_res) -> np.ndarray:
    """Karto-style covariance of a match from the response surface around the optimum."""
    a, i, j = best
    r = resp[a]
    top = r.max()
    w = np.where(r >= 0.9 * top, r, 0.0) if top > 0 else np.ones_like(r)
    w = w / w.sum()
    gx, gy = np.meshgrid(dxs, dys, indexing="ij")
    mx, my = (w * gx).sum(), (w * gy).sum()
    cxx = (w * (gx - mx) ** 2).sum() + fine_res**2 / 4
    cyy = (w * (gy - my) ** 2).sum() + fine_res**2 / 4
    cxy = (w * (gx - mx) * (gy - my)).sum()
    ra = resp[:, i, j]
    wa = np.where(ra >= 0.9 * ra.max(), ra, 0.0) if ra.max() > 0 else np.ones_like(ra)
    wa = wa / wa.sum()
    ma = (wa * thetas).sum()
    caa = (wa * (thetas - ma) ** 2).sum() + (np.deg2rad(0.2)) ** 2
    return np.array([[cxx, cxy, 0.0], [cxy, cyy, 0.0], [0.0, 0.0, caa]])


def _penalty(dx, dy, dth):
    """Karto's response penalty for leaving the odometry guess (``ScanMatcher::CorrelateScan``).

    ``1 - 0.2 d^2 / 0.5`` (at least 0.5) times ``1 - 0.2 dtheta^2 / 1.0`` (at least 0.9):
    slam_toolbox's distance/angle variance penalties 0.5 / 1.0 and minimum penalties
    0.5 / 0.9. Where the response is flat (a corridor), the guess wins.
    """
    d = np.maximum(1.0 - 0.2 * (dx * dx + dy * dy) / 0.5, 0.5)
    a = np.maximum(1.0 - 0.2 * dth * dth / 1.0, 0.9)
    return d * a


def correlative_match(
    points: np.ndarray,
    guess: np.ndarray,
    coarse: LookupTable,
    fine: LookupTable,
    half_width: float,
    half_angle: float,
    coarse_step: float,
    coarse_angle: float,
    fine_step: float,
    fine_angle: float,
    penalize: bool = False,
) -> tuple[MatchResult, float]:
    """Coarse-to-fine correlative scan matching of robot-frame ``points`` around ``guess``.

    Returns the fine :class:`MatchResult` and the coarse response.

    Parameters
    ----------
    points : (K, 2) float array
        Scan endpoints in the robot frame.
    guess : (3,) float array
        Initial pose ``(x, y, theta)``.
    coarse, fine : LookupTable
        Likelihood fields of the submap at two resolutions.
    half_width, half_angle : float
        Search window around ``guess``: metres and radians.
    coarse_step, coarse_angle : float
        Steps of the coarse search.
    fine_step, fine_angle : float
        Steps of the fine search around the coarse optimum.
    penalize : bool
        Penalise distance from ``guess`` (Karto's response penalty).

    Returns
    -------
    match : MatchResult
        Pose, response and covariance of the fine search.
    coarse_response : float

    Examples
    --------
    >>> ang = np.linspace(0, 2 * np.pi, 180, endpoint=False)
    >>> sq = np.stack([np.clip(2 * np.cos(ang), -1.5, 1.5), np.clip(2 * np.sin(ang), -1, 1)], 1)
    >>> c = LookupTable(sq, 0.05, 0.1, 1.0); f = LookupTable(sq, 0.02, 0.04, 1.0)
    >>> res, _ = correlative_match(sq - [0.1, -0.05], np.zeros(3), c, f, 0.25, 0.2,
    ...                            0.05, 0.035, 0.02, 0.0035)
    >>> np.round(res.pose, 2).tolist()
    [0.1, -0.05, 0.0]
    """
    gx, gy, gt = (float(v) for v in guess)
    dxs = _grid(half_width, coarse_step)
    ths = gt + _grid(half_angle, coarse_angle)
    resp = coarse.correlate(points, gx, gy, dxs, dxs, ths)
    if penalize:
        resp = resp * _penalty(dxs[None, :, None], dxs[None, None, :], ths[:, None, None] - gt)
    best = np.unravel_index(int(np.argmax(resp)), resp.shape)
    coarse_resp = float(resp[best])
    cx, cy, ct = gx + dxs[best[1]], gy + dxs[best[2]], ths[best[0]]
    fxs = _grid(coarse_step, fine_step)
    fts = ct + _grid(coarse_angle, fine_angle)
    fresp = fine.correlate(points, cx, cy, fxs, fxs, fts)
    if penalize:
        fresp = fresp * _penalty(
            cx - gx + fxs[None, :, None], cy - gy + fxs[None, None, :], fts[:, None, None] - gt
        )
    fb = np.unravel_index(int(np.argmax(fresp)), fresp.shape)
    pose = np.array([cx + fxs[fb[1]], cy + fxs[fb[2]], wrap_angle(fts[fb[0]])])
    cov = _covariance(fresp, fxs, fxs, fts, fb, fine_step)
    # positional spread of the coarse surface is what Karto thresholds for loop closures
    coarse_cov = _covariance(resp, dxs, dxs, ths, best, coarse_step)
    # ambiguity: the best response more than ``4 coarse steps`` away from the optimum
    # (over all angles), relative to the optimum -- near 1 in a featureless corridor
    gx_, gy_ = np.meshgrid(dxs, dxs, indexing="ij")
    far = np.hypot(gx_ - dxs[best[1]], gy_ - dxs[best[2]]) > 4 * coarse_step
    runner_up = float(resp[:, far].max()) if far.any() else 0.0
    result = MatchResult(pose, float(fresp[fb]), cov)
    result.coarse_covariance = coarse_cov  # type: ignore[attr-defined]
    result.ambiguity = runner_up / coarse_resp if coarse_resp > 0 else 1.0  # type: ignore[attr-defined]
    return result, coarse_resp


# ----------------------------------------------------------------------------- back end
def _se2_residual(pi: np.ndarray, pj: np.ndarray, z: np.ndarray) -> np.ndarray:
    d = relative_pose(pi, pj) - z
    d[..., 2] = wrap_angle(d[..., 2])
    return d


def _se2_jacobian(pi: np.ndarray, pj: np.ndarray) -> np.ndarray:
    """(m, 3, 6) Jacobian of :func:`_se2_residual` ``Xi^-1 Xj - z`` with respect to
    ``(x_i, y_i, theta_i, x_j, y_j, theta_j)``, per edge (unwhitened)."""
    c, s = np.cos(pi[:, 2]), np.sin(pi[:, 2])
    dx, dy = pj[:, 0] - pi[:, 0], pj[:, 1] - pi[:, 1]
    j = np.zeros((len(pi), 3, 6))
    # d e / d node i
    j[:, 0, 0], j[:, 0, 1], j[:, 0, 2] = -c, -s, -s * dx + c * dy
    j[:, 1, 0], j[:, 1, 1], j[:, 1, 2] = s, -c, -c * dx - s * dy
    j[:, 2, 2] = -1.0
    # d e / d node j
    j[:, 0, 3], j[:, 0, 4] = c, s
    j[:, 1, 3], j[:, 1, 4] = -s, c
    j[:, 2, 5] = 1.0
    return j


def optimize_pose_graph(
    poses: np.ndarray,
    edges: list[tuple[int, int, np.ndarray, np.ndarray]],
    loss: str = "huber",
    f_scale: float = 3.0,
) -> np.ndarray:
    """Optimise SE(2) poses given relative constraints, the first pose fixed.

    ``edges`` holds ``(i, j, z_ij, sqrt_info)``: the measured pose of ``j`` in the
    frame of ``i`` and the 3x3 square root of its information matrix. Solved with
    ``scipy.optimize.least_squares`` (trust-region reflective with the LSMR
    solver, an analytic sparse Jacobian, robust ``loss``).

    Parameters
    ----------
    poses : (N, 3) float array
        Initial poses; ``poses[0]`` stays fixed.
    edges : list of (i, j, z_ij, sqrt_info)
        Relative constraints.
    loss : str
        ``scipy.optimize.least_squares`` loss (``"huber"``, ``"linear"``, ...).
    f_scale : float
        Scale of the robust loss (whitened residual units).

    Returns
    -------
    (N, 3) float array
        Optimised poses, angles wrapped.

    Examples
    --------
    >>> p = np.array([[0, 0, 0], [1.2, 0, 0], [2.1, 0.3, 0.0]])
    >>> e = [(0, 1, np.array([1.0, 0, 0]), np.eye(3)), (1, 2, np.array([1.0, 0, 0]), np.eye(3)),
    ...      (0, 2, np.array([2.0, 0, 0]), np.eye(3))]
    >>> (np.round(optimize_pose_graph(p, e), 3)[:, :2] + 0.0).tolist()
    [[0.0, 0.0], [1.0, 0.0], [2.0, 0.0]]
    """
    poses = np.asarray(poses, float)
    n = len(poses)
    if n < 2 or not edges:
        return poses.copy()
    ii = np.array([e[0] for e in edges])
    jj = np.array([e[1] for e in edges])
    zz = np.array([e[2] for e in edges])
    ll = np.array([e[3] for e in edges])
    p0 = poses[0].copy()

    def fun(x):
        p = np.vstack([p0, x.reshape(-1, 3)])
        r = _se2_residual(p[ii], p[jj], zz)
        return np.einsum("kab,kb->ka", ll, r).ravel()

    m = len(edges)
    # sparsity pattern of the Jacobian: each edge's 3 residuals touch its 2 nodes
    rows = np.repeat(np.arange(3 * m).reshape(m, 3), 6, axis=1).reshape(m, 3, 6)
    cols = np.concatenate(
        [3 * (ii - 1)[:, None] + np.arange(3), 3 * (jj - 1)[:, None] + np.arange(3)], axis=1
    )
    cols = np.broadcast_to(cols[:, None, :], (m, 3, 6))
    keep = np.broadcast_to(
        np.concatenate([np.repeat(ii[:, None] > 0, 3, 1), np.repeat(jj[:, None] > 0, 3, 1)], 1)[
            :, None, :
        ],
        (m, 3, 6),
    )

    def jac(x):
        """Analytic Jacobian of the whitened residuals ``L (Xi^-1 Xj - z)``."""
        p = np.vstack([p0, x.reshape(-1, 3)])
        j = np.einsum("kab,kbc->kac", ll, _se2_jacobian(p[ii], p[jj]))
        return csr_matrix((j[keep], (rows[keep], cols[keep])), shape=(3 * m, 3 * (n - 1)))

    sol = least_squares(
        fun,
        poses[1:].ravel(),
        jac=jac,
        loss=loss,
        f_scale=f_scale,
        method="trf",
        tr_solver="lsmr",
        x_scale="jac",
        max_nfev=100,
    )
    out = np.vstack([p0, sol.x.reshape(-1, 3)])
    out[:, 2] = wrap_angle(out[:, 2])
    return out


def gauss_newton_pose_graph(
    poses: np.ndarray,
    edges: list[tuple[int, int, np.ndarray, np.ndarray]],
    f_scale: float = 3.0,
    iterations: int = 20,
    tol: float = 1e-6,
) -> np.ndarray:
    """Optimise SE(2) poses, the first fixed: Gauss-Newton with Huber weights (IRLS) and
    a sparse direct solve of the normal equations.

    The same problem as :func:`map2map.slam.graph.optimize_pose_graph` (residuals
    ``L (Xi^-1 Xj - z)`` whitened by the square root ``L`` of each edge's information,
    the same analytic Jacobian) with the Huber weight ``min(1, f_scale / |r|)`` on each
    edge's whitened residual norm; the normal equations are sparse (block
    tridiagonal plus the closures) and solved directly (SuperLU), which on a few
    hundred nodes takes milliseconds where the trust-region LSMR solver takes about a
    second.

    Parameters
    ----------
    poses : (N, 3) float array
        Initial poses; ``poses[0]`` stays fixed.
    edges : list of (i, j, z_ij, sqrt_info)
        Relative constraints: the pose of ``j`` in the frame of ``i`` and the 3x3
        square root of its information.
    f_scale : float
        Huber scale (whitened residual units).
    iterations : int
        Most Gauss-Newton steps.
    tol : float
        Stop when no pose moves more than this (metres or radians).

    Returns
    -------
    (N, 3) float array

    Examples
    --------
    >>> p = np.array([[0, 0, 0], [1.2, 0, 0], [2.1, 0.3, 0.0]])
    >>> e = [(0, 1, np.array([1.0, 0, 0]), np.eye(3)), (1, 2, np.array([1.0, 0, 0]), np.eye(3)),
    ...      (0, 2, np.array([2.0, 0, 0]), np.eye(3))]
    >>> (np.round(gauss_newton_pose_graph(p, e), 3)[:, :2] + 0.0).tolist()
    [[0.0, 0.0], [1.0, 0.0], [2.0, 0.0]]
    """
    p = np.array(poses, float)
    n = len(p)
    if n < 2 or not edges:
        return p
    ii = np.array([e[0] for e in edges])
    jj = np.array([e[1] for e in edges])
    zz = np.array([e[2] for e in edges])
    ll = np.array([e[3] for e in edges])
    m = len(edges)
    # block (a, b) of edge k sits at rows 3*node_a.., cols 3*node_b..
    nodes = np.stack([ii, jj], 1)  # (m, 2)
    ra = np.arange(3)
    rows = 3 * nodes[:, :, None, None, None] + ra[None, None, None, :, None]  # (m,2,1,3,1)
    cols = 3 * nodes[:, None, :, None, None] + ra[None, None, None, None, :]  # (m,1,2,1,3)
    rows = np.broadcast_to(rows, (m, 2, 2, 3, 3)).ravel()
    cols = np.broadcast_to(cols, (m, 2, 2, 3, 3)).ravel()
    free = slice(3, 3 * n)
    for _ in range(iterations):
        pi, pj = p[ii], p[jj]
        r = _se2_residual(pi, pj, zz)
        jw = np.einsum("kab,kbc->kac", ll, _se2_jacobian(pi, pj))  # whitened (m, 3, 6)
        rw = np.einsum("kab,kb->ka", ll, r)
        norm = np.sqrt((rw * rw).sum(1))
        w = np.where(norm <= f_scale, 1.0, f_scale / np.maximum(norm, 1e-300))
        jb = jw.reshape(m, 3, 2, 3).transpose(0, 2, 1, 3)  # (m, 2 nodes, 3 res, 3 vars)
        blocks = np.einsum("k,kari,kbrj->kabij", w, jb, jb)  # (m, 2, 2, 3, 3)
        h = coo_matrix((blocks.ravel(), (rows, cols)), shape=(3 * n, 3 * n)).tocsc()
        g = np.zeros(3 * n)
        np.add.at(
            g, (3 * nodes[:, :, None] + ra).ravel(), np.einsum("k,kari,kr->kai", w, jb, rw).ravel()
        )
        hf = h[free, free]
        hf = (
            hf
            + 1e-9
            * coo_matrix((np.ones(3 * n - 3), (np.arange(3 * n - 3), np.arange(3 * n - 3)))).tocsc()
        )
        step = -spsolve(hf, g[free])
        p[1:] += step.reshape(-1, 3)
        p[:, 2] = wrap_angle(p[:, 2])
        if np.max(np.abs(step)) < tol:
            break
    return p


def _sqrt_info(cov: np.ndarray) -> np.ndarray:
    info = np.linalg.inv(cov)
    return np.linalg.cholesky(info).T
