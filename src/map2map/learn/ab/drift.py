"""Parametric drift on synthesized SLAM maps (issue #15: realism of Model_AB's maps).

Model_AB's network draws the plan's walls where the plan has them: straight, in the plan's
frame. A SLAM map of the same plan (simulated or real) carries the run's accumulated pose
error: bent walls, rooms slightly rotated or shifted against each other. The parametric
CAD->SLAM model (thesis 3.2, :mod:`map2map.parametric`) models exactly that error as a
displacement field ``d = d_L + d_O``; this module draws such a field for a plan and warps
a generated map along it, so that the learned model supplies *what* the robot maps
(coverage, wall thickness, clutter) and the parametric model *how far off* it is.

For one plan and one random generator (:func:`drift_field`, settings
:class:`DriftParams`; the defaults are this list):

1. a trajectory over the plan's roadmap touring 12 nodes
   (:func:`map2map.parametric.pipeline.make_trajectory`, thesis 3.2 / Fig. 3.3, the
   tour of ``map2map dataset build``'s parametric pairs), optionally cut to its first
   ``duration`` seconds;
2. the parametric model along it (:func:`map2map.parametric.pipeline.deform`): LIDAR
   field ``d_L`` (thesis eqs. 3.8-3.30), odometry errors (thesis eqs. 3.31-3.53) turned
   into the odometry field ``d_O`` by the additive method (thesis eqs. 3.81-3.90, the
   default) or EKF-SLAM (thesis eqs. 3.54-3.80), ``d = d_L + d_O`` on the pixels the
   LIDAR saw;
3. the field carried to the pixels the model's LIDAR did not see (the generated map may
   have mapped more, or other, rooms than this trajectory): each takes the displacement
   of its nearest observed pixel, so a room moves as a whole;
4. optionally smoothed (``smooth_m``), resized (``magnitude_px``, ``resolution_ref``)
   and scaled by ``scale`` (1: the parametric model's own magnitude).

``drift="rooms"`` (:class:`~map2map.learn.ab.room_drift.RoomDriftParams`) draws instead one
rigid transform per room of the plan, chained along a walk through the doors and blended
across the walls (:mod:`map2map.learn.ab.room_drift`), plus by default this module's field
smoothed 0.2 m: the simulated maps' wall error without torn walls (opt-in; docs/synthesize.md,
"Room-wise drift").

:func:`apply_drift` then moves the generated map's content at ``p`` to ``p + d(p)`` with
:func:`map2map.parametric.field.warp_map` (field inversion, nearest sampling, every wall
pixel splatted so walls stay closed). By default (``coverage="map"``) the generated map
keeps its own unknown cells: the drift moves what the network mapped, it does not decide
what was seen; ``coverage="route"`` also hides what the route did not see.

Measured (docs/synthesize.md, "Drift"): on the 61 held-out test plans of gen6300 the
defaults bring the shipped Model_AB's worst realism ratio from 16.6 to 5.4;
:data:`TUNED_ON_VAL` (tuned on the val plans) reaches 6.3 there.

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

import math
from dataclasses import dataclass, field, replace

import numpy as np
from scipy import ndimage

from ...core.errors import InputError
from ...core.grid import OccupancyMap
from ...parametric.field import DisplacementField, warp_map
from ...parametric.params import ParametricParams
from ...parametric.pipeline import METHODS, deform, make_trajectory
from ...trajectory.timing import Trajectory
from .room_drift import (
    RoomDrift,
    RoomDriftParams,
    apply_room_drift,
    room_drift_field,
    solenoidal,
)

__all__ = ["DRIFTS", "DRIFT_METHODS", "COVERAGES", "DEFAULT_FOV_DEG", "TUNED_ON_VAL",
           "DEFAULT_SQUARE_RESOLUTION", "DriftParams", "DriftField", "drift_params",
           "drift_rng", "drift_field", "apply_drift", "drift_maps"]

#: ``drift`` choices of :func:`map2map.learn.ab.synthesize.synthesize` (``"rooms"``: the
#: room-wise rigid drift of :mod:`map2map.learn.ab.room_drift`).
DRIFTS = ("parametric", "rooms", "none")
#: The parametric model's odometry-to-map conversions (``drift_method``).
DRIFT_METHODS = METHODS
#: What a drifted map shows (:func:`apply_drift`).
COVERAGES = ("map", "route")
#: LIDAR field of view of the drift model (the dataset build's simulated LIDAR).
DEFAULT_FOV_DEG = 180.0
#: Metres per pixel assumed for a dataset square whose resolution is not given: the
#: median of the 256 px squares of ``map2map dataset build --plans generated`` (0.025 to
#: 0.12 m over the first 60 pairs of gen6300).
DEFAULT_SQUARE_RESOLUTION = 0.06
#: Stream of :func:`drift_rng` (keeps the drift draws apart from other uses of a seed).
_STREAM = 0xD21F7


@dataclass(frozen=True)
class DriftParams:
    """How a drift field is drawn and applied (module doc).

    Parameters
    ----------
    method : {"additive", "ekf"}
        The parametric model's odometry-to-map conversion (thesis eqs. 3.81-3.90 or
        3.54-3.80).
    scale : float
        Final factor on the field (>= 0; 1: as drawn).
    tour : int
        Roadmap nodes the route tours (``map2map dataset build``'s ``tour``: 12).
    duration : float or None
        Seconds of the route kept (its first ``duration`` s), as a simulated exploration
        runs out of time (the dataset build's 420 s); ``None``: the whole tour.
    smooth_m : float
        Standard deviation [m] of a Gaussian filter on the carried field (0: none): keeps
        the drift (rooms moved, walls bent), drops the pixel-scale part of ``d``, which
        erodes thin features of the generated map under the warp's nearest sampling.
    magnitude_px : float or None
        Rescale the field so that its mean ``|d|`` over the observed pixels is
        ``magnitude_px * exp(spread * z)`` map pixels (``z`` a standard normal draw):
        keeps the model's spatial structure, sets its size in pixels of the map; ``None``:
        the model's metric magnitude at the plan's resolution.
    spread : float
        Log-normal spread of that magnitude across draws.
    resolution_ref : float or None
        Multiply the field by ``resolution / resolution_ref``: its size in map pixels as if
        the plan had ``resolution_ref`` metres per pixel (a simulated SLAM map's error in
        pixels of the 256 px square hardly depends on the plan's size; the metric model's
        does, through the resolution); ``None``: no such factor.
    coverage : {"map", "route"}
        ``"map"``: the generated map's own mapped area is kept; ``"route"``: also unknown
        where the drift's route did not see (the parametric model's partial mapping,
        thesis Fig. 5.13), grown by ``margin_px``.
    margin_px : int
        Pixels by which ``coverage="route"`` grows what the route saw (the route sees a
        wall's first pixel; the generated map draws it thicker).
    """

    method: str = "additive"
    scale: float = 1.0
    tour: int = 12
    duration: float | None = None
    smooth_m: float = 0.0
    magnitude_px: float | None = None
    spread: float = 0.0
    resolution_ref: float | None = None
    coverage: str = "map"
    margin_px: int = 2

    def __post_init__(self):
        if self.method not in DRIFT_METHODS:
            raise InputError("drift_method",
                             f"must be one of {', '.join(DRIFT_METHODS)}, got {self.method!r}")
        if not (math.isfinite(self.scale) and self.scale >= 0):
            raise InputError("drift_scale", f"must be >= 0, got {self.scale}")
        if self.coverage not in COVERAGES:
            raise InputError("coverage", f"must be one of {', '.join(COVERAGES)}, "
                                         f"got {self.coverage!r}")
        bad = [n for n in ("smooth_m", "spread", "margin_px") if not getattr(self, n) >= 0]
        bad += [n for n in ("duration", "magnitude_px", "resolution_ref")
                if getattr(self, n) is not None and not getattr(self, n) > 0]
        if self.tour < 2:
            bad.append("tour")
        if bad:
            raise InputError(bad[0], f"out of range: {getattr(self, bad[0])!r}")

    def describe(self) -> str:
        """One line naming every setting.

        Examples
        --------
        >>> DriftParams(scale=2.0, duration=420.0).describe()[:30]
        'additive x2, tour 12 for 420 s'
        """
        out = f"{self.method} x{self.scale:g}, tour {self.tour}"
        out += f" for {self.duration:g} s" if self.duration else ""
        if self.magnitude_px is not None:
            out += f", mean {self.magnitude_px:g} px (spread {self.spread:g})"
        if self.resolution_ref is not None:
            out += f", sized as at {self.resolution_ref:g} m/px"
        out += f", smoothed {self.smooth_m:g} m, coverage {self.coverage}"
        return out + (f" +{self.margin_px} px" if self.coverage == "route" else "")


#: The variant tuned on the validation plans of gen6300 (lowest worst realism ratio of the
#: 19 variants tried on its 66 val plans: 3.62 against 6.74 for the defaults); on the 61 test plans
#: its worst ratio is 6.27 against the defaults' 5.43, so it is not the default
#: (docs/synthesize.md, "Drift").
TUNED_ON_VAL = DriftParams(scale=1.75, duration=420.0, smooth_m=0.2, coverage="route",
                           margin_px=2)


def drift_params(drift: str | DriftParams | RoomDriftParams, method: str | None = None,
                 scale: float | None = None) -> DriftParams | RoomDriftParams | None:
    """``drift`` (``"parametric"``: the default :class:`DriftParams`, ``"rooms"``: the
    default :class:`~map2map.learn.ab.room_drift.RoomDriftParams`, ``"none"``: None, or
    either dataclass) with ``method`` and ``scale`` replaced where given (the room-wise
    drift has no odometry conversion: ``method`` is checked and otherwise ignored there;
    with ``RoomDriftParams(parametric=True)`` it goes to the added parametric field).

    Examples
    --------
    >>> drift_params("parametric", "ekf").method
    'ekf'
    >>> drift_params("none") is None
    True
    >>> drift_params("rooms", "additive", 2.0).scale
    2.0
    >>> try:
    ...     drift_params("wobble")
    ... except InputError as exc:
    ...     print(exc)
    drift: must be one of parametric, rooms, none, got 'wobble'
    """
    if isinstance(drift, RoomDriftParams) or drift == "rooms":
        if method is not None and method not in DRIFT_METHODS:
            DriftParams(method=method)                   # the error names the choice
        p = drift if isinstance(drift, RoomDriftParams) else RoomDriftParams()
        if method is not None and p.parametric:
            p = replace(p, method=method)
        return p if scale is None else replace(p, scale=float(scale))
    if isinstance(drift, DriftParams):
        p = drift
    elif drift == "parametric":
        p = DriftParams()
    elif drift == "none":
        if method is not None and method not in DRIFT_METHODS:
            DriftParams(method=method)                   # the error names the choice
        return None
    else:
        raise InputError("drift", f"must be one of {', '.join(DRIFTS)}, got {drift!r}")
    if method is not None:
        p = replace(p, method=method)
    if scale is not None:
        p = replace(p, scale=float(scale))
    return p


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
        Displacement [px] of every pixel, carried to the unobserved ones, smoothed and
        scaled as ``params`` say.
    observed : (H, W) bool
        Pixels the parametric model's LIDAR saw along ``trajectory``.
    trajectory : Trajectory
    params : DriftParams
    drawn : dict
        The parametric model's drawn coefficients (``DeformResult.drawn``).
    """

    field: DisplacementField
    observed: np.ndarray
    trajectory: Trajectory
    params: DriftParams
    drawn: dict = field(default_factory=dict)

    def stats(self) -> dict:
        """Mean and maximum ``|d|`` [px] over the observed pixels."""
        return self.field.stats(self.observed)


def _carry(f: DisplacementField, observed: np.ndarray) -> DisplacementField:
    """Every unobserved pixel takes the displacement of its nearest observed pixel."""
    if observed.all() or not observed.any():
        return f
    idx = ndimage.distance_transform_edt(~observed, return_distances=False,
                                         return_indices=True)
    return DisplacementField(f.dx[idx[0], idx[1]], f.dy[idx[0], idx[1]])


def drift_field(plan: OccupancyMap, rng: np.random.Generator,
                params: DriftParams | None = None,
                model: ParametricParams | None = None, *,
                trajectory: Trajectory | None = None) -> DriftField:
    """A parametric drift field for ``plan`` (module doc, steps 1-4).

    Parameters
    ----------
    plan : OccupancyMap
        The plan, at its true resolution (the error model is metric).
    rng : numpy.random.Generator
        Every random draw (route, LIDAR and odometry errors, magnitude); see
        :func:`drift_rng`.
    params : DriftParams, optional
        Default :class:`DriftParams`.
    model : ParametricParams, optional
        The parametric model's parameters; default its defaults with a
        :data:`DEFAULT_FOV_DEG` LIDAR.
    trajectory : Trajectory, optional
        Drive the model along this path (plan frame; e.g. an exploration's true poses,
        :func:`map2map.learn.ab.coverage.explore_plan`) instead of step 1's roadmap tour;
        ``params.duration`` still cuts it, and ``rng`` then draws no route.

    Returns
    -------
    DriftField, or RoomDrift for a :class:`~map2map.learn.ab.room_drift.RoomDriftParams`
    (:func:`~map2map.learn.ab.room_drift.room_drift_field` of the plan's pixels; with
    ``parametric=True`` the default parametric field, smoothed ``smooth_m`` and scaled
    ``scale``, is drawn first from the same ``rng`` and added; with ``conserve=True``
    only its divergence-free part, :func:`~map2map.learn.ab.room_drift.solenoidal`)

    Raises
    ------
    InputError
        A plan the robot cannot drive (no free space wider than the robot, nodes not
        connected).
    """
    if isinstance(params, RoomDriftParams):
        extra = None
        if params.parametric:
            extra = drift_field(plan, rng, DriftParams(method=params.method,
                                                       smooth_m=params.smooth_m,
                                                       scale=params.scale), model,
                                trajectory=trajectory).field
            if params.conserve:
                extra = solenoidal(extra)
        rd = room_drift_field(plan.data, rng, params)
        rd.extra = extra
        return rd
    dp = params or DriftParams()
    p = model or ParametricParams(fov_deg=DEFAULT_FOV_DEG)
    if trajectory is None:
        traj, _ = make_trajectory(plan, p, rng, tour=dp.tour)
    else:
        traj = trajectory
    if dp.duration is not None and traj.t[-1] > dp.duration:
        n = max(2, int(np.searchsorted(traj.t, dp.duration, side="right")))
        traj = Trajectory(traj.t[:n], traj.x[:n], traj.y[:n], traj.theta[:n], traj.v[:n],
                          traj.omega[:n], dict(traj.meta))
    res = deform(plan, traj, dp.method, p, rng)
    f = _carry(res.field, res.observed)
    if dp.smooth_m > 0:
        sig = dp.smooth_m / plan.resolution
        f = DisplacementField(ndimage.gaussian_filter(f.dx, sig, mode="nearest"),
                              ndimage.gaussian_filter(f.dy, sig, mode="nearest"))
    k = dp.scale
    if dp.resolution_ref is not None:
        k *= plan.resolution / dp.resolution_ref
    if dp.magnitude_px is not None:
        target = dp.magnitude_px * math.exp(dp.spread * float(rng.standard_normal()))
        now = f.stats(res.observed)["mean"]
        k *= target / now if now > 1e-9 else 0.0
    if k != 1.0:
        f = DisplacementField(f.dx * np.float32(k), f.dy * np.float32(k))
    return DriftField(f, res.observed, traj, dp, res.drawn)


def apply_drift(m: np.ndarray, drift: DriftField | RoomDrift) -> np.ndarray:
    """Map ``m`` (plan frame, same shape as the drift's plan) warped along the drift:
    content at ``p`` moves to ``p + d(p)`` (:func:`map2map.parametric.field.warp_map`);
    ``m``'s own unknown cells stay unknown, and with ``coverage="route"`` so do the cells
    the route did not see.

    Parameters
    ----------
    m : (H, W) uint8
        Ternary map (occupied 0, unknown 127, free 255).
    drift : DriftField or RoomDrift
        (a RoomDrift: :func:`~map2map.learn.ab.room_drift.apply_room_drift`, plus its
        ``extra`` parametric field)

    Returns
    -------
    (H, W) uint8
    """
    if isinstance(drift, RoomDrift):
        return apply_room_drift(m, drift, drift.extra)
    m = np.asarray(m, np.uint8)
    if m.shape != drift.field.shape:
        raise ValueError(f"map {m.shape} and drift field {drift.field.shape} differ in shape")
    dp = drift.params
    if dp.coverage == "map":
        seen = np.ones(m.shape, bool)
    elif dp.margin_px > 0:
        seen = ndimage.binary_dilation(drift.observed, iterations=int(dp.margin_px))
    else:
        seen = drift.observed
    return warp_map(m, drift.field, seen)


def drift_maps(maps, plans, resolutions, seed: int = 0, params: DriftParams | None = None,
               model: ParametricParams | None = None, trajectories=None
               ) -> tuple[np.ndarray, list[str]]:
    """Map ``i`` of ``maps`` warped along a drift field of plan ``i`` drawn from
    :func:`drift_rng` ``(seed, i)``.

    Parameters
    ----------
    maps, plans : (N, H, W) uint8
        Generated maps and their plans (same pixels).
    resolutions : float or (N,) floats
        Metres per pixel of each plan.
    seed : int
    params, model
        As :func:`drift_field`.
    trajectories : sequence of Trajectory or None, optional
        Per map, the path of its drift (:func:`drift_field` ``trajectory``; ``None``:
        the roadmap tour).

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
            d = drift_field(OccupancyMap(plans[i], float(res[i])), drift_rng(seed, i), params,
                            model, trajectory=None if trajectories is None else trajectories[i])
        except InputError as exc:
            warns.append(f"map {i}: no drift ({exc.problem})")
            continue
        out[i] = apply_drift(maps[i], d)
    return out, warns
