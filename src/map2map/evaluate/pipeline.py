"""The whole assessment of Fig. 1 of the appendix paper: align, optimise, measure.

:func:`register` aligns a source (SLAM) map to a target (plan) and runs the
nonrigid optimisation of the affinely aligned edge points (the transforms of
``map2map align``); :func:`evaluate_maps` adds the rigid chain, the error metric
of Algorithm 1 for both chains with the paper's choice between them, the IoU of
the aligned maps and the vanilla ICP baseline (``map2map evaluate``).

Examples
--------
>>> from map2map.core.grid import OccupancyMap
>>> from map2map.maps.synthetic import draw_walls, office_walls
>>> plan = draw_walls((240, 300), office_walls(300, 240))
>>> built = draw_walls((240, 300), office_walls(300, 240, partition_shift=(6.0, 0.0)))
>>> ev = evaluate_maps(OccupancyMap(built, 0.05), OccupancyMap(plan, 0.05), resolution=0.05)
>>> ev.report["chosen_chain"]
'rigid'
>>> round(ev.report["errors"]["rigid"]["max_m"], 1)      # a partition built 30 cm off
0.3
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass, field
from typing import Any

import numpy as np
from scipy.spatial import cKDTree

from ..core.geometry import apply, decompose_similarity, transform_normals
from ..core.grid import FREE, OCCUPIED, UNKNOWN, OccupancyMap
from ..maps.solids import hollow_solids
from .align import Alignment, AlignParams, align_maps, check_map
from .anchors import Anchors
from .confidence import evaluation_notes, evaluation_warnings
from .features import edge_points, subsample
from .icp import icp
from .metric import ChainErrors, choose_chain, iou, local_errors
from .nonrigid import PiecewiseAffine, SideFields, control_points, optimise, warp_image
from .orientation import dominant_orientation, wall_families

__all__ = ["EvaluateParams", "Registration", "Evaluation", "register", "evaluate_maps"]


@dataclass
class EvaluateParams:
    """Parameters of the optimisation and the metric (lengths in metres of the target).

    ``sigma_f`` and ``sigma_n`` are the annealing schedules of eq. 7 (the paper
    uses sigma_f = 1 +- 0.4 m and sigma_n = 8 +- 4 m; the schedule ends finer so
    that the points settle on the walls).
    """

    align: AlignParams = field(default_factory=AlignParams)
    sigma_f: tuple[float, ...] = (1.0, 0.5, 0.25, 0.1)
    sigma_n: tuple[float, ...] = (8.0, 4.0, 2.0, 1.0)
    iterations: int = 5
    control_spacing: float = 0.5
    chain_tolerance: float = 0.02
    max_edge_points: int = 40000
    icp_points: int = 3000
    seed: int = 0


@dataclass
class Registration:
    """Alignment plus the optimised edge points and warp of the nonrigid chain."""

    alignment: Alignment
    fields: SideFields
    X: np.ndarray
    normals: np.ndarray
    X_affine: np.ndarray
    X_optimised: np.ndarray
    warp: PiecewiseAffine | None
    timings: dict[str, float]
    source_warp: PiecewiseAffine | None = None

    def map_points(self, pts: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Source pixels -> target pixels by the similarity, and by the nonrigid chain.

        When the target is the partial map (the alignment ran target onto source),
        the nonrigid correction comes from the target's walls optimised onto the
        source (``source_warp``, in source pixels): only walls both maps saw move.
        """
        pts = np.asarray(pts, float).reshape(-1, 2)
        sim = apply(self.alignment.similarity, pts)
        if self.source_warp is not None:
            return sim, apply(self.alignment.affine, self.source_warp.forward(pts))
        nonrigid = apply(self.alignment.affine, pts)
        if self.warp is not None:
            nonrigid = self.warp.forward(nonrigid)
        return sim, nonrigid

    __call__ = map_points


def _schedule(metres: tuple[float, ...], resolution: float) -> tuple[float, ...]:
    return tuple(max(1.0, m / resolution) for m in metres)


def _optimise_chain(X, normals, T, fields, p: EvaluateParams, res: float):
    Xa = apply(T, X)
    na = transform_normals(T, normals)
    Xo = optimise(
        Xa,
        na,
        fields,
        sigma_f=_schedule(p.sigma_f, res),
        sigma_n=_schedule(p.sigma_n, res),
        iterations=p.iterations,
    )
    return Xa, na, Xo


