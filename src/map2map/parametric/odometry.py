"""Proprioceptive (odometry) error model, thesis section 3.2.2, thesis eqs. 3.31-3.53.

The systematic errors of a differential-drive robot as UMBmark measures them
(Borenstein & Feng, refs. [19, 20]): a wheelbase error ``E_b`` and a ratio ``E_d`` of
the right to left wheel diameters. The UMBmark angles ``alpha_Eb``, ``alpha_Ed`` [deg]
and the curvature angle ``beta`` [deg] are drawn once per map from zero-mean normal
distributions with the experimental standard deviations (params
``alpha_eb_std_deg``, ``alpha_ed_std_deg``, ``beta_std_deg``). Between successive key
poses the wheel rotations ``gamma`` follow from the nominal motion; the same rotations
with the actual wheel diameters and wheelbase give the actual motion, and the
per-step differences nominal - actual are the error terms ``sigma`` of thesis eqs. 3.48-3.53.

Conventions: ``gamma`` is defined so that thesis eq. 3.38 holds as written, ``Delta d = gamma D``
(``gamma`` is half the wheel's rotation angle in radians). ``beta`` enters thesis eq. 3.33 in
radians. The previous heading ``theta_{k-1}`` of thesis eqs. 3.42-3.43 and 3.46-3.47 is the
nominal one for both, so the ``sigma`` are per-step errors (their accumulation is what
the conversion methods model). The products of thesis eqs. 3.51-3.53 are read as
``sigma_xy = Dx_nom Dy_nom - Dx_act Dy_act`` (and likewise for ``x theta``, ``y theta``).

Examples
--------
>>> round(wheelbase_error(0.5, 0.4), 6)             # thesis eq. 3.31: 90 / (90 - 0.9)
1.010101
>>> dl, dr = actual_diameters(1.0, 0.066)           # E_d = 1: both wheels nominal
>>> round(dl, 6), round(dr, 6)
(0.066, 0.066)
"""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass

import numpy as np

from ..core.geometry import wrap_angle
from ..trajectory.timing import Trajectory
from .params import ParametricParams

__all__ = [
    "OdometryCoefficients",
    "OdometryErrors",
    "draw_odometry_coefficients",
    "wheelbase_error",
    "actual_wheelbase",
    "curvature_radius",
    "diameter_ratio",
    "average_diameter",
    "actual_diameters",
    "wheel_displacement",
    "centre_increment",
    "pose_increment",
    "error_terms",
    "straight_run_length",
    "odometry_errors",
]


@dataclass(frozen=True)
class OdometryCoefficients:
    """Per-map draws of the UMBmark angles [deg]."""

    alpha_eb: float = 0.0
    alpha_ed: float = 0.0
    beta: float = 0.0

    def as_dict(self) -> dict:
        return asdict(self)


def draw_odometry_coefficients(
    p: ParametricParams, rng: np.random.Generator
) -> OdometryCoefficients:
    """Draw ``alpha_Eb``, ``alpha_Ed``, ``beta`` [deg] from N(0, std) (refs. [19, 20]).

    Parameters
    ----------
    p : ParametricParams
        ``alpha_eb_std_deg``, ``alpha_ed_std_deg``, ``beta_std_deg``.
    rng : numpy.random.Generator
        Source of the draws.

    Returns
    -------
    OdometryCoefficients
    """
    v = rng.normal(0.0, 1.0, 3) * np.array([p.alpha_eb_std_deg, p.alpha_ed_std_deg, p.beta_std_deg])
    return OdometryCoefficients(float(v[0]), float(v[1]), float(v[2]))


def wheelbase_error(alpha_eb: float, alpha_ed: float) -> float:
    """Thesis eq. 3.31: ``E_b = 90 / (90 - (alpha_Eb + alpha_Ed))`` (angles in degrees).

    Parameters
    ----------
    alpha_eb, alpha_ed : float
        UMBmark angles, degrees.

    Returns
    -------
    float

    Examples
    --------
    >>> wheelbase_error(0.0, 0.0)
    1.0
    """
    return 90.0 / (90.0 - (alpha_eb + alpha_ed))


def actual_wheelbase(e_b: float, b_nominal: float) -> float:
    """Thesis eq. 3.32: ``b_actual = E_b b_nominal``.

    Parameters
    ----------
    e_b : float
        Wheelbase error factor.
    b_nominal : float
        Nominal wheelbase, metres.

    Returns
    -------
    float

    Examples
    --------
    >>> round(actual_wheelbase(1.5, 0.2), 6)
    0.3
    """
    return e_b * b_nominal


