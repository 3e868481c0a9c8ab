"""Thesis Fig. 5.3 / Fig. 5.14: Model_AB vs the parametric model vs simulated SLAM.

The thesis compared, by eye, Model_AB's SLAM-map hypotheses of held-out plans (Fig. 5.3)
and, on the same plans, the parametric model's map and a simulated SLAM map (Fig. 5.14):
"both methods give very realistic results", the parametric one closer to the simulation
of the same trajectory, Model_AB better at removed walls and room shrinkage, the
parametric one better at doors. Here: plans built with
:func:`map2map.datasets.build.build_dataset` (``source="both"``: for each plan a
simulated TurtleBot3 + rbpf SLAM map and a parametric map, thesis 4.1 preprocessing),
Model_AB's hypothesis of the same plan (:func:`map2map.learn.synthesize.synthesize`,
pretrained weights), all three drawn side by side and measured against the plan with
the same numbers (:func:`map2map.evaluate.wallmetrics.wall_metrics`: wall recall,
boundary F1, Chamfer distance; unknown share).

Examples
--------
>>> KINDS
('simulated', 'parametric', 'Model_AB')
"""

from __future__ import annotations

import warnings

import numpy as np

from ._base import Context, Output, fmt, png_of
from ._learn import need_torch

TITLE = "Fig. 5.3 / Fig. 5.14: Model_AB vs parametric vs simulated SLAM maps"
KINDS = ("simulated", "parametric", "Model_AB")


def run(ctx: Context, out: Output) -> None:
    need_torch()
    from map2map.core.grid import UNKNOWN
    from map2map.datasets.build import build_dataset, pair_dir
    from map2map.datasets.pair import BuildParams
    from map2map.evaluate.wallmetrics import wall_metrics
    from map2map.learn.synthesize import synthesize
    from map2map.maps.formats import load_map

    plans = ctx.size(4, 2, 1)
    params = BuildParams(source="both") if not ctx.tiny else \
        BuildParams(source="both", duration=60.0, size=64)
    ds = ctx.work / "both"
    build_dataset(ds, "generated", 2 * plans, ctx.seed + 500, params, workers=0,
                  progress=False, figures=False)  # fmt: skip
    shown, stats = [], {k: [] for k in KINDS}
    model_note = ""
    for j in range(plans):
        d_sim, d_par = pair_dir(ds, 2 * j), pair_dir(ds, 2 * j + 1)
        if not ((d_sim / "A.yaml").is_file() and (d_par / "B.yaml").is_file()):
            out.note(f"plan {j}: a pair failed to build; left out")
            continue
        plan = load_map(d_sim / "A.yaml")
        sim, par = load_map(d_sim / "B.yaml").data, load_map(d_par / "B.yaml").data
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always")
            syn = synthesize(plan, "pretrained", samples=1, seed=ctx.seed)
        if caught and not model_note:
            model_note = str(caught[0].message)
        ab = syn.maps[0].data
        if ab.shape != plan.shape:
            import cv2

            ab = cv2.resize(ab, plan.shape[::-1], interpolation=cv2.INTER_NEAREST)
        for k, m in zip(KINDS, (sim, par, ab), strict=True):
            w = wall_metrics(m, plan.data)
            known = plan.data != UNKNOWN
            stats[k].append({**w, "unknown_share": float((m[known] == UNKNOWN).mean())})
        shown.append((plan.data, sim, par, ab))
    if not shown:
        raise RuntimeError("no plan built both its simulated and its parametric pair")
    keys = ("wall_recall", "boundary_f1", "chamfer_px", "unknown_share")
    rows, res = [], {}
    for k in KINDS:
        means = {q: float(np.nanmean([s[q] for s in stats[k]])) for q in keys}
        res[k] = means
        rows.append([k, *(fmt(means[q], 3) for q in keys)])
    out.table(["map", "wall recall", "boundary F1 (2 px)", "Chamfer (px)", "unknown share"],
              rows, caption=f"Each kind of SLAM map against its plan, mean over {len(shown)} "
                            "held-out plans")  # fmt: skip
    if model_note:
        out.note(f"Model_AB: {model_note}")
    out.result("plans", len(shown))
    out.result("metrics", res)
    closer = min(("parametric", "Model_AB"),
                 key=lambda k: abs(res[k]["wall_recall"] - res["simulated"]["wall_recall"]))
    out.compare("realism (Fig. 5.3, 5.14)", "judged by eye: both realistic, parametric closer "
                "to the simulation of the same trajectory",
                f"wall recall simulated {res['simulated']['wall_recall']:.2f}, parametric "
                f"{res['parametric']['wall_recall']:.2f}, Model_AB "
                f"{res['Model_AB']['wall_recall']:.2f}",
                f"measured instead of judged; the {closer} map is the closer to the "
                "simulated one in wall recall (the parametric map here follows its own "
                "trajectory, not the simulator's).")  # fmt: skip
    out.comparison_table()
    out.figure(_figure(shown), "Fig. 5.14: plan | simulated SLAM map (TurtleBot3 + rbpf) | "
               "parametric model | Model_AB hypothesis, per held-out plan",
               alt="plans with three kinds of SLAM map")  # fmt: skip


def _figure(shown):
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    names = ("plan", *KINDS)
    fig, axes = plt.subplots(len(shown), 4, figsize=(9, 2.4 * len(shown)), squeeze=False)
    for r, maps in enumerate(shown):
        for c, (img, name) in enumerate(zip(maps, names, strict=True)):
            ax = axes[r, c]
            ax.imshow(img, cmap="gray", vmin=0, vmax=255, interpolation="nearest")
            ax.set_xticks([])
            ax.set_yticks([])
            if r == 0:
                ax.set_title(name, fontsize=9)
    fig.tight_layout()
    return png_of(fig)
