"""Thesis Table 5.3 / Fig. 5.12: does Model_BA bring SLAM maps closer to their plans?

The thesis evaluated 20 held-out SLAM maps (Map 6 failed to align) with the appendix
paper's metric: Error(sim) of the SLAM map against its CAD plan, Error(gen) of Model_BA's
CAD-like output against the same plan; 15 of 20 differences Error(sim) - Error(gen) are
positive ("75 % improved"; its text calls the negative ones improvements, its table and
box plot the positive ones), the box plot spanning about -4 to +7. Here: held-out pairs
never used in training (generated plans, seeds from 100,000, the parametric model's SLAM
map: :func:`map2map.learn.synthetic.make_pairs`), the pretrained Model_BA
(:func:`map2map.learn.autocorrect.autocorrect_many`), the same metric
(:func:`map2map.evaluate.evaluate_maps`, chosen chain's mean, pixels), the one-sided
sign test, and wall recall as a guard against maps that score low errors by losing walls.

Examples
--------
>>> sum(v > 0 for v in THESIS), len(THESIS)      # the thesis's "75 % improved"
(15, 20)
"""

from __future__ import annotations

import warnings

import numpy as np

from ._base import Context, Output, fmt, png_of
from ._learn import need_torch

TITLE = "Table 5.3 / Fig. 5.12: Model_BA, SLAM map -> CAD-like plan"
HELD_OUT_SEED = 100_000
#: Thesis Table 5.3: Error(sim) - Error(gen) of maps 1-21 (Map 6 failed to align).
THESIS = [3.605497191, -1.213548915, 1.091363786, 0.411571549, 1.740986643, 4.656658349,
          -1.012509943, 7.317520375, 0.670650887, 1.861008056, -1.476125407, 6.222065703,
          1.210678083, 0.507280654, -2.556146321, 2.899847685, 0.084914512, -3.870882335,
          0.579974187, 6.350456144]  # fmt: skip


def _error(src: np.ndarray, plan: np.ndarray) -> float:
    from map2map.core.grid import OccupancyMap
    from map2map.evaluate.pipeline import evaluate_maps

    try:
        ev = evaluate_maps(OccupancyMap(src, 0.05), OccupancyMap(plan, 0.05))
    except Exception:  # the alignment fails on some maps (the thesis's Map 6)
        return float("nan")
    return float(ev.report["chosen_errors"]["mean_px"])


