"""``map2map synthesize``: SLAM-map hypotheses for a CAD plan with Model_AB (thesis 3.1,
5.1, Fig. 5.3), in the plan's frame and resolution.

The default model is ``"scans"`` (:data:`SCANS`, :mod:`map2map.learn.ab.scans`): no
network, each hypothesis the simulated robot's own exploration mapped at its particle
filter's poses (a simulated ``rbpf`` run's map; ``ScanMapParams(pose_error="drawn")``
draws the pose error instead). On the frozen tests of docs/synthesize.md its maps are
told from simulated ones far less often than the network's; ``model="pretrained"`` (or a
run) is Model_AB, below.

The thesis's Model_AB gives one SLAM map per plan and calls that a weakness against the
parametric model (sec. 5.2). Here one plan gives ``K`` hypotheses: the generator's
decoder dropout (:class:`~map2map.learn.nets.progressive.StochasticUNet`, trained with it on)
stays on at test time, and the ``K`` copies of the plan run as one batch, each with its
own dropout masks, all drawn from ``seed`` (same seed, same maps, bit for bit on CPU).
Their **diversity** is measured, not assumed: the mean over pairs of hypotheses of the
share of the plan's content pixels whose class (occupied / free / unknown) differs
(:func:`pairwise_disagreement`). A diversity near zero means the dropout noise has
collapsed (pix2pix's known limitation); it is reported with a warning.

Frame: the plan's known part is cut into a square (as the datasets are,
:func:`map2map.learn.ba.autocorrect` does the same), resized to the model's data size and
its walls thickened as in the training pairs, reduced to the resolution the model was
trained up to, run, raised to the square's size with SLAM-like walls
(:func:`map2map.learn.ab.render.render_slam`: bilinear class memberships, walls kept as
the band of the training targets' wall thickness along the faces that border free space,
wall interiors unknown; ``render="plain"``: the previous output, snapped and upsampled by
nearest neighbour) and pasted into a map of the plan's shape, resolution and origin,
unknown outside.

**Defaults** (session 11, issue #15's realism rule on the gen900 validation plans:
docs/synthesize.md, "Rendering what a LIDAR leaves"): :func:`synthesize` draws the
room-wise drift (``drift="rooms"``), hides what each hypothesis's own exploration did not
see (``coverage="explore"``; ``coverage="rays"`` takes the free space from what that
exploration's rays crossed, issue #33, measured and not made the default) and draws the
LIDAR traces (``traces="lidar"`` with
``render="slam"``). The previous defaults are ``drift="parametric", coverage="none",
traces="none"`` (bit for bit). :func:`synthesize_squares`, the evaluation helper, keeps
those previous defaults: its callers (the benchmarks) name what they measure.

Drift (``drift="parametric"``; :mod:`map2map.learn.ab.drift`): the network
draws straight walls in the plan's frame, a SLAM map carries the run's accumulated pose
error. Each hypothesis ``k`` is warped along a displacement field the parametric
CAD->SLAM model (thesis 3.2) draws for the plan from its own generator
(:func:`~map2map.learn.ab.drift.drift_rng` ``(seed, k)``): a route touring the plan, the
LIDAR and odometry error fields ``d_L + d_O`` (additive method by default,
``drift_method``), as :class:`~map2map.learn.ab.drift.DriftParams` says (``drift_scale``
replaces its final factor). ``drift="rooms"`` (or a
:class:`~map2map.learn.ab.room_drift.RoomDriftParams`): one rigid transform per room of the
plan, chained along a walk through its doors and blended across walls, plus the
parametric field smoothed (:mod:`map2map.learn.ab.room_drift`; the default of
:func:`synthesize`). ``drift="none"``: the
network's map as rendered (the output before drift existed, bit for bit).

Coverage (:mod:`map2map.learn.ab.coverage`, beyond the thesis): the network maps every room;
a 7-minute exploration does not. ``coverage="explore"`` lets the simulator's robot explore
the plan (``oracle`` mapper, seeded per hypothesis by
:func:`~map2map.learn.ab.coverage.explore_rng` ``(seed, k)``) and turns unknown every pixel
of hypothesis ``k`` the exploration did not see (beyond a band of the rendered wall
thickness); ``drift_route="explore"`` drives the drift along that exploration's true
path instead of the roadmap tour. One exploration serves both; ``coverage="none"`` with
``drift_route="tour"`` is the output without them, bit for bit.

LIDAR traces (:class:`~map2map.learn.ab.render.TraceParams`, ``traces="lidar"``): the
walls drawn as a band of metric width with a ragged back edge, their faces moved one
pixel into the network's wall cells, and stray hits off the walls (module doc of
:mod:`map2map.learn.ab.render`); ``traces="none"``: the band of the training targets'
thickness, as before.

Examples
--------
An untrained generator (``"pretrained"`` or a run folder in practice):

>>> import torch
>>> from map2map.learn.nets.progressive import StochasticUNet
>>> from map2map.maps.floorplan import generate_floorplan
>>> _ = torch.manual_seed(0)
>>> net = ABModel(StochasticUNet(size=32, channels=8, min_size=16), resolution=32, alpha=1.0,
...               data_size=64, header={}, source="untrained")
>>> plan = generate_floorplan(3, size=(10, 8))
>>> res = synthesize(plan, net, samples=3, seed=0)
>>> len(res.maps), res.maps[0].shape == plan.shape, res.maps[0].resolution == plan.resolution
(3, True, True)
>>> 0.0 < res.diversity < 1.0
True
"""

