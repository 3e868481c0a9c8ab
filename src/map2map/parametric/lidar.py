"""Exteroceptive (2-D LIDAR) error model, thesis section 3.2.1, thesis eqs. 3.8-3.30.

Every pixel of the plan is treated as a landmark seen at slant range ``D`` [m] and
horizontal angle ``alpha`` [rad]. In the thesis both are random per pixel and median
filtered, so that neighbouring pixels get similar readings (``lidar_geometry="random"``);
alternatively they are the actual range and bearing from the first key pose that saw the
pixel (``"geometry"``). The calibration errors of ref. [13] (thesis eqs. 3.9-3.10) and the beam
model of refs. [55, 56] (hit, short, max and random readings, thesis eqs. 3.13-3.26) each give a
displacement of the pixel; their weighted sum (thesis eqs. 3.27-3.28) is the LIDAR deformation
field ``(d_xL, d_yL)`` in pixels, and thesis eqs. 3.29-3.30 give the measured range and angle.

Reading of the thesis, where it is ambiguous
--------------------------------------------
* Thesis eq. 3.10 writes ``b4`` twice; the second term is ``b5 cos 2 alpha`` (the text names
  ``b4`` and ``b5`` the non-orthogonality terms).
* Thesis eqs. 3.18-3.19, 3.22-3.23 and 3.25-3.26 are printed as ``pm (D cos a - E cos(a - da))``,
  which would displace every pixel by ``pm D`` (metres of range turned into pixels) even
  with every error zero. They are read like thesis eq. 3.11: the reading with error ``E`` lies
  at range ``D - E``, i.e. ``pm (D cos a - (D - E) cos(a - da))``. One function,
  :func:`polar_displacement`, implements all four pairs.
* A short reading (thesis eq. 3.16) is drawn for *every* pixel and its error ``E_short`` is of
  the order of the range itself; applied in full (weight 0.3) it would scatter each wall
  by decimetres, which neither SLAM maps nor the thesis's Fig. 5.13-5.15 show. It is
  therefore scaled by ``short_scale`` (default 0.02; 1.0 is the literal model) and, like
  D and alpha, drawn from a median-filtered random field.
* Thesis eq. 3.29 divides a pixel displacement by a cosine and subtracts it from a range in
  metres; the displacement is converted to metres first (divided by ``pm``).
* Angles are measured in the image frame (x right, y down). With ``"geometry"`` the
  displacement of thesis eqs. 3.11-3.12 is in the sensor frame and is rotated by the heading of
  the observing pose.

Examples
--------
>>> import numpy as np
>>> float(range_error(2.0, 0.01, 0.005))                    # thesis eq. 3.9: 0.01 + 0.005 * 2
0.02
>>> dx, dy = polar_displacement(2.0, 0.0, 0.02, 0.0, 20.0)  # 2 cm short at 20 px/m
>>> round(float(dx), 6), round(float(dy), 6)
(0.4, 0.0)
"""

from __future__ import annotations

from dataclasses import asdict, dataclass

import cv2
import numpy as np
from scipy import ndimage

from .params import ParametricParams

__all__ = [
    "LidarCoefficients",
    "LidarField",
    "draw_lidar_coefficients",
    "random_range_angle",
    "median_smooth",
    "landmark_position",
    "range_error",
    "angle_error",
    "polar_displacement",
    "p_short",
    "p_max",
    "p_rand",
    "short_range",
    "short_error",
    "max_range",
    "max_error",
    "rand_error",
    "weighted_field",
    "measured",
    "lidar_field",
]


def _arr(x):
    """``x`` as a floating array, keeping float32 arrays float32."""
    if isinstance(x, np.ndarray) and x.dtype.kind == "f":
        return x
    return np.asarray(x, float)


@dataclass(frozen=True)
class LidarCoefficients:
    """Per-map draws: calibration coefficients (thesis eqs. 3.9-3.10) and Max_err, Ran_err [m]."""

    a0: float = 0.0
    a1: float = 0.0
    b: tuple[float, float, float, float, float, float] = (0.0,) * 6
    max_err: float = 0.0
    ran_err: float = 0.0

    def as_dict(self) -> dict:
        d = asdict(self)
        d["b"] = [float(v) for v in self.b]
        return d