def register(
    source: OccupancyMap,
    target: OccupancyMap,
    *,
    anchors: Anchors | None = None,
    params: EvaluateParams | None = None,
    names: tuple[str | None, str | None] = ("source", "target"),
) -> Registration:
    """Align ``source`` to ``target`` and optimise the nonrigid chain (Fig. 1, c-d-f).

    Both maps' solid regions count by their faces: their inside is unknown
    (:func:`~map2map.maps.solids.hollow_solids`; a map never sees inside a wall). Only
    the target hollowed, a plan aligned to another drawing of itself (two versions of
    a plan, the alignment sweep's copies) lost its rotation: a solid block against its
    own faces (``align_sweep``: 6 of 12 cases of one irregular plan flagged, 9 % off in
    scale)."""
    return _register(hollow_solids(source), hollow_solids(target), anchors, params, names)


def _register(source: OccupancyMap, target: OccupancyMap, anchors: Anchors | None,
              params: EvaluateParams | None, names: tuple[str | None, str | None]
              ) -> Registration:
    """:func:`register` on a target already hollowed."""
    p = params or EvaluateParams()
    timings: dict[str, float] = {}
    t0 = time.perf_counter()
    al = align_maps(source.data, target.data, anchors=anchors, params=p.align, names=names)
    timings["alignment"] = time.perf_counter() - t0
    t0 = time.perf_counter()
    fields = al.fields  # the plan's side-aware distance fields, computed by the alignment
    if fields is None:
        theta = dominant_orientation(target.data)[0]
        fields = SideFields.from_map(
            target.data, theta, families=wall_families(target.data, theta, target.resolution)
        )
    X, normals = edge_points(source.data)
    if len(X) > p.max_edge_points:
        keep = subsample(np.arange(len(X))[:, None], p.max_edge_points, p.seed)[:, 0]
        X, normals = X[keep], normals[keep]
    timings["fields"] = time.perf_counter() - t0
    t0 = time.perf_counter()
    res = target.resolution
    Xa, na, Xo = _optimise_chain(X, normals, al.affine, fields, p, res)
    warp = _warp(Xa, na, Xo, fields, p, res)
    source_warp = None
    if al.hypotheses.get("direction") == "target->source":
        # the target is the partial map: its walls, optimised onto the source, say
        # where the source must bend (in source pixels)
        box = check_map(source.data, names[0])
        fields_s = SideFields.from_map(source.data, al.orientation["source"], window=box,
                                       families=al.families.get("source", ()))
        Y, ny = edge_points(target.data)
        keep = subsample(np.arange(len(Y))[:, None], p.max_edge_points, p.seed)[:, 0]
        Ai = np.linalg.inv(al.affine)
        Ys, nys, Yo = _optimise_chain(Y[keep], ny[keep], Ai, fields_s, p, source.resolution)
        inverse = _warp(Ys, nys, Yo, fields_s, p, source.resolution)
        if inverse is not None:  # optimised -> as aligned: source pixels to corrected ones
            source_warp = PiecewiseAffine(inverse.dst, inverse.src)
    timings["nonrigid"] = time.perf_counter() - t0
    return Registration(al, fields, X, normals, Xa, Xo, warp, timings, source_warp)


def _warp(Xa, na, Xo, fields, p: EvaluateParams, res: float) -> PiecewiseAffine | None:
    """Piecewise-affine warp from the aligned to the optimised positions of supported points.

    The warp is defined by the points that found their wall on the plan (within 3
    sigma_f of the finest stage, over its known space); the others only followed.
    """
    _, d, inside = fields.nearest(Xo, na)
    supported = inside & fields.is_known(Xo) & (d <= 3.0 * max(1.0, p.sigma_f[-1] / res))
    if supported.sum() < 3:
        supported[:] = True
    idx = np.flatnonzero(supported)
    ctrl = idx[control_points(Xa[idx], max(2.0, p.control_spacing / res))]
    if len(ctrl) < 3:
        return None
    try:
        return PiecewiseAffine(Xa[ctrl], Xo[ctrl])
    except Exception:  # noqa: BLE001 - collinear control points: no warp
        return None


def _iou_known(warped: np.ndarray, plan: np.ndarray) -> float:
    """IoU of the free space of two aligned maps over the cells both know."""
    both = (warped != UNKNOWN) & (plan != UNKNOWN)
    return iou((warped == FREE) & both, (plan == FREE) & both)


@dataclass
class Evaluation:
    """Everything ``map2map evaluate`` writes: the report and the arrays behind the figures."""

    registration: Registration
    errors: dict[str, ChainErrors]
    chosen: str
    report: dict[str, Any]
    warped: dict[str, np.ndarray]