from __future__ import annotations

import os
import warnings
from dataclasses import asdict, dataclass
from pathlib import Path

import numpy as np

from ...core.errors import InputError
from ...core.grid import FREE, OCCUPIED, UNKNOWN, OccupancyMap
from ...maps.preprocess import content_square, square_resize, thicken
from . import render as slam_render
from .coverage import (
    ExploreParams,
    coverage_options,
    explore_plan,
    explore_rng,
    free_from_rays,
    hide_unseen,
)
from .drift import (
    DEFAULT_SQUARE_RESOLUTION,
    DriftParams,
    apply_drift,
    drift_field,
    drift_maps,
    drift_params,
    drift_rng,
)
from .model import ABModel, load_ab_model
from .render import (
    RENDERS,
    TraceParams,
    band_px,
    snap,
    stray_hits,
    trace_params,
    trace_rng,
)
from .room_drift import RoomDriftParams
from .scans import ScanMapParams, scan_map

#: ``model`` name of the generator without a network (:mod:`map2map.learn.ab.scans`).
SCANS = "scans"

__all__ = ["SCANS", "SynthesisResult", "synthesize", "synthesize_squares", "snap",
           "pairwise_disagreement", "save_synthesis_figure", "dataset_thicken"]



def pairwise_disagreement(maps: np.ndarray, mask: np.ndarray | None = None) -> np.ndarray:
    """(K, H, W) ternary maps -> (K, K) share of the ``mask`` pixels whose class differs.

    Examples
    --------
    >>> m = np.array([[[0, 255]], [[0, 0]], [[0, 255]]], np.uint8)
    >>> pairwise_disagreement(m).tolist()
    [[0.0, 0.5, 0.0], [0.5, 0.0, 0.5], [0.0, 0.5, 0.0]]
    """
    maps = np.asarray(maps)
    flat = maps.reshape(len(maps), -1)
    if mask is not None:
        flat = flat[:, np.asarray(mask, bool).ravel()]
    n = max(1, flat.shape[1])
    return np.array([[np.count_nonzero(a != b) / n for b in flat] for a in flat])


@dataclass
class SynthesisResult:
    """K hypotheses of one plan and how far apart they are."""

    maps: list[OccupancyMap]
    diversity: float
    pairwise: np.ndarray
    warnings: list[str]
    model: str

    def summary(self) -> dict:
        k = len(self.maps)
        off = self.pairwise[~np.eye(k, dtype=bool)] if k > 1 else np.zeros(0)
        return {"samples": k, "model": self.model,
                "diversity_mean_pairwise_disagreement": self.diversity,
                "pairwise_min": float(off.min()) if off.size else 0.0,
                "pairwise_max": float(off.max()) if off.size else 0.0,
                "occupied_share": [float(np.mean(m.data == OCCUPIED)) for m in self.maps],
                "unknown_share": [float(np.mean(m.data == UNKNOWN)) for m in self.maps],
                "warnings": self.warnings}