def curvature_radius(L: float, beta_deg: float) -> float:
    """Thesis eq. 3.33: ``R = (L / 2) / sin(beta / 2)``; infinite (straight) when ``beta = 0``.

    Parameters
    ----------
    L : float
        Straight-run length, metres.
    beta_deg : float
        UMBmark angle ``beta``, degrees.

    Returns
    -------
    float

    Examples
    --------
    >>> round(curvature_radius(4.0, 2.0), 3)
    114.597
    """
    s = math.sin(math.radians(beta_deg) / 2.0)
    return math.inf if s == 0 else (L / 2.0) / s


def diameter_ratio(R: float, b_actual: float) -> float:
    """Thesis eq. 3.34: ``E_d = D_R / D_L = (R + b/2) / (R - b/2)``; 1 for a straight run (R
    infinite).

    Parameters
    ----------
    R : float
        Curvature radius, metres (may be infinite).
    b_actual : float
        Actual wheelbase, metres.

    Returns
    -------
    float

    Examples
    --------
    >>> diameter_ratio(math.inf, 0.3)
    1.0
    """
    if math.isinf(R):
        return 1.0
    return (R + b_actual / 2.0) / (R - b_actual / 2.0)


def average_diameter(d_r: float, d_l: float) -> float:
    """Thesis eq. 3.35: ``D_a = (D_R + D_L) / 2``.

    Parameters
    ----------
    d_r, d_l : float
        Wheel diameters, metres.

    Returns
    -------
    float

    Examples
    --------
    >>> round(average_diameter(0.066, 0.064), 6)
    0.065
    """
    return (d_r + d_l) / 2.0


def actual_diameters(e_d: float, d_a: float) -> tuple[float, float]:
    """Thesis eqs. 3.36-3.37: ``D_L = 2 D_a / (E_d + 1)``, ``D_R = 2 D_a / (1 / E_d + 1)``.

    Returns ``(D_L, D_R)``.

    Parameters
    ----------
    e_d : float
        Diameter ratio.
    d_a : float
        Average diameter, metres.

    Returns
    -------
    D_L, D_R : float

    Examples
    --------
    >>> actual_diameters(1.0, 0.066)
    (0.066, 0.066)
    """
    return 2.0 / (e_d + 1.0) * d_a, 2.0 / (1.0 / e_d + 1.0) * d_a


def wheel_displacement(gamma, diameter: float):
    """Thesis eqs. 3.38-3.39: ``Delta d = gamma D`` for one wheel.

    Parameters
    ----------
    gamma : float or ndarray
        Half the wheel's rotation angle, radians (module docstring).
    diameter : float
        Wheel diameter, metres.

    Returns
    -------
    ndarray
        Metres.
    """
    return np.asarray(gamma, float) * diameter


def centre_increment(dd_r, dd_l, b: float):
    """Thesis eqs. 3.40-3.41 (actual) and 3.44-3.45 (nominal): ``Delta d = (d_R + d_L) / 2``,
    ``Delta theta = (d_R - d_L) / b``.

    Parameters
    ----------
    dd_r, dd_l : float or ndarray
        Right and left wheel displacements, metres.
    b : float
        Wheelbase, metres.

    Returns
    -------
    dd, dth : float or ndarray

    Examples
    --------
    >>> [round(float(v), 6) for v in centre_increment(0.2, 0.1, 0.25)]
    [0.15, 0.4]
    """
    dd_r = np.asarray(dd_r, float)
    dd_l = np.asarray(dd_l, float)
    return (dd_r + dd_l) / 2.0, (dd_r - dd_l) / b


def pose_increment(dd, dth, theta_prev):
    """Thesis eqs. 3.42-3.43 (actual) and 3.46-3.47 (nominal):
    ``Delta x = Delta d cos(theta + Delta theta / 2)``, ``Delta y = Delta d sin(...)``.

    Parameters
    ----------
    dd : float or ndarray
        Distance increments, metres.
    dth : float or ndarray
        Heading increments, radians.
    theta_prev : float or ndarray
        Headings before the step.

    Returns
    -------
    dx, dy : ndarray
    """
    a = np.asarray(theta_prev, float) + np.asarray(dth, float) / 2.0
    return np.asarray(dd, float) * np.cos(a), np.asarray(dd, float) * np.sin(a)


def error_terms(nom: dict, act: dict) -> dict:
    """Thesis eqs. 3.48-3.53: covariance terms as nominal minus actual increments.

    ``nom`` and ``act`` hold arrays ``dx``, ``dy``, ``dth``.

    Parameters
    ----------
    nom, act : dict
        Nominal and actual increments.

    Returns
    -------
    dict
        ``x``, ``y``, ``t``: nominal minus actual.

    Examples
    --------
    >>> e = error_terms({"dx": 1.0, "dy": 2.0, "dth": 0.1}, {"dx": 0.9, "dy": 2.0, "dth": 0.1})
    >>> round(float(e["x"]), 6), round(float(e["xy"]), 6), round(float(e["xt"]), 6)
    (0.1, 0.2, 0.01)
    """
    return {
        "x": np.asarray(nom["dx"] - act["dx"]),
        "y": np.asarray(nom["dy"] - act["dy"]),
        "t": np.asarray(nom["dth"] - act["dth"]),
        "xy": np.asarray(nom["dx"] * nom["dy"] - act["dx"] * act["dy"]),
        "xt": np.asarray(nom["dx"] * nom["dth"] - act["dx"] * act["dth"]),
        "yt": np.asarray(nom["dy"] * nom["dth"] - act["dy"] * act["dth"]),
    }


