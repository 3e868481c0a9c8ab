"""Odometry error to map error by EKF-SLAM, thesis eqs. 3.54-3.80 (ref. [57]).

The robot drives the key poses of the trajectory; its odometry reports each step with
the error of the model (nominal - actual, thesis eqs. 3.40-3.50), so its dead-reckoned pose
drifts. The
filter state ``X = (x, y, theta, lambda_1x, lambda_1y, ...)`` holds the robot pose and
the landmarks seen so far, ``P`` their covariance:

1. prediction with the odometry (thesis eqs. 3.54-3.57), Jacobian ``A`` (3.60) and process
   noise ``Q`` built from the error terms (3.58-3.59, 3.61), thesis eqs. 3.62-3.63;
2. update with every re-observed landmark: range and bearing measured by the LIDAR model
   (thesis eqs. 3.64-3.66 with 3.29-3.30), noise ``R`` (3.67-3.69), Jacobian ``H`` (3.70-3.71),
   gain and state update (3.72-3.73);
3. augmentation with the new landmarks (3.74-3.80).

At the end, the final landmark estimates minus their original (plan) positions are the
odometry deformation field at the landmarks ("the difference between the original and
final state of each observed pixel"); it is interpolated to every pixel. With
``ekf_reference="initial"`` the reference is instead the estimate each landmark was
added with, so the field holds only the filter's corrections after that.

Landmarks. The thesis makes every observed pixel a landmark, so the state grows to
``2 H W`` and a 256 x 256 run never finished. Here the landmarks are the observed wall
pixels decimated on a regular grid (the coarsest stride that leaves at most
``ekf_max_landmarks``), and the field between them is interpolated linearly (nearest
value outside their convex hull). All re-observations at one pose are applied as one
stacked update (the same linearisation point as sequential updates, one BLAS call).

Reading of the thesis, where it is ambiguous
--------------------------------------------
* Thesis eqs. 3.54-3.57 apply to the odometry increments (whose error is ``sigma``), so that the
  state is the robot pose: the reading is the true step between key poses (in the
  robot's estimated frame) minus the ``sigma`` of thesis eqs. 3.48-3.50, its heading change
  ``Delta theta`` the true one minus ``sigma_theta`` (thesis eq. 3.54); ``Delta thrust`` is
  recovered from the y increment (thesis eq. 3.55) or, where ``sin(theta)`` is small, from the
  x increment. With zero error parameters the filter reproduces the plan exactly.
* Thesis eq. 3.62 is ``A P A^T + Q``; ``Q`` (3.61) is projected on the nearest positive
  semi-definite matrix (thesis eqs. 3.51-3.53 do not guarantee one).
* Thesis eq. 3.70 omits the range normalisation of the standard Jacobian (ref. [57]); the rows
  are divided by ``r`` and ``r^2`` so that ``H`` is the derivative of range and bearing.
* ``R`` (3.69) uses ``|r c|`` and ``|delta d|``, floored by ``ekf_range_var_min`` and
  ``ekf_bearing_var_min`` (it is singular when ``a1`` or ``b1`` is zero).
* The covariance update ``P = (I - K H) P`` that the thesis leaves implicit is applied.
* Angles are in the image frame (x right, y down), positions in metres along the image
  axes.

Examples
--------
>>> A = motion_jacobian(*jacobian_terms(1.0, 0.0))  # thesis eqs. 3.56-3.57, 3.60: thrust 1 along x
>>> A.tolist()
[[1.0, 0.0, -0.0], [0.0, 1.0, 1.0], [0.0, 0.0, 1.0]]
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.interpolate import LinearNDInterpolator, NearestNDInterpolator

from ..core.geometry import wrap_angle
from .lidar import LidarCoefficients, angle_error, measured, polar_displacement, range_error
from .odometry import OdometryErrors
from .params import ParametricParams
from .visibility import Visibility

__all__ = [
    "EkfResult",
    "heading_change",
    "thrust",
    "jacobian_terms",
    "initial_covariance",
    "motion_jacobian",
    "process_noise",
    "predict_covariance",
    "measurement",
    "measurement_noise",
    "measurement_jacobian",
    "kalman_update",
    "landmark_jacobians",
    "augment_covariance",
    "choose_landmarks",
    "ekf_field",
]


def heading_change(sigma_t):
    """Thesis eq. 3.54: ``Delta theta = sigma_theta`` (the heading increment of the prediction).

    Parameters
    ----------
    sigma_t : float or ndarray
        Heading error terms.

    Returns
    -------
    ndarray
    """
    return np.asarray(sigma_t, float)


def thrust(dx_inc, dy_inc, theta):
    """Thesis eq. 3.55: ``Delta thrust = Delta y / sin(theta)`` (``Delta x / cos(theta)`` where
    ``|sin theta| < |cos theta|``, the same quantity better conditioned).

    Parameters
    ----------
    dx_inc, dy_inc : float or ndarray
        Position increments.
    theta : float or ndarray
        Heading, radians.

    Returns
    -------
    ndarray

    Examples
    --------
    >>> round(float(thrust(0.0, 0.5, np.pi / 2)), 6), round(float(thrust(0.5, 0.0, 0.0)), 6)
    (0.5, 0.5)
    """
    s, c = np.sin(theta), np.cos(theta)
    return np.where(np.abs(s) >= np.abs(c), dy_inc / np.where(s == 0, 1, s), dx_inc / c)


def jacobian_terms(length, angle):
    """Thesis eqs. 3.56-3.57 (and the terms of 3.74): ``Delta x = l sin(angle)``,
    ``Delta y = l cos(angle)``.

    Parameters
    ----------
    length : float or ndarray
        Distance ``l``.
    angle : float or ndarray
        Angle, radians.

    Returns
    -------
    dx, dy : ndarray

    Examples
    --------
    >>> [round(float(v), 6) for v in jacobian_terms(2.0, 0.0)]
    [0.0, 2.0]
    """
    return length * np.sin(angle), length * np.cos(angle)


def initial_covariance(sigma: dict) -> np.ndarray:
    """Thesis eqs. 3.58-3.59: the initial ``P = P^rr`` from the first step's error terms.

    Parameters
    ----------
    sigma : dict
        Error terms ``x``, ``y``, ``t`` (arrays; the first step is used).

    Returns
    -------
    (3, 3) ndarray
    """
    return process_noise({k: np.asarray(v).ravel()[:1] for k, v in sigma.items()})[0]


def motion_jacobian(dx: float, dy: float) -> np.ndarray:
    """Thesis eq. 3.60: ``A = [[1, 0, -Delta x], [0, 1, Delta y], [0, 0, 1]]``.

    Parameters
    ----------
    dx, dy : float
        Terms of :func:`jacobian_terms`.

    Returns
    -------
    (3, 3) ndarray

    Examples
    --------
    >>> motion_jacobian(0.5, 0.25)[:2].tolist()
    [[1.0, 0.0, -0.5], [0.0, 1.0, 0.25]]
    """
    return np.array([[1.0, 0.0, -dx], [0.0, 1.0, dy], [0.0, 0.0, 1.0]])


def process_noise(sigma: dict) -> np.ndarray:
    """Thesis eq. 3.61: ``Q`` from the error terms of thesis eqs. 3.48-3.53, for every step (N, 3,
    3).

    Projected on the positive semi-definite cone (negative eigenvalues set to zero).

    Parameters
    ----------
    sigma : dict
        Error terms ``x``, ``y``, ``t`` per step, arrays (N,).

    Returns
    -------
    (N, 3, 3) ndarray
        Positive semi-definite.
    """
    sx, sy, st = (np.asarray(sigma[k], float) for k in ("x", "y", "t"))
    sxy, sxt, syt = (np.asarray(sigma[k], float) for k in ("xy", "xt", "yt"))
    q = np.empty((sx.size, 3, 3))
    q[:, 0, 0], q[:, 1, 1], q[:, 2, 2] = sx**2, sy**2, st**2
    q[:, 0, 1] = q[:, 1, 0] = sxy
    q[:, 0, 2] = q[:, 2, 0] = sxt
    q[:, 1, 2] = q[:, 2, 1] = syt
    w, v = np.linalg.eigh(q)
    return np.einsum("nij,nj,nkj->nik", v, np.clip(w, 0.0, None), v)


def predict_covariance(P: np.ndarray, n: int, A: np.ndarray, Q: np.ndarray) -> None:
    """Thesis eqs. 3.62-3.63 in place on the active ``n x n`` block: ``P^rr = A P^rr A^T + Q``,
    ``P^ri = A P^ri`` (and ``P^ir`` its transpose).

    Parameters
    ----------
    P : (S, S) ndarray
        Full covariance buffer, updated in place.
    n : int
        Active size (3 + 2 x landmarks).
    A : (3, 3) ndarray
        Motion Jacobian.
    Q : (3, 3) ndarray
        Process noise.
    """
    P[:3, :3] = A @ P[:3, :3] @ A.T + Q
    if n > 3:
        P[:3, 3:n] = A @ P[:3, 3:n]
        P[3:n, :3] = P[:3, 3:n].T


def measurement(r_true, b_true, coeffs: LidarCoefficients):
    """Thesis eqs. 3.64-3.66: ``z = (r, delta) = (z_meas, alpha_meas)`` of landmarks at true range
    ``r_true`` [m] and bearing ``b_true`` [rad], through the LIDAR model (thesis eqs. 3.9-3.12,
    3.29-3.30).

    Parameters
    ----------
    r_true, b_true : float or ndarray
        True range [m] and bearing [rad] of the landmarks.
    coeffs : LidarCoefficients
        The drawn LIDAR calibration.

    Returns
    -------
    r, delta : ndarray
        Measured range and bearing.
    """
    dD = range_error(r_true, coeffs.a0, coeffs.a1)
    da = angle_error(b_true, r_true, coeffs.b)
    dx_hit, dy_hit = polar_displacement(r_true, b_true, dD, da, 1.0)
    return measured(r_true, b_true, dx_hit, dy_hit, da, 1.0)


def measurement_noise(r, delta, a1: float, b1: float, r_min: float, b_min: float) -> np.ndarray:
    """Thesis eqs. 3.67-3.69: ``c = a1``, ``d = b1``, ``R = diag(r c, delta d)`` per landmark (M,
    2).

    Parameters
    ----------
    r, delta : (M,) arrays
        Measured ranges [m] and bearings [rad].
    a1, b1 : float
        Scale coefficients ``c`` and ``d``.
    r_min, b_min : float
        Variance floors.

    Returns
    -------
    (M, 2) ndarray
        Diagonal of ``R`` per landmark.
    """
    c, d = a1, b1
    return np.stack(
        [np.maximum(np.abs(r * c), r_min), np.maximum(np.abs(delta * d), b_min)], axis=-1
    )


def measurement_jacobian(x, y, lx, ly):
    """Thesis eqs. 3.70-3.71 per landmark: robot block ``H^{2x3}`` (M, 2, 3) and landmark block
    ``H^k = -H^{2x2}`` (M, 2, 2), with the range normalisation of ref. [57].

    Parameters
    ----------
    x, y : float
        Robot position.
    lx, ly : (M,) arrays
        Landmark positions.

    Returns
    -------
    hr : (M, 2, 3) ndarray
    hl : (M, 2, 2) ndarray
    """
    ddx, ddy = x - lx, y - ly
    r2 = np.maximum(ddx * ddx + ddy * ddy, 1e-12)
    r = np.sqrt(r2)
    hr = np.zeros((np.size(lx), 2, 3))
    hr[:, 0, 0], hr[:, 0, 1] = ddx / r, ddy / r
    hr[:, 1, 0], hr[:, 1, 1], hr[:, 1, 2] = (ly - y) / r2, (x - lx) / r2, -1.0
    return hr, -hr[:, :, :2]


def kalman_update(X, P, n, cols, hr, hl, innovation, rdiag) -> None:
    """Thesis eqs. 3.72-3.73 (stacked over the re-observed landmarks, in place):
    ``K = P H^T (H P H^T + R)^-1``, ``X = X + K (z - h)``, then ``P = P - K H P``.

    ``cols`` are the state columns of each landmark's x (M,), ``hr``/``hl`` the blocks of
    :func:`measurement_jacobian`, ``innovation`` (M, 2), ``rdiag`` (M, 2).

    Parameters
    ----------
    X : (S,) ndarray
        State buffer, updated in place.
    P : (S, S) ndarray
        Covariance buffer, updated in place.
    n : int
        Active size.
    cols : (M,) int array
        State column of each landmark's x.
    hr, hl : ndarrays
        Jacobian blocks.
    innovation : (M, 2) ndarray
        ``z - h``.
    rdiag : (M, 2) ndarray
        Diagonal of ``R``.
    """
    m = cols.size
    Pa = P[:n, :n]
    lcols = np.stack([cols, cols + 1], 1)  # (M, 2)
    # P H^T without forming H: robot part plus each landmark's 2 columns
    pht = np.einsum("nk,mjk->nmj", Pa[:, :3], hr)
    pht += np.einsum("nmk,mjk->nmj", Pa[:, lcols], hl)
    pht = pht.reshape(n, 2 * m)
    # S = H P H^T + R
    hp_r = pht[:3, :]  # rows of P H^T at the robot
    hp_l = pht[lcols.ravel(), :].reshape(m, 2, 2 * m)
    S = np.einsum("mjk,kc->mjc", hr, hp_r) + np.einsum("mjk,mkc->mjc", hl, hp_l)
    S = S.reshape(2 * m, 2 * m)
    S[np.diag_indices(2 * m)] += rdiag.ravel()
    S = 0.5 * (S + S.T)
    K = np.linalg.solve(S, pht.T).T  # (n, 2M)
    X[:n] += K @ innovation.ravel()
    Pa -= K @ pht.T
    Pa[:] = 0.5 * (Pa + Pa.T)


def landmark_jacobians(r, angle) -> tuple[np.ndarray, np.ndarray]:
    """Thesis eqs. 3.74-3.75 per new landmark at range ``r`` and absolute angle ``theta + delta``:
    ``J_xr = [[1, 0, -Delta x], [0, 1, Delta y]]`` (M, 2, 3) and
    ``J_z = [[cos, -r sin], [sin, r cos]]`` (M, 2, 2).

    Parameters
    ----------
    r : (M,) array
        Measured ranges.
    angle : (M,) array
        Absolute angles ``theta + delta``.

    Returns
    -------
    jxr : (M, 2, 3) ndarray
    jz : (M, 2, 2) ndarray
    """
    dx, dy = jacobian_terms(r, angle)
    m = np.size(r)
    jxr = np.zeros((m, 2, 3))
    jxr[:, 0, 0] = jxr[:, 1, 1] = 1.0
    jxr[:, 0, 2], jxr[:, 1, 2] = -dx, dy
    jz = np.empty((m, 2, 2))
    c, s = np.cos(angle), np.sin(angle)
    jz[:, 0, 0], jz[:, 0, 1], jz[:, 1, 0], jz[:, 1, 1] = c, -r * s, s, r * c
    return jxr, jz


def augment_covariance(P, n, jxr, jz, rdiag) -> int:
    """Thesis eqs. 3.76-3.80 in place for M new landmarks; returns the new active size.

    ``P^{N+1,N+1} = J_xr P^rr J_xr^T + J_z R J_z^T`` (3.76), robot-landmark
    ``P^{r,N+1} = P^rr J_xr^T`` (3.77-3.78), landmark-landmark
    ``P^{N+1,i} = J_xr P^{ri}`` (3.79-3.80); cross terms between the new landmarks follow
    from the same product.

    Parameters
    ----------
    P : (S, S) ndarray
        Covariance buffer, updated in place.
    n : int
        Active size before.
    jxr, jz : ndarrays
        From :func:`landmark_jacobians`.
    rdiag : (M, 2) ndarray
        Diagonal of ``R``.

    Returns
    -------
    int
        ``n + 2 M``.
    """
    m = jxr.shape[0]
    G = jxr.reshape(2 * m, 3)
    new = G @ P[:3, :n]  # (2M, n): columns 0..2 are 3.77 transposed, the rest 3.79
    nn = n + 2 * m
    P[n:nn, :n] = new
    P[:n, n:nn] = new.T
    block = G @ P[:3, :3] @ G.T
    jrj = np.einsum("mij,mj,mkj->mik", jz, rdiag, jz)
    for i in range(2):
        for j in range(2):
            block[i::2, j::2][np.diag_indices(m)] += jrj[:, i, j]
    P[n:nn, n:nn] = block
    return nn


def choose_landmarks(walls: np.ndarray, max_landmarks: int) -> np.ndarray:
    """Flat indices of wall pixels decimated on the coarsest-needed regular grid.

    One pixel (the first in raster order) per ``s x s`` block, with the smallest stride
    ``s`` that leaves at most ``max_landmarks``.

    Parameters
    ----------
    walls : (H, W) bool array
        Landmark candidates.
    max_landmarks : int
        Upper bound on the count.

    Returns
    -------
    (M,) int64 array
        Flat indices, M <= ``max_landmarks``.

    Examples
    --------
    >>> w = np.zeros((10, 10), bool); w[0, :] = True
    >>> choose_landmarks(w, 5).tolist()
    [0, 2, 4, 6, 8]
    """
    h, w = walls.shape
    rows, cols = np.nonzero(walls)
    if rows.size == 0:
        return np.zeros(0, np.int64)
    s = 1
    while True:
        key = (rows // s) * (w // s + 1) + cols // s
        _, first = np.unique(key, return_index=True)
        if first.size <= max_landmarks:
            break
        s += 1
    first = np.sort(first)
    return rows[first] * w + cols[first]


@dataclass
class EkfResult:
    """Landmarks (flat pixel indices), their field [px] and the interpolated field."""

    landmarks: np.ndarray
    landmark_dx: np.ndarray
    landmark_dy: np.ndarray
    dx: np.ndarray
    dy: np.ndarray
    robot_error: np.ndarray  # (K, 3) estimate minus true pose


def ekf_field(
    vis: Visibility,
    walls_observed: np.ndarray,
    poses_px: np.ndarray,
    odo: OdometryErrors,
    coeffs: LidarCoefficients,
    p: ParametricParams,
    resolution: float,
) -> EkfResult:
    """The odometry deformation field ``(d_xO, d_yO)`` [px] by EKF-SLAM.

    Parameters
    ----------
    vis : Visibility
        Pixels seen from each key pose.
    walls_observed : (H, W) bool
        Observed occupied pixels (landmark candidates).
    poses_px : (K, 3) array
        True key poses in pixels ``(x, y, angle)``.
    odo : OdometryErrors
        Per-step nominal and actual increments and error terms.
    coeffs : LidarCoefficients
        LIDAR calibration (measurement model and R).
    p : ParametricParams
        ``ekf_max_landmarks``, ``ekf_range_var_min``, ``ekf_bearing_var_min``.
    resolution : float
        Metres per pixel.

    Returns
    -------
    EkfResult
        Landmarks, their field and the field interpolated to every pixel, and the
        robot's estimate error per key pose.
    """
    h, w = vis.shape
    lm_pix = choose_landmarks(walls_observed, int(p.ekf_max_landmarks))
    n_lm = lm_pix.size
    lm_id = np.full(h * w, -1, np.int64)
    lm_id[lm_pix] = np.arange(n_lm)
    lm_rows, lm_cols = np.divmod(lm_pix, w)
    lm_true = np.stack([lm_cols, lm_rows], 1).astype(float) * resolution  # metres
    truth = np.asarray(poses_px, float).copy()
    truth[:, :2] *= resolution
    k_poses = truth.shape[0]
    size = 3 + 2 * n_lm
    X = np.zeros(size)
    P = np.zeros((size, size))
    X[:3] = truth[0]
    sigma = odo.sigma
    if k_poses > 1:
        P[:3, :3] = initial_covariance(sigma)
    Qs = process_noise(sigma) if k_poses > 1 else np.zeros((0, 3, 3))
    slot = np.full(n_lm, -1, np.int64)  # state column of each landmark's x
    init = np.zeros((n_lm, 2))  # estimate each landmark was added with
    n = 3
    robot_error = np.zeros((k_poses, 3))
    for k in range(k_poses):
        if k > 0:
            # odometry reading: the true increment, rotated into the estimated heading, plus
            # the error model's actual - nominal difference (thesis eqs. 3.40-3.50)
            th = X[2]
            step = truth[k] - truth[k - 1]
            dth = heading_change(wrap_angle(step[2], keep_in_range=True) - sigma["t"][k - 1])
            rot = th - truth[k - 1, 2]
            c, s = np.cos(rot), np.sin(rot)
            ex, ey = -sigma["x"][k - 1], -sigma["y"][k - 1]
            ddx = c * (step[0] + ex) - s * (step[1] + ey)
            ddy = s * (step[0] + ex) + c * (step[1] + ey)
            dthrust = thrust(ddx, ddy, th + dth / 2)
            jx, jy = jacobian_terms(dthrust, th + dth / 2)
            X[0] += ddx
            X[1] += ddy
            X[2] = wrap_angle(th + dth, keep_in_range=True)
            predict_covariance(P, n, motion_jacobian(jx, jy), Qs[k - 1])
        robot_error[k] = X[:3] - truth[k]
        robot_error[k, 2] = wrap_angle(robot_error[k, 2], keep_in_range=True)
        ids = lm_id[vis.seen_from(k)]
        ids = ids[ids >= 0]
        if ids.size == 0:
            continue
        # LIDAR measurements from the true pose (thesis eqs. 3.64-3.66)
        rel = lm_true[ids] - truth[k, :2]
        r_true = np.hypot(rel[:, 0], rel[:, 1])
        b_true = wrap_angle(np.arctan2(rel[:, 1], rel[:, 0]) - truth[k, 2], keep_in_range=True)
        z_r, z_b = measurement(r_true, b_true, coeffs)
        z_b = wrap_angle(z_b, keep_in_range=True)
        rdiag = measurement_noise(
            z_r, z_b, coeffs.a1, coeffs.b[0], p.ekf_range_var_min, p.ekf_bearing_var_min
        )
        old = slot[ids] >= 0
        if old.any():
            cols = slot[ids[old]]
            lx, ly = X[cols], X[cols + 1]
            x, y, th = X[0], X[1], X[2]
            h_r = np.hypot(lx - x, ly - y)
            h_b = wrap_angle(np.arctan2(ly - y, lx - x) - th, keep_in_range=True)
            hr, hl = measurement_jacobian(x, y, lx, ly)
            innov = np.stack([z_r[old] - h_r, wrap_angle(z_b[old] - h_b, keep_in_range=True)], 1)
            kalman_update(X, P, n, cols, hr, hl, innov, rdiag[old])
            X[2] = wrap_angle(X[2], keep_in_range=True)
        new = ~old
        if new.any():
            ang = X[2] + z_b[new]
            rr = z_r[new]
            m = int(new.sum())
            cols = n + 2 * np.arange(m)
            X[cols] = X[0] + rr * np.cos(ang)
            X[cols + 1] = X[1] + rr * np.sin(ang)
            init[ids[new], 0] = X[cols]
            init[ids[new], 1] = X[cols + 1]
            jxr, jz = landmark_jacobians(rr, ang)
            n = augment_covariance(P, n, jxr, jz, rdiag[new])
            slot[ids[new]] = cols
    seen = slot >= 0
    est = np.stack([X[slot[seen]], X[slot[seen] + 1]], 1)
    ref = lm_true[seen] if p.ekf_reference == "plan" else init[seen]
    d_lm = (est - ref) / resolution
    ldx = np.zeros(n_lm)
    ldy = np.zeros(n_lm)
    ldx[seen], ldy[seen] = d_lm[:, 0], d_lm[:, 1]
    dx, dy = _interpolate(np.stack([lm_cols[seen], lm_rows[seen]], 1), d_lm, (h, w))
    return EkfResult(lm_pix, ldx, ldy, dx, dy, robot_error)


def _interpolate(points: np.ndarray, values: np.ndarray, shape) -> tuple[np.ndarray, np.ndarray]:
    """Linear interpolation of landmark values to every pixel, nearest outside the hull."""
    h, w = shape
    if points.shape[0] == 0:
        return np.zeros(shape), np.zeros(shape)
    gy, gx = np.mgrid[0:h, 0:w]
    q = np.stack([gx.ravel(), gy.ravel()], 1).astype(float)
    near = NearestNDInterpolator(points, values)
    if points.shape[0] >= 3 and np.linalg.matrix_rank(points - points.mean(0)) == 2:
        lin = LinearNDInterpolator(points, values)(q)
        bad = np.isnan(lin[:, 0])
        lin[bad] = near(q[bad])
    else:
        lin = near(q)
    return lin[:, 0].reshape(shape), lin[:, 1].reshape(shape)