def draw_lidar_coefficients(p: ParametricParams, rng: np.random.Generator) -> LidarCoefficients:
    """Draw the calibration coefficients uniformly within their bounds (ref. [13]).

    Parameters
    ----------
    p : ParametricParams
        ``a0_bound`` ... ``b6_bound``, ``max_err_bound``, ``rand_err_bound``.
    rng : numpy.random.Generator
        Source of the draws.

    Returns
    -------
    LidarCoefficients
    """
    bounds = np.array(
        [
            p.a0_bound,
            p.a1_bound,
            p.b1_bound,
            p.b2_bound,
            p.b3_bound,
            p.b4_bound,
            p.b5_bound,
            p.b6_bound,
        ]  # fmt: skip
    )
    v = rng.uniform(-1.0, 1.0, bounds.size) * bounds
    errs = rng.uniform(0.0, 1.0, 2) * np.array([p.max_err_bound, p.rand_err_bound])
    return LidarCoefficients(
        a0=float(v[0]),
        a1=float(v[1]),
        b=tuple(float(x) for x in v[2:]),
        max_err=float(errs[0]),
        ran_err=float(errs[1]),
    )


def random_range_angle(
    shape: tuple[int, int],
    range_min: float,
    range_max: float,
    median_size: int,
    rng: np.random.Generator,
) -> tuple[np.ndarray, np.ndarray]:
    """Random per-pixel range D [m] and angle alpha [rad], median filtered (thesis 3.2.1).

    Parameters
    ----------
    shape : (H, W)
        Map size.
    range_min, range_max : float
        Range bounds, metres.
    median_size : int
        Median filter size, pixels.
    rng : numpy.random.Generator
        Source of the draws.

    Returns
    -------
    D, alpha : (H, W) float32 arrays
        Range [m] and angle [rad].
    """
    d = median_smooth(rng.uniform(range_min, range_max, shape), median_size)
    a = median_smooth(rng.uniform(-np.pi, np.pi, shape), median_size)
    return d, a


def median_smooth(a: np.ndarray, size: int) -> np.ndarray:
    """Median filter over ``size x size`` pixels, edges replicated; returns float32.

    Uses :func:`cv2.medianBlur` for sizes 3 and 5 (an order of magnitude faster than
    :func:`scipy.ndimage.median_filter`, which handles the other sizes).

    Parameters
    ----------
    a : (H, W) array
        Values.
    size : int
        Odd filter size.

    Returns
    -------
    (H, W) float32 array

    Examples
    --------
    >>> median_smooth(np.array([[0, 0, 0], [0, 9, 0], [0, 0, 0]], float), 3).tolist()
    [[0.0, 0.0, 0.0], [0.0, 0.0, 0.0], [0.0, 0.0, 0.0]]
    """
    if size <= 1:
        return np.asarray(a, np.float32)
    a32 = np.ascontiguousarray(a, np.float32)
    if size in (3, 5):
        return cv2.medianBlur(a32, size)
    return ndimage.median_filter(a32, size=size, mode="nearest")


def landmark_position(xl, yl, D, alpha):
    """Thesis eq. 3.8: ``X_L = [X_l, Y_l] - D [cos alpha, sin alpha]``.

    With ``(X_l, Y_l)`` the landmark seen at range ``D`` and angle ``alpha``, this is the
    point the beam comes from (the sensor); conversely the landmark is at the sensor
    position plus ``D [cos alpha, sin alpha]``.

    Parameters
    ----------
    xl, yl : float or ndarray
        Landmark position.
    D, alpha : float or ndarray
        Range and angle of the beam.

    Returns
    -------
    x, y : ndarray
        The sensor position.

    Examples
    --------
    >>> [round(float(v), 9) + 0.0 for v in landmark_position(3.0, 4.0, 5.0, np.arctan2(4, 3))]
    [0.0, 0.0]
    """
    D = _arr(D)
    return np.asarray(xl) - D * np.cos(alpha), np.asarray(yl) - D * np.sin(alpha)


def range_error(D, a0: float, a1: float):
    """Thesis eq. 3.9: ``Delta D = a0 + a1 D`` (zero offset plus scale error).

    Parameters
    ----------
    D : float or ndarray
        True range, metres.
    a0, a1 : float
        Zero offset [m] and scale error.

    Returns
    -------
    ndarray
        ``Delta D``, metres.

    Examples
    --------
    >>> float(range_error(2.0, 0.01, 0.005))
    0.02
    """
    return a0 + a1 * _arr(D)


