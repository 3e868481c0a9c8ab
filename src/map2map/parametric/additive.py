"""Odometry error to map error by the additive method of ref. [58], thesis eqs. 3.81-3.90.

Ref. [58] is entry 58 of the thesis's bibliography (not in the thesis text this package
was written from), the source of the method and of its linear error fits (eqs. 3.81-3.82).

From the per-step odometry errors (thesis eqs. 3.48-3.53) the linear and angular odometry
errors ``E_lin`` and ``E_ang`` (thesis eqs. 3.81-3.82) are computed for every key pose. At each
key pose the pixels in the LIDAR's field of view (the *mask*, from
:mod:`map2map.parametric.visibility`) get a range error ``sigma_mz`` (thesis eq. 3.83) and an
angular error ``sigma_mtheta`` (thesis eq. 3.84), turned into a displacement (thesis eqs. 3.85-3.88)
and *added* to the pixel's odometry field (thesis eqs. 3.89-3.90): a pixel seen from many poses
accumulates many errors - the approximation the thesis contrasts with the EKF. The loop
over poses and mask pixels runs in numba, calling the very functions below compiled with
:func:`numba.njit` (each equation is written once).

Reading of the thesis: thesis eqs. 3.85-3.86 decompose the error along the beam
(``sigma_mz``, range) and across it (angle ``sigma_mtheta``), i.e. in the beam frame;
thesis eqs. 3.87-3.88 express that in the map frame by rotating by the beam's bearing from the
pose to the pixel (``d = R(phi) sigma``). Taken literally in the map frame, every pixel of
every map would be pushed the same way (+x), whatever the trajectory. Errors in metres
are converted to pixels (``pm`` pixels per metre). ``z_meas(mask)`` is the range the
LIDAR measures to each masked pixel *from this pose*: the true pose-to-pixel range plus
the LIDAR model's range error ``z_meas - D`` (thesis eq. 3.29) of that pixel. For pose 0 there is
no motion yet
(``Delta l = Delta theta = 0``).

Examples
--------
>>> float(linear_error(1.0, 0.02))                  # thesis eq. 3.81: 0.09 * 1 + 0.02
0.11
>>> round(float(angular_error(0.1, 0.01)), 6)       # thesis eq. 3.82: 0.095 * 0.1 + 0.01
0.0195
"""

from __future__ import annotations

import math

import numba
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


def linear_error(dl, sigma, gain=0.09):
    """Thesis eq. 3.81: ``E_lin(Delta l) = 0.09 Delta l + sigma``.

    Parameters
    ----------
    dl : float or ndarray
        Distance travelled, metres.
    sigma : float or ndarray
        Linear error term.
    gain : float
        0.09 in the thesis.

    Returns
    -------
    float or ndarray

    Examples
    --------
    >>> round(linear_error(1.0, 0.01), 6)
    0.1
    """
    return gain * dl + sigma


def angular_error(dtheta, alpha, gain=0.095):
    """Thesis eq. 3.82: ``E_ang(Delta theta) = 0.095 Delta theta + alpha``.

    Parameters
    ----------
    dtheta : float or ndarray
        Heading change, radians.
    alpha : float or ndarray
        Angular error term.
    gain : float
        0.095 in the thesis.

    Returns
    -------
    float or ndarray
    """
    return gain * dtheta + alpha


def map_range_error(z_meas, eta, e_lin, noise=0.0):
    """Thesis eq. 3.83: ``sigma_mz = z_meas(mask) eta + E_lin(Delta l) + N(0, eps_lin)``.

    Parameters
    ----------
    z_meas : float or ndarray
        Measured ranges of the pose's pixels, metres.
    eta : float
        Range gain.
    e_lin : float
        ``E_lin`` of the step.
    noise : float or ndarray
        ``N(0, eps_lin)`` draw.

    Returns
    -------
    float or ndarray
    """
    return z_meas * eta + e_lin + noise


def map_angle_error(beta, e_ang, noise=0.0):
    """Thesis eq. 3.84: ``sigma_mtheta = beta / 2 + E_ang(Delta theta) + N(0, eps_ang)``.

    Parameters
    ----------
    beta : float
        Beam aperture, radians.
    e_ang : float
        ``E_ang`` of the step.
    noise : float or ndarray
        ``N(0, eps_ang)`` draw.

    Returns
    -------
    float or ndarray
    """
    return beta / 2.0 + e_ang + noise


def beam_frame_error(s_mz, s_mtheta):
    """Thesis eqs. 3.85-3.86: ``sigma_mx = sigma_mz cos(sigma_mtheta)``,
    ``sigma_my = sigma_mz sin(...)``.

    Parameters
    ----------
    s_mz, s_mtheta : float or ndarray
        Range and angle errors.

    Returns
    -------
    s_mx, s_my : float or ndarray

    Examples
    --------
    >>> [round(float(v), 6) for v in beam_frame_error(2.0, np.pi / 6)]
    [1.732051, 1.0]
    """
    return s_mz * np.cos(s_mtheta), s_mz * np.sin(s_mtheta)


