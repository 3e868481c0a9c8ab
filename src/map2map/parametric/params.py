"""Parameters of the parametric CAD->SLAM model (thesis section 3.2), with documented defaults.

Every number the model uses lives in :class:`ParametricParams`; nothing is hidden in
module constants. A parameter file is YAML: either a flat mapping of field names, or
the ``params.yaml`` that ``map2map deform`` writes beside every map (its ``parameters:``
section is read, its informational ``run:`` and ``drawn:`` sections are ignored), so
that a run can be repeated exactly. Unknown keys, non-numbers and NaN/inf are rejected
with :class:`~map2map.core.errors.InputError`.

Examples
--------
>>> p = ParametricParams()
>>> p.z_weights
(0.4, 0.3, 0.2, 0.1)
>>> zero = p.zero_error()
>>> zero.a0_bound, zero.alpha_eb_std_deg, zero.eta
(0.0, 0.0, 0.0)
"""

from __future__ import annotations

import math
import os
from dataclasses import asdict, dataclass, fields, replace
from typing import Any

import yaml

from ..core._io import atomic_path
from ..core.errors import InputError

__all__ = ["ParametricParams", "load_params", "save_params", "params_to_dict"]


@dataclass(frozen=True)
class ParametricParams:
    """All parameters of the parametric model. Units in brackets.

    Robot and sensor (TurtleBot3 Waffle Pi with LDS-01, thesis chapter 4)
        ``v_max`` 0.26 [m/s], ``omega_max`` 1.82 [rad/s], ``acc_lin`` 2.5 [m/s^2] and
        ``acc_ang`` 3.2 [rad/s^2] (TurtleBot3 DWA limits), ``wheelbase`` 0.287 [m],
        ``wheel_radius`` 0.033 [m], ``robot_radius`` 0.15 [m] (clearance of the roadmap),
        ``dt`` 0.1 [s] trajectory sampling, ``range_min`` 0.12 / ``range_max`` 3.5 [m],
        ``fov_deg`` 360 (or 180 as in the thesis experiments), ``beam_aperture_deg`` 1.0
        (LDS-01 angular resolution; the beta of thesis eq. 3.84).
    Key poses
        The map is built from key poses taken whenever the robot has moved
        ``keyframe_distance`` 1.0 [m] or turned ``keyframe_angle`` 0.5 [rad] (the scan
        update thresholds ``linearUpdate`` / ``angularUpdate`` of gmapping); visibility
        and both conversions run on them. The additive method sums one error per key
        pose that sees a pixel, so its field grows as these shrink.
    LIDAR model, thesis eqs. 3.8-3.30
        ``lidar_geometry`` "random" (thesis: D, alpha random per pixel and median filtered
        over ``median_size`` 5 pixels) or "geometry" (D, alpha from the first key pose that
        saw the pixel). Calibration coefficients of thesis eqs. 3.9-3.10 are drawn per map,
        uniformly in +-bound (ref. [13] order of magnitude): ``a0_bound`` 0.01 [m]
        (zero offset), ``a1_bound`` 0.005 (scale), ``b1_bound`` 0.001 (encoder scale),
        ``b2_bound``/``b3_bound`` 0.002 [rad] (horizontal eccentricity),
        ``b4_bound``/``b5_bound`` 0.001 [rad] (non-orthogonality), ``b6_bound`` 0.002
        [rad m] (collimation). ``lambda_short`` 0.5 [1/m] (thesis eq. 3.13, ref. [56]),
        ``short_scale`` 0.02 (fraction of the short-reading error E_short applied to the
        map, see :func:`map2map.parametric.lidar.short_error`), ``max_err_bound`` and
        ``rand_err_bound`` 0.05 [m] (Max_err, Ran_err drawn uniformly in [0, bound],
        thesis eqs. 3.21, 3.24), ``z_weights`` (0.4, 0.3, 0.2, 0.1) (thesis eqs. 3.27-3.28,
        ref. [56]).
    Odometry model, thesis eqs. 3.31-3.53 (UMBmark, refs. [19, 20])
        Standard deviations of the drawn systematic errors: ``alpha_eb_std_deg`` 0.5 and
        ``alpha_ed_std_deg`` 0.5 [deg] (thesis eq. 3.31), ``beta_std_deg`` 0.5 [deg]
        (thesis eq. 3.33;
        with the trajectory's straight runs of 1-3 m this gives ``E_d - 1`` of about
        0.1 %, a well-built robot before calibration).
    Additive conversion of [58], thesis eqs. 3.81-3.90
        ``lin_gain`` 0.09 (thesis eq. 3.81), ``ang_gain`` 0.095 (thesis eq. 3.82), ``eta`` 0.01
        (thesis eq. 3.83,
        "typically about 1%"), ``eps_lin`` 0 [m] and ``eps_ang`` 0 [rad] (noise of
        thesis eqs. 3.83-3.84; zero in the thesis).
    EKF conversion, thesis eqs. 3.54-3.80
        ``ekf_max_landmarks`` 400 (wall pixels decimated on a regular grid to at most this
        many landmarks), ``ekf_range_var_min`` 1e-4 [m^2] and ``ekf_bearing_var_min``
        3e-4 [rad^2] (floors of R, thesis eq. 3.69, which is singular when a1 or b1 is zero),
        ``ekf_reference`` "plan" (the field is the final landmark estimate minus the
        landmark's plan position: the map error) or "initial" (minus the estimate the
        landmark was added with: only the filter's later corrections).
    Roadmap (thesis Fig. 3.3, ref. [54])
        ``prm_nodes_per_m2`` 2.0, ``prm_k`` 10 nearest neighbours, ``prm_skeleton_step``
        0.4 [m] spacing of the extra nodes on the free-space skeleton.
    """

    # robot and sensor
    v_max: float = 0.26
    omega_max: float = 1.82
    acc_lin: float = 2.5
    acc_ang: float = 3.2
    wheelbase: float = 0.287
    wheel_radius: float = 0.033
    robot_radius: float = 0.15
    dt: float = 0.1
    range_min: float = 0.12
    range_max: float = 3.5
    fov_deg: float = 360.0
    beam_aperture_deg: float = 1.0
    # key poses
    keyframe_distance: float = 1.0
    keyframe_angle: float = 0.5
    # LIDAR model
    lidar_geometry: str = "random"
    median_size: int = 5
    a0_bound: float = 0.01
    a1_bound: float = 0.005
    b1_bound: float = 0.001
    b2_bound: float = 0.002
    b3_bound: float = 0.002
    b4_bound: float = 0.001
    b5_bound: float = 0.001
    b6_bound: float = 0.002
    lambda_short: float = 0.5
    short_scale: float = 0.02
    max_err_bound: float = 0.05
    rand_err_bound: float = 0.05
    z_weights: tuple[float, float, float, float] = (0.4, 0.3, 0.2, 0.1)
    # odometry model
    alpha_eb_std_deg: float = 0.5
    alpha_ed_std_deg: float = 0.5
    beta_std_deg: float = 0.5
    # additive conversion
    lin_gain: float = 0.09
    ang_gain: float = 0.095
    eta: float = 0.01
    eps_lin: float = 0.0
    eps_ang: float = 0.0
    # EKF conversion
    ekf_max_landmarks: int = 400
    ekf_range_var_min: float = 1e-4
    ekf_bearing_var_min: float = 3e-4
    ekf_reference: str = "plan"
    # roadmap
    prm_nodes_per_m2: float = 2.0
    prm_k: int = 10
    prm_skeleton_step: float = 0.4

    def __post_init__(self) -> None:
        problem = _check(self)
        if problem:
            raise ValueError(problem)

    def zero_error(self) -> ParametricParams:
        """The same parameters with every error source switched off (field must be zero).

        Returns
        -------
        ParametricParams
        """
        zero = {
            f.name: 0.0
            for f in fields(self)
            if f.name.endswith("_bound") or f.name.endswith("_std_deg")
        }
        zero.update(short_scale=0.0, eta=0.0, eps_lin=0.0, eps_ang=0.0)
        return replace(self, **zero)