def angle_error(alpha, D, b, sincos=None):
    """Thesis eq. 3.10:
    ``Delta alpha = b1 a + b2 sin a + b3 cos a + b4 sin 2a + b5 cos 2a + b6 / D``.

    ``sincos`` may pass precomputed ``(sin a, cos a)``; ``sin 2a`` and ``cos 2a`` follow
    from them.

    Parameters
    ----------
    alpha : float or ndarray
        Beam angle, radians.
    D : float or ndarray
        Range, metres.
    b : sequence of 6 floats
        ``b1 .. b6``.
    sincos : (sin, cos), optional
        Precomputed ``sin alpha``, ``cos alpha``.

    Returns
    -------
    ndarray
        ``Delta alpha``, radians.

    Examples
    --------
    >>> round(float(angle_error(0.0, 2.0, (0, 0, 0.01, 0, 0.02, 0.004))), 6)  # b3+b5+b6/2
    0.032
    """
    a = _arr(alpha)
    s, c = (np.sin(a), np.cos(a)) if sincos is None else sincos
    b1, b2, b3, b4, b5, b6 = b
    return b1 * a + b2 * s + b3 * c + b4 * (2 * s * c) + b5 * (c * c - s * s) + b6 / D


def polar_displacement(D, alpha, dD, dalpha, pm: float, trig=None):
    """Displacement [px] of a point seen at ``(D, alpha)``, measured at ``(D - dD, alpha - da)``.

    Thesis eqs. 3.11-3.12 (hit, ``dD = Delta D``) and, with ``dD`` the error ``E`` of the
    reading type, thesis eqs. 3.18-3.19 (short), 3.22-3.23 (max), 3.25-3.26 (random)::

        d_x = pm (D cos(alpha) - (D - dD) cos(alpha - dalpha))
        d_y = pm (D sin(alpha) - (D - dD) sin(alpha - dalpha))

    ``trig`` may pass precomputed ``(cos a, sin a, cos(a - da), sin(a - da))``.

    Parameters
    ----------
    D, alpha : float or ndarray
        True range [m] and angle [rad].
    dD, dalpha : float or ndarray
        Range and angle errors.
    pm : float
        Pixels per metre.
    trig : tuple of arrays, optional
        Precomputed trigonometry (above).

    Returns
    -------
    d_x, d_y : ndarray
        Pixels.

    Examples
    --------
    >>> [round(float(v), 9) for v in polar_displacement(2.0, 0.0, 0.1, 0.0, 20.0)]
    [2.0, 0.0]
    """
    D = _arr(D)
    if trig is None:
        alpha = _arr(alpha)
        a = alpha - dalpha
        trig = (np.cos(alpha), np.sin(alpha), np.cos(a), np.sin(a))
    c0, s0, c1, s1 = trig
    r = D - dD
    return pm * (D * c0 - r * c1), pm * (D * s0 - r * s1)


def p_short(z, z_star, lam: float):
    """Thesis eq. 3.13: truncated-exponential density of a short reading ``z`` for true range
    ``z*``.

    Parameters
    ----------
    z : float or ndarray
        Reading, metres.
    z_star : float or ndarray
        True range, metres.
    lam : float
        ``lambda_short`` [1/m].

    Returns
    -------
    ndarray
        Density (0 outside ``[0, z*]``).
    """
    z = _arr(z)
    z_star = _arr(z_star)
    dens = lam * np.exp(-lam * z) / (1.0 - np.exp(-lam * z_star))
    return np.where((z >= 0) & (z <= z_star), dens, 0.0)


def p_max(z, z_max):
    """Thesis eq. 3.14: 1 where the reading is the maximum range, else 0.

    Parameters
    ----------
    z : ndarray
        Readings.
    z_max : float
        Maximum range.

    Returns
    -------
    ndarray
        Same dtype as ``z``.
    """
    z = _arr(z)
    return (z == z_max).astype(z.dtype)


