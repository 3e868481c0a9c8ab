"""How sure an alignment or an evaluation is: the figures behind it and its warnings.

A confident wrong number is the worst output an assessment can give. Every
alignment therefore carries the figures that say whether it can be trusted, and a
warning in words for each one that says it cannot:

* **ambiguity**: the best placement must beat the best *substantially different*
  one (its wall points moved apart by more than 5% of the map's extent on average)
  clearly; a runner-up scoring ``ambiguity`` (0.8) of the winner or more means two
  placements fit (almost) equally well — a symmetric building, a repetitive floor
  — and the maps alone cannot tell which is right;
* **fitness**: eq. 8 of the wall surfaces (sigma 0.5% of the map's extent, at least
  2 px) in the better of the two directions (either map may be the partial one)
  below ``min_fitness`` (0.5): most walls of one map land away from the other's;
* **free space**: the share of one map's free cells landing on the other's free
  cells (of those landing on its known cells) below ``min_free_agreement`` (0.75):
  rooms lie over walls or solid blocks;
* **metric scale**: when both maps carry a resolution the scale is known (a LIDAR
  SLAM map has no global scale error, appendix paper section 3.2); a similarity
  whose scale differs from it by more than ``scale_mismatch`` (3%) means a
  resolution or the alignment is wrong;

and, for an evaluation (:func:`evaluation_warnings`):

* **free-space IoU** of the aligned maps (chosen chain) below ``min_iou_free``
  (0.5) over the area both maps know;
* **unmatched points**: more than ``max_unmatched`` (50%) of the SLAM map's wall
  points match no plan wall (:mod:`.metric`).

The thresholds were set on the known-similarity sweep (``benchmarks/align_sweep.py``:
correct alignments score fitness >= 0.98, free agreement >= 0.99, runner-up ratio
<= 0.52 except on a symmetric one-room plan, 0.96-1.0) and on pairs of different
plans (runner-up 0.84-1.0, fitness 0.38-0.85) and of Halmstad sensor maps against
the other building's layout (fitness 0.21-0.26). Real sensor maps against their own
layout (Halmstad E5) score a runner-up of 0.88-0.90 and fitness 0.37-0.49: they are
flagged as doubtful, which the keypoint residuals (2x the floor) bear out.

Examples
--------
>>> q = {"fitness": 0.93, "free_agreement": 0.99, "runner_up_ratio": 0.97,
...      "scale": 1.0, "metric_scale": 1.0}
>>> alignment_warnings(q)[0][:60]
'ambiguous alignment: a placement rotated by 180.0 deg, scale'
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

__all__ = ["ConfidenceParams", "alignment_warnings", "evaluation_warnings"]


@dataclass
class ConfidenceParams:
    """Thresholds of the warnings (see the module docstring)."""

    ambiguity: float = 0.8
    min_fitness: float = 0.5
    min_free_agreement: float = 0.75
    scale_mismatch: float = 0.03
    min_iou_free: float = 0.5
    max_unmatched: float = 0.5


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
        out.append(
            f"ambiguous alignment: a placement rotated by {rot:.1f} deg, scale {sc:.3f} from "
            f"the chosen one fits {100 * r:.0f}% as well (symmetric or repetitive layout?); "
            "the alignment may be wrong: check the overlay or give --anchors"
        )
    fit = q.get("fitness")
    if fit is not None and fit < p.min_fitness:
        out.append(
            f"poor fit: only {100 * fit:.0f}% fitness (eq. 8) of the walls on each other "
            f"(< {100 * p.min_fitness:.0f}%); the maps may not show the same place or the "
            "alignment is wrong"
        )
    fa = q.get("free_agreement")
    if fa is not None and fa < p.min_free_agreement:
        out.append(
            f"free space disagrees: {100 * (1 - fa):.0f}% of the free space lands on walls "
            "or solid blocks of the other map; the alignment is doubtful"
        )
    m, s = q.get("metric_scale"), q.get("scale")
    if m is not None and s is not None and abs(s / m - 1.0) > p.scale_mismatch:
        out.append(
            f"scale mismatch: the maps align at scale {s:.4f}, their resolutions give "
            f"{m:.4f} ({100 * (s / m - 1):+.1f}%); a resolution is wrong or the alignment is"
        )
    return out


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
            "the wall statistics describe a minority of the map"
        )
    return out