_POSITIVE = {
    "v_max", "omega_max", "acc_lin", "acc_ang", "wheelbase", "wheel_radius", "dt",
    "range_max", "keyframe_distance", "keyframe_angle", "lambda_short",
    "ekf_range_var_min", "ekf_bearing_var_min", "prm_nodes_per_m2", "prm_skeleton_step",
}  # fmt: skip


def _check(p: ParametricParams) -> str | None:
    for f in fields(p):
        v = getattr(p, f.name)
        if f.name == "lidar_geometry":
            if v not in ("random", "geometry"):
                return f"lidar_geometry must be 'random' or 'geometry', got {v!r}"
            continue
        if f.name == "ekf_reference":
            if v not in ("plan", "initial"):
                return f"ekf_reference must be 'plan' or 'initial', got {v!r}"
            continue
        if f.name == "z_weights":
            vals = tuple(v)
            if len(vals) != 4 or not all(_finite(x) for x in vals):
                return f"z_weights must be four finite numbers, got {v!r}"
            continue
        if not _finite(v):
            return f"{f.name} must be a finite number, got {v!r}"
        if f.name in _POSITIVE and v <= 0:
            return f"{f.name} must be > 0, got {v!r}"
        if v < 0 and f.name not in ("z_weights",):
            return f"{f.name} must be >= 0, got {v!r}"
    if p.fov_deg not in (180.0, 360.0):
        return f"fov_deg must be 180 or 360, got {p.fov_deg!r}"
    if p.range_min >= p.range_max:
        return "range_min must be smaller than range_max"
    if int(p.median_size) != p.median_size or p.median_size < 1:
        return "median_size must be a positive integer"
    if int(p.ekf_max_landmarks) != p.ekf_max_landmarks or p.ekf_max_landmarks < 1:
        return "ekf_max_landmarks must be a positive integer"
    if int(p.prm_k) != p.prm_k or p.prm_k < 1:
        return "prm_k must be a positive integer"
    return None