def p_rand(z, z_max):
    """Thesis eq. 3.15: uniform density ``1 / z_max`` over ``[0, z_max]``.

    Parameters
    ----------
    z : ndarray
        Readings.
    z_max : float
        Maximum range.

    Returns
    -------
    ndarray
        Same dtype as ``z``.

    Examples
    --------
    >>> p_rand(np.array([1.0, 5.0]), 4.0).tolist()
    [0.25, 0.0]
    """
    z = _arr(z)
    return np.where((z >= 0) & (z <= z_max), 1.0 / z_max, 0.0).astype(z.dtype)


def short_range(p, z_star, lam: float):
    """Thesis eq. 3.16: the short reading whose density (thesis eq. 3.13) is ``p`` (inverse of
    3.13).

    Parameters
    ----------
    p : float or ndarray
        Density value.
    z_star : float or ndarray
        True range, metres.
    lam : float
        ``lambda_short`` [1/m].

    Returns
    -------
    ndarray
        The short reading, metres.

    Examples
    --------
    >>> z = short_range(p_short(0.7, 2.0, 0.5), 2.0, 0.5)
    >>> round(float(z), 9)
    0.7
    """
    z_star = _arr(z_star)
    return -np.log(_arr(p) * (1.0 - np.exp(-lam * z_star)) / lam) / lam


def short_error(z_star, z):
    """Thesis eq. 3.17: ``E_short = z* - z``.

    Parameters
    ----------
    z_star, z : float or ndarray
        True range and short reading, metres.

    Returns
    -------
    ndarray
    """
    return _arr(z_star) - _arr(z)


def max_range(z):
    """Thesis eq. 3.20: ``z_max = max(z)`` over all readings.

    Parameters
    ----------
    z : ndarray
        All readings.

    Returns
    -------
    float
    """
    return float(np.max(z))


def max_error(z, z_max: float, max_err: float):
    """Thesis eq. 3.21: ``E_max = Max_err P_max`` where the reading is the maximum, else 0.

    Parameters
    ----------
    z : ndarray
        Readings.
    z_max : float
        Maximum range.
    max_err : float
        ``Max_err``, metres.

    Returns
    -------
    ndarray
    """
    return max_err * p_max(z, z_max)


def rand_error(z, z_max: float, ran_err: float):
    """Thesis eq. 3.24: ``E_rand = Ran_err P_rand`` for readings in ``[0, z_max]``, else 0.

    Parameters
    ----------
    z : ndarray
        Readings.
    z_max : float
        Maximum range.
    ran_err : float
        ``Ran_err``, metres.

    Returns
    -------
    ndarray
    """
    return ran_err * p_rand(z, z_max)


def weighted_field(fields, weights):
    """Thesis eqs. 3.27-3.28: ``d_L = Z_hit d_hit + Z_short d_short + Z_max d_max + Z_rand d_rand``.

    ``fields`` is the sequence of the four components (x or y), ``weights`` Z.

    Parameters
    ----------
    fields : sequence of 4 arrays
        ``d_hit``, ``d_short``, ``d_max``, ``d_rand`` (one component).
    weights : sequence of 4 floats
        ``Z_hit``, ``Z_short``, ``Z_max``, ``Z_rand``.

    Returns
    -------
    ndarray

    Examples
    --------
    >>> weighted_field([np.ones(2)] * 4, (0.4, 0.3, 0.2, 0.1)).round(6).tolist()
    [1.0, 1.0]
    """
    out = np.zeros_like(_arr(fields[0]))
    for f, w in zip(fields, weights, strict=True):
        out = out + w * _arr(f)
    return out


def measured(D, alpha, dx_l, dy_l, dalpha, pm: float, cos_sin=None):
    """Thesis eqs. 3.29-3.30: ``z_meas = D - (d_xL / pm) / cos(alpha - Delta alpha)``,
    ``alpha_meas = alpha - Delta alpha``.

    Thesis eq. 3.29 recovers the range from the x component of the field, which is
    ill-conditioned where ``cos(alpha - Delta alpha)`` is small; there (where
    ``|sin| > |cos|``) the same relation is applied to the y component,
    ``D - (d_yL / pm) / sin(alpha - Delta alpha)``. ``cos_sin`` may pass precomputed
    ``(cos, sin)`` of ``alpha - Delta alpha``.

    Parameters
    ----------
    D, alpha : float or ndarray
        True range [m] and angle [rad].
    dx_l, dy_l : float or ndarray
        LIDAR field components, pixels.
    dalpha : float or ndarray
        Angle error, radians.
    pm : float
        Pixels per metre.
    cos_sin : (cos, sin), optional
        Precomputed trigonometry of ``alpha - Delta alpha``.

    Returns
    -------
    z_meas, alpha_meas : ndarray

    Examples
    --------
    >>> z, a = measured(2.0, 0.0, 0.4, 0.0, 0.0, 20.0)   # 0.4 px at 20 px/m: 2 cm short
    >>> round(float(z), 6), float(a)
    (1.98, 0.0)
    """
    D = _arr(D)
    a_meas = _arr(alpha) - dalpha
    c, s = (np.cos(a_meas), np.sin(a_meas)) if cos_sin is None else cos_sin
    use_x = np.abs(c) >= np.abs(s)
    num = np.where(use_x, _arr(dx_l), _arr(dy_l)) / pm
    return D - num / np.where(use_x, c, s), a_meas