def evaluate_maps(
    source: OccupancyMap,
    target: OccupancyMap,
    *,
    anchors: Anchors | None = None,
    params: EvaluateParams | None = None,
    resolution: float | None = None,
    rigid_scale: float | None = None,
    names: tuple[str | None, str | None] = ("source", "target"),
) -> Evaluation:
    """Align, optimise both chains, measure (Algorithm 1), IoU and ICP; see module docstring.

    ``resolution`` (metres per target pixel) turns pixel errors into metres; without
    it only pixel figures are reported. ``rigid_scale`` is the metric scale ratio
    ``res_source / res_target`` (1 when both maps share a resolution).
    """
    p = params or EvaluateParams()
    # as register() sees them (the alignment, IoU, fields, metric)
    source, target = hollow_solids(source), hollow_solids(target)
    if rigid_scale is not None:
        p = EvaluateParams(**{**p.__dict__})
        p.align = AlignParams(
            **{
                **p.align.__dict__,
                "rigid_scale": float(rigid_scale),
                "metric_scale": float(rigid_scale),
            }
        )
    t_all = time.perf_counter()
    reg = _register(source, target, anchors, p, names)
    al = reg.alignment
    timings = dict(reg.timings)
    t0 = time.perf_counter()
    Xr, nr, Xor = _optimise_chain(reg.X, reg.normals, al.rigid, reg.fields, p, target.resolution)
    timings["rigid_chain"] = time.perf_counter() - t0
    t0 = time.perf_counter()
    n_aff = transform_normals(al.affine, reg.normals)
    # a point matches a plan wall when the optimisation brought it within 3 sigma_f of
    # the last stage of a plan surface facing its way (the support of eq. 7's fitness)
    match_px = 3.0 * _schedule(p.sigma_f, target.resolution)[-1]
    errors = {
        "nonrigid": local_errors(Xr, reg.X_optimised, reg.fields, n_aff, match_px=match_px),
        "rigid": local_errors(Xr, Xor, reg.fields, nr, match_px=match_px),
    }
    chosen, reason = choose_chain(
        al.similarity, al.affine, p.align.rigid_scale, tolerance=p.chain_tolerance
    )
    timings["metric"] = time.perf_counter() - t0

    # IoU of the aligned maps (rigid chain, and the nonrigid warp)
    t0 = time.perf_counter()
    shape = target.shape
    warped = {
        "rigid": warp_image(source.data, al.rigid, shape),
        "nonrigid": warp_image(source.data, al.affine, shape, reg.warp),
    }
    ious = {}
    for k, w in warped.items():
        ious[k] = {
            "free": iou(w == FREE, target.data == FREE),
            "occupied": iou(w == OCCUPIED, target.data == OCCUPIED),
        }
    timings["iou"] = time.perf_counter() - t0

    # vanilla ICP baseline: from the identity, and from the rigid alignment
    t0 = time.perf_counter()
    tgt_pts, _ = edge_points(target.data)
    tree = cKDTree(tgt_pts)
    src_pts = subsample(reg.X, p.icp_points, p.seed)
    icp_out = {}
    for name, T0 in (("from_identity", np.eye(3)), ("from_alignment", al.rigid)):
        r = icp(src_pts, tgt_pts, T0, scale=p.align.rigid_scale, tree=tree, iterations=40)
        s, a, tx, ty = decompose_similarity(r.T)
        icp_out[name] = {
            "mean_px": r.mean_distance,
            "max_px": r.max_distance,
            "mean_m": None if resolution is None else r.mean_distance * resolution,
            "max_m": None if resolution is None else r.max_distance * resolution,
            "iterations": r.iterations,
            "rotation_deg": math.degrees(a),
            "translation": [tx, ty],
            "matrix": r.T.tolist(),
        }
    timings["icp"] = time.perf_counter() - t0
    timings["total"] = time.perf_counter() - t_all

    report = {
        "source": names[0],
        "target": names[1],
        "resolution_m_per_px": resolution,
        "p_correct": al.p_correct,
        "alignment": al.to_dict(),
        "errors": {k: e.summary(resolution) for k, e in errors.items()},
        "chosen_chain": chosen,
        "chosen_reason": reason,
        "chosen_errors": errors[chosen].summary(resolution),
        "iou": ious,
        "icp": icp_out,
        "edge_points": int(len(reg.X)),
        "warnings": list(al.warnings)
        + evaluation_warnings(
            _iou_known(warped[chosen], target.data),
            errors[chosen].summary(None)["unmatched_share"],
            p.align.confidence,
        ),
        "notes": list(al.notes)
        + evaluation_notes(errors[chosen].summary(None)["unmatched_share"], p.align.confidence),
        "timings_s": {k: round(v, 4) for k, v in timings.items()},
    }
    report["iou"][chosen]["free_known"] = _iou_known(warped[chosen], target.data)
    return Evaluation(reg, errors, chosen, report, warped)
