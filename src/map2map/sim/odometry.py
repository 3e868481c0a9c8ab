"""Wheel odometry from simulated encoder ticks, with systematic and random errors.

The physical cause of odometry drift is simulated rather than its effect: the
*true* robot has wheel diameters ``D_L``, ``D_R`` and wheelbase ``b_actual`` that
differ from the nominal values the odometry integrates with. Each wheel turns by
the angle its true diameter needs to roll the true ground distance (plus random
slip); the encoders count ticks of that rotation; the odometry converts ticks back
to distances with the *nominal* radius and wheelbase.

The systematic errors follow the UMBmark model (Borenstein & Feng 1996) that the
parametric model of the thesis uses (its eqs. 3.31-3.37, implemented in
:mod:`map2map.parametric.odometry`): ``E_d = D_R / D_L`` (wheel-diameter ratio)
and ``E_b = b_actual / b_nominal`` (wheelbase ratio), with the mean diameter
``D_a = (D_R + D_L) / 2`` equal to ``scale`` times the nominal one. Random slip
adds to each wheel's rolled distance a Gaussian of standard deviation
``slip_sigma * sqrt(|distance|)`` (a random walk per metre).

Defaults (documented in :class:`OdometryErrors`): ``E_d = 1.002``, ``E_b = 1.01``,
``scale = 1.0``, ``slip_sigma = 0.005`` m per square-root metre, 4096 ticks per
wheel revolution (the Dynamixel XM430 of the TurtleBot3). ``OdometryErrors.none()``
switches every error off (and the tick quantisation with ``ticks_per_rev=0``),
in which case the odometry reproduces the true path.

Examples
--------
>>> import numpy as np
>>> odo = WheelOdometry(OdometryErrors.none(ticks_per_rev=0), rng=np.random.default_rng(0))
>>> odo.step(ds=1.0, dth=0.0)
>>> [round(v, 9) for v in odo.pose]
[1.0, 0.0, 0.0]
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from .robot import WAFFLE_PI, RobotParams, arc_step

__all__ = ["OdometryErrors", "WheelOdometry"]


@dataclass(frozen=True)
class OdometryErrors:
    """Systematic (UMBmark) and random odometry errors.

    Parameters
    ----------
    wheel_diameter_ratio : float
        ``E_d = D_R / D_L`` of the true wheels (1 = equal wheels). Default 1.002.
    wheelbase_ratio : float
        ``E_b = b_actual / b_nominal``. Default 1.01 (a wheelbase 1 % larger than
        the odometry assumes, i.e. every turn is under-estimated by 1 %).
    scale : float
        True mean wheel diameter / nominal diameter. Default 1.0.
    slip_sigma : float
        Random slip per wheel, metres per square-root metre rolled. Default 0.005.
    ticks_per_rev : int
        Encoder resolution; 0 means ideal (unquantised) encoders. Default 4096.
    """

    wheel_diameter_ratio: float = 1.002
    wheelbase_ratio: float = 1.01
    scale: float = 1.0
    slip_sigma: float = 0.005
    ticks_per_rev: int = 4096

    def __post_init__(self) -> None:
        if min(self.wheel_diameter_ratio, self.wheelbase_ratio, self.scale) <= 0:
            raise ValueError("odometry error ratios must be > 0")
        if self.slip_sigma < 0 or self.ticks_per_rev < 0:
            raise ValueError("slip_sigma and ticks_per_rev must be >= 0")

    @classmethod
    def none(cls, ticks_per_rev: int = 4096) -> OdometryErrors:
        """No systematic error and no slip.

        Parameters
        ----------
        ticks_per_rev : int
            Encoder resolution kept.

        Returns
        -------
        OdometryErrors
        """
        return cls(1.0, 1.0, 1.0, 0.0, ticks_per_rev)


class WheelOdometry:
    """Encoder-tick odometry of a differential-drive robot (see module docstring).

    Parameters
    ----------
    errors : OdometryErrors
    params : RobotParams
        Nominal geometry the odometry integrates with.
    rng : numpy.random.Generator
        Source of the slip noise.
    pose : (x, y, theta)
        Initial odometry pose (the odometry frame's origin, by default).
    """

    def __init__(
        self,
        errors: OdometryErrors = OdometryErrors(),
        params: RobotParams = WAFFLE_PI,
        *,
        rng: np.random.Generator,
        pose=(0.0, 0.0, 0.0),
    ):
        self.errors = errors
        self.params = params
        self.rng = rng
        self.pose = tuple(float(v) for v in pose)
        e = errors
        d_a = 2 * params.wheel_radius * e.scale
        # D_R / D_L = E_d with (D_R + D_L) / 2 = D_a
        self.r_left = d_a / (e.wheel_diameter_ratio + 1)
        self.r_right = d_a * e.wheel_diameter_ratio / (e.wheel_diameter_ratio + 1)
        self.b_true = params.wheelbase * e.wheelbase_ratio
        self._phi_l = self._phi_r = 0.0  # accumulated true wheel angles (rad)
        self._ticks_l = self._ticks_r = 0

    def step(self, ds: float, dth: float) -> None:
        """The true robot moved ``ds`` metres while turning ``dth`` rad; update the pose.

        Parameters
        ----------
        ds : float
            Metres.
        dth : float
            Radians.
        """
        e, p = self.errors, self.params
        roll_l = ds - dth * self.b_true / 2
        roll_r = ds + dth * self.b_true / 2
        if e.slip_sigma > 0 and (ds != 0.0 or dth != 0.0):
            n_l, n_r = self.rng.standard_normal(2)
            roll_l += e.slip_sigma * math.sqrt(abs(roll_l)) * float(n_l)
            roll_r += e.slip_sigma * math.sqrt(abs(roll_r)) * float(n_r)
        dphi_l = roll_l / self.r_left
        dphi_r = roll_r / self.r_right
        if e.ticks_per_rev > 0:
            self._phi_l += dphi_l
            self._phi_r += dphi_r
            k = e.ticks_per_rev / (2 * math.pi)
            tl = math.floor(self._phi_l * k)
            tr = math.floor(self._phi_r * k)
            per_tick = 2 * math.pi / e.ticks_per_rev * p.wheel_radius
            d_left = (tl - self._ticks_l) * per_tick
            d_right = (tr - self._ticks_r) * per_tick
            self._ticks_l, self._ticks_r = tl, tr
        else:
            d_left = dphi_l * p.wheel_radius
            d_right = dphi_r * p.wheel_radius
        self.pose = arc_step(self.pose, (d_left + d_right) / 2, (d_right - d_left) / p.wheelbase)