def _finite(v: Any) -> bool:
    return isinstance(v, int | float) and not isinstance(v, bool) and math.isfinite(v)


def params_to_dict(p: ParametricParams) -> dict[str, Any]:
    """Plain-YAML-friendly dict of every parameter.

    Parameters
    ----------
    p : ParametricParams

    Returns
    -------
    dict

    Examples
    --------
    >>> params_to_dict(ParametricParams())["lin_gain"]
    0.09
    """
    d = asdict(p)
    d["z_weights"] = [float(x) for x in p.z_weights]
    return d


def params_from_dict(d: dict[str, Any], source: str = "parameters") -> ParametricParams:
    """Build parameters from a mapping, rejecting unknown keys, NaN and bad values.

    Parameters
    ----------
    d : dict
        Parameter names to values.
    source : str
        Named in errors (a file).

    Returns
    -------
    ParametricParams

    Raises
    ------
    InputError
        Unknown key, wrong type or value out of range.

    Examples
    --------
    >>> params_from_dict({"lin_gain": 0.1}).lin_gain
    0.1
    """
    if not isinstance(d, dict):
        raise InputError(source, "parameter file must hold a mapping of name: value")
    names = {f.name: f for f in fields(ParametricParams)}
    unknown = sorted(set(map(str, d)) - set(names))
    if unknown:
        raise InputError(source, f"unknown parameter(s): {', '.join(unknown)}")
    kwargs: dict[str, Any] = {}
    for key, value in d.items():
        default = getattr(ParametricParams, key)
        if key in ("lidar_geometry", "ekf_reference"):
            kwargs[key] = value
            continue
        if key == "z_weights":
            if not isinstance(value, list | tuple) or len(value) != 4:
                raise InputError(source, "z_weights must be a list of four numbers")
            vals = []
            for x in value:
                if not _finite(x):
                    raise InputError(source, f"z_weights holds a non-finite value {x!r}")
                vals.append(float(x))
            kwargs[key] = tuple(vals)
            continue
        if not _finite(value):
            raise InputError(source, f"{key} must be a finite number, got {value!r}")
        kwargs[key] = int(value) if isinstance(default, int) else float(value)
    try:
        return ParametricParams(**kwargs)
    except ValueError as exc:
        raise InputError(source, str(exc)) from None


def load_params(path: str | os.PathLike) -> ParametricParams:
    """Read a parameter YAML file (flat, or a ``params.yaml`` written by ``map2map deform``).

    Parameters
    ----------
    path : path-like
        The YAML file.

    Returns
    -------
    ParametricParams

    Raises
    ------
    InputError
        Missing file, not YAML, bad keys or values.
    """
    source = os.fspath(path)
    try:
        with open(path, encoding="utf-8") as fh:
            data = yaml.safe_load(fh)
    except OSError as exc:
        raise InputError(source, f"cannot read parameter file ({exc.strerror})") from None
    except yaml.YAMLError as exc:
        raise InputError(source, f"not valid YAML ({str(exc).splitlines()[0]})") from None
    if data is None:
        data = {}
    if isinstance(data, dict) and "parameters" in data:
        extra = sorted(set(data) - {"parameters", "run", "drawn"})
        if extra:
            raise InputError(source, f"unknown section(s): {', '.join(map(str, extra))}")
        data = data["parameters"] or {}
    return params_from_dict(data, source)


def save_params(
    p: ParametricParams,
    path: str | os.PathLike,
    run: dict[str, Any] | None = None,
    drawn: dict[str, Any] | None = None,
) -> None:
    """Write ``parameters`` (and informational ``run`` / ``drawn`` sections) atomically.

    Parameters
    ----------
    p : ParametricParams
        Parameters written under ``parameters``.
    path : path-like
        The YAML file.
    run, drawn : dict, optional
        Informational sections (run settings, drawn coefficients).

    Examples
    --------
    >>> import tempfile, pathlib
    >>> path = pathlib.Path(tempfile.mkdtemp()) / "params.yaml"
    >>> save_params(ParametricParams(eta=0.02), path)
    >>> load_params(path).eta
    0.02
    """
    doc: dict[str, Any] = {}
    if run:
        doc["run"] = run
    doc["parameters"] = params_to_dict(p)
    if drawn:
        doc["drawn"] = drawn
    with atomic_path(path) as tmp:
        tmp.write_text(yaml.safe_dump(doc, sort_keys=False), encoding="utf-8")
