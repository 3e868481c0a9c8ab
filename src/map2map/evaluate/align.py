"""Global alignment of a source (SLAM) map to a target (plan): similarity, affine, rigid.

Section 3.2.1 (preliminary alignment) and 3.2.2 (anchoring) of the appendix paper,
on a three-level pyramid so that a 1585 x 1585 pair aligns in about a second:

1. *search level* (about 160 px): dominant orientations and direction families (a
   wing at 45 degrees; :mod:`.orientation`; the dense hypotheses try the rotations that
   lay each family of one map onto each of the other's), wall lines by radiography
   (:mod:`.radiography`), faces and their OMBBs (:mod:`.decomposition`), hypotheses
   from face pairs with non-similarities rejected, plus dense FFT hypotheses
   (:mod:`.hypotheses`), all scored by the fitness of eq. 8 (:mod:`.fitness`) times
   the share of the source's free space that lands inside the plan;
2. *refine level* (about 400 px): the best hypotheses are refined by robust
   Gaussian-weighted least squares on distance-transform correspondences
   (an annealed maximisation of eq. 8) and the best of both directions is kept,
   the placement that fits both ways deciding between near ties (:func:`_two_way`);
3. *full resolution*: the winner is refined again, then an affine refinement and
   the rigid variant (scale held at ``rigid_scale``, 1 when both maps share a
   resolution) are fitted the same way; last, against a line-drawn plan, the
   similarity is polished by maximising eq. 8 itself (:func:`maximise_fitness`; when
   no hypothesis passed, the rigid fallback's similarity, with its scale held).

Anchors (eqs. 1-6), given or found automatically (:mod:`.anchors`), are applied
last. When no hypothesis reaches ``min_score`` (eq. 8 at the refine level times the
free-space share; real pairs score 0.3-1, unrelated maps about 0.15) or
``min_fitness`` at full resolution, a warning says so and the best
rigid (or anchored) result is returned instead -- unless the best hypothesis, below
``min_score``, still fits ``weak_margin`` times better than that rigid fallback at full
resolution: then it is kept with a low-confidence note.

Examples
--------
>>> import numpy as np, cv2
>>> from map2map.core.geometry import similarity_matrix, decompose_similarity
>>> plan = np.full((300, 300), 127, np.uint8)
>>> _ = cv2.rectangle(plan, (40, 40), (250, 200), 255, -1)
>>> _ = cv2.rectangle(plan, (40, 40), (250, 200), 0, 3)
>>> _ = cv2.line(plan, (120, 40), (120, 150), 0, 3)
>>> _ = cv2.line(plan, (120, 150), (250, 150), 0, 3)
>>> T = similarity_matrix(0.8, 0.5, 60.0, -20.0)
>>> src = cv2.warpAffine(plan, T[:2], (300, 300), flags=cv2.INTER_NEAREST, borderValue=127)
>>> res = align_maps(src, plan)
>>> s, a, tx, ty = decompose_similarity(res.similarity)
>>> round(s, 2), round(a, 2)                      # the inverse: scale 1/0.8, angle -0.5
(1.25, -0.5)
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass, field, replace
from typing import Any

import cv2
import numpy as np
from scipy import ndimage, optimize

from ..core.errors import InputError
from ..core.geometry import (
    apply,
    decompose_similarity,
    fit_affine,
    fit_similarity,
    similarity_matrix,
    transform_normals,
)
from ..core.grid import FREE, OCCUPIED, UNKNOWN
from .anchors import Anchors, anchor, auto_anchors
from .confidence import ConfidenceParams, alignment_notes, alignment_warnings, p_correct
from .decomposition import Face, decompose
from .features import (
    downsample,
    edge_points,
    occupied_points,
    subsample,
    surface_mask,
    surface_points,
)
from .fitness import distance_map, fitness, lookup
from .hypotheses import Hypothesis, dense_hypotheses, face_hypotheses, suppress_duplicates
from .nonrigid import SideFields, to_plane
from .orientation import dominant_orientation, wall_families

__all__ = [
    "AlignParams",
    "Alignment",
    "align_maps",
    "check_map",
    "maximise_fitness",
    "refine",
    "thin_walls",
    "MIN_MAP_SIZE",
]

#: smallest map side (pixels of known content) that can be decomposed
MIN_MAP_SIZE = 16


@dataclass
class AlignParams:
    """Knobs of :func:`align_maps` (defaults suit 0.02-0.1 m/px building maps).

    ``rigid_scale`` is the scale of the rigid variant: target pixels per source
    pixel for the same metric length (``res_source / res_target``); 1 when both
    maps share a resolution, which the paper assumes. ``min_score`` and
    ``min_fitness`` decide whether any hypothesis passed; a hypothesis scoring below
    ``min_score`` is still kept (with a low-confidence note) when at full resolution
    it fits ``weak_margin`` times better than the rigid fallback. ``full_sigmas`` are the
    final Gaussian widths (px) of the full-resolution fit, ``line_sigmas`` replace
    them when one map draws its walls as lines (a plan) and ``affine_line`` applies
    them to the affine refinement too; ``surface_sigmas`` are those of the final
    face-to-face refinement; ``direct_sigma`` (px, None to skip) is the width of
    the fitness map on which the final similarity is polished by maximising eq. 8
    directly (:func:`maximise_fitness`) when one map is line-drawn.

    ``metric_scale`` (``res_source / res_target``, None when a resolution is unknown)
    bounds the similarity's scale to within ``prior_tolerance`` (10 %) of it; when the
    fit there scores under ``prior_recheck`` the scale is also searched blind, and a
    far better fit elsewhere is reported as a warning, never taken.
    """

    scale_range: tuple[float, float] = (0.5, 2.0)
    max_anisotropy: float = 0.25
    search_size: int = 128
    refine_size: int = 400
    top_k: int = 10
    rigid_scale: float = 1.0
    fitness_sigma: float = 2.0
    min_fitness: float = 0.1
    min_score: float = 0.2
    weak_margin: float = 1.5
    surface_sigmas: tuple[float, ...] = (2.0, 1.0)
    full_sigmas: tuple[float, ...] = (1.5, 1.0)
    line_sigmas: tuple[float, ...] = (8.0, 6.0)
    affine_line: bool = True
    direct_sigma: float | None = 4.0
    auto_anchor: bool = True
    metric_scale: float | None = None
    prior_tolerance: float = 0.1
    prior_recheck: float = 0.35
    distinct: int = 4
    confidence: ConfidenceParams = field(default_factory=ConfidenceParams)
    max_points: int = 20000
    seed: int = 0


@dataclass
class Alignment:
    """Result of :func:`align_maps`; all matrices map source to target pixels (x, y)."""

    similarity: np.ndarray
    affine: np.ndarray
    rigid: np.ndarray
    fitness: float
    fitness_affine: float
    fitness_rigid: float
    anchored: str = "none"
    anchors: Anchors | None = None
    warnings: list[str] = field(default_factory=list)
    hypotheses: dict[str, Any] = field(default_factory=dict)
    orientation: dict[str, float] = field(default_factory=dict)
    families: dict[str, list[float]] = field(default_factory=dict)
    faces: dict[str, Any] = field(default_factory=dict)
    fields: SideFields | None = None
    timings: dict[str, float] = field(default_factory=dict)
    notes: list[str] = field(default_factory=list)
    p_correct: float | None = None

    def to_dict(self) -> dict[str, Any]:
        s, a, tx, ty = decompose_similarity(self.similarity)
        return {
            "similarity": self.similarity.tolist(),
            "affine": self.affine.tolist(),
            "rigid": self.rigid.tolist(),
            "fitness": self.fitness,
            "fitness_affine": self.fitness_affine,
            "fitness_rigid": self.fitness_rigid,
            "p_correct": self.p_correct,
            "scale": s,
            "rotation_deg": math.degrees(a),
            "translation": [tx, ty],
            "anchored": self.anchored,
            "anchors": None
            if self.anchors is None
            else {"source": self.anchors.source.tolist(), "target": self.anchors.target.tolist()},
            "hypotheses": self.hypotheses,
            "orientation_deg": {k: math.degrees(v) for k, v in self.orientation.items()},
            "families_deg": {k: [math.degrees(a) for a in v] for k, v in self.families.items()},
            "warnings": list(self.warnings),
            "notes": list(self.notes),
            "timings_s": self.timings,
        }


def check_map(data: np.ndarray, name: str | None) -> tuple[int, int, int, int]:
    """Validate a map for alignment; returns its content box (row0, row1, col0, col1).

    Raises :class:`InputError` for a map with no occupied cells or one whose known
    content is smaller than :data:`MIN_MAP_SIZE` pixels on a side.
    """
    if not (data == OCCUPIED).any():
        raise InputError(
            name,
            "map has no occupied pixels (no walls to align; if its walls are grey, "
            "read them with `occupied_thresh` or `negate`)",
        )
    known = data != UNKNOWN
    rows = np.flatnonzero(known.any(axis=1))
    cols = np.flatnonzero(known.any(axis=0))
    box = (int(rows[0]), int(rows[-1]) + 1, int(cols[0]), int(cols[-1]) + 1)
    if min(box[1] - box[0], box[3] - box[2]) < MIN_MAP_SIZE:
        raise InputError(
            name,
            f"map content is {box[3] - box[2]} x {box[1] - box[0]} px, too small to decompose "
            f"(at least {MIN_MAP_SIZE} x {MIN_MAP_SIZE} px needed)",
        )
    if not (data == FREE).any():
        raise InputError(name, "map has no free pixels (all walls or unknown): nothing to align")
    return box


def thin_walls(data: np.ndarray, max_thickness: float = 3.0) -> bool:
    """Whether a map's walls are drawn as lines (mean thickness <= ``max_thickness`` px).

    For a wall ``t`` cells thick the mean distance of its cells to the nearest
    non-wall cell is ``(t / 2 + 1) / 2``.
    """
    occ = (data == OCCUPIED).astype(np.uint8)
    if not occ.any():
        return True
    d = cv2.distanceTransform(occ, cv2.DIST_L2, cv2.DIST_MASK_PRECISE)
    mean = float(d[occ > 0].mean())
    return mean <= (max_thickness / 2 + 1) / 2 + 1e-6


def _scale(a: float) -> np.ndarray:
    return np.diag([a, a, 1.0])


def _shift(dx: float, dy: float) -> np.ndarray:
    T = np.eye(3)
    T[:2, 2] = (dx, dy)
    return T


class _Level:
    """One pyramid level of a (cropped) map: cells, occupied points, distance fields."""

    def __init__(self, data: np.ndarray, factor: int, *, max_points: int, seed: int):
        self.factor = factor
        self.data = downsample(data, factor)
        self.surface = surface_mask(self.data)
        self.pts = subsample(surface_points(self.data), max_points, seed)
        fr, fc = np.nonzero(self.data == FREE)
        self.free_pts = subsample(np.column_stack([fc + 0.5, fr + 0.5]), max_points, seed)
        # free cells grown by one cell: free space of the other map may cross a thin wall
        self.free_ok = (
            cv2.dilate((self.data == FREE).astype(np.uint8), np.ones((3, 3), np.uint8)) > 0
        )
        self._edt: tuple[np.ndarray, np.ndarray] | None = None

    @property
    def edt(self) -> tuple[np.ndarray, np.ndarray]:
        """Distance transform (and nearest-cell indices) of the wall surfaces."""
        if self._edt is None:
            self._edt = distance_map(self.surface, return_indices=True)
        return self._edt

    @property
    def known(self) -> np.ndarray:
        """Known cells grown by one cell (walls at the edge of the explored area)."""
        import cv2

        return cv2.dilate((self.data != UNKNOWN).astype(np.uint8), np.ones((3, 3), np.uint8)) > 0

    def fitness_map(self, sigma: float) -> np.ndarray:
        d = self.edt[0].astype(np.float64)
        return np.exp(-(d**2) / (2 * sigma**2)).astype(np.float32)


def refine(
    pts: np.ndarray,
    edt: tuple[np.ndarray, np.ndarray],
    T: np.ndarray,
    *,
    model: str = "similarity",
    sigmas: tuple[float, ...] = (8.0, 4.0, 2.0, 1.0),
    iterations: int = 8,
    scale: float | None = None,
    known: np.ndarray | None = None,
) -> np.ndarray:
    """Maximise eq. 8 from ``T`` by Gaussian-weighted least squares on EDT correspondences.

    Each iteration pairs every source point (mapped by ``T``) with its nearest
    target wall cell (the distance transform's indices) and refits ``model``
    (``"similarity"``, ``"affine"`` or ``"rigid"`` with the fixed ``scale``)
    with weights ``M_f = exp(-d^2 / 2 sigma^2)``: the fixed point is a stationary
    point of the fitness of eq. 8. ``sigma`` is annealed through ``sigmas``. With
    ``known`` (the target's known cells), points over its unknown space are ignored:
    either map may be the partial one.
    """
    _, idx = edt
    h, w = idx.shape[1:]
    T = T.copy()
    for sigma in sigmas:
        for _ in range(iterations):
            q = apply(T, pts)
            c = np.floor(q[:, 0]).astype(np.int64)
            r = np.floor(q[:, 1]).astype(np.int64)
            ok = (r >= 0) & (r < h) & (c >= 0) & (c < w)
            if ok.sum() < 3:
                return T
            rr, cc = r[ok], c[ok]
            near = np.column_stack([idx[1, rr, cc] + 0.5, idx[0, rr, cc] + 0.5])
            d2 = ((near - q[ok]) ** 2).sum(1)
            wgt = np.exp(-d2 / (2 * sigma**2))
            if known is not None:  # nothing to match over the target's unknown space
                wgt = wgt * known[rr, cc]
            if wgt.sum() < 3:
                break
            if model == "affine":
                T_new = fit_affine(pts[ok], near, wgt)
            elif model == "rigid":
                T_new = fit_similarity(pts[ok], near, wgt, scale=scale)
            else:
                T_new = fit_similarity(pts[ok], near, wgt)
            step = np.abs(
                apply(T_new, pts[ok][:: max(1, ok.sum() // 200)])
                - apply(T, pts[ok][:: max(1, ok.sum() // 200)])
            ).max()
            T = T_new
            if step < 0.02:
                break
    return T


def refine_surfaces(
    X: np.ndarray,
    normals: np.ndarray,
    fields: SideFields,
    T: np.ndarray,
    *,
    model: str = "similarity",
    scale: float | None = None,
    sigmas: tuple[float, ...] = (2.0, 1.0),
    iterations: int = 10,
) -> np.ndarray:
    """Like :func:`refine`, on wall-surface points matched to plan surfaces facing their way.

    Matching surfaces rather than all occupied cells removes the sub-pixel bias of
    thick walls (a point inside a wall is its own nearest wall cell) and never
    pairs the two faces of a wall; the residuals are taken along the point's normal
    (point-to-plane), so the pixel rounding of the correspondences along a wall
    does not pull the transform towards whole pixels.
    """
    T = T.copy()
    for sigma in sigmas:
        for _ in range(iterations):
            q = apply(T, X)
            n = transform_normals(T, normals)
            near, d, inside = fields.nearest(q, n)
            near = to_plane(q, near, n)
            wgt = np.where(inside, np.exp(-(d**2) / (2 * sigma**2)), 0.0)
            if wgt.sum() < 3:
                return T
            if model == "affine":
                T_new = fit_affine(X, near, wgt)
            elif model == "rigid":
                T_new = fit_similarity(X, near, wgt, scale=scale)
            else:
                T_new = fit_similarity(X, near, wgt)
            probe = X[:: max(1, len(X) // 200)]
            step = np.abs(apply(T_new, probe) - apply(T, probe)).max()
            T = T_new
            if step < 0.01:
                break
    return T


def maximise_fitness(
    pts: np.ndarray, Mf: np.ndarray, T: np.ndarray, *, tol: float = 1e-4, rigid: bool = False
) -> np.ndarray:
    """Maximise eq. 8 over the similarities near ``T`` directly (Powell's method).

    The least-squares refinement of :func:`refine` converges to a stationary point
    of a *linearised* eq. 8 whose correspondences (nearest wall cells) are biased
    by clutter and by thick, noisy walls; this polishes its result by maximising the
    fitness itself, with ``M_f`` looked up bilinearly so that it is smooth in the
    parameters (log scale, angle, translation about the points' centroid).

    ``Mf`` is a fitness map of the target (eq. 8, any sigma; :func:`align_maps`
    uses ``AlignParams.direct_sigma`` = 4 px), ``pts`` the source's occupied points
    and ``T`` the starting similarity; the result is never less fit than ``T``.
    On Halmstad, HIH_layout -> HIH_03 went from 6.0 to 4.2 px of keypoint residual
    (floor 3.8 px) and the median similarity residual from 9.1 to 8.7 px: the
    least-squares fixed point had the scale 1.4% too large, held by clutter
    beside a sparsely observed wall. Sigma 2 px overfits the sensor noise
    (E5_09, HIH_layout -> HIH_01 worse), 6 px is too blunt. ``rigid`` holds ``T``'s
    scale (angle and translation only).
    """
    Mf = np.asarray(Mf, np.float32)
    centre = apply(T, pts).mean(0)

    def compose(x: np.ndarray) -> np.ndarray:
        x = np.concatenate([[0.0], x]) if rigid else x
        D = similarity_matrix(math.exp(x[0]), x[1], 0.0, 0.0)
        D[:2, 2] = centre - apply(D, [centre])[0] + x[2:]
        return D @ T

    def cost(x: np.ndarray) -> float:
        q = apply(compose(x), pts)
        return -float(ndimage.map_coordinates(Mf, [q[:, 1] - 0.5, q[:, 0] - 0.5], order=1).mean())

    x0 = np.zeros(3 if rigid else 4)
    res = optimize.minimize(cost, x0, method="Powell", options={"xtol": tol, "ftol": 1e-7})
    return compose(res.x) if res.fun < cost(x0) else T


def _score(level_t: _Level, Mf: np.ndarray, pts: np.ndarray, free_pts: np.ndarray, T) -> float:
    """Eq. 8 of the wall surfaces times the share of source free cells on plan free cells.

    Free space must land on free space: landing on the plan's unknown space (off
    the plan) or inside its solid occupied blocks both count against the hypothesis.
    """
    fit = fitness(Mf, apply(T, pts))
    if len(free_pts) == 0:
        return fit
    free = lookup(level_t.free_ok, apply(T, free_pts)).mean()
    return fit * free


def _dense(level_s: _Level, level_t: _Level, rotations, scales, sigma: float) -> list[Hypothesis]:
    """Dense hypotheses at the search level, scored like :func:`_score`."""
    Mf = level_t.fitness_map(sigma)
    hyps = dense_hypotheses(level_s.pts, Mf, rotations, scales, peaks_per_pose=3)
    for h in hyps:
        h.score = _score(level_t, Mf, level_s.pts, level_s.free_pts, h.T)
    return hyps


@dataclass
class _Search:
    """Outcome of the hypothesis search in one direction (refine-level coordinates)."""

    T: np.ndarray | None
    score: float
    stats: dict[str, Any]
    theta: tuple[float, float]
    faces: tuple[list[Face], list[Face]]
    levels: tuple[_Level, _Level]
    timings: dict[str, float]
    refined: list[tuple[float, np.ndarray]] = field(default_factory=list)
    level2: tuple[_Level, _Level, np.ndarray] | None = None
    two_way: float = -1.0
    families: tuple[list[float], list[float]] = ([], [])


def _search(src: np.ndarray, tgt: np.ndarray, f1: int, f2: int, p: AlignParams) -> _Search:
    """Hypotheses at the search level, the best refined at the refine level."""
    timings: dict[str, float] = {}
    t0 = time.perf_counter()
    S1 = _Level(src, f1, max_points=3000, seed=p.seed)
    T1 = _Level(tgt, f1, max_points=3000, seed=p.seed)
    theta_s, str_s = dominant_orientation(S1.data)
    theta_t, str_t = dominant_orientation(T1.data)
    # a building with a wing at 45 degrees has two wall families; the two maps' dominant
    # angles may name different ones (resolution: the search level's at ~5 cm/px)
    fam_s = wall_families(S1.data, theta_s, 0.05 * f1)
    fam_t = wall_families(T1.data, theta_t, 0.05 * f1)
    timings["orientation"] = time.perf_counter() - t0
    t1 = time.perf_counter()
    gap = max(2, int(round(1.0 / 0.05 / f1)))  # doorways of ~1 m at ~5 cm/px
    min_len = max(4, int(round(0.6 / 0.05 / f1)))
    faces_s = decompose(
        S1.data, theta_s, min_area=max(6, 0.002 * S1.data.size), gap=gap, min_length=min_len
    )
    faces_t = decompose(
        T1.data, theta_t, min_area=max(6, 0.002 * T1.data.size), gap=gap, min_length=min_len
    )
    timings["decomposition"] = time.perf_counter() - t1
    t1 = time.perf_counter()
    lo, hi = p.scale_range
    face_h, stats = face_hypotheses(
        faces_s, theta_s, faces_t, theta_t, scale_range=(lo, hi), max_anisotropy=p.max_anisotropy
    )
    sigma1 = 1.5
    Mf1 = T1.fitness_map(sigma1)
    for h in face_h:
        h.score = _score(T1, Mf1, S1.pts, S1.free_pts, h.T)
    rotations = _rotations(fam_s, fam_t)
    if min(str_s, str_t) < 0.25:  # no clear rectilinear structure: search all rotations
        rotations = np.concatenate([rotations, np.radians(np.arange(0, 360, 15.0))])
    n_scales = int(math.ceil(math.log(hi / lo) / math.log(1.1))) + 1
    dense_h = _dense(S1, T1, rotations, np.geomspace(lo, hi, n_scales), sigma1)
    stats.update(dense=len(dense_h), accepted=len(face_h) + len(dense_h))
    # how much the best hypothesis stands out from the typical (wrong) placement
    all_scores = np.array([h.score for h in face_h + dense_h])
    typical = float(np.median([h.score for h in dense_h])) if dense_h else 0.0
    stats["distinctiveness"] = (
        float(all_scores.max() / max(typical, 1e-9)) if len(all_scores) else 0.0
    )
    timings["hypotheses"] = time.perf_counter() - t1

    t1 = time.perf_counter()
    # quick refinement of the top hypotheses at the search level, the best few at level 2
    cands = suppress_duplicates(face_h + dense_h, translation=2.0)[: p.top_k]
    pts1 = subsample(S1.pts, 1500, p.seed)
    quick = []
    for h in cands:
        T = refine(pts1, T1.edt, h.T, sigmas=(2.0, 1.0), iterations=4)
        if lo <= decompose_similarity(T)[0] <= hi:
            quick.append((_score(T1, Mf1, S1.pts, S1.free_pts, T), T))
    quick.sort(key=lambda st: -st[0])
    S2 = _Level(src, f2, max_points=4000, seed=p.seed)
    T2 = _Level(tgt, f2, max_points=4000, seed=p.seed)
    up = _scale(f1 / f2)
    Mf2 = T2.fitness_map(1.0)
    # the best few *distinct* solutions go on to level 2: the winner, and the best
    # substantially different one it must beat clearly (see :func:`_runner_up`)
    tol1 = _distinct_px(S1.pts)
    chosen: list[np.ndarray] = []
    for _, T in quick:
        if all(_displacement(S1.pts, T, U) > tol1 for U in chosen):
            chosen.append(T)
        if len(chosen) >= p.distinct:
            break
    refined: list[tuple[float, np.ndarray]] = []
    for T in chosen:
        T = up @ T @ np.linalg.inv(up)
        T = refine(S2.pts, T2.edt, T, sigmas=(3.0, 1.5, 1.0), iterations=6)
        if not lo <= decompose_similarity(T)[0] <= hi:
            continue
        refined.append((_score(T2, Mf2, S2.pts, S2.free_pts, T), T))
    refined.sort(key=lambda st: -st[0])
    best, best_score = (refined[0][1], refined[0][0]) if refined else (None, -1.0)
    stats["runner_up"] = _runner_up(S2.pts, refined, _distinct_px(S2.pts))
    stats["refined"] = len(cands)
    timings["refine"] = time.perf_counter() - t1
    return _Search(
        best, best_score, stats, (theta_s, theta_t), (faces_s, faces_t), (S1, T1), timings,
        refined, (S2, T2, Mf2), families=(fam_s, fam_t),
    )  # fmt: skip


def _rotations(fam_s: list[float], fam_t: list[float]) -> np.ndarray:
    """Rotations that lay a wall family of the source onto one of the target: the
    dominant angles' first (four, a quarter turn apart), then those of every other
    pair of families."""
    pairs = [(fam_t[0], fam_s[0])] + [(t, s) for t in fam_t for s in fam_s][1:]
    return np.concatenate([t - s + np.arange(4) * np.pi / 2 for t, s in pairs])


def _displacement(pts: np.ndarray, T: np.ndarray, U: np.ndarray) -> float:
    """Mean distance (target px) between the images of ``pts`` under ``T`` and ``U``."""
    return float(np.hypot(*(apply(T, pts) - apply(U, pts)).T).mean())


def _distinct_px(pts: np.ndarray) -> float:
    """Two placements are substantially different when they move the source's wall
    points apart by more than 5% of the source's extent on average (at least 2 px)."""
    if len(pts) == 0:
        return 2.0
    return max(2.0, 0.05 * float(np.ptp(pts, axis=0).max()))


def _runner_up(pts: np.ndarray, refined: list[tuple[float, np.ndarray]], tol: float) -> dict:
    """The best refined solution substantially different from the winner, and how it scores.

    ``ratio`` is its score over the winner's: near 1, the maps fit (almost) as well in
    two different placements (a symmetric building, a repetitive floor), and which one
    is right cannot be told from the maps.
    """
    if not refined:
        return {"ratio": 0.0}
    s0, T0 = refined[0]
    for s1, T1 in refined[1:]:
        if _displacement(pts, T0, T1) > tol:
            sc, ang, _, _ = decompose_similarity(T1 @ np.linalg.inv(T0))
            return {
                "ratio": float(s1 / max(s0, 1e-9)),
                "rotation_deg": math.degrees(ang),
                "scale": sc,
                "displacement_px": _displacement(pts, T0, T1),
            }
    return {"ratio": 0.0}


def _prior_band(p: AlignParams) -> tuple[float, float]:
    """Scale range of the search: ``scale_range``, narrowed around ``metric_scale`` if known."""
    lo, hi = p.scale_range
    if p.metric_scale is None:
        return lo, hi
    m, t = p.metric_scale, 1.0 + p.prior_tolerance
    return max(lo, min(m / t, hi)), min(hi, max(m * t, lo))


def _search_both(src, tgt, f1, f2, p: AlignParams) -> tuple[_Search, _Search, bool]:
    """The search source onto target and target onto source; whether the reverse won.

    The placement is chosen by :func:`_two_way` from the refined solutions of both.
    """
    fwd = _search(src, tgt, f1, f2, p)
    bwd = _search(tgt, src, f1, f2, _invert_similarity_range(p))
    return _two_way(fwd, bwd, p.confidence.ambiguity)


def _two_way(fwd: _Search, bwd: _Search, tie: float) -> tuple[_Search, _Search, bool]:
    """The placement kept from both searches, and whether the reverse direction refines it.

    Each refined solution (level 2, where both directions share the pixel grid) has
    its *one-way* score, in its own search's direction (:func:`_score`: eq. 8 of the
    walls times the share of free space on free space), and a *two-way* score, the
    geometric mean of its scores in both directions. The one-way score decides, as it
    always did, except between solutions it cannot tell apart: those scoring ``tie``
    (0.85, the ambiguity of :mod:`.confidence`) of the best one-way score or more;
    among these the two-way score decides.

    Why not the one-way score alone: it rewards laying the larger map, shrunk, inside
    the explored part of the smaller one, whose walls and free space then land on the
    other's while the other map's walls land nowhere near its own. Halmstad HIH_01
    against its layout (the layout read as ``map2map`` reads the picture): the layout
    laid at scale 1/1.71 into the sensor map scores 0.258 one way, the right placement
    0.236 (0.91 of it); the other way 0.023 and 0.097; two-way 0.077 and 0.151. Why not
    the two-way score alone: it penalises a partial map for what it did not explore (a
    quarter of a generated apartment scores 1.0 one way at the right placement and
    about 0.06 the other way), so it prefers a wrong placement that half fits both ways.

    The solutions within the distinct-placement distance (:func:`_distinct_px`) of the
    chosen one are the same placement; of these, the best one-way one is kept and
    refined in its direction (on E5_01 with its resolutions, a copy of the right
    placement at a 5 % larger scale, refined by the reverse search, fits better both
    ways but lands 41 px off; the forward copy, 9 px). ``score`` of each search becomes
    the kept placement's score in its direction. The runner-up is the best other
    placement by its one-way ratio to the kept one (what the search always reported),
    or, for one scoring better one way than the kept one (which only the two-way score
    put behind), by its two-way ratio: HIH_01's layout laid into the sensor map, at
    1.09 of the kept placement one way, is a runner-up at 0.48, not a coin flip.
    """
    if fwd.level2 is None or bwd.level2 is None or not (fwd.refined or bwd.refined):
        reverse = bwd.T is not None and (fwd.T is None or bwd.score > fwd.score)
        return fwd, bwd, reverse
    S2, T2, Mf_t = fwd.level2  # source and target levels, the target's fitness map
    _, _, Mf_s = bwd.level2  # (target, source) levels, the source's fitness map

    def scores(T):  # a source -> target placement scored both ways
        sf = _score(T2, Mf_t, S2.pts, S2.free_pts, T)
        sb = _score(S2, Mf_s, T2.pts, T2.free_pts, np.linalg.inv(T))
        return sf, sb, math.sqrt(max(sf, 0.0) * max(sb, 0.0))

    # (one-way, two-way, source -> target score, target -> source score, T, reverse)
    pool = []
    for rev, refined in ((False, fwd.refined), (True, bwd.refined)):
        for own, T in refined:
            T = np.linalg.inv(T) if rev else T
            sf, sb, two = scores(T)
            pool.append((own, two, sf, sb, T, rev))
    best_own = max(c[0] for c in pool)
    chosen = max((c for c in pool if c[0] >= tie * best_own), key=lambda c: c[1])
    tol = _distinct_px(S2.pts)
    same = [c for c in pool if _displacement(S2.pts, c[4], chosen[4]) <= tol]
    own, _, s_f, s_b, T, reverse = max(same, key=lambda c: c[0])
    two = max(c[1] for c in same)
    fwd.T, fwd.score, bwd.T, bwd.score = T, s_f, np.linalg.inv(T), s_b
    fwd.two_way = bwd.two_way = two
    # the runner-up, in the kept direction's frame and points
    pts = bwd.level2[0].pts if reverse else S2.pts
    K = np.linalg.inv(T) if reverse else T
    runner: dict[str, Any] = {"ratio": 0.0}
    for c in pool:
        U = np.linalg.inv(c[4]) if reverse else c[4]
        if _displacement(pts, K, U) <= _distinct_px(pts):
            continue
        # judged by the score that decided between it and the kept placement: the
        # one-way score, unless it scores better one way (then the two-way score did)
        ratio = c[0] / max(own, 1e-9) if c[0] <= own else c[1] / max(two, 1e-9)
        if ratio > runner["ratio"]:
            sc, ang, _, _ = decompose_similarity(U @ np.linalg.inv(K))
            runner = {"ratio": float(ratio), "rotation_deg": math.degrees(ang), "scale": sc,
                      "displacement_px": _displacement(pts, K, U),
                      "one_way_ratio": float(c[0] / max(own, 1e-9)),
                      "two_way_ratio": float(c[1] / max(two, 1e-9))}  # fmt: skip
    fwd.stats["runner_up"] = bwd.stats["runner_up"] = runner
    fwd.stats["two_way_score"] = bwd.stats["two_way_score"] = two
    return fwd, bwd, reverse


def _invert_similarity_range(p: AlignParams) -> AlignParams:
    lo, hi = p.scale_range
    m = None if p.metric_scale is None else 1.0 / p.metric_scale
    return replace(
        p, scale_range=(1.0 / hi, 1.0 / lo), rigid_scale=1.0 / p.rigid_scale, metric_scale=m
    )


@dataclass
class _Crop:
    """The known content of both maps (+ margin): the search works in these windows."""

    s: tuple[int, int, int, int]  # source rows r0:r1, columns c0:c1
    t: tuple[int, int, int, int]  # target rows r0:r1, columns c0:c1

    @classmethod
    def of(cls, bs, bt, margin: int = 4) -> _Crop:
        def box(b):
            return max(0, b[0] - margin), b[1] + margin, max(0, b[2] - margin), b[3] + margin

        return cls(box(bs), box(bt))

    def cut(self, source: np.ndarray, target: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        (r0s, r1s, c0s, c1s), (r0t, r1t, c0t, c1t) = self.s, self.t
        return source[r0s:r1s, c0s:c1s], target[r0t:r1t, c0t:c1t]


def _coarse(src, tgt, f1: int, f2: int, p: AlignParams, warnings: list[str]):
    """Hypothesis search both ways, within ``prior_tolerance`` of the metric scale if known.

    Given resolutions are a constraint, not a hint: the search never leaves their
    scale band (the result stays within ``prior_tolerance``, 10 %, of their scale; see
    :func:`_keep_scale`). When the fit there is poor, the scale is searched blind too,
    and a far better fit elsewhere is reported as a warning (a resolution may be
    wrong), never silently taken: until 2026-11-27 it was taken, so that HIH_01 with
    both maps told 0.05 m/px (their true ratio is 1.17) still aligned at scale 1.71.
    """
    prior = p.metric_scale
    band = _prior_band(p)
    fwd, bwd, reverse = _search_both(src, tgt, f1, f2, replace(p, scale_range=band))
    if prior is not None and max(fwd.score, bwd.score) < p.prior_recheck:
        # a poor fit at the metric scale: are the resolutions wrong?
        fwd2, bwd2, rev2 = _search_both(src, tgt, f1, f2, p)
        free_best = bwd2 if rev2 else fwd2
        s_free = decompose_similarity(fwd2.T)[0] if fwd2.T is not None else prior
        at_prior = max(fwd.two_way, 0.0)
        if free_best.two_way > 1.25 * max(at_prior, 1e-9) and not band[0] <= s_free <= band[1]:
            warnings.append(
                f"the maps fit far better at scale {s_free:.3f} (score {free_best.two_way:.2f}) "
                f"than at the scale {prior:.3f} their resolutions give (score {at_prior:.2f}): "
                "check the resolutions (the alignment keeps within "
                f"{p.prior_tolerance:.0%} of their scale)"
            )
    return fwd, bwd, reverse


def _keep_scale(T: np.ndarray, band: tuple[float, float], pts: np.ndarray) -> np.ndarray:
    """``T`` with its scale brought into ``band`` (about the centroid of ``pts`` mapped).

    The search keeps to the band of the metric scale; the full-resolution refinements
    and anchoring after it are free, and could carry the scale a little beyond it. With
    resolutions given the scale stays within ``prior_tolerance`` of theirs.

    Examples
    --------
    >>> T = similarity_matrix(1.3, 0.2, 5.0, -3.0)
    >>> round(decompose_similarity(_keep_scale(T, (0.9, 1.1), np.ones((3, 2))))[0], 6)
    1.1
    """
    s = decompose_similarity(T)[0]
    c = float(np.clip(s, *band))
    if c == s or len(pts) == 0:
        return T
    centre = apply(T, pts).mean(0)
    D = _shift(*centre) @ _scale(c / s) @ _shift(-centre[0], -centre[1])
    return D @ T


def _search_stats(fwd: _Search, bwd: _Search, reverse: bool, p: AlignParams) -> dict[str, Any]:
    stats = dict(fwd.stats)
    stats["direction"] = "target->source" if reverse else "source->target"
    stats["score_source_to_target"] = fwd.score
    stats["score_target_to_source"] = bwd.score
    stats["runner_up"] = (bwd if reverse else fwd).stats.get("runner_up", {"ratio": 0.0})
    band = _prior_band(p) if p.metric_scale is not None else p.scale_range
    stats["scale_range"] = list(band)
    return stats


def _full_resolution(srch: _Search, a, b, q: AlignParams, f1: int, f2: int, anchored: bool,
                     warnings: list[str], notes: list[str],
                     band: tuple[float, float] | None = None):
    """Refine the winning hypothesis (a -> b) at full resolution: similarity, affine, rigid.

    Returns ``(sim, aff, rig, passed, line_plan)``; when no hypothesis passes, all three
    are the best rigid fit (with a warning). ``band`` is the scale range searched,
    source to target (for that warning).
    """
    lo, hi = band or q.scale_range
    best = srch.T
    # full resolution starts from a passed hypothesis: all occupied cells, as tuned on
    # the Halmstad maps (their sensor walls are clouds whose inner cells carry the fit)
    A3 = subsample(occupied_points(a), q.max_points, q.seed)
    edt3 = distance_map(b == OCCUPIED, return_indices=True)
    known3 = cv2.dilate((b != UNKNOWN).astype(np.uint8), np.ones((7, 7), np.uint8)) > 0
    Mf3 = np.exp(-(edt3[0] ** 2) / (2 * q.fitness_sigma**2)).astype(np.float32)
    down = _scale(f2)
    centre = A3.mean(0)

    def rigid_from(T: np.ndarray) -> np.ndarray:
        _, ang, _, _ = decompose_similarity(T)
        R = similarity_matrix(q.rigid_scale, ang, 0.0, 0.0)
        R[:2, 2] = apply(T, [centre])[0] - apply(R, [centre])[0]
        return refine(
            A3,
            edt3,
            R,
            model="rigid",
            scale=q.rigid_scale,
            sigmas=(8.0 * f2, 4.0 * f2, 2.0, 1.0),
            iterations=8,
        )

    def fallback_rigid() -> np.ndarray:
        S1, T1 = srch.levels
        return _fallback_rigid(
            S1, T1, A3, edt3, q, srch.families, f1, lambda T: fitness(Mf3, apply(T, A3))
        )

    passed = best is not None
    line_plan = False
    weak = passed and srch.score < q.min_score
    fallback = "falling back to the best rigid" + (" anchored" if anchored else "") + " result"
    rig = None
    if passed:
        sim = down @ best @ np.linalg.inv(down)
        # a line-drawn plan against a noisy map: a wide final sigma averages over the
        # map's wall noise instead of locking onto the nearest face (Halmstad: the
        # worst keypoint ratio 1.81 -> 1.46 x the floor)
        line_plan = thin_walls(a) or thin_walls(b)
        sigmas = (2.0 * f2, *(q.line_sigmas if line_plan else q.full_sigmas))
        sim = refine(A3, edt3, sim, sigmas=sigmas, iterations=8, known=known3)
        fit_sim = fitness(Mf3, apply(sim, A3))
        passed = fit_sim >= q.min_fitness
        if weak and passed:
            # below the search score that confirms a match, the hypothesis is kept only
            # when at full resolution it fits far better than the rigid fallback would
            # (Halmstad HIH_04: score 0.19, the fallback at scale 1 lands 31 px off, the
            # hypothesis at the floor, 6 px); it still carries its warning
            rig = fallback_rigid()
            fit_rig = fitness(Mf3, apply(rig, A3))
            passed = fit_sim >= q.weak_margin * fit_rig
            if passed:  # a fact: whether it is right is p_correct's to say
                notes.append(
                    f"low-confidence alignment: the best hypothesis scored {srch.score:.3f} in "
                    f"the search (< {q.min_score} confirms a match); kept because it fits "
                    f"{fit_sim:.0%} of the walls against {fit_rig:.0%} for the best rigid "
                    "fallback; check the overlay"
                )
        if weak and not passed:
            warnings.append(
                f"no alignment hypothesis passed (best score {srch.score:.3f} < {q.min_score}: "
                f"the maps do not match at any scale in {lo:.3g}-{hi:.3g}); {fallback}"
            )
        elif not passed:
            warnings.append(
                f"no alignment hypothesis passed (best fitness {fit_sim:.3f} < {q.min_fitness}); "
                + fallback
            )
    else:
        warnings.append("no alignment hypothesis passed the similarity test; " + fallback)
    if passed:
        aff_sigmas = q.line_sigmas if line_plan and q.affine_line else (1.5, 1.0)
        aff = refine(A3, edt3, sim, model="affine", sigmas=aff_sigmas, iterations=8, known=known3)
        rig = rigid_from(sim)
    else:
        rig = fallback_rigid() if rig is None else rig
        sim = aff = rig
    return sim, aff, rig, passed, line_plan


def _surfaces(source, target, src, a, b, sims, crop: _Crop, fam_t: list[float], passed: bool,
              line_plan: bool, reverse: bool, p: AlignParams):
    """Final refinement on wall surfaces, in full-image coordinates.

    ``sims`` (similarity, affine, rigid) map source to target full images. Returns the
    refined three and the target's side fields.
    """
    sim, aff, rig = sims
    (r0s, _, c0s, _), (r0t, r1t, c0t, c1t) = crop.s, crop.t
    fields = SideFields.from_map(target, fam_t[0], window=(r0t, r1t, c0t, c1t), families=fam_t)
    X, N = edge_points(src)
    keep = subsample(np.arange(len(X))[:, None], p.max_points, p.seed)[:, 0]
    X, N = X[keep] + (c0s, r0s), N[keep]
    # Wall faces are matched to the plan's faces, free of the sub-pixel bias of thick
    # walls (inside a wall every cell is its own nearest wall cell). A plan drawn with
    # line-thin walls has no faces: matching faces to its lines would bias the scale by
    # half the real walls' thickness, so there the similarity and affine keep the
    # occupied-cell fit (the rigid variant, which carries the metric, is always refined).
    if passed and not thin_walls(target):
        sim = refine_surfaces(X, N, fields, sim, sigmas=p.surface_sigmas)
        aff = refine_surfaces(X, N, fields, aff, model="affine", sigmas=p.surface_sigmas)
    rig = refine_surfaces(
        X, N, fields, rig, model="rigid", scale=p.rigid_scale, sigmas=p.surface_sigmas
    )
    if not passed:
        sim = aff = rig
    if p.direct_sigma and line_plan:
        # polish the similarity on eq. 8 itself, in the winning direction (a -> b); only
        # against line-drawn plans: on a plan with real wall faces the surface fit above
        # is exact, and a 4 px wide fitness would be pulled by walls built a few px off.
        # A fallback's similarity is its rigid polished with the scale held: its surface
        # fit locks onto the nearest faces (Halmstad HIH_01-03 auto-corrected, whose
        # search scores 0.15-0.20 fall under min_score: keypoints 10.5 / 11.6 / 8.2 px
        # -> 9.2 / 8.8 / 5.3 against their inputs' 9.5 / 8.7 / 4.9); the rigid variant,
        # which carries Algorithm 1, is left as it is
        pa = subsample(occupied_points(a), p.max_points, p.seed)
        off_a, off_b = ((c0t, r0t), (c0s, r0s)) if reverse else ((c0s, r0s), (c0t, r0t))
        d_b = distance_map(b == OCCUPIED)
        Mfd = np.exp(-(d_b**2) / (2 * p.direct_sigma**2)).astype(np.float32)
        S = np.linalg.inv(sim) if reverse else sim
        S = _shift(-off_b[0], -off_b[1]) @ S @ _shift(*off_a)
        S = maximise_fitness(pa, Mfd, S, rigid=not passed)
        S = _shift(*off_b) @ S @ _shift(-off_a[0], -off_a[1])
        sim = np.linalg.inv(S) if reverse else S
        if not passed:  # the fallback's similarity: its rigid polished the same way
            aff = sim
    return (sim, aff, rig), fields


def _anchoring(source, target, sims, passed: bool, anchors: Anchors | None, p: AlignParams,
               score, timings: dict[str, float]):
    """Manual anchors, or automatic ones kept only when they raise the fitness (eq. 8).

    Returns ``(sims, anchored, used)``: the three transforms, how they were anchored
    and the anchors used.
    """
    sim, aff, rig = sims
    anchored = "none"
    used = anchors
    if anchors is not None:
        if passed:
            sim = anchor(sim, anchors.source, anchors.target)
            aff = anchor(aff, anchors.source, anchors.target)
        else:
            sim = aff = anchor(np.eye(3), anchors.source, anchors.target)
        rig = anchor(rig, anchors.source, anchors.target)
        anchored = "manual"
    elif p.auto_anchor and passed:
        t1 = time.perf_counter()
        found = auto_anchors(source, target, aff)
        if found is not None:
            cand = anchor(aff, found.source, found.target)
            # automatic anchors are accepted only when they improve the fitness (eq. 8)
            if score(cand) > score(aff):
                aff = cand
                sim = anchor(sim, found.source, found.target)
                rig = anchor(rig, found.source, found.target)
                anchored, used = "auto", found
            else:
                anchored = "auto-rejected"
        else:
            anchored = "auto-none"
        timings["anchoring"] = time.perf_counter() - t1
    return (sim, aff, rig), anchored, used


def align_maps(
    source: np.ndarray,
    target: np.ndarray,
    *,
    anchors: Anchors | None = None,
    params: AlignParams | None = None,
    names: tuple[str | None, str | None] = ("source", "target"),
) -> Alignment:
    """Align ``source`` to ``target`` (uint8 occupancy arrays); see the module docstring.

    Returns an :class:`Alignment` whose ``similarity``, ``affine`` and ``rigid``
    3x3 matrices map source pixel coordinates (x = column, y = row, origin
    top-left, continuous: pixel centres at +0.5) to target pixel coordinates.

    The search runs both ways (source onto target and target onto source) and keeps
    the direction that scores best: the fitness of eq. 8 is only meaningful when the
    points scored are a *part* of the map they are scored against, and either map
    may be the partial one (a SLAM map of part of a building, or a plan of one
    wing of what the robot mapped). The winning direction is refined at full
    resolution and inverted if needed. The steps: :func:`_coarse` (hypotheses both
    ways), :func:`_full_resolution`, :func:`_surfaces` (wall faces), :func:`_anchoring`,
    then the quality figures and warnings (:mod:`map2map.evaluate.confidence`).
    """
    p = params or AlignParams()
    timings: dict[str, float] = {}
    warnings: list[str] = []
    notes: list[str] = []
    t0 = time.perf_counter()
    crop = _Crop.of(check_map(source, names[0]), check_map(target, names[1]))
    src, tgt = crop.cut(source, target)
    big = max(*src.shape, *tgt.shape)
    f1 = max(1, int(math.ceil(big / p.search_size)))
    f2 = min(f1, max(1, int(round(big / p.refine_size))))

    fwd, bwd, reverse = _coarse(src, tgt, f1, f2, p, warnings)
    for k, v in fwd.timings.items():
        timings[k] = v + bwd.timings.get(k, 0.0)
    stats = _search_stats(fwd, bwd, reverse, p)
    srch, a, b, q = (bwd, tgt, src, _invert_similarity_range(p)) if reverse else (fwd, src, tgt, p)

    t1 = time.perf_counter()
    sim, aff, rig, passed, line_plan = _full_resolution(
        srch, a, b, q, f1, f2, anchors is not None, warnings, notes, _prior_band(p)
    )
    if reverse:
        sim, aff, rig = (np.linalg.inv(T) for T in (sim, aff, rig))
    timings["full_resolution"] = time.perf_counter() - t1

    # back to full-image coordinates
    (r0s, _, c0s, _), (r0t, r1t, c0t, c1t) = crop.s, crop.t
    A, B = _shift(c0t, r0t), _shift(-c0s, -r0s)
    t1 = time.perf_counter()
    sims, fields = _surfaces(
        source, target, src, a, b, tuple(A @ T @ B for T in (sim, aff, rig)), crop,
        fwd.families[1], passed, line_plan, reverse, p,
    )  # fmt: skip
    timings["surfaces"] = time.perf_counter() - t1
    S3f = subsample(surface_points(source), p.max_points, p.seed)
    Mf3f = np.zeros(target.shape, np.float32)  # eq. 8 fitness map of the whole target
    d_t = distance_map(surface_mask(tgt))
    Mf3f[r0t:r1t, c0t:c1t] = np.exp(-(d_t**2) / (2 * p.fitness_sigma**2))

    def score(T: np.ndarray) -> float:
        return fitness(Mf3f, apply(T, S3f))

    (sim, aff, rig), anchored, used = _anchoring(
        source, target, sims, passed, anchors, p, score, timings
    )

    if p.metric_scale is not None:
        sim = _keep_scale(sim, _prior_band(p), S3f)
    stats["passed"] = bool(passed)
    quality = _quality(source, target, sim, p, crop.s)
    quality["runner_up_ratio"] = stats["runner_up"].get("ratio", 0.0)
    if "rotation_deg" in stats["runner_up"]:
        quality["runner_up_rotation_deg"] = stats["runner_up"]["rotation_deg"]
        quality["runner_up_scale"] = stats["runner_up"]["scale"]
    quality["p_correct"] = p_correct(quality)
    stats["quality"] = quality
    warnings.extend(alignment_warnings(quality, p.confidence))
    timings["total"] = time.perf_counter() - t0
    theta_s, theta_t = fwd.theta
    return Alignment(
        similarity=sim,
        affine=aff,
        rigid=rig,
        fitness=score(sim),
        fitness_affine=score(aff),
        fitness_rigid=score(rig),
        anchored=anchored,
        anchors=used,
        warnings=warnings,
        hypotheses=stats,
        orientation={"source": theta_s, "target": theta_t},
        families={"source": fwd.families[0], "target": fwd.families[1]},
        fields=fields,
        faces={
            "source": fwd.faces[0],
            "target": fwd.faces[1],
            "factor": f1,
            "offset_source": (c0s, r0s),
            "offset_target": (c0t, r0t),
        },
        timings=timings,
        notes=notes + alignment_notes(quality, p.confidence),
        p_correct=quality["p_correct"],
    )


def _free_agreement(a: np.ndarray, b: np.ndarray, T: np.ndarray, n: int, seed: int) -> float:
    """Share of ``a``'s free cells mapped by ``T`` onto ``b``'s free cells (grown by one
    cell), of those landing on ``b``'s known cells (1 when none lands there)."""
    r, c = np.nonzero(a == FREE)
    pts = subsample(np.column_stack([c + 0.5, r + 0.5]), n, seed)
    if len(pts) == 0:
        return 1.0
    q = apply(T, pts)
    known = lookup(b != UNKNOWN, q) > 0
    if not known.any():
        return 1.0
    free = cv2.dilate((b == FREE).astype(np.uint8), np.ones((3, 3), np.uint8))
    return float(lookup(free, q[known]).mean())


def _fitness_of(data: np.ndarray, sigma: float) -> np.ndarray:
    """Eq. 8 fitness map of a map's wall surfaces, computed on its known content only."""
    r0, r1, c0, c1 = check_map(data, None)
    m = 4 + int(3 * sigma)
    r0, c0 = max(0, r0 - m), max(0, c0 - m)
    r1, c1 = min(data.shape[0], r1 + m), min(data.shape[1], c1 + m)
    d = distance_map(surface_mask(data[r0:r1, c0:c1]))
    out = np.zeros(data.shape, np.float32)
    out[r0:r1, c0:c1] = np.exp(-(d**2) / (2 * sigma**2))
    return out


def _quality(source, target, sim, p: AlignParams, box_s) -> dict[str, Any]:
    """The figures of :mod:`.confidence`: fitness both ways, free-space agreement, scale."""
    r0, r1, c0, c1 = box_s
    scale = decompose_similarity(sim)[0]
    # the width of the agreement: 0.5% of the map's extent (at least fitness_sigma px),
    # so that a large real map's wall noise is not read as disagreement
    sig_t = max(p.fitness_sigma, 0.005 * max(r1 - r0, c1 - c0) * scale)
    sig_s = sig_t / scale
    S_pts = subsample(surface_points(source), p.max_points, p.seed)
    T_pts = subsample(surface_points(target), p.max_points, p.seed)
    Mf_t = _fitness_of(target, sig_t)
    fit_st = fitness(Mf_t, apply(sim, S_pts))
    fit_ts = fitness(_fitness_of(source, sig_s), apply(np.linalg.inv(sim), T_pts))
    fa_st = _free_agreement(source, target, sim, p.max_points, p.seed)
    fa_ts = _free_agreement(target, source, np.linalg.inv(sim), p.max_points, p.seed)
    return {
        "agreement_sigma_px": float(sig_t),
        "fitness_source_to_target": float(fit_st),
        "fitness_target_to_source": float(fit_ts),
        "fitness": float(max(fit_st, fit_ts)),
        "free_agreement": float(0.5 * (fa_st + fa_ts)),
        "free_agreement_source_to_target": fa_st,
        "free_agreement_target_to_source": fa_ts,
        "scale": decompose_similarity(sim)[0],
        "metric_scale": p.metric_scale,
    }


def _fallback_rigid(S1, T1, S3, edt3, p: AlignParams, families, f1, fit3) -> np.ndarray:
    """Best rigid transform (scale fixed) from dense hypotheses, refined at full resolution."""
    rotations = np.concatenate([_rotations(*families), np.radians(np.arange(0, 360, 15.0))])
    hyps = _dense(S1, T1, rotations, np.array([p.rigid_scale]), 1.5)
    if not hyps:
        return similarity_matrix(p.rigid_scale, 0.0, 0.0, 0.0)
    down = _scale(f1)
    best, best_fit = None, -1.0
    for h in sorted(hyps, key=lambda h: -h.score)[:5]:
        T = down @ h.T @ np.linalg.inv(down)
        T = refine(
            S3,
            edt3,
            T,
            model="rigid",
            scale=p.rigid_scale,
            sigmas=(4.0 * f1, 2.0 * f1, 2.0, 1.0),
            iterations=6,
        )
        f = fit3(T)
        if f > best_fit:
            best, best_fit = T, f
    return best
