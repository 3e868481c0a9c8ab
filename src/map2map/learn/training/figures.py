"""Figures of the learning stage: loss curves (thesis Fig. 5.2), sample grids, before/after.

Examples
--------
>>> import numpy as np, tempfile, pathlib
>>> d = pathlib.Path(tempfile.mkdtemp())
>>> rows = [{"epoch": 1, "loss_G": 3.0, "loss_D": 1.2}, {"epoch": 2, "loss_G": 2.5, "loss_D": 1.3}]
>>> save_loss_curves(rows, d / "losses.png")
>>> g = np.zeros((2, 8, 8), np.uint8)
>>> save_sample_grid(g, g.astype(np.float32), g, d / "grid.png")
>>> sorted(p.name for p in d.iterdir())
['grid.png', 'losses.png']
"""

from __future__ import annotations

import os

import cv2
import numpy as np

from ...core._io import atomic_path
from ...core.grid import OccupancyMap

__all__ = ["save_loss_curves", "save_sample_grid", "save_before_after"]

TERMS = ("gan_domain_3_3", "gan_real_fake_3_4", "fm_3_5", "ic_3_6", "l1_3_7",
         "d_domain_3_3", "d_real_fake_3_4")


def save_loss_curves(history: list[dict], path: str | os.PathLike, title: str = "Model_BA",
                     figure: str = "5.2") -> None:
    """Generator (G) and discriminator (D) losses per epoch, as thesis Fig. 5.2 (Model_BA;
    ``figure="5.1"`` for Model_AB), and every term of eq. 3.2 in a second panel. Where
    the rows carry a ``resolution`` (progressive training), every switch is marked by a
    dashed line and the new resolution."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    ep = [r["epoch"] for r in history]
    fig, axes = plt.subplots(1, 2, figsize=(11, 4))
    axes[0].plot(ep, [r["loss_G"] for r in history], label="G")
    axes[0].plot(ep, [r["loss_D"] for r in history], label="D")
    axes[0].set(xlabel="epoch", ylabel="loss",
                title=f"{title}: G and D losses (Fig. {figure})")
    terms = [t for t in TERMS if history and t in history[0]]
    for t in terms:
        axes[1].plot(ep, [max(r[t], 1e-6) for r in history], label=t)
    axes[1].set(xlabel="epoch", yscale="log", title="terms of eq. 3.2 (l1 unweighted)")
    for prev, row in zip(history, history[1:], strict=False):
        if row.get("resolution") != prev.get("resolution"):
            for ax in axes:
                ax.axvline(row["epoch"] - 0.5, color="0.5", ls="--", lw=0.8)
            axes[0].annotate(f"{row['resolution']} px", (row["epoch"] - 0.5, 1.0),
                             xycoords=("data", "axes fraction"), fontsize=7, ha="left",
                             va="top", rotation=90)
    axes[0].legend()
    if terms:
        axes[1].legend(fontsize=7)
    fig.tight_layout()
    with atomic_path(path) as tmp:
        fig.savefig(tmp, dpi=90, format="png")
    plt.close(fig)


def save_sample_grid(inputs: np.ndarray, outputs: np.ndarray, targets: np.ndarray,
                     path: str | os.PathLike, scale: int | None = None) -> None:
    """Rows of ``input | output | target`` maps (grey, [0, 255]), enlarged to >= 128 px
    with nearest neighbour so single pixels stay visible, separated by a mid-grey line."""
    n, s = len(inputs), inputs.shape[-1]
    scale = scale or max(1, 128 // s)
    rows = []
    for i in range(n):
        tiles = [np.clip(np.asarray(m[i], np.float32), 0, 255).astype(np.uint8)
                 for m in (inputs, outputs, targets)]
        tiles = [np.kron(t, np.ones((scale, scale), np.uint8)) for t in tiles]
        sep = np.full((s * scale, 2), 64, np.uint8)
        rows.append(np.concatenate([tiles[0], sep, tiles[1], sep, tiles[2]], 1))
    grid = np.concatenate([np.concatenate([r, np.full((2, r.shape[1]), 64, np.uint8)])
                           for r in rows])
    head = np.full((18, grid.shape[1]), 255, np.uint8)
    w = s * scale + 2
    for k, name in enumerate(("input", "output", "target")):
        cv2.putText(head, name, (k * w + 4, 13), cv2.FONT_HERSHEY_SIMPLEX, 0.4, 0, 1)
    with atomic_path(path) as tmp:
        ok, buf = cv2.imencode(".png", np.concatenate([head, grid]))
        tmp.write_bytes(buf.tobytes())


def save_before_after(before: OccupancyMap, after: OccupancyMap, path: str | os.PathLike,
                      segments: np.ndarray | None = None, title: str = "",
                      label: str = "Model_BA") -> None:
    """Input SLAM map | auto-corrected map (its wall segments in red, continuous pixel
    coordinates of the map), metric axes, zoomed on the input's known part; ``label``
    names what corrected it (the right panel's title)."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    h, w = before.shape
    ext = (0, w * before.resolution, 0, h * before.resolution)
    fig, axes = plt.subplots(1, 2, figsize=(11, 5.5 * h / max(w, 1) + 0.8))
    for ax, m, name in ((axes[0], before, "SLAM map (input)"),
                        (axes[1], after, f"auto-corrected ({label})")):
        ax.imshow(m.data, cmap="gray", vmin=0, vmax=255, extent=ext, interpolation="nearest")
        ax.set(title=name, xlabel="m")
    r = before.resolution
    if segments is not None and len(segments):
        for x0, y0, x1, y1 in segments:
            axes[1].plot([x0 * r, x1 * r], [(h - y0) * r, (h - y1) * r], "r-", lw=0.8)
    box = before.content_bbox()
    if box is not None:  # zoom on the known part (plus 5 %)
        r0, r1, c0, c1 = box
        pad = 0.05 * max(r1 - r0, c1 - c0)
        for ax in axes:
            ax.set_xlim(max(0, c0 - pad) * r, min(w, c1 + pad) * r)
            ax.set_ylim((h - min(h, r1 + pad)) * r, (h - max(0, r0 - pad)) * r)
    if title:
        fig.suptitle(title, fontsize=9)
    fig.tight_layout()
    with atomic_path(path) as tmp:
        fig.savefig(tmp, dpi=100, format="png")
    plt.close(fig)
