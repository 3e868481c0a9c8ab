"""Parametric drift on synthesized SLAM maps (issue #15: realism of Model_AB's maps).

Model_AB's network draws the plan's walls where the plan has them: straight, in the plan's
frame. A SLAM map of the same plan (simulated or real) carries the run's accumulated pose
error: bent walls, rooms slightly rotated or shifted against each other. The parametric
CAD->SLAM model (thesis 3.2, :mod:`map2map.parametric`) models exactly that error as a
displacement field ``d = d_L + d_O``; this module draws such a field for a plan and warps
a generated map along it, so that the learned model supplies *what* the robot maps
(coverage, wall thickness, clutter) and the parametric model *how far off* it is.

For one plan and one random generator (:func:`drift_field`):

1. a trajectory over the plan's roadmap touring :data:`DEFAULT_TOUR` nodes
   (:func:`map2map.parametric.pipeline.make_trajectory`, thesis 3.2 / Fig. 3.3, the
   tour of ``map2map dataset build``'s parametric pairs);
2. the parametric model along it (:func:`map2map.parametric.pipeline.deform`): LIDAR
   field ``d_L`` (thesis eqs. 3.8-3.30), odometry errors (thesis eqs. 3.31-3.53) turned
   into the odometry field ``d_O`` by the additive method (thesis eqs. 3.81-3.90, the
   default) or EKF-SLAM (thesis eqs. 3.54-3.80), ``d = d_L + d_O`` on the pixels the
   LIDAR saw;
3. the field carried to the pixels the model's LIDAR did not see (the generated map may
   have mapped more, or other, rooms than this trajectory): each takes the displacement
   of its nearest observed pixel, so a room moves as a whole;
4. optionally scaled by ``scale`` (1: the parametric model's own magnitude).

:func:`apply_drift` then moves the generated map's content at ``p`` to ``p + d(p)`` with
:func:`map2map.parametric.field.warp_map` (field inversion, nearest sampling, every wall
pixel splatted so walls stay closed). The generated map keeps its own unknown cells: the
drift moves what the network mapped, it does not decide what was seen.

Seeds: hypothesis ``k`` of seed ``s`` draws everything (route, LIDAR and odometry errors)
from its own generator :func:`drift_rng` ``(s, k)``, so the ``K`` hypotheses of a plan
drift differently and the same seed gives the same bytes.

Examples
--------
>>> from map2map.maps.floorplan import generate_floorplan
>>> plan = generate_floorplan(3, size=(10, 8))
>>> d = drift_field(plan, drift_rng(0, 0))
>>> d.field.shape == plan.shape, bool(d.observed.any())
(True, True)
>>> out = apply_drift(plan.data, d)
>>> out.shape == plan.shape, set(np.unique(out).tolist()) <= {0, 127, 255}
(True, True)
>>> bool(np.array_equal(out, apply_drift(plan.data, drift_field(plan, drift_rng(0, 0)))))
True
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
from scipy import ndimage

from ..core.errors import InputError
from ..core.grid import OccupancyMap
from ..parametric.field import DisplacementField, warp_map
from ..parametric.params import ParametricParams
from ..parametric.pipeline import METHODS, deform, make_trajectory
from ..trajectory.timing import Trajectory

__all__ = ["DRIFTS", "DRIFT_METHODS", "DEFAULT_TOUR", "DEFAULT_FOV_DEG", "DEFAULT_SCALE",
           "DEFAULT_SQUARE_RESOLUTION", "DriftField", "drift_rng", "drift_field",
           "apply_drift", "drift_maps", "check_drift"]

#: ``drift`` choices of :func:`map2map.learn.synthesize.synthesize`.
DRIFTS = ("parametric", "none")
#: The parametric model's odometry-to-map conversions (``drift_method``).
DRIFT_METHODS = METHODS
#: Roadmap nodes the drift trajectory tours (``map2map dataset build``'s ``tour``).
DEFAULT_TOUR = 12
#: LIDAR field of view of the drift model (the dataset build's simulated LIDAR).
DEFAULT_FOV_DEG = 180.0
#: Factor on the parametric field (1: the model's own magnitude).
DEFAULT_SCALE = 1.0
#: Metres per pixel assumed for a dataset square whose resolution is not given: the
#: median of the 256 px squares of ``map2map dataset build --plans generated`` (0.025 to
#: 0.12 m over the first 60 pairs of gen6300).
DEFAULT_SQUARE_RESOLUTION = 0.06
#: Stream of :func:`drift_rng` (keeps the drift draws apart from other uses of a seed).
_STREAM = 0xD21F7


def check_drift(drift: str, method: str) -> None:
    """:class:`InputError` naming ``--drift`` / ``--drift-method`` for an unknown choice.

    Examples
    --------
    >>> check_drift("none", "additive")
    >>> try:
    ...     check_drift("wobble", "additive")
    ... except InputError as exc:
    ...     print(exc)
    --drift: must be one of parametric, none, got 'wobble'
    """
    if drift not in DRIFTS:
        raise InputError("--drift", f"must be one of {', '.join(DRIFTS)}, got {drift!r}")
    if method not in DRIFT_METHODS:
        raise InputError("--drift-method",
                         f"must be one of {', '.join(DRIFT_METHODS)}, got {method!r}")


def drift_rng(seed: int, k: int) -> np.random.Generator:
    """The generator of hypothesis (or plan) ``k`` under ``seed``: its own stream,
    a pure function of both.

    Examples
    --------
    >>> float(drift_rng(0, 1).random()) == float(drift_rng(0, 1).random())
    True
    >>> float(drift_rng(0, 1).random()) == float(drift_rng(0, 2).random())
    False
    """
    return np.random.default_rng(np.random.SeedSequence(int(seed), spawn_key=(_STREAM, int(k))))


@dataclass
class DriftField:
    """A drift field for one plan (module doc).

    Attributes
    ----------
    field : DisplacementField
        Displacement [px] of every pixel, ``scale`` applied, carried to unobserved pixels.
    observed : (H, W) bool
        Pixels the parametric model's LIDAR saw along ``trajectory``.
    trajectory : Trajectory or None
    method : str
    scale : float
    drawn : dict
        The parametric model's drawn coefficients (``DeformResult.drawn``).
    """

    field: DisplacementField
    observed: np.ndarray
    trajectory: Trajectory | None
    method: str
    scale: float
    drawn: dict = field(default_factory=dict)

    def stats(self) -> dict:
        """Mean and maximum ``|d|`` [px] over the observed pixels, and the method."""
        return {**self.field.stats(self.observed), "method": self.method, "scale": self.scale}


def _carry(f: DisplacementField, observed: np.ndarray) -> DisplacementField:
    """Every unobserved pixel takes the displacement of its nearest observed pixel."""
    if observed.all() or not observed.any():
        return f
    idx = ndimage.distance_transform_edt(~observed, return_distances=False,
                                         return_indices=True)
    return DisplacementField(f.dx[idx[0], idx[1]], f.dy[idx[0], idx[1]])


def drift_field(plan: OccupancyMap, rng: np.random.Generator, *, method: str = "additive",
                scale: float = DEFAULT_SCALE, tour: int = DEFAULT_TOUR,
                params: ParametricParams | None = None) -> DriftField:
    """A parametric drift field for ``plan`` (module doc, steps 1-4).

    Parameters
    ----------
    plan : OccupancyMap
        The plan, at its true resolution (the error model is metric).
    rng : numpy.random.Generator
        Every random draw (route, LIDAR and odometry errors); see :func:`drift_rng`.
    method : {"additive", "ekf"}
        The parametric model's odometry-to-map conversion.
    scale : float
        Factor on the field (>= 0).
    tour : int
        Roadmap nodes the route tours.
    params : ParametricParams, optional
        Default: the parametric defaults with a :data:`DEFAULT_FOV_DEG` LIDAR.

    Returns
    -------
    DriftField

    Raises
    ------
    InputError
        Unknown method, negative scale, or a plan the robot cannot drive (no free space
        wider than the robot, nodes not connected).
    """
    if method not in DRIFT_METHODS:
        raise InputError("--drift-method",
                         f"must be one of {', '.join(DRIFT_METHODS)}, got {method!r}")
    if not (np.isfinite(scale) and scale >= 0):
        raise InputError("--drift-scale", f"must be >= 0, got {scale}")
    p = params or ParametricParams(fov_deg=DEFAULT_FOV_DEG)
    traj, _ = make_trajectory(plan, p, rng, tour=tour)
    res = deform(plan, traj, method, p, rng)
    f = _carry(res.field, res.observed)
    if scale != 1.0:
        f = DisplacementField(f.dx * np.float32(scale), f.dy * np.float32(scale))
    return DriftField(f, res.observed, traj, method, float(scale), res.drawn)


def apply_drift(m: np.ndarray, drift: DriftField) -> np.ndarray:
    """Map ``m`` (plan frame, same shape as the drift's plan) warped along the drift:
    content at ``p`` moves to ``p + d(p)``
    (:func:`map2map.parametric.field.warp_map`); ``m``'s own unknown cells stay unknown.

    Parameters
    ----------
    m : (H, W) uint8
        Ternary map (occupied 0, unknown 127, free 255).
    drift : DriftField

    Returns
    -------
    (H, W) uint8
    """
    m = np.asarray(m, np.uint8)
    if m.shape != drift.field.shape:
        raise ValueError(f"map {m.shape} and drift field {drift.field.shape} differ in shape")
    return warp_map(m, drift.field, np.ones(m.shape, bool))


def drift_maps(maps, plans, resolutions, seed: int = 0, *, method: str = "additive",
               scale: float = DEFAULT_SCALE, tour: int = DEFAULT_TOUR,
               params: ParametricParams | None = None) -> tuple[np.ndarray, list[str]]:
    """Map ``i`` of ``maps`` warped along a drift field of plan ``i`` drawn from
    :func:`drift_rng` ``(seed, i)``.

    Parameters
    ----------
    maps, plans : (N, H, W) uint8
        Generated maps and their plans (same pixels).
    resolutions : float or (N,) floats
        Metres per pixel of each plan.
    seed : int
    method, scale, tour, params
        As :func:`drift_field`.

    Returns
    -------
    maps : (N, H, W) uint8
    warnings : list of str
        One per map left without drift (a plan the robot cannot drive), which is returned
        unchanged.
    """
    maps = np.asarray(maps, np.uint8)
    plans = np.asarray(plans, np.uint8)
    res = np.broadcast_to(np.asarray(resolutions, float), (len(maps),))
    out = maps.copy()
    warns = []
    for i in range(len(maps)):
        try:
            d = drift_field(OccupancyMap(plans[i], float(res[i])), drift_rng(seed, i),
                            method=method, scale=scale, tour=tour, params=params)
        except InputError as exc:
            if exc.source in ("--drift-method", "--drift-scale"):
                raise
            warns.append(f"map {i}: no drift ({exc.problem})")
            continue
        out[i] = apply_drift(maps[i], d)
    return out, warns
