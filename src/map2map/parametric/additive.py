"""Odometry error to map error by the additive method of ref. [58], eqs. 3.81-3.90.

From the per-step odometry errors (eqs. 3.48-3.53) the linear and angular odometry
errors ``E_lin`` and ``E_ang`` (eqs. 3.81-3.82) are computed for every key pose. At each
key pose the pixels in the LIDAR's field of view (the *mask*, from
:mod:`map2map.parametric.visibility`) get a range error ``sigma_mz`` (eq. 3.83) and an
angular error ``sigma_mtheta`` (eq. 3.84), turned into a displacement (eqs. 3.85-3.88)
and *added* to the pixel's odometry field (eqs. 3.89-3.90): a pixel seen from many poses
accumulates many errors - the approximation the thesis contrasts with the EKF.

Reading of the thesis: eqs. 3.85-3.86 decompose the error along the beam
(``sigma_mz``, range) and across it (angle ``sigma_mtheta``), i.e. in the beam frame;
eqs. 3.87-3.88 express that in the map frame by rotating by the beam's bearing from the
pose to the pixel (``d = R(phi) sigma``). Taken literally in the map frame, every pixel of
every map would be pushed the same way (+x), whatever the trajectory. Errors in metres
are converted to pixels (``pm`` pixels per metre). ``z_meas(mask)`` is the range the
LIDAR measures to each masked pixel *from this pose*: the true pose-to-pixel range plus
the LIDAR model's range error ``z_meas - D`` (eq. 3.29) of that pixel. For pose 0 there is
no motion yet
(``Delta l = Delta theta = 0``).

Examples
--------
>>> float(linear_error(1.0, 0.02))                  # eq. 3.81: 0.09 * 1 + 0.02
0.11
>>> round(float(angular_error(0.1, 0.01)), 6)       # eq. 3.82: 0.095 * 0.1 + 0.01
0.0195
"""

from __future__ import annotations

import numpy as np

from .odometry import OdometryErrors
from .params import ParametricParams
from .visibility import Visibility

__all__ = [
    "linear_error",
    "angular_error",
    "map_range_error",
    "map_angle_error",
    "beam_frame_error",
    "map_frame_error",
    "accumulate",
    "additive_field",
]


def linear_error(dl, sigma: float, gain: float = 0.09):
    """Eq. 3.81: ``E_lin(Delta l) = 0.09 Delta l + sigma``."""
    return gain * np.asarray(dl, float) + sigma


def angular_error(dtheta, alpha: float, gain: float = 0.095):
    """Eq. 3.82: ``E_ang(Delta theta) = 0.095 Delta theta + alpha``."""
    return gain * np.asarray(dtheta, float) + alpha


def map_range_error(z_meas, eta: float, e_lin, noise=0.0):
    """Eq. 3.83: ``sigma_mz = z_meas(mask) eta + E_lin(Delta l) + N(0, eps_lin)``."""
    return np.asarray(z_meas, float) * eta + e_lin + noise


def map_angle_error(beta: float, e_ang, noise=0.0):
    """Eq. 3.84: ``sigma_mtheta = beta / 2 + E_ang(Delta theta) + N(0, eps_ang)``."""
    return beta / 2.0 + e_ang + noise


def beam_frame_error(s_mz, s_mtheta):
    """Eqs. 3.85-3.86: ``sigma_mx = sigma_mz cos(sigma_mtheta)``, ``sigma_my = sigma_mz sin(...)``.

    >>> [round(float(v), 6) for v in beam_frame_error(2.0, np.pi / 6)]
    [1.732051, 1.0]
    """
    return s_mz * np.cos(s_mtheta), s_mz * np.sin(s_mtheta)


def map_frame_error(s_mx, s_my, bearing):
    """Eqs. 3.87-3.88: ``d_m = sigma_m`` in the map frame (rotated by the beam bearing)."""
    c, s = np.cos(bearing), np.sin(bearing)
    return c * s_mx - s * s_my, s * s_mx + c * s_my


def accumulate(d_o: np.ndarray, mask, d_m):
    """Eqs. 3.89-3.90: ``d_O(mask) = d_O(mask) + d_m`` (in place, flat indices ``mask``)."""
    d_o[mask] += d_m
    return d_o


def additive_field(
    vis: Visibility,
    poses_px: np.ndarray,
    z_meas: np.ndarray,
    D: np.ndarray,
    odo: OdometryErrors,
    p: ParametricParams,
    pm: float,
    rng: np.random.Generator,
) -> tuple[np.ndarray, np.ndarray]:
    """The odometry deformation field ``(d_xO, d_yO)`` [px] by the method of [58].

    Parameters
    ----------
    vis : Visibility
        Pixels seen from each key pose (the masks).
    poses_px : (K, 3) array
        Key poses in pixels ``(x, y, angle)``.
    z_meas, D : (H, W) arrays
        Measured (eq. 3.29) and modelled range of every pixel [m]; their difference is the
        LIDAR range error added to the true range from each pose.
    odo : OdometryErrors
        Per-step errors between key poses (K - 1 steps).
    p : ParametricParams
        ``lin_gain``, ``ang_gain``, ``eta``, ``beam_aperture_deg``, ``eps_lin``, ``eps_ang``.
    pm : float
        Pixels per metre.
    rng : numpy.random.Generator
        Source of the N(0, eps) terms (drawn only when eps > 0).
    """
    h, w = vis.shape
    k = vis.n_poses
    s_t = np.concatenate([[0.0], odo.sigma["t"]])
    s_x = np.concatenate([[0.0], odo.sigma["x"]])
    # Delta l = sigma_p = sigma_x / cos(sigma_theta); sigma, alpha their means (after 3.82)
    dl = s_x / np.cos(s_t)
    e_lin = linear_error(dl, float(dl[1:].mean()) if k > 1 else 0.0, p.lin_gain)
    e_ang = angular_error(s_t, float(s_t[1:].mean()) if k > 1 else 0.0, p.ang_gain)
    beta = np.radians(p.beam_aperture_deg)
    zerr = (np.asarray(z_meas, float) - np.asarray(D, float)).ravel()
    dxo = np.zeros(h * w)
    dyo = np.zeros(h * w)
    for i in range(k):
        idx = vis.seen_from(i)
        if idx.size == 0:
            continue
        n_lin = rng.normal(0.0, p.eps_lin, idx.size) if p.eps_lin > 0 else 0.0
        n_ang = rng.normal(0.0, p.eps_ang, idx.size) if p.eps_ang > 0 else 0.0
        rows, cols = np.divmod(idx, w)
        ry, rx = rows - poses_px[i, 1], cols - poses_px[i, 0]
        bearing = np.arctan2(ry, rx)
        z_pose = np.hypot(rx, ry) / pm + zerr[idx]  # range measured from this pose [m]
        s_mz = map_range_error(z_pose, p.eta, e_lin[i], n_lin)
        s_mt = map_angle_error(beta, e_ang[i], n_ang)
        s_mx, s_my = beam_frame_error(s_mz, s_mt)
        d_mx, d_my = map_frame_error(s_mx, s_my, bearing)
        accumulate(dxo, idx, pm * d_mx)
        accumulate(dyo, idx, pm * d_my)
    return dxo.reshape(h, w), dyo.reshape(h, w)
