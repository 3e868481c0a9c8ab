"""Figures of the assessment: overlay of the aligned maps, error heat map, batch box plot.

All drawn in the plan's pixel coordinates (x = column, y = row) with a metric
scale bar (:mod:`map2map.core.viz`), cropped to the known content of both maps.

Examples
--------
>>> import numpy as np, tempfile, pathlib
>>> from map2map.core.grid import OccupancyMap
>>> plan = OccupancyMap(np.full((40, 60), 255, np.uint8), 0.05); plan.data[20, :] = 0
>>> warped = plan.data.copy(); warped[20, :] = 255; warped[22, :] = 0
>>> out = pathlib.Path(tempfile.mkdtemp())
>>> overlay_figure(plan, warped, out / "overlay.png")
>>> pts = np.column_stack([np.arange(60) + 0.5, np.full(60, 22.5)])
>>> error_map_figure(plan, pts, np.full(60, 2.0), out / "error_map.png")
>>> error_boxplot({"a": np.ones(5), "b": np.arange(5.0)}, out / "box.png", unit="px")
>>> sorted(p.name for p in out.iterdir())
['box.png', 'error_map.png', 'overlay.png']
"""

from __future__ import annotations

import os

import numpy as np

from ..core.grid import FREE, OCCUPIED, UNKNOWN, OccupancyMap
from ..core.viz import add_scale_bar, new_figure, save_figure

__all__ = ["overlay_figure", "error_map_figure", "error_boxplot"]

PLAN_COLOUR = np.array([0.12, 0.35, 0.85])  # blue
SLAM_COLOUR = np.array([0.90, 0.30, 0.05])  # orange-red
BOTH_COLOUR = np.array([0.10, 0.10, 0.10])  # where the walls agree


def _crop_box(*masks: np.ndarray, pad: int = 10) -> tuple[int, int, int, int]:
    known = np.zeros_like(masks[0], bool)
    for m in masks:
        known |= m
    rows = np.flatnonzero(known.any(1))
    cols = np.flatnonzero(known.any(0))
    if rows.size == 0:
        return 0, masks[0].shape[0], 0, masks[0].shape[1]
    h, w = known.shape
    return (
        max(0, rows[0] - pad),
        min(h, rows[-1] + pad + 1),
        max(0, cols[0] - pad),
        min(w, cols[-1] + pad + 1),
    )


def _thicken(mask: np.ndarray, size: int) -> np.ndarray:
    """Walls thickened so that they survive the figure's downsampling."""
    if size <= 1:
        return mask
    import cv2

    return cv2.dilate(mask.astype(np.uint8), np.ones((size, size), np.uint8)) > 0


def overlay_figure(
    plan: OccupancyMap,
    warped: np.ndarray,
    path: str | os.PathLike,
    *,
    title: str = "SLAM map aligned to the plan",
) -> None:
    """Plan walls in blue, aligned SLAM walls in orange, agreeing walls in black."""
    r0, r1, c0, c1 = _crop_box(plan.data != UNKNOWN, warped != UNKNOWN)
    p = plan.data[r0:r1, c0:c1]
    s = warped[r0:r1, c0:c1]
    thick = max(1, int(round(max(p.shape) / 900)))
    pw = _thicken(p == OCCUPIED, thick)
    sw = _thicken(s == OCCUPIED, thick)
    rgb = np.ones((*p.shape, 3))
    rgb[(p == FREE) | (s == FREE)] = 0.97
    rgb[(p == UNKNOWN) & (s == UNKNOWN)] = 0.85
    rgb[pw] = PLAN_COLOUR
    rgb[sw] = SLAM_COLOUR
    rgb[pw & sw] = BOTH_COLOUR
    view = OccupancyMap(p.copy(), plan.resolution)
    fig, ax = new_figure(view, panel_inches=7.0)
    ax.imshow(rgb, interpolation="antialiased", extent=(c0, c1, r1, r0))
    ax.set_xlabel("plan x (px)")
    ax.set_ylabel("plan y (px)")
    ax.set_title(title, fontsize=10)
    from matplotlib.patches import Patch

    ax.legend(
        handles=[
            Patch(color=PLAN_COLOUR, label="plan walls"),
            Patch(color=SLAM_COLOUR, label="SLAM walls (aligned)"),
            Patch(color=BOTH_COLOUR, label="both"),
        ],
        loc="upper right",
        fontsize=8,
        framealpha=0.8,
    )
    if plan.scale_known:
        add_scale_bar(ax, plan.resolution, c1 - c0)
    save_figure(fig, path)


UNMATCHED_COLOUR = "#d01cc8"  # magenta: points that match no plan wall