def run(ctx: Context, out: Output) -> None:
    need_torch()
    from scipy.stats import binomtest

    from map2map.core.grid import OccupancyMap
    from map2map.evaluate.wallmetrics import wall_metrics
    from map2map.learn.autocorrect import autocorrect_many, load_model
    from map2map.learn.synthetic import make_pairs

    n = ctx.size(20, 8, 2)
    size = 256 if not ctx.tiny else 128
    pairs = make_pairs(n, size, seed=HELD_OUT_SEED, progress=False)
    source_words = "the parametric model's (generated plans never used in training), not Gazebo's"
    model = load_model("pretrained")
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        gen = np.stack([r.map.data for r in
                        autocorrect_many([OccupancyMap(x, 0.05) for x in pairs.b], model)])
    rows, diff, rec = [], [], []
    for i in range(n):
        es, eg = _error(pairs.b[i], pairs.a[i]), _error(gen[i], pairs.a[i])
        ws, wg = wall_metrics(pairs.b[i], pairs.a[i]), wall_metrics(gen[i], pairs.a[i])
        diff.append(es - eg)
        rec.append((ws["wall_recall"], wg["wall_recall"]))
        rows.append([i + 1, fmt(es, 3), fmt(eg, 3), fmt(es - eg, 3),
                     fmt(ws["wall_recall"]), fmt(wg["wall_recall"])])  # fmt: skip
    d = np.array(diff)
    ok = np.isfinite(d)
    improved, worse = int((d[ok] > 0).sum()), int((d[ok] < 0).sum())
    p = binomtest(improved, improved + worse, 0.5, alternative="greater").pvalue \
        if improved + worse else float("nan")
    t = np.array(THESIS)
    out.table(["map", "Error(sim) px", "Error(gen) px", "sim - gen", "wall recall sim",
               "wall recall gen"], rows,
              caption=f"Our Table 5.3 on {n} held-out pairs (generated plans, seeds "
                      f"{HELD_OUT_SEED}..{HELD_OUT_SEED + n - 1}, parametric SLAM maps), "
                      f"pretrained Model_BA ({model.source})")  # fmt: skip
    out.numbers({"improved": f"{improved}/{int(ok.sum())} (thesis 15/20)",
                 "sign test p": fmt(p, 3),
                 "median sim - gen": f"{np.nanmedian(d):.2f} px (thesis "
                                     f"{np.median(t):.2f})",
                 "alignment failed": f"{int((~ok).sum())} (thesis 1, Map 6)"})  # fmt: skip
    out.result("n", n)
    out.result("improved", improved)
    out.result("evaluated", int(ok.sum()))
    out.result("share_improved", improved / max(int(ok.sum()), 1))
    out.result("p_value", p)
    out.result("median_diff_px", float(np.nanmedian(d)) if ok.any() else float("nan"))
    out.result("median_wall_recall", {"sim": float(np.median([r[0] for r in rec])),
                                      "gen": float(np.median([r[1] for r in rec]))})
    out.result("model", str(model.source))
    share = improved / max(int(ok.sum()), 1)
    why = ("as often as the thesis's model" if share >= 0.75 else
           "less often than the thesis's 75 %: the shipped Model_BA weights are provisional "
           "(CPU-trained on a few hundred pairs, docs/learn.md) against the thesis's 4,224 "
           "Gazebo pairs")
    out.compare("share improved (Table 5.3)", "15/20 = 75 %",
                f"{improved}/{int(ok.sum())} = {100 * share:.0f} % (p = {p:.2g})",
                f"improved {why}; our held-out SLAM maps are {source_words}.")  # fmt: skip
    if ok.any():
        med_d = float(np.nanmedian(d))
        spread = ("positive median: Model_BA brings the maps closer to their plans, as in the "
                  "thesis" if med_d > 0 else
                  "negative median: on these maps Model_BA's outputs score further from the "
                  "plan than the SLAM maps themselves (the thesis's median was positive); "
                  "see the examples below")
        out.compare("Fig. 5.12 spread", f"{t.min():.1f} .. {t.max():.1f} px, median "
                    f"{np.median(t):.2f}",
                    f"{np.nanmin(d):.1f} .. {np.nanmax(d):.1f} px, median {med_d:.2f}",
                    spread + ".")  # fmt: skip
    out.comparison_table()
    out.figure(_boxplot(t, d[ok]), "Fig. 5.12: Error(sim) - Error(gen), thesis (left) and "
               "ours (right); above 0: Model_BA improved the map", alt="box plots")
    out.figure(_examples(pairs.b, gen, pairs.a, d), "SLAM map | Model_BA output | plan, for "
               "the best and the worst maps", alt="examples")


def _boxplot(thesis, ours):
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(4.5, 4))
    ax.boxplot([thesis, ours if len(ours) else [np.nan]])
    ax.set_xticks([1, 2], ["thesis (20)", f"map2map ({len(ours)})"])
    ax.axhline(0, color="grey", lw=0.8)
    ax.set_ylabel("Error(sim) - Error(gen) [px]")
    fig.tight_layout()
    return png_of(fig)


def _examples(b, gen, a, d):
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    order = np.argsort(np.where(np.isfinite(d), -d, np.inf))
    picks = list(dict.fromkeys([int(order[0]), int(order[-1])]))
    fig, axes = plt.subplots(len(picks), 3, figsize=(7.5, 2.6 * len(picks)), squeeze=False)
    for row, i in enumerate(picks):
        for col, (img, name) in enumerate(((b[i], "SLAM map"), (gen[i], "Model_BA"),
                                           (a[i], "plan"))):
            ax = axes[row, col]
            ax.imshow(img, cmap="gray", vmin=0, vmax=255, interpolation="nearest")
            ax.set_xticks([])
            ax.set_yticks([])
            ax.set_title(f"{name}" + (f" (map {i + 1}, {d[i]:+.2f} px)" if col == 0 else ""),
                         fontsize=8)
    fig.tight_layout()
    return png_of(fig)