def dataset_thicken(header: dict) -> int:
    """Pixels the training plans' walls were thickened by (:func:`~map2map.maps.preprocess.
    thicken`), from a model header: ``dataset.thicken`` (synthetic pairs) or the dataset
    build's ``dataset.identity.params.thicken``; 0 when neither is there.

    Examples
    --------
    >>> dataset_thicken({"dataset": {"identity": {"params": {"thicken": 1}}}})
    1
    >>> dataset_thicken({"dataset": {"thicken": 2}}), dataset_thicken({})
    (2, 0)
    """
    ds = header.get("dataset") or {}
    k = ds.get("thicken")
    if k is None:
        k = ((ds.get("identity") or {}).get("params") or {}).get("thicken")
    return int(k or 0)


def synthesize(plan: OccupancyMap, model: str | os.PathLike | ABModel | None = SCANS,
               *, samples: int = 4, seed: int = 0, device: str = "cpu",
               render: str = "slam", drift: str | DriftParams = "rooms",
               drift_method: str | None = None, drift_scale: float | None = None,
               coverage: str = "explore", drift_route: str = "tour",
               explore: ExploreParams | None = None,
               traces: str | TraceParams | None = None,
               scans: ScanMapParams | None = None, start=None) -> SynthesisResult:
    """``samples`` SLAM-map hypotheses of ``plan`` (module doc), in its frame.

    Parameters
    ----------
    plan : OccupancyMap
        The CAD plan (internal convention; any size and resolution).
    model : "scans", "pretrained", run folder, weights file or ABModel
        ``"scans"`` (:data:`SCANS`, the default): no network; each hypothesis is the robot's own
        exploration mapped at its particle filter's poses (:mod:`map2map.learn.ab.scans`,
        settings
        ``scans``); ``render``, ``drift``, ``coverage``, ``traces`` and their options do
        not apply and are refused when changed.
    samples : int
        Number of hypotheses ``K`` (1: dropout off, the thesis's single output).
    seed : int
        Seeds the dropout masks.
    device : str
    render : {"slam", "plain"}
        ``"slam"``: walls as a SLAM map draws them, the faces bordering free space with
        the training targets' thickness (:func:`~map2map.learn.ab.render.render_slam`);
        ``"plain"``: the previous output (snap, nearest-neighbour upsampling).
    drift : {"rooms", "parametric", "none"}, DriftParams or RoomDriftParams
        Warp each hypothesis along its own room-wise drift (``"rooms"``, the default,
        :mod:`map2map.learn.ab.room_drift`), along its own parametric drift field (module
        doc; :class:`~map2map.learn.ab.drift.DriftParams`, or the given ones), or not.
    drift_method : {"additive", "ekf"}, optional
        Replaces the drift's odometry-to-map conversion (thesis eqs. 3.81-3.90 or
        3.54-3.80).
    drift_scale : float, optional
        Replaces the drift's final factor on its field.
    coverage : {"rays", "explore", "none"}
        ``"explore"`` (default): unknown wherever hypothesis ``k``'s own exploration of
        the plan did not see (module doc, :func:`~map2map.learn.ab.coverage.hide_unseen`;
        about 0.5 s a hypothesis on gen900's plans); ``"rays"``: the same exploration,
        and free space where its rays crossed
        (:func:`~map2map.learn.ab.coverage.free_from_rays`; docs/synthesize.md: its
        frozen test, not the default); ``"none"``: every room drawn.
    drift_route : {"tour", "explore"}
        The drift's path: the roadmap tour, or hypothesis ``k``'s exploration (no effect
        with ``drift="none"``).
    explore : ExploreParams, optional
        The exploration's settings (default :class:`~map2map.learn.ab.coverage.ExploreParams`:
        275 s, 180 degree LIDAR, ``oracle``, band = rendered wall thickness).
    scans : ScanMapParams, optional
        With ``model="scans"``: the exploration, pose error and mapping settings.
    start : (x, y, yaw), optional
        With ``model="scans"``: where the robot starts every hypothesis (metres and
        radians in the plan's frame); by default each hypothesis draws its own.
    traces : {"lidar", "none"}, TraceParams or None
        ``"lidar"`` (the default, ``None``, with ``render="slam"``; ``None`` with
        ``render="plain"`` is ``"none"``): what a LIDAR + SLAM leaves beyond the faces
        (:class:`~map2map.learn.ab.render.TraceParams`: a metric wall band with a ragged
        back edge, stray hits; ``render="slam"`` only), seeded per hypothesis by
        :func:`~map2map.learn.ab.render.trace_rng` ``(seed, k)``, drawn before the
        coverage (band) and after it (stray hits), before the drift.

    Returns
    -------
    SynthesisResult
    """
    if samples < 1:
        raise InputError("samples", f"must be >= 1, got {samples}")
    if isinstance(model, str) and model == SCANS:
        changed = [n for n, v, d in (("render", render, "slam"), ("drift", drift, "rooms"),
                                     ("drift_method", drift_method, (None, "additive")),
                                     ("drift_scale", drift_scale, None),
                                     ("coverage", coverage, "explore"),
                                     ("drift_route", drift_route, "tour"),
                                     ("explore", explore, None), ("traces", traces, None))
                   if not (v in d if isinstance(d, tuple) else v == d)]
        if changed:
            raise InputError(changed[0], "does not apply to model 'scans' (the robot's own "
                             "scans mapped at its particle filter's poses, no network)")
        return _synthesize_scans(plan, samples, seed, scans or ScanMapParams(), start)
    for name, v in (("scans", scans), ("start", start)):
        if v is not None:
            raise InputError(name, "applies to model 'scans' only")
    if render not in RENDERS:
        raise InputError("render", f"must be one of {', '.join(RENDERS)}, got {render!r}")
    dp, tp, hide, along, ep = _options(drift, drift_method, drift_scale, traces, render,
                                       coverage, drift_route, explore)
    net = load_ab_model(model, device)
    sq = content_square(plan, net.data_size)
    if sq is None:
        raise InputError(None, "the plan holds no known cells; nothing to synthesize")
    square, row0, col0, side = sq.data, sq.row0, sq.col0, sq.side
    k_thick = dataset_thicken(net.header)
    inp = thicken(square_resize(square, net.data_size), k_thick)
    grey = net.sample(inp, samples, seed)
    wall_px = net.wall_px * side / net.data_size
    H, W = plan.shape
    rs, re = max(0, row0), min(H, row0 + side)
    cs, ce = max(0, col0), min(W, col0 + side)
    maps, drifted, explored = [], {}, {}
    warns = []
    if tp is not None:
        wall_px = band_px(plan.resolution, tp)
    for k in range(samples):
        trng = trace_rng(seed, k) if tp is not None else None
        s = slam_render.render(grey[k], side, render, wall_px, tp, trng)
        data = np.full((H, W), UNKNOWN, np.uint8)
        data[rs:re, cs:ce] = s[rs - row0:re - row0, cs - col0:ce - col0]
        ex = None
        if hide or along:
            try:
                ex = explore_plan(plan, explore_rng(seed, k), ep)
            except InputError as exc:
                warns.append(f"hypothesis {k + 1}: no exploration ({exc.problem})")
            else:
                explored[k] = ex.stats()
                margin = ep.margin(wall_px + (tp.inset_px if tp is not None else 0.0))
                if coverage == "rays":
                    data = free_from_rays(data, ex.seen, ex.free, margin, ep.reach_px,
                                          ep.hits_px)
                elif hide:
                    data = hide_unseen(data, ex.seen, margin)
        if tp is not None:
            data = stray_hits(data, trng, plan.resolution, tp)
        if dp is not None:
            try:
                d = drift_field(plan, drift_rng(seed, k), dp,
                                trajectory=ex.trajectory if along and ex is not None else None)
            except InputError as exc:
                warns.append(f"hypothesis {k + 1}: no drift ({exc.problem})")
            else:
                data = apply_drift(data, d)
                drifted[k] = {k2: round(float(v), 3) for k2, v in d.stats().items()}
        maps.append(plan.copy(data=data))
    # the square's known pixels are the plan's known pixels (the square holds them all)
    pw = pairwise_disagreement(np.stack([m.data for m in maps]), plan.data != UNKNOWN)
    div = float(pw[~np.eye(samples, dtype=bool)].mean()) if samples > 1 else 0.0
    if net.alpha < 1.0:
        warns.append(f"the model stopped during the fade-in of its {net.resolution} px stage "
                     f"(alpha {net.alpha:.2f}); it is run with that blend")
    cell = side / net.resolution
    if cell > 2:
        drawn = (f"walls drawn {wall_px:.1f} px thick along their free faces, but placed"
                 if render == "slam" else "walls drawn and placed")
        warns.append(f"the model was trained up to {net.resolution} px: one output cell is "
                     f"{cell:.1f} plan pixels ({cell * plan.resolution:.2f} m); {drawn} "
                     "to a cell; finer SLAM detail is not modelled")
    if samples > 1 and div < 0.005:
        warns.append(f"the {samples} hypotheses differ in only {div:.2%} of the plan's pixels: "
                     "the dropout noise barely changes this model's output")
    if "PROVISIONAL" in str(net.header.get("note", "")):
        warns.append("provisional weights (reduced CPU training, see their note): the "
                     "hypotheses show the method; they do not meet the realism target "
                     "against simulated SLAM maps (docs/synthesize.md)")
    for w in warns:
        warnings.warn(w, stacklevel=2)
    for m in maps:
        m.meta["synthesize"] = {"model": net.source, "seed": seed, "samples": samples,
                                "render": render, "wall_px": round(wall_px, 3),
                                "drift": _drift_name(dp)}
        if dp is not None:
            m.meta["synthesize"]["drift_params"] = asdict(dp)
    for k, st in drifted.items():
        maps[k].meta["synthesize"]["drift_px"] = st
    if tp is not None:                  # the default's meta stays as it was, key for key
        for m in maps:
            m.meta["synthesize"]["traces"] = asdict(tp)
    if hide or along:                   # the default's meta stays as it was, key for key
        for k, m in enumerate(maps):
            m.meta["synthesize"].update(coverage=coverage, drift_route=drift_route,
                                        explore=asdict(ep))
            if k in explored:
                m.meta["synthesize"]["exploration"] = explored[k]
    return SynthesisResult(maps, div, pw, warns, net.source)


