"""The ceiling of a Model_BA that moves walls, and how much of the move the SLAM map shows.

Issue #32 asks for a network that predicts a dense, sub-pixel displacement field moving
the SLAM map's walls to where the plan has them (median Error(gen) <= 0.75 px; input
about 1.09, true-pose floor about 0.64). This script measures, on held-out pairs:

1. **The ceiling.** The plan is brought into the SLAM map's pixels by the rigid part of
   the evaluation's own alignment (:func:`map2map.evaluate.align.align_maps`; the metric
   measures from ``X_rigid``, Algorithm 1, so the rigid part is not the field's to undo).
   A coarse field (``--grid`` x ``--grid`` control points, bicubic to the map) is then
   *fitted to that map's plan* by Adam on the registration loss a network would be taught
   with: every SLAM wall face (an occupied pixel whose 4-neighbour in a direction is
   free) moved by the field lands on a plan face looking the same way (distance sampled
   bilinearly, Charbonnier, faces more than 4 px from any such plan face left out as
   clutter) plus ``--smooth`` x the squared differences of neighbouring control points.
   The map warped by that field (nearest neighbour) is measured by Table 5.3's metric,
   both variants. No network can beat a field fitted to the answer, so this is the
   most a field Model_BA of this resolution can reach.
2. **What the map predicts.** Per SLAM wall face, the signed offset along its normal to
   the nearest plan face looking the same way (within 4 px): its mean is the part common
   to every map (a bias a network learns at once), its spread the part that differs wall
   by wall (drift), which only the map's own content could reveal.

    python3 -m map2map.experiments.table53.field_ceiling --data DS --split val --n 40

Prints one line per map and the medians; README.md (the table53 write-up) has the
result.
"""

from __future__ import annotations

import argparse
import sys
import warnings

import cv2
import numpy as np

from map2map.core.grid import UNKNOWN, OccupancyMap
from map2map.evaluate.align import AlignParams, align_maps
from map2map.evaluate.pipeline import EvaluateParams, evaluate_maps
from map2map.experiments.table53.measure import heldout_pairs_from_dataset
from map2map.learn.ba.field import face_sets, fit_field, warp


def plan_in_slam_frame(plan: np.ndarray, slam: np.ndarray) -> np.ndarray:
    """The plan resampled into the SLAM map's pixels by the rigid part of the alignment."""
    al = align_maps(slam, plan, params=AlignParams(seed=0))
    half = np.array([[1.0, 0, 0.5], [0, 1, 0.5], [0, 0, 1]])
    m_cv = np.linalg.inv(half) @ al.rigid @ half          # OpenCV: pixel centres at 0
    return cv2.warpAffine(plan, m_cv[:2], (slam.shape[1], slam.shape[0]),
                          flags=cv2.INTER_NEAREST | cv2.WARP_INVERSE_MAP, borderValue=UNKNOWN)


def face_offsets(slam: np.ndarray, plan_b: np.ndarray, reach: int = 4) -> np.ndarray:
    """Signed offsets (px, positive towards the free side) from each SLAM face to the
    nearest plan face looking the same way along its normal, NaN where none within
    ``reach``.

    >>> p = np.full((5, 9), 255, np.uint8); p[:, 2] = 0
    >>> s = np.full((5, 9), 255, np.uint8); s[:, 1] = 0
    >>> face_offsets(s, p)[:2].tolist()          # the SLAM wall lies 1 px short of the plan's
    [1.0, 1.0]
    """
    fs, fp = face_sets(slam), face_sets(plan_b)
    H, W = slam.shape
    out = []
    for k, (step_y, step_x) in enumerate(((0, 1), (1, 0), (0, -1), (-1, 0))):  # DIRECTIONS
        ys, xs = np.nonzero(fs[k])
        best = np.full(len(ys), np.nan)
        for s in sorted(range(-reach, reach + 1), key=abs):
            yy, xx = ys + s * step_y, xs + s * step_x
            ok = (yy >= 0) & (yy < H) & (xx >= 0) & (xx < W)
            hit = np.zeros(len(ys), bool)
            hit[ok] = fp[k][yy[ok], xx[ok]]
            new = hit & np.isnan(best)
            best[new] = s
        out.append(best)
    return np.concatenate(out) if out else np.zeros(0)


def _errors(m: np.ndarray, plan: np.ndarray) -> tuple[float, float]:
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            ev = evaluate_maps(OccupancyMap(m, 0.05), OccupancyMap(plan, 0.05),
                               params=EvaluateParams(seed=0))
        c = ev.report["chosen_errors"]
        return float(c["mean_px"]), float(c["mean_all_px"])
    except Exception:  # the alignment fails on some maps
        return float("nan"), float("nan")


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(prog="python -m map2map.experiments.table53.field_ceiling",
                                 description=__doc__.split("\n\n")[0])
    ap.add_argument("--data", required=True, help="dataset folder or packed .npz")
    ap.add_argument("--split", nargs="+", default=["val"])
    ap.add_argument("--n", type=int, default=40)
    ap.add_argument("--all", action="store_true", help="every finished pair, not only 'complete'")
    ap.add_argument("--grid", type=int, default=64, help="control points per side (default 64)")
    ap.add_argument("--smooth", type=float, default=1.0, help="smoothness weight (default 1)")
    a = ap.parse_args(argv)
    pairs = heldout_pairs_from_dataset(a.data, tuple(a.split), a.n,
                                       keep=() if a.all else ("complete",))
    rows, offs = [], []
    for i, pid in enumerate(pairs.plan_id):
        plan, slam = pairs.a[i], pairs.b[i]
        plan_b = plan_in_slam_frame(plan, slam)
        u = fit_field(slam, plan_b, a.grid, a.smooth)
        off = face_offsets(slam, plan_b)
        offs.append(off[~np.isnan(off)])
        r = (*_errors(slam, plan), *_errors(warp(slam, u), plan), float(np.abs(u).mean()))
        rows.append(r)
        print(f"{pid}: input {r[0]:.3f} / {r[1]:.3f} px, fitted field {r[2]:.3f} / {r[3]:.3f} px "
              f"(mean |u| {r[4]:.2f} px)", flush=True)
    r = np.array(rows)
    med = np.nanmedian(r, axis=0)
    off = np.concatenate(offs)
    print(f"\n{len(rows)} maps, median Error (matched points / every point):")
    print(f"  input                     {med[0]:.3f} / {med[1]:.3f} px")
    print(f"  field fitted to the plan  {med[2]:.3f} / {med[3]:.3f} px  ({a.grid}x{a.grid}, "
          f"smooth {a.smooth}; median mean |u| {med[4]:.2f} px)")
    print(f"face offsets to the plan ({len(off)} faces within 4 px): mean {off.mean():+.3f} px "
          f"(towards free space), std {off.std():.3f} px, |offset| <= 0.5 px on "
          f"{100 * np.mean(np.abs(off) <= 0.5):.0f} %; mean |offset| {np.abs(off).mean():.3f} px, "
          f"after removing the common bias {np.abs(off - off.mean()).mean():.3f} px")
    return 0


if __name__ == "__main__":
    sys.exit(main())
