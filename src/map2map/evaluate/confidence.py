"""How sure an alignment or an evaluation is: the figures behind it, its warnings and notes.

A confident wrong number is the worst output an assessment can give; a warning that
fires on almost every good result is the next worst (it teaches users to ignore
warnings). So every alignment carries the figures that say whether it can be
trusted, a **warning** for each figure that says it may be wrong, and a **note** for
each fact that does not make it doubtful but limits what its numbers describe (the
real map differs from the plan: furniture, clutter, unmapped parts).

Warnings of an alignment (:func:`alignment_warnings`):

* **ambiguity**: the best placement must beat the best *substantially different*
  one (its wall points moved apart by more than 5% of the map's extent on average)
  clearly; a runner-up scoring ``ambiguity`` (0.8) of the winner or more means two
  placements fit (almost) equally well — a symmetric building, a repetitive floor,
  a small map inside a large plan — and the maps alone cannot tell which is right;
* **poor fit**: eq. 8 of the wall surfaces (sigma 0.5% of the map's extent, at least
  2 px) in the better of the two directions (either map may be the partial one)
  below ``min_fitness`` (0.15): almost no wall of one map lies on the other's; or
  below ``note_fitness`` (0.5) while the free-space agreement is below ``note_free``
  (0.95): neither the walls nor the rooms agree well;
* **free space**: the share of one map's free cells landing on the other's free
  cells (of those landing on its known cells) below ``min_free_agreement`` (0.75):
  rooms lie over walls or solid blocks;
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

Calibration (``map2map.experiments.halmstad_accuracy``: 36 Halmstad sensor map <-> layout
pairs scored by annotated keypoints, 35 good (similarity within 1.5 x the keypoint
floor), 1 bad (E5_layout -> E5_01, 1.96 x), plus 4 sensor maps against the other
building's layout; the synthetic cases of ``tests/test_trust.py`` and
``tests/test_confidence.py``; the known-similarity sweep
``map2map.experiments.align_sweep``):

* fitness does not separate right from wrong on real maps: good Halmstad pairs
  score 0.21-0.58 (their sensor walls are clouds, the rooms hold furniture), wrong
  maps 0.05-0.40, pairs of different synthetic plans 0.34-0.41, correct synthetic
  alignments >= 0.88. The old threshold 0.5 fired on 30 of the 35 good Halmstad
  pairs; 0.15 lies below every correct alignment measured and still catches the
  worst wrong map (0.05). Between 0.15 and 0.5 it takes the rooms to tell: the
  good Halmstad pairs agree on free space to 0.957-0.98, so a fitness under 0.5
  with an agreement under 0.95 still warns (a second line behind the ambiguity on
  HIH_01 against the E5 layout, 0.946, and on synthetic different plans,
  0.70-0.89; a thin margin, 0.011, on the Halmstad side)
  and with 0.95 or more it is a note, not an alarm;
* free-space agreement is the strongest single figure: good Halmstad pairs
  0.96-0.98, correct synthetic ones >= 0.99, wrong maps and different plans
  0.50-0.99 (fires on 0 good, 2 of 4 wrong Halmstad maps, 1 of 8 synthetic
  different-plan pairs);
* the runner-up ratio of good Halmstad pairs is 0.00-0.90 (>= 0.8 on E5_01, E5_04,
  E5_12 in both directions), of the bad pair 0.88 and of the wrong maps 0.90-0.97,
  of different synthetic plans 0.77-0.95, of a symmetric room 1.0: no threshold
  separates them (0.90 on a good pair, 0.90 on a wrong one), so 0.8 stays and
  the warning fires on 5 of 35 good pairs — the maps alone *are* ambiguous there
  (a runner-up at 0.6 x the scale fits 88% as well). Neither its free-space
  agreement (runner-ups 0.94-0.97, as high as the winners') nor its eq. 8 fitness
  refined at full resolution (0.69-0.87 of the winner's on good pairs, 0.72-0.74
  on wrong maps) settles it. What does: a known metric scale. With the E5 scale
  given (0.83), E5_01 and E5_04 score a runner-up of 0.75 and 0.52 (no warning,
  same transform) and E5_12 keeps 0.81 (its runner-up is the building turned
  180 deg: truly ambiguous); so when the runner-up lies at another scale and no
  resolutions were given, the warning says to give them;
* the unmatched share of good Halmstad pairs is 0.41-0.83, of the wrong maps
  0.77-0.97, of correct synthetic alignments < 0.1: above 0.9 the maps share no
  walls (a warning), above 0.5 it is a fact about what the statistics describe.

Every wrong or doubtful case above still carries a warning: the wrong Halmstad
maps (ambiguity, free space, poor fit), the bad Halmstad pair (ambiguity), the
synthetic different plans (ambiguity, free space, scale), a wrong resolution
(scale), unrelated clutter (no hypothesis passed).

Examples
--------
>>> q = {"fitness": 0.93, "free_agreement": 0.99, "runner_up_ratio": 0.97,
...      "scale": 1.0, "metric_scale": 1.0}
>>> alignment_warnings(q)[0][:60]
'ambiguous alignment: a placement rotated by 180.0 deg, scale'
>>> q = {"fitness": 0.41, "free_agreement": 0.96, "runner_up_ratio": 0.3,
...      "agreement_sigma_px": 6.4, "scale": 0.83, "metric_scale": None}
>>> alignment_warnings(q)
[]
>>> alignment_notes(q)[0][:58]
'the maps differ: 41% of the walls of one map lie on the ot'
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

__all__ = [
    "ConfidenceParams",
    "alignment_warnings",
    "alignment_notes",
    "evaluation_warnings",
    "evaluation_notes",
]


@dataclass
class ConfidenceParams:
    """Thresholds of the warnings and notes (measured figures: the module docstring).

    ``min_fitness`` (0.15, was 0.5) warns below every correct alignment measured
    (Halmstad good pairs >= 0.21). Between it and ``note_fitness`` (0.5) a fitness
    warns when the free-space agreement is below ``note_free`` (0.95; good Halmstad
    pairs >= 0.957) and is a note (the maps differ, the rooms agree) above it.
    ``max_unmatched`` (0.9, was 0.5) warns above every good Halmstad pair (<= 0.83);
    ``note_unmatched`` (0.5) notes what the wall statistics describe.
    """

    ambiguity: float = 0.8
    min_fitness: float = 0.15
    min_free_agreement: float = 0.75
    scale_mismatch: float = 0.03
    min_iou_free: float = 0.5
    max_unmatched: float = 0.9
    note_fitness: float = 0.5
    note_free: float = 0.95
    note_unmatched: float = 0.5


def alignment_warnings(q: dict[str, Any], params: ConfidenceParams | None = None) -> list[str]:
    """Warnings of an alignment from its quality figures ``q``.

    ``q`` holds ``fitness``, ``free_agreement``, ``runner_up_ratio`` (with
    ``runner_up_rotation_deg`` and ``runner_up_scale`` when known), ``scale`` (of the
    similarity) and ``metric_scale`` (None when a resolution is unknown).
    """
    p = params or ConfidenceParams()
    out = []
    r = q.get("runner_up_ratio", 0.0) or 0.0
    if r >= p.ambiguity:
        rot = q.get("runner_up_rotation_deg", 180.0)
        sc = q.get("runner_up_scale", 1.0)
        hint = "check the overlay or give --anchors"
        if q.get("metric_scale") is None and abs(math.log(max(sc, 1e-9))) > math.log(1.1):
            # the runner-up is at another scale: a known metric scale would rule it out
            hint = (
                "check the overlay, give --anchors, or give both maps' resolutions "
                "(--source-resolution, --target-resolution): the search then keeps to "
                "their scale, which rules out a placement at another"
            )
        out.append(
            f"ambiguous alignment: a placement rotated by {rot:.1f} deg, scale {sc:.3f} from "
            f"the chosen one fits {100 * r:.0f}% as well in the search (symmetric or "
            "repetitive layout, or a small map that fits several places of a large one); "
            f"the maps alone cannot tell which is right: {hint}"
        )
    fit, fa = q.get("fitness"), q.get("free_agreement")
    if fit is not None and fit < p.min_fitness:
        out.append(
            f"poor fit: only {100 * fit:.0f}% fitness (eq. 8) of the walls on each other "
            f"(< {100 * p.min_fitness:.0f}%, below every correct alignment measured); the maps "
            "may not show the same place or the alignment is wrong"
        )
    elif fit is not None and fit < p.note_fitness and fa is not None and fa < p.note_free:
        out.append(
            f"poor fit: only {100 * fit:.0f}% fitness (eq. 8) of the walls on each other and "
            f"{100 * fa:.0f}% of the free space on free space (< {100 * p.note_free:.0f}%): "
            "neither walls nor rooms agree well; the maps may not show the same place or the "
            "alignment is wrong"
        )
    if fa is not None and fa < p.min_free_agreement:
        out.append(
            f"free space disagrees: {100 * (1 - fa):.0f}% of the free space lands on walls "
            "or solid blocks of the other map; the alignment is doubtful"
        )
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