def _synthesize_scans(plan: OccupancyMap, samples: int, seed: int,
                      params: ScanMapParams, start=None) -> SynthesisResult:
    """:func:`synthesize` with ``model="scans"``: hypothesis ``k`` is
    :func:`~map2map.learn.ab.scans.scan_map` ``(plan, seed, k, params, start)``."""
    if not (plan.data == FREE).any():
        raise InputError(None, "the plan has no free space; nothing to explore")
    maps, warns = [], []
    for k in range(samples):
        h = scan_map(plan, seed, k, params, start)
        m = h.map
        m.meta["synthesize"] = {"model": SCANS, "seed": seed, "samples": samples,
                                "scans": params.to_dict(), "hypothesis": h.info}
        maps.append(m)
    pw = pairwise_disagreement(np.stack([m.data for m in maps]), plan.data != UNKNOWN)
    div = float(pw[~np.eye(samples, dtype=bool)].mean()) if samples > 1 else 0.0
    if samples > 1 and div < 0.005:
        warns.append(f"the {samples} hypotheses differ in only {div:.2%} of the plan's pixels")
    if params.pose_error == "learned":
        warns.append("the learned pose error does not yet pass for a simulated run: a "
                     "classifier tells its maps apart with AUC 0.666 (two simulated runs "
                     "0.489), their walls bend and are saved twice more often "
                     "(docs/synthesize.md)")
    for w in warns:
        warnings.warn(w, stacklevel=3)
    return SynthesisResult(maps, div, pw, warns, SCANS)