@dataclass
class LidarField:
    """Result of the LIDAR model on a grid: field [px] and the measured range/angle."""

    dx: np.ndarray
    dy: np.ndarray
    z_meas: np.ndarray
    alpha_meas: np.ndarray
    D: np.ndarray
    alpha: np.ndarray


def lidar_field(
    D: np.ndarray,
    alpha: np.ndarray,
    coeffs: LidarCoefficients,
    p: ParametricParams,
    pm: float,
    rng: np.random.Generator,
    heading: np.ndarray | float = 0.0,
) -> LidarField:
    """The LIDAR deformation field of every pixel, thesis eqs. 3.9-3.30.

    Parameters
    ----------
    D, alpha : (H, W) arrays
        Range [m] and angle [rad, sensor frame] of every pixel.
    coeffs : LidarCoefficients
        Drawn calibration coefficients and Max_err / Ran_err.
    p : ParametricParams
        ``lambda_short``, ``short_scale``, ``median_size``, ``z_weights``.
    pm : float
        Pixels per metre.
    rng : numpy.random.Generator
        Source of the per-pixel short-reading density (thesis eq. 3.13).
    heading : float or (H, W) array
        Sensor heading [rad] that rotates the sensor-frame field into the image frame.

    Returns
    -------
    LidarField
        ``dx``, ``dy`` [px], ``z_meas`` [m], ``alpha_meas`` [rad], ``D`` and ``alpha``.
    """
    # float32: the field is stored as float32 anyway, and this halves the memory traffic
    D = np.asarray(D, np.float32)
    alpha = np.asarray(alpha, np.float32)
    dD = range_error(D, coeffs.a0, coeffs.a1)
    c0, s0 = np.cos(alpha), np.sin(alpha)
    da = angle_error(alpha, D, coeffs.b, (s0, c0))
    a_m = alpha - da
    trig = (c0, s0, np.cos(a_m), np.sin(a_m))
    d_hit = polar_displacement(D, alpha, dD, da, pm, trig)
    # short readings: a density drawn uniformly between p_short(z*) = lam e / (1 - e) and
    # p_short(0) = lam / (1 - e), e = exp(-lam z*) (thesis eq. 3.13), turned into z by
    # thesis eq. 3.16
    lam = p.lambda_short
    u = median_smooth(rng.uniform(0.0, 1.0, D.shape), p.median_size)
    e = np.exp(-lam * D)
    z = short_range(lam * (e + u * (1.0 - e)) / (1.0 - e), D, lam)
    e_short = p.short_scale * short_error(D, z)
    d_short = polar_displacement(D, alpha, e_short, da, pm, trig)
    z_max = max_range(z)
    d_max = polar_displacement(D, alpha, max_error(z, z_max, coeffs.max_err), da, pm, trig)
    d_rand = polar_displacement(D, alpha, rand_error(z, z_max, coeffs.ran_err), da, pm, trig)
    comps = (d_hit, d_short, d_max, d_rand)
    dx = weighted_field([c[0] for c in comps], p.z_weights)
    dy = weighted_field([c[1] for c in comps], p.z_weights)
    z_meas, a_meas = measured(D, alpha, dx, dy, da, pm, trig[2:])
    if np.any(heading != 0.0):
        c, s = np.cos(heading), np.sin(heading)
        dx, dy = c * dx - s * dy, s * dx + c * dy
    return LidarField(dx=dx, dy=dy, z_meas=z_meas, alpha_meas=a_meas, D=D, alpha=alpha)