def map_frame_error(s_mx, s_my, cos_b, sin_b):
    """Thesis eqs. 3.87-3.88: ``d_m = sigma_m`` in the map frame, i.e. rotated by the beam's
    bearing ``b`` from the pose to the pixel (given as ``cos b``, ``sin b``).

    Parameters
    ----------
    s_mx, s_my : float or ndarray
        Beam-frame errors.
    cos_b, sin_b : float or ndarray
        Bearing of each pixel from the pose.

    Returns
    -------
    d_x, d_y : float or ndarray
    """
    return cos_b * s_mx - sin_b * s_my, sin_b * s_mx + cos_b * s_my


def accumulate(d_o, mask, d_m):
    """Thesis eqs. 3.89-3.90: ``d_O(mask) = d_O(mask) + d_m`` (in place, flat indices ``mask``).

    Parameters
    ----------
    d_o : (N,) ndarray
        Flat field, updated in place.
    mask : int array
        Flat indices of the pixels seen.
    d_m : ndarray
        Their displacement.

    Returns
    -------
    ndarray
        ``d_o``.

    Examples
    --------
    >>> d = np.zeros(4)
    >>> accumulate(d, np.array([1, 3]), np.array([0.5, 1.0])).tolist()
    [0.0, 0.5, 0.0, 1.0]
    """
    d_o[mask] += d_m
    return d_o


# the same equations, compiled for the per-pixel loop of the kernel below
_range_nb = numba.njit(cache=True)(map_range_error)
_beam_nb = numba.njit(cache=True)(beam_frame_error)
_frame_nb = numba.njit(cache=True)(map_frame_error)
_accumulate_nb = numba.njit(cache=True)(accumulate)


@numba.njit(cache=True)
def _additive_kernel(indptr, pixels, w, poses, zerr, pm, eta, e_lin, s_mt, n_lin, n_ang, dxo, dyo):
    """Thesis eqs. 3.83-3.90 for every key pose and every pixel of its mask."""  # pragma: no cover
    per_pixel_noise = n_lin.size > 0
    per_pixel_angle = n_ang.size > 0
    for k in range(indptr.size - 1):
        # sigma_mx / sigma_mz and sigma_my / sigma_mz of this pose (thesis eqs. 3.85-3.86, linear
        # in s_mz)
        cx, cy = _beam_nb(1.0, s_mt[k])
        for j in range(indptr[k], indptr[k + 1]):
            idx = pixels[j]
            rx = idx % w - poses[k, 0]
            ry = idx // w - poses[k, 1]
            r = math.sqrt(rx * rx + ry * ry)
            if r == 0.0:
                continue
            z = r / pm + zerr[idx]  # range measured from this pose [m]
            s_mz = _range_nb(z, eta, e_lin[k], n_lin[j] if per_pixel_noise else 0.0)
            if per_pixel_angle:
                s_mx, s_my = _beam_nb(s_mz, s_mt[k] + n_ang[j])
            else:
                s_mx, s_my = s_mz * cx, s_mz * cy
            d_mx, d_my = _frame_nb(s_mx, s_my, rx / r, ry / r)
            _accumulate_nb(dxo, idx, pm * d_mx)
            _accumulate_nb(dyo, idx, pm * d_my)


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
        Measured (thesis eq. 3.29) and modelled range of every pixel [m]; their difference is the
        LIDAR range error added to the true range from each pose.
    odo : OdometryErrors
        Per-step errors between key poses (K - 1 steps).
    p : ParametricParams
        ``lin_gain``, ``ang_gain``, ``eta``, ``beam_aperture_deg``, ``eps_lin``, ``eps_ang``.
    pm : float
        Pixels per metre.
    rng : numpy.random.Generator
        Source of the N(0, eps) terms (drawn only when eps > 0).

    Returns
    -------
    d_xO, d_yO : (H, W) float arrays
        Pixels.
    """
    h, w = vis.shape
    k = vis.n_poses
    s_t = np.concatenate([[0.0], odo.sigma["t"]])
    s_x = np.concatenate([[0.0], odo.sigma["x"]])
    # Delta l = sigma_p = sigma_x / cos(sigma_theta); sigma, alpha their means (after 3.82)
    dl = s_x / np.cos(s_t)
    e_lin = linear_error(dl, float(dl[1:].mean()) if k > 1 else 0.0, p.lin_gain)
    e_ang = angular_error(s_t, float(s_t[1:].mean()) if k > 1 else 0.0, p.ang_gain)
    s_mt = map_angle_error(np.radians(p.beam_aperture_deg), e_ang)  # thesis eq. 3.84 per pose
    nnz = vis.pixels.size
    n_lin = rng.normal(0.0, p.eps_lin, nnz) if p.eps_lin > 0 else np.zeros(0)
    n_ang = rng.normal(0.0, p.eps_ang, nnz) if p.eps_ang > 0 else np.zeros(0)
    zerr = (np.asarray(z_meas, float) - np.asarray(D, float)).ravel()
    dxo = np.zeros(h * w)
    dyo = np.zeros(h * w)
    _additive_kernel(
        vis.indptr, vis.pixels, w, np.ascontiguousarray(poses_px, float), zerr, float(pm),
        float(p.eta), np.ascontiguousarray(e_lin, float), np.ascontiguousarray(s_mt, float),
        n_lin, n_ang, dxo, dyo,
    )  # fmt: skip
    return dxo.reshape(h, w), dyo.reshape(h, w)