def _options(drift, drift_method, drift_scale, traces, render, coverage, drift_route,
             explore):
    """The drift, LIDAR traces, hiding, drift route and exploration settings of
    :func:`synthesize` and :func:`synthesize_squares`, checked."""
    dp = drift_params(drift, drift_method, drift_scale)
    tp = _traces(traces, render)
    hide, along = coverage_options(coverage, drift_route)
    return dp, tp, hide, along and dp is not None, explore or ExploreParams()


def _traces(traces, render: str) -> TraceParams | None:
    """:func:`~map2map.learn.ab.render.trace_params`, refused with ``render="plain"``
    (``None``: ``"lidar"`` with ``render="slam"``, ``"none"`` with ``"plain"``)."""
    if traces is None:
        traces = "lidar" if render == "slam" else "none"
    try:
        tp = trace_params(traces)
    except ValueError as exc:
        raise InputError("traces", str(exc)) from None
    if tp is not None and render != "slam":
        raise InputError("traces", "LIDAR traces need render='slam'")
    return tp


def _drift_name(dp) -> str:
    """``meta["synthesize"]["drift"]`` of drift settings ``dp``."""
    return "none" if dp is None else "rooms" if isinstance(dp, RoomDriftParams) else \
        "parametric"


def synthesize_squares(model: str | os.PathLike | ABModel | None, plans: np.ndarray, *,
                       seed: int = 0, device: str = "cpu", batch: int = 16,
                       render: str = "slam", drift: str | DriftParams = "parametric",
                       drift_method: str | None = None, drift_scale: float | None = None,
                       resolution=None, coverage: str = "none", drift_route: str = "tour",
                       explore: ExploreParams | None = None,
                       traces: str | TraceParams | None = "none",
                       seen: np.ndarray | None = None) -> np.ndarray:
    """Model_AB's SLAM map of each preprocessed dataset plan (``A.png``: already square,
    resized and thickened as the training inputs were), raised to the plans' size as
    ``render`` says (:func:`synthesize`): (N, S, S) uint8, the thesis's single output
    (dropout off), warped along a parametric drift field of its plan as ``drift`` says
    (:func:`synthesize`; plan ``i`` of the call draws from
    :func:`~map2map.learn.ab.drift.drift_rng` ``(seed, i)``). For evaluations on a dataset's
    own pixels (:mod:`map2map.experiments.realism.measure`,
    :mod:`map2map.experiments.fig514.measure`).

    ``resolution`` (metres per pixel of the squares: one float or one per plan) scales the
    metric drift model; the dataset's squares differ (``map2map.datasets.pair.
    window_resolution``); default
    :data:`~map2map.learn.ab.drift.DEFAULT_SQUARE_RESOLUTION`. A plan the drift model's
    robot cannot drive keeps its undrifted map, with a warning.

    ``coverage``, ``drift_route`` and ``explore`` as :func:`synthesize`: plan ``i``'s
    square is explored at its metric resolution, seeded by
    :func:`~map2map.learn.ab.coverage.explore_rng` ``(seed, i)``. ``traces`` as
    :func:`synthesize` (plan ``i`` draws from :func:`~map2map.learn.ab.render.trace_rng`
    ``(seed, i)``, its band from its own ``resolution``).

    ``seen`` ((N, S, S) bool, optional; ``coverage="explore"`` with ``drift_route="tour"``
    only) replaces the exploration of each square by cells seen elsewhere, e.g. by an
    exploration of the plan at its own resolution mapped onto the square
    (:func:`map2map.experiments.realism.measure.native_seen`, what :func:`synthesize` does for a
    plan).
    A 256 px square of a dataset pair is 0.04-0.12 m a pixel with walls thickened for the
    network, so the robot exploring it may not fit through doors it passes at 0.05 m.

    Examples
    --------
    >>> from map2map.learn.nets.progressive import StochasticUNet
    >>> net = ABModel(StochasticUNet(size=16, channels=8), resolution=16, alpha=1.0,
    ...               data_size=32, header={}, source="untrained")
    >>> synthesize_squares(net, np.full((3, 32, 32), 255, np.uint8)).shape
    (3, 32, 32)
    """
    if render not in RENDERS:
        raise ValueError(f"render must be one of {RENDERS}, got {render!r}")
    dp, tp, hide, along, ep = _options(drift, drift_method, drift_scale, traces, render,
                                       coverage, drift_route, explore)
    net = load_ab_model(model, device)
    plans = np.asarray(plans, np.uint8)
    S = plans.shape[-1]
    wall_px = net.wall_px * S / net.data_size
    res = DEFAULT_SQUARE_RESOLUTION if resolution is None else resolution
    rs = np.broadcast_to(np.asarray(res, float), (len(plans),))
    walls = np.full(len(plans), wall_px) if tp is None else \
        np.array([band_px(r, tp) for r in rs])
    trngs = [trace_rng(seed, i) if tp is not None else None for i in range(len(plans))]
    inset = tp.inset_px if tp is not None else 0.0    # the faces lie this much deeper
    out = np.empty(plans.shape, np.uint8)
    for i in range(0, len(plans), batch):
        grey = net.sample_many(plans[i:i + batch], 1, seed)[:, 0]
        for j, gmap in enumerate(grey):
            out[i + j] = slam_render.render(gmap, S, render, walls[i + j], tp, trngs[i + j])
    trajs = None
    if seen is not None:
        seen = np.asarray(seen, bool)
        if seen.shape != plans.shape:
            raise ValueError(f"seen {seen.shape} and plans {plans.shape} differ in shape")
        if not hide or along:
            raise ValueError("seen= needs coverage='explore' and a drift route other than "
                             "'explore' (no trajectory comes with it)")
        if coverage == "rays":
            raise ValueError("seen= cannot serve coverage='rays' (it needs the rays' free "
                             "cells): let the squares be explored")
        for i in range(len(plans)):
            out[i] = hide_unseen(out[i], seen[i], ep.margin(walls[i] + inset))
    elif hide or along:
        trajs = [None] * len(plans)
        for i in range(len(plans)):
            try:
                ex = explore_plan(OccupancyMap(plans[i], float(rs[i])), explore_rng(seed, i), ep)
            except InputError as exc:
                warnings.warn(f"map {i}: no exploration ({exc.problem})", stacklevel=2)
                continue
            if coverage == "rays":
                out[i] = free_from_rays(out[i], ex.seen, ex.free,
                                        ep.margin(walls[i] + inset), ep.reach_px, ep.hits_px)
            elif hide:
                out[i] = hide_unseen(out[i], ex.seen, ep.margin(walls[i] + inset))
            if along:
                trajs[i] = ex.trajectory
    if tp is not None:
        for i in range(len(plans)):
            out[i] = stray_hits(out[i], trngs[i], float(rs[i]), tp)
    if dp is not None:
        out, warns = drift_maps(out, plans, res, seed, dp, trajectories=trajs)
        for w in warns:
            warnings.warn(w, stacklevel=2)
    return out


