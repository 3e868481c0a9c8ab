"""What gives a generator away: the crops the classifier two-sample test finds most telling,
and where in them it looks (issue #33).

Reads the maps ``per_plan.variants --save-maps DIR`` wrote (``DIR/NAME.npz``: the plans,
runs 1-3 and the variant's maps), trains one classifier of the two-sample test on run 3
against the variant's maps on three quarters of the plans
(:func:`map2map.learn.two_sample.telling_crops`), and on the held-out quarter prints its
AUC and draws the crops where the variant's map scores most above run 3's of the same
plan: plan | run 3 | variant | the gradient of the variant crop's score (where the
network looks), with two crops of median score below them for contrast::

    python -m map2map.experiments.realism.per_plan.tells DIR/NAME.npz --out tells.png
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import numpy as np


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(prog="python -m map2map.experiments.realism.per_plan.tells",
                                 description=__doc__.split("\n\n")[0])
    ap.add_argument("maps", help="a NAME.npz of per_plan.variants --save-maps")
    ap.add_argument("--out", default="tells.png", help="the figure (default tells.png)")
    ap.add_argument("--top", type=int, default=6, help="telling crops drawn (default 6)")
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--steps", type=int, default=12000,
                    help="the most Adam steps (early stopping, patience 5; default 12000)")
    ap.add_argument("--against", default="run3", choices=("run1", "run2", "run3"),
                    help="the simulated maps the variant is told from (default run3; "
                    "run2 against run3 is the floor: no crop should tell)")
    a = ap.parse_args(argv)
    from map2map.learn.two_sample import telling_crops

    path = Path(a.maps)
    try:
        with np.load(path) as z:
            plans, sim, gen = z["plans"], z[a.against], z["maps"]
    except (OSError, KeyError, ValueError) as exc:
        print(f"error: {path}: not a per_plan.variants --save-maps file ({exc})",
              file=sys.stderr)
        return 2
    t = telling_crops(plans, sim, gen, top=a.top, seed=a.seed, steps=a.steps)
    print(describe(t, path.stem, a.against, len(plans), a.top))
    _figure(t, plans, sim, gen, a.top, a.against, path.stem, Path(a.out))
    print(f"figure: {a.out}")
    return 0


def describe(t, name: str, against: str, plans: int, top: int) -> str:
    """Two lines on a :class:`~map2map.learn.two_sample.TellingCrops`.

    Examples
    --------
    >>> from map2map.learn.two_sample import TellingCrops
    >>> crops = np.array([[3, 0, 0, 2.5, 1.0], [4, 32, 0, -0.5, -1.0]])
    >>> t = TellingCrops(0.75, np.array([3, 4]), crops, np.zeros((1, 8, 8), np.float32), 400)
    >>> print(describe(t, "scans", "run3", 8, 1))   # doctest: +NORMALIZE_WHITESPACE
    scans against run3: 8 plans, held out 2; classifier trained 400 steps, held-out AUC 0.750
    crops of the held-out plans: 2; the variant's scores higher than run3's on 50 %,
    by +1.00 on average (top 1: [2.5])
    """
    d = t.crops[:, 3]
    return (f"{name} against {against}: {plans} plans, held out {len(t.test)}; classifier "
            f"trained {t.steps} steps, held-out AUC {t.auc:.3f}\n"
            f"crops of the held-out plans: {len(d)}; the variant's scores higher than "
            f"{against}'s on {100 * np.mean(d > 0):.0f} %,\nby {np.mean(d):+.2f} on average "
            f"(top {top}: {np.round(d[:top], 1).tolist()})")


def _figure(t, plans, sim, gen, top, against, name, out: Path) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    mid = len(t.crops) // 2
    rows = [(r, t.saliency[k] if k < len(t.saliency) else None)
            for k, r in enumerate(t.crops[:top])] + [(r, None) for r in t.crops[mid:mid + 2]]
    crop = t.saliency.shape[-1] if len(t.saliency) else 64
    fig, axs = plt.subplots(len(rows), 4, figsize=(8, 2.1 * len(rows)), squeeze=False)
    for ax_row, (r, sal) in zip(axs, rows, strict=True):
        i, y, x = (int(v) for v in r[:3])
        sl = (slice(y, y + crop), slice(x, x + crop))
        for ax, m, title in ((ax_row[0], plans[i], f"plan {i}"),
                             (ax_row[1], sim[i], against),
                             (ax_row[2], gen[i], f"{name}: +{r[3]:.1f}" if r[3] >= 0
                              else f"{name}: {r[3]:.1f}")):
            ax.imshow(m[sl], cmap="gray", vmin=0, vmax=255, interpolation="nearest")
            ax.set_title(title, fontsize=7)
        if sal is not None:
            ax_row[3].imshow(sal, cmap="hot", interpolation="nearest")
            ax_row[3].set_title("where it looks", fontsize=7)
        for ax in ax_row:
            ax.axis("off")
    fig.suptitle(f"most telling crops first (held-out AUC {t.auc:.3f}); last two: median",
                 fontsize=8)
    fig.tight_layout()
    out.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(out, dpi=80)
    plt.close(fig)


if __name__ == "__main__":
    sys.exit(main())