def error_map_figure(
    plan: OccupancyMap,
    points: np.ndarray,
    errors_px: np.ndarray,
    path: str | os.PathLike,
    *,
    resolution: float | None = None,
    excluded: np.ndarray | None = None,
    unmatched: np.ndarray | None = None,
    title: str = "Local error of the SLAM walls (Algorithm 1)",
) -> None:
    """Each SLAM wall point at its rigidly aligned position, coloured by its error.

    The colour bar is in centimetres when ``resolution`` is known, else pixels;
    points that match no plan wall (``unmatched``: clutter, unplanned structure) are
    drawn in magenta, points left out as corners (``excluded``) small and grey.
    Points are drawn at least 2.5 pt wide so that they stay visible in print.
    """
    import matplotlib.pyplot as plt
    from matplotlib.lines import Line2D

    pts = np.asarray(points, float).reshape(-1, 2)
    inside = (
        (pts[:, 0] >= 0) & (pts[:, 0] < plan.width) & (pts[:, 1] >= 0) & (pts[:, 1] < plan.height)
    )
    mask = np.zeros(plan.shape, bool)
    ij = np.floor(pts[inside]).astype(int)
    mask[ij[:, 1], ij[:, 0]] = True
    r0, r1, c0, c1 = _crop_box(plan.data != UNKNOWN, mask)
    p = plan.data[r0:r1, c0:c1]
    bg = np.ones((*p.shape, 3))
    bg[p == UNKNOWN] = 0.9
    bg[p == OCCUPIED] = 0.55
    unit, scale = ("cm", resolution * 100.0) if resolution else ("px", 1.0)
    e = np.asarray(errors_px, float) * scale
    n = len(pts)
    corner = np.zeros(n, bool) if excluded is None else np.asarray(excluded, bool)
    unm = np.zeros(n, bool) if unmatched is None else np.asarray(unmatched, bool)
    corner = corner & ~unm
    keep = ~corner & ~unm
    view = OccupancyMap(p.copy(), plan.resolution)
    fig, ax = new_figure(view, panel_inches=7.0)
    ax.imshow(bg, interpolation="antialiased", extent=(c0, c1, r1, r0))
    # marker area in pt^2: dense maps get smaller dots, never below ~2.5 pt across
    size = float(np.clip(12000.0 / max(n, 1), 6.0, 36.0))
    if corner.any():
        ax.scatter(pts[corner, 0], pts[corner, 1], s=size * 0.6, c="0.55", lw=0)
    if unm.any():
        ax.scatter(pts[unm, 0], pts[unm, 1], s=size, c=UNMATCHED_COLOUR, marker="x", lw=0.8)
    vmax = float(np.percentile(e[keep], 99)) if keep.any() else 1.0
    sc = ax.scatter(
        pts[keep, 0], pts[keep, 1], s=size, c=e[keep], cmap="turbo", vmin=0.0,
        vmax=max(vmax, 1e-6), lw=0,
    )  # fmt: skip
    cb = fig.colorbar(sc, ax=ax, fraction=0.046, pad=0.02)
    cb.set_label(f"wall error ({unit})")
    handles = [
        Line2D([], [], ls="", marker="o", color="tab:blue", label=f"wall points ({keep.sum()})"),
        Line2D([], [], ls="", marker="x", color=UNMATCHED_COLOUR,
               label=f"match no plan wall ({unm.sum()})"),
        Line2D([], [], ls="", marker="o", color="0.55", label=f"corners ({corner.sum()})"),
    ]  # fmt: skip
    ax.legend(handles=handles, loc="upper right", fontsize=8, framealpha=0.85)
    ax.set_xlim(c0, c1)
    ax.set_ylim(r1, r0)
    ax.set_title(title, fontsize=10)
    ax.set_xlabel("plan x (px)")
    ax.set_ylabel("plan y (px)")
    if plan.scale_known:
        add_scale_bar(ax, plan.resolution, c1 - c0)
    save_figure(fig, path)
    plt.close("all")


def error_boxplot(
    errors: dict[str, np.ndarray], path: str | os.PathLike, *, unit: str = "cm"
) -> None:
    """One box per map pair of its per-point errors (the thesis's Fig. 5.12)."""
    import matplotlib.pyplot as plt

    names = list(errors)
    fig, ax = plt.subplots(figsize=(max(4.0, 0.6 * len(names) + 2), 4.0))
    ax.boxplot([np.asarray(errors[n], float) for n in names], showfliers=False)
    ax.set_xticks(range(1, len(names) + 1), names, rotation=45, ha="right", fontsize=8)
    ax.set_ylabel(f"local error ({unit})")
    ax.set_title("Errors per map pair (whiskers 1.5 IQR, outliers hidden)", fontsize=10)
    ax.grid(axis="y", alpha=0.3)
    save_figure(fig, path)