def save_synthesis_figure(plan: OccupancyMap, result: SynthesisResult,
                          path: str | os.PathLike, title: str = "", show: int = 5) -> None:
    """Plan | up to ``show`` hypotheses | per-pixel disagreement (share of hypotheses not
    agreeing with the majority class), zoomed on the plan's known part.

    Examples
    --------
    >>> import tempfile, pathlib
    >>> from map2map.learn.nets.progressive import StochasticUNet
    >>> from map2map.maps.floorplan import generate_floorplan
    >>> plan = generate_floorplan(3, size=(10, 8))
    >>> net = ABModel(StochasticUNet(size=16, channels=8), resolution=16, alpha=1.0,
    ...               data_size=32, header={}, source="untrained")
    >>> res = synthesize(plan, net, samples=2)
    >>> p = pathlib.Path(tempfile.mkdtemp()) / "f.png"; save_synthesis_figure(plan, res, p)
    >>> p.stat().st_size > 1000
    True
    """
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from ...core._io import atomic_path

    hyps = result.maps[:show]
    stack = np.stack([m.data for m in result.maps])
    counts = np.stack([(stack == v).sum(0) for v in (OCCUPIED, UNKNOWN, FREE)])
    disagree = 1.0 - counts.max(0) / len(stack)
    panels = [(plan.data, "plan (input)", "gray")] + \
        [(m.data, f"hypothesis {i + 1}", "gray") for i, m in enumerate(hyps)] + \
        [(disagree, f"disagreement (mean pairwise {result.diversity:.1%})", "magma")]
    h, w = plan.shape
    r = plan.resolution
    ext = (0, w * r, 0, h * r)
    fig, axes = plt.subplots(1, len(panels), figsize=(3.2 * len(panels), 3.6 * h / max(w, 1)
                                                      + 0.9), squeeze=False)
    box = plan.content_bbox()
    for ax, (img, name, cmap) in zip(axes[0], panels, strict=True):
        vmax = 255 if cmap == "gray" else 1
        ax.imshow(img, cmap=cmap, vmin=0, vmax=vmax, extent=ext, interpolation="nearest")
        ax.set_title(name, fontsize=8)
        ax.set_xlabel("m", fontsize=7)
        ax.tick_params(labelsize=6)
        if box is not None:
            r0, r1, c0, c1 = box
            pad = 0.05 * max(r1 - r0, c1 - c0)
            ax.set_xlim(max(0, c0 - pad) * r, min(w, c1 + pad) * r)
            ax.set_ylim((h - min(h, r1 + pad)) * r, (h - max(0, r0 - pad)) * r)
    fig.suptitle(title or f"Model_AB: {len(result.maps)} SLAM-map hypotheses "
                 f"({Path(result.model).name})", fontsize=9)
    fig.tight_layout()
    with atomic_path(path) as tmp:
        fig.savefig(tmp, dpi=100, format="png")
    plt.close(fig)


