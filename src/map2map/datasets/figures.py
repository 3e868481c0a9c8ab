"""Figures of a dataset: a contact sheet of sample pairs, histograms, the cleaner's report.

All figures are saved atomically (PNG).

Examples
--------
>>> import tempfile, pathlib
>>> rows = [{"kind": "simulate", "coverage": c, "wall_error": 0.05, "ate": 0.1}
...         for c in (0.5, 0.9, 0.95)]
>>> histograms(rows, pathlib.Path(tempfile.mkdtemp()) / "h.png").stat().st_size > 0
True
"""

from __future__ import annotations

import json
import os
from pathlib import Path

import numpy as np

from .pairfolder import pair_dir, pictures

__all__ = ["contact_sheet", "histograms", "cleaner_figure"]


def _save(fig, path: Path) -> Path:
    from ..core._io import atomic_path

    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    with atomic_path(path) as tmp:
        fig.savefig(tmp, format="png", dpi=110, bbox_inches="tight")
    import matplotlib.pyplot as plt

    plt.close(fig)
    return path


def contact_sheet(ds: str | os.PathLike, rows, path: str | os.PathLike, n: int = 12) -> Path:
    """Up to ``n`` pairs spread over the dataset: A (plan) beside B (SLAM map), N x N.

    ``rows`` are manifest rows of done pairs (index, kind, coverage, wall error).
    """
    import cv2
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    rows = list(rows)
    pick = [rows[int(k)] for k in np.unique(np.linspace(0, len(rows) - 1, min(n, len(rows))))]
    cols = 4  # two pairs per line
    lines = int(np.ceil(len(pick) / 2))
    fig, axes = plt.subplots(lines, cols, figsize=(2.6 * cols, 2.8 * lines), squeeze=False)
    for ax in axes.ravel():
        ax.axis("off")
    for k, r in enumerate(pick):
        for j, picture in enumerate(pictures(pair_dir(ds, r["idx"]))):
            img = cv2.imread(str(picture), cv2.IMREAD_GRAYSCALE)
            ax = axes[k // 2, (k % 2) * 2 + j]
            if img is not None:
                ax.imshow(img, cmap="gray", vmin=0, vmax=255, interpolation="nearest")
            cov = r["coverage"]
            title = (
                f"#{r['idx']} plan {r['plan_id']}"
                if j == 0
                else f"{r['kind']}, cov {100 * cov:.0f} %"
                if cov is not None
                else r["kind"]
            )
            ax.set_title(title, fontsize=7)
    fig.suptitle("sample pairs: A (plan, preprocessed) | B (SLAM map)", fontsize=10)
    return _save(fig, Path(path))


def histograms(rows, path: str | os.PathLike) -> Path:
    """Histograms of coverage of the reachable free space, map (wall) error and ATE,
    simulated and parametric pairs apart."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    rows = list(rows)
    fig, axes = plt.subplots(1, 3, figsize=(13, 3.6))
    series = [
        ("coverage", "coverage of reachable free space", 1.0),
        ("wall_error", "map error: SLAM wall to nearest plan wall, mean (m)", 1.0),
        ("ate", "ATE RMSE (m), simulated pairs", 1.0),
    ]
    for ax, (key, label, _) in zip(axes, series, strict=True):
        for kind, color in (("simulate", "tab:blue"), ("deform", "tab:orange")):
            v = np.array([r[key] for r in rows if r["kind"] == kind and r[key] is not None], float)
            if v.size:
                ax.hist(v, bins=20, alpha=0.6, color=color, label=f"{kind} (n={v.size})")
        ax.set_xlabel(label, fontsize=8)
        ax.set_ylabel("pairs", fontsize=8)
        if ax.get_legend_handles_labels()[0]:
            ax.legend(fontsize=7)
    return _save(fig, Path(path))


def cleaner_figure(report: dict, path: str | os.PathLike) -> Path:
    """Confusion matrix (cross-validated) and feature importances of the cleaner."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, (a0, a1) = plt.subplots(1, 2, figsize=(12, 4.5), gridspec_kw={"width_ratios": [1, 2]})
    cm = np.asarray(report["confusion"], float)
    a0.imshow(cm, cmap="Blues")
    names = report["classes"]
    a0.set_xticks(range(len(names)), names)
    a0.set_yticks(range(len(names)), names)
    a0.set_xlabel("predicted")
    a0.set_ylabel("label")
    for (i, j), v in np.ndenumerate(cm):
        a0.text(j, i, f"{int(v)}", ha="center", va="center", fontsize=11)
    a0.set_title(f"cross-validated accuracy {100 * report['cv_accuracy']:.1f} %", fontsize=10)
    imp = report["importances"]
    order = sorted(imp, key=imp.get)
    a1.barh(range(len(order)), [imp[k] for k in order], color="tab:green")
    a1.set_yticks(range(len(order)), order, fontsize=7)
    a1.set_xlabel("feature importance (mean decrease in impurity)")
    fig.suptitle(json.dumps(report.get("labels_from", "")), fontsize=8)
    return _save(fig, Path(path))
