"""How sure an alignment or an evaluation is: the figures behind it, its warnings and notes.

A confident wrong number is the worst output an assessment can give; a warning that
fires on almost every good result is the next worst (it teaches users to ignore
warnings). So every alignment carries the figures that say whether it can be
trusted, a **warning** for each figure that says it may be wrong, and a **note** for
each fact that does not make it doubtful but limits what its numbers describe (the
real map differs from the plan: furniture, clutter, unmapped parts).

Every alignment carries ``p_correct`` (:func:`p_correct`): the probability that it is
right, a logistic model of four figures of its quality dict (:data:`FEATURES`: the wall
fitness of eq. 8 in the better and the worse direction, the share of free space on free
space, the runner-up ratio) whose :data:`COEFFICIENTS` were fitted on 207 alignments with
a known truth (``python3 -m map2map.experiments.alignment_confidence``, 2026-11-27):
135 synthetic ones (plans against rotated, scaled, partial copies of themselves, with
and without the metric scale, against other plans, symmetric rooms, wrong resolutions),
36 Halmstad sensor map <-> layout pairs (right when within 1.5 x the keypoint floor) and
36 sensor maps against the other building's layout (wrong). Held out (6 folds grouped by
plan and by building: every E5 map predicted by a model that saw none), its Brier score
is 0.085 (0.228 for a constant).

Warnings of an alignment (:func:`alignment_warnings`):

* **doubtful alignment**: ``p_correct`` below ``doubtful_below`` (0.45), or a
  substantially different placement (its wall points moved apart by more than 5% of
  the map's extent on average) fitting ``ambiguity`` (0.85) as well or better (the maps
  alone cannot tell which is right). It names its causes: a runner-up at 0.8 or more
  (with the hint to give the resolutions when it lies at another scale), walls of one
  map hardly on the other's (the worse direction under 10%), free space on walls (under
  95% on free space), else the figures themselves. The threshold is the highest that
  warns at most 10% of the right alignments of each data set held out; no threshold
  also warns every wrong one (that needs 0.93, which warns every right Halmstad pair).
  Held out it warns 2 of 88 right synthetic alignments and 22 of 25 wrong ones, 3 of 35
  right Halmstad pairs (E5_01, E5_04 both ways: a runner-up at 0.6 x the scale fits
  88-90% as well; the resolutions clear it) and the 1 wrong one, all 36 wrong-building
  pairs, and all 22 alignments of symmetric rooms (right or wrong by a coin flip). With
  the stored coefficients (fit on all, in-sample) the same but 34 of 36 wrong-building
  pairs (E5_04 <-> HIH_layout, p 0.54-0.56, escape). It replaces the former ambiguity
  (runner-up >= 0.8), poor-fit and free-space warnings, which fired on 5 of 35 right
  Halmstad pairs and 2 of 88 right synthetic ones; the "low-confidence alignment" of a
  weak search hypothesis (2 right Halmstad pairs, no wrong one) is now a note;
* **metric scale**: when both maps carry a resolution the scale is known (a LIDAR
  SLAM map has no global scale error, appendix paper section 3.2); a similarity
  whose scale differs from it by more than ``scale_mismatch`` (3%) means a
  resolution or the alignment is wrong;

and of an evaluation (:func:`evaluation_warnings`):

* **free-space IoU** of the aligned maps (chosen chain) below ``min_iou_free``
  (0.5) over the area both maps know;
* **no shared walls**: more than ``max_unmatched`` (90%) of the SLAM map's wall
  points match no plan wall (:mod:`.metric`).

Notes (:func:`alignment_notes`, :func:`evaluation_notes`): a fitness below
``note_fitness`` (0.5) while the free space agrees to ``note_free`` (95%) or more
(the walls differ, the rooms coincide), and more than ``note_unmatched`` (50%) of
the SLAM map's wall points matching no plan wall (the wall statistics describe the
rest).

Figures behind the model (the same runs):

* fitness in the better direction does not separate right from wrong on real maps:
  right Halmstad pairs score 0.21-0.58 (their sensor walls are clouds, the rooms hold
  furniture), wrong-building pairs 0.00-0.88, right synthetic alignments >= 0.97; in
  the worse direction right Halmstad pairs score 0.11-0.39 and wrong-building pairs
  0.00-0.07;
* free space on free space: right Halmstad pairs 0.957-0.980, right synthetic ones
  >= 0.99, wrong ones 0.50-0.99;
* the runner-up ratio: right Halmstad pairs 0.00-0.90, right synthetic ones (symmetric
  rooms aside) 0.00-0.89, wrong ones 0.66-1.00;
* what no figure here separates: a generated apartment laid on another one without
  the metric scale (fitness 0.52, free space 0.98: the figures of a right real pair;
  held-out p 0.92), and a one-room plan whose chosen placement, turned 180 deg, beats
  the right one (p 0.90-0.97);
* the unmatched share of good Halmstad pairs is 0.41-0.83, of the wrong maps
  0.77-0.97, of correct synthetic alignments < 0.1: above 0.9 the maps share no
  walls (a warning), above 0.5 it is a fact about what the statistics describe.

Examples
--------
>>> q = {"fitness": 0.93, "free_agreement": 0.99, "runner_up_ratio": 0.97,
...      "scale": 1.0, "metric_scale": 1.0}
>>> alignment_warnings(q)[0][:60]
'doubtful alignment: two placements fit (almost) equally well'
>>> q = {"fitness": 0.41, "free_agreement": 0.96, "runner_up_ratio": 0.3,
...      "agreement_sigma_px": 6.4, "scale": 0.83, "metric_scale": None}
>>> round(p_correct(q), 2)
0.9
>>> alignment_warnings(q)
[]
>>> alignment_notes(q)[0][:58]
'the maps differ: 41% of the walls of one map lie on the ot'
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np

__all__ = [
    "FEATURES",
    "COEFFICIENTS",
    "INTERCEPT",
    "alignment_features",
    "p_correct",
    "ConfidenceParams",
    "alignment_warnings",
    "alignment_notes",
    "evaluation_warnings",
    "evaluation_notes",
]


#: the figures of an alignment's quality dict ``q`` that ``p_correct`` rests on
FEATURES = (
    "fitness",  # eq. 8 of the walls, the better direction
    "fitness_min",  # the same, the worse direction: ~0 when the maps are of different places
    "free_agreement_log",  # -log(1.01 - free_agreement): high when rooms lie on rooms
    "runner_up_log",  # -log(1.02 - runner_up_ratio): high when another placement fits as well
)
#: logistic coefficients of :data:`FEATURES` and the intercept, fitted (scikit-learn,
#: C = 1) on all 207 labelled alignments of ``python3 -m
#: map2map.experiments.alignment_confidence --collect`` (2026-11-27; it prints them)
COEFFICIENTS = (0.6247, 0.9345, 1.8336, -1.7368)
INTERCEPT = -3.4044


def alignment_features(q: dict[str, Any]) -> np.ndarray:
    """The vector of :data:`FEATURES` from an alignment's quality dict ``q``.

    Parameters
    ----------
    q : dict
        ``fitness_source_to_target``, ``fitness_target_to_source`` (or ``fitness`` alone:
        both directions are then taken equal), ``free_agreement`` and
        ``runner_up_ratio`` (missing: 1 and 0).

    Returns
    -------
    numpy.ndarray
        Four floats, in the order of :data:`FEATURES`.

    Examples
    --------
    >>> f = alignment_features({"fitness": 0.9, "free_agreement": 1.0, "runner_up_ratio": 0.0})
    >>> f.round(3).tolist()
    [0.9, 0.9, 4.605, -0.02]
    """
    fit = float(q.get("fitness") or 0.0)
    st, ts = q.get("fitness_source_to_target"), q.get("fitness_target_to_source")
    fit_min = fit if st is None or ts is None else float(min(st, ts))
    fa = q.get("free_agreement")
    fa = 1.0 if fa is None else float(fa)
    r = float(q.get("runner_up_ratio") or 0.0)
    return np.array(
        [fit, fit_min, -math.log(1.01 - min(fa, 1.0)), -math.log(1.02 - min(r, 1.0))]
    )


def p_correct(q: dict[str, Any]) -> float:
    """Probability that the alignment is right, from its quality dict ``q``.

    A logistic model of :func:`alignment_features` with the stored
    :data:`COEFFICIENTS` (numpy only; the fit is the experiment's). Calibrated on
    alignments with a known truth: synthetic plans against moved, partial or
    different copies, the Halmstad sensor maps against their layout and against the
    other building's (``docs/evaluate.md``).

    Examples
    --------
    >>> clean = {"fitness": 0.99, "free_agreement": 1.0, "runner_up_ratio": 0.3}
    >>> p_correct(clean) > 0.9
    True
    >>> wrong = {"fitness": 0.3, "fitness_source_to_target": 0.3,
    ...          "fitness_target_to_source": 0.02, "free_agreement": 0.6,
    ...          "runner_up_ratio": 0.97}
    >>> p_correct(wrong) < 0.1
    True
    """
    z = INTERCEPT + float(np.dot(COEFFICIENTS, alignment_features(q)))
    return float(1.0 / (1.0 + math.exp(-z)))


@dataclass
class ConfidenceParams:
    """Thresholds of the warnings and notes (measured figures: the module docstring).

    ``doubtful_below`` (0.45): an alignment is *doubtful* when :func:`p_correct` is
    below it, the threshold that warned at most 10% of the right alignments held out
    (``map2map.experiments.alignment_confidence``); or when a substantially different
    placement fits ``ambiguity`` (0.85) as well or better (the maps alone cannot tell:
    it warns 2 of 88 right synthetic alignments, a sliver of a floor of repeated offices,
    and no right Halmstad pair that ``p_correct`` does not already warn; the next right
    Halmstad pair, E5_12, lies at 0.80).
    The doubtful warning names its causes: a runner-up at ``runner_up_cause`` (0.8) or
    more, walls the other way below ``min_fitness`` (0.1), free space on free space
    below ``note_free`` (0.95). ``min_fitness`` and ``note_fitness`` (0.5) with
    ``note_free`` also decide the note "the maps differ" (walls differ, rooms agree).
    ``max_unmatched`` (0.9, was 0.5) warns above every good Halmstad pair (<= 0.83);
    ``note_unmatched`` (0.5) notes what the wall statistics describe.
    """

    doubtful_below: float = 0.45
    ambiguity: float = 0.85
    runner_up_cause: float = 0.8
    min_fitness: float = 0.1
    scale_mismatch: float = 0.03
    min_iou_free: float = 0.5
    max_unmatched: float = 0.9
    note_fitness: float = 0.5
    note_free: float = 0.95
    note_unmatched: float = 0.5


def _causes(q: dict[str, Any], p: ConfidenceParams) -> tuple[list[str], str]:
    """What makes an alignment doubtful, in words, and what to do about it."""
    out = []
    hint = "check the overlay or give --anchors"
    r = q.get("runner_up_ratio", 0.0) or 0.0
    if r >= p.runner_up_cause:
        rot = q.get("runner_up_rotation_deg", 180.0)
        sc = q.get("runner_up_scale", 1.0)
        out.append(
            f"a placement rotated by {rot:.1f} deg, scale {sc:.3f} from the chosen one fits "
            f"{100 * r:.0f}% as well in the search (symmetric or repetitive layout, or a small "
            "map that fits several places of a large one): the maps alone cannot tell which "
            "is right"
        )
        if q.get("metric_scale") is None and abs(math.log(max(sc, 1e-9))) > math.log(1.1):
            # the runner-up is at another scale: a known metric scale would rule it out
            hint = (
                "check the overlay, give --anchors, or give both maps' resolutions "
                "(--source-resolution, --target-resolution): the search then keeps to "
                "their scale, which rules out a placement at another"
            )
    f = alignment_features(q)
    if f[1] < p.min_fitness:
        out.append(
            f"only {100 * f[1]:.0f}% of the walls of one map lie on the other's "
            f"({100 * f[0]:.0f}% the other way): the maps may not show the same place"
        )
    fa = q.get("free_agreement")
    if fa is not None and fa < p.note_free:
        out.append(
            f"{100 * (1 - fa):.0f}% of the free space lands on walls or solid blocks of the "
            "other map"
        )
    if not out:
        out.append(
            f"its figures (wall fitness {f[0]:.2f} and {f[1]:.2f} the other way, free space "
            f"on free space {fa if fa is not None else 1.0:.3f}, runner-up {r:.2f}) are "
            "those of wrong alignments as often as of right ones"
        )
    return out, hint


def alignment_warnings(q: dict[str, Any], params: ConfidenceParams | None = None) -> list[str]:
    """Warnings of an alignment from its quality figures ``q``.

    ``q`` holds ``fitness`` (and ``fitness_source_to_target``,
    ``fitness_target_to_source``), ``free_agreement``, ``runner_up_ratio`` (with
    ``runner_up_rotation_deg`` and ``runner_up_scale`` when known), ``scale`` (of the
    similarity), ``metric_scale`` (None when a resolution is unknown) and ``p_correct``
    (computed by :func:`p_correct` when absent).

    Two warnings: **doubtful alignment** (:func:`p_correct` below ``doubtful_below``, or
    a runner-up at ``ambiguity``), naming its causes, and **scale mismatch** (the
    resolutions contradict the alignment's scale).
    """
    p = params or ConfidenceParams()
    out = []
    pc = q.get("p_correct")
    pc = p_correct(q) if pc is None else float(pc)
    r = q.get("runner_up_ratio", 0.0) or 0.0
    if pc < p.doubtful_below or r >= p.ambiguity:
        causes, hint = _causes(q, p)
        why = (
            f"probability of being right {pc:.2f} (< {p.doubtful_below})"
            if pc < p.doubtful_below
            else f"two placements fit (almost) equally well (probability of being right {pc:.2f})"
        )
        out.append(f"doubtful alignment: {why}: " + "; ".join(causes) + f"; {hint}")
    m, s = q.get("metric_scale"), q.get("scale")
    if m is not None and s is not None and abs(s / m - 1.0) > p.scale_mismatch:
        out.append(
            f"scale mismatch: the maps align at scale {s:.4f}, their resolutions give "
            f"{m:.4f} ({100 * (s / m - 1):+.1f}%); a resolution is wrong, the alignment is, or "
            "the plan's walls are much thicker than the surfaces a LIDAR sees (the demo plan's "
            "0.1-0.3 m walls give +2.7 % against their own surfaces)"
        )
    return out


def alignment_notes(q: dict[str, Any], params: ConfidenceParams | None = None) -> list[str]:
    """Facts about an alignment that limit what its numbers describe (no doubt on it).

    A fitness between ``min_fitness`` and ``note_fitness`` while the free space
    agrees: the walls of the two maps differ (clutter, furniture, walls one map
    lacks), the rooms coincide. Keys of ``q`` as in :func:`alignment_warnings`
    (and ``agreement_sigma_px``, the width of the agreement).
    """
    p = params or ConfidenceParams()
    fit, fa = q.get("fitness"), q.get("free_agreement")
    if fit is None or not p.min_fitness <= fit < p.note_fitness:
        return []
    if fa is None or fa < p.note_free:
        return []
    sig = q.get("agreement_sigma_px")
    within = f" (eq. 8, within ~{sig:.0f} px)" if sig else " (eq. 8)"
    return [
        f"the maps differ: {100 * fit:.0f}% of the walls of one map lie on the other's"
        f"{within} while {100 * fa:.0f}% of the free space lies on free space: furniture, "
        "clutter or walls only one map shows; the placement rests on the rooms and the "
        "walls both maps share"
    ]


def evaluation_warnings(
    iou_free: float | None, unmatched_share: float | None, params: ConfidenceParams | None = None
) -> list[str]:
    """Warnings of an evaluation: free-space IoU of the aligned maps, unmatched wall points."""
    p = params or ConfidenceParams()
    out = []
    if iou_free is not None and iou_free == iou_free and iou_free < p.min_iou_free:
        out.append(
            f"aligned maps disagree: free-space IoU {iou_free:.2f} (< {p.min_iou_free}) over "
            "the area both maps know"
        )
    if unmatched_share is not None and unmatched_share > p.max_unmatched:
        out.append(
            f"{100 * unmatched_share:.0f}% of the SLAM map's wall points match no plan wall: "
            "the maps share almost no walls (not the same place, or a wrong alignment); the "
            f"wall statistics describe only {100 * (1 - unmatched_share):.0f}% of the map"
        )
    return out


def evaluation_notes(
    unmatched_share: float | None, params: ConfidenceParams | None = None
) -> list[str]:
    """Facts about an evaluation: which share of the SLAM map's walls the statistics describe.

    Examples
    --------
    >>> evaluation_notes(0.75)[0][:45]
    'the wall error figures describe 25% of the SL'
    """
    p = params or ConfidenceParams()
    u = unmatched_share
    if u is None or not p.note_unmatched < u <= p.max_unmatched:
        return []
    return [
        f"the wall error figures describe {100 * (1 - u):.0f}% of the SLAM map's wall points: "
        f"the other {100 * u:.0f}% match no plan wall (furniture, clutter, walls the plan "
        "lacks or parts of the map beyond the plan)"
    ]
