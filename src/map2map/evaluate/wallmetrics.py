"""Wall-level agreement of a map with its plan, in the same frame: the guards that keep a
mean-error metric honest (a map that drops walls has a low mean error but a low recall).

* **wall recall** -- share of the plan's wall pixels within ``tol`` px of a map wall pixel;
* **wall precision** -- share of the map's wall pixels within ``tol`` px of a plan wall;
* **boundary F1** -- their harmonic mean (``tol`` = 2 px by default);
* **Chamfer distance** -- mean over both directions of the mean distance (px) from each
  wall pixel to the nearest wall pixel of the other map;
* **per-class IoU** -- occupied, free and unknown cells.

Examples
--------
>>> import numpy as np
>>> plan = np.full((20, 20), 255, np.uint8); plan[10, 2:18] = 0
>>> moved = np.roll(plan, 1, axis=0)                     # the wall one pixel lower
>>> m = wall_metrics(moved, plan)
>>> m["wall_recall"], m["boundary_f1"], m["chamfer_px"], round(m["iou_occupied"], 2)
(1.0, 1.0, 1.0, 0.0)
"""

from __future__ import annotations

import numpy as np
from scipy import ndimage

from ..core.grid import FREE, OCCUPIED, UNKNOWN

__all__ = ["wall_metrics"]


def _iou(a: np.ndarray, b: np.ndarray) -> float:
    union = np.logical_or(a, b).sum()
    return float(np.logical_and(a, b).sum() / union) if union else float("nan")


def wall_metrics(data: np.ndarray, plan: np.ndarray, tol: float = 2.0) -> dict[str, float]:
    """Wall recall, precision, boundary F1, Chamfer distance and per-class IoU of ``data``
    against ``plan`` (two uint8 maps of the same shape, internal convention)."""
    data, plan = np.asarray(data), np.asarray(plan)
    if data.shape != plan.shape:
        raise ValueError(f"maps differ in shape: {data.shape} vs {plan.shape}")
    mw, pw = data == OCCUPIED, plan == OCCUPIED
    out: dict[str, float] = {}
    if mw.any() and pw.any():
        d_to_map = ndimage.distance_transform_edt(~mw)
        d_to_plan = ndimage.distance_transform_edt(~pw)
        recall = float((d_to_map[pw] <= tol).mean())
        precision = float((d_to_plan[mw] <= tol).mean())
        chamfer = float(0.5 * (d_to_map[pw].mean() + d_to_plan[mw].mean()))
    else:
        recall = 0.0 if pw.any() else float("nan")
        precision = 0.0 if mw.any() else float("nan")
        chamfer = float("inf") if (mw.any() or pw.any()) else float("nan")
    f1 = 2 * recall * precision / (recall + precision) if recall + precision > 0 else 0.0
    out.update(wall_recall=recall, wall_precision=precision, boundary_f1=float(f1),
               chamfer_px=chamfer)
    for name, v in (("occupied", OCCUPIED), ("free", FREE), ("unknown", UNKNOWN)):
        out[f"iou_{name}"] = _iou(data == v, plan == v)
    return out