def straight_run_length(traj: Trajectory, min_length: float = 0.5) -> float:
    """Mean length [m] of the straight runs of a trajectory (``L`` of thesis eq. 3.33).

    A run is a maximal stretch of steps that move without turning. Falls back to the
    UMBmark square side, 4 m, when the trajectory has no straight run of ``min_length``.

    Parameters
    ----------
    traj : Trajectory
        The robot's trajectory.
    min_length : float
        Shortest run counted, metres.

    Returns
    -------
    float
        Metres.
    """
    step = np.hypot(np.diff(traj.x), np.diff(traj.y))
    turn = np.abs(wrap_angle(np.diff(traj.theta), keep_in_range=True))
    straight = (step > 1e-6) & (turn < 1e-4)
    if not straight.any():
        return 4.0
    edges = np.diff(np.concatenate([[0], straight.astype(np.int8), [0]]))
    starts, ends = np.flatnonzero(edges == 1), np.flatnonzero(edges == -1)
    csum = np.concatenate([[0.0], np.cumsum(step)])
    runs = csum[ends] - csum[starts]
    runs = runs[runs >= min_length]
    return float(runs.mean()) if runs.size else 4.0


@dataclass
class OdometryErrors:
    """Per-step quantities between successive key poses (arrays of length K - 1)."""

    sigma: dict  # thesis eqs. 3.48-3.53: x, y, t, xy, xt, yt
    nominal: dict  # dd, dth, dx, dy
    actual: dict  # dd, dth, dx, dy
    e_b: float
    e_d: float
    L: float


def odometry_errors(
    poses: np.ndarray, coeffs: OdometryCoefficients, p: ParametricParams, L: float
) -> OdometryErrors:
    """Per-step odometry errors between successive key poses, thesis eqs. 3.31-3.53.

    Parameters
    ----------
    poses : (K, 3) array
        Nominal key poses ``(x, y, theta)`` in metres and radians.
    coeffs : OdometryCoefficients
        Drawn UMBmark angles.
    p : ParametricParams
        ``wheelbase`` and ``wheel_radius`` (nominal geometry).
    L : float
        Straight-run length [m] of thesis eq. 3.33.

    Returns
    -------
    OdometryErrors
        Error terms, nominal and actual increments, ``E_b``, ``E_d`` and ``L``.
    """
    poses = np.asarray(poses, float).reshape(-1, 3)
    b_nom = p.wheelbase
    d_nom = 2.0 * p.wheel_radius  # D_Rnom = D_Lnom
    e_b = wheelbase_error(coeffs.alpha_eb, coeffs.alpha_ed)
    b_act = actual_wheelbase(e_b, b_nom)
    R = curvature_radius(L, coeffs.beta)
    e_d = diameter_ratio(R, b_act)
    d_a = average_diameter(d_nom, d_nom)
    d_l_act, d_r_act = actual_diameters(e_d, d_a)
    # nominal motion between key poses: forward distance and heading change
    delta = np.diff(poses[:, :2], axis=0)
    th_prev = poses[:-1, 2]
    dth_n = wrap_angle(np.diff(poses[:, 2]), keep_in_range=True)
    dd_n = delta[:, 0] * np.cos(th_prev + dth_n / 2) + delta[:, 1] * np.sin(th_prev + dth_n / 2)
    # wheel rotations that produce it with the nominal geometry (Delta d = gamma D)
    gamma_r = (dd_n + b_nom * dth_n / 2.0) / d_nom
    gamma_l = (dd_n - b_nom * dth_n / 2.0) / d_nom
    dd_nom, dth_nom = centre_increment(
        wheel_displacement(gamma_r, d_nom), wheel_displacement(gamma_l, d_nom), b_nom
    )
    dx_nom, dy_nom = pose_increment(dd_nom, dth_nom, th_prev)
    dd_act, dth_act = centre_increment(
        wheel_displacement(gamma_r, d_r_act), wheel_displacement(gamma_l, d_l_act), b_act
    )
    dx_act, dy_act = pose_increment(dd_act, dth_act, th_prev)
    nominal = {"dd": dd_nom, "dth": dth_nom, "dx": dx_nom, "dy": dy_nom}
    actual = {"dd": dd_act, "dth": dth_act, "dx": dx_act, "dy": dy_act}
    return OdometryErrors(
        sigma=error_terms(nominal, actual), nominal=nominal, actual=actual, e_b=e_b, e_d=e_d, L=L
    )
