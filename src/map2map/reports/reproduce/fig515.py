"""Thesis Fig. 5.15: a plan with its trajectory, the displacement field, the deformed map.

The thesis shows one CAD map, a user-chosen trajectory, the parametric model's
displacement field and the deformed (modelled SLAM) map, and argues that the field is a
ground truth for assessing alignment methods. Here: a generated apartment at 256 x 256
(thesis 4.1 size), a 5-node tour, the additive conversion (the one the thesis kept),
drawn by :func:`map2map.parametric.figures.deform_figure`; its numbers (path length, key
poses, mean and max displacement) go to ``results.json``.

Examples
--------
>>> TITLE.split(":")[0]
'Fig. 5.15'
"""

from __future__ import annotations

import tempfile
from pathlib import Path

import numpy as np

from ._base import Context, Output

TITLE = "Fig. 5.15: plan, trajectory, displacement field, deformed map"


def run(ctx: Context, out: Output) -> None:
    from map2map.maps.floorplan import generate_floorplan
    from map2map.maps.preprocess import preprocess
    from map2map.parametric import ParametricParams, deform, make_trajectory
    from map2map.parametric.figures import deform_figure

    params = ParametricParams()
    plan = preprocess(generate_floorplan(ctx.seed + 10, kind="apartment"), 256)
    rng = np.random.default_rng(ctx.seed)
    traj, _ = make_trajectory(plan, params, rng, tour=5)
    res = deform(plan, traj, "additive", params, rng)
    st = res.field.stats(res.observed)
    out.text(
        f"A generated apartment (seed {ctx.seed + 10}) at 256 x 256 ({plan.resolution:.3f} "
        f"m/px), a {traj.length:.1f} m tour of 5 roadmap nodes ({res.drawn['key_poses']} key "
        "poses), the additive conversion: the field is the ground truth of every pixel's "
        "displacement, what the appendix paper's metric should find."
    )
    with tempfile.TemporaryDirectory() as tmp:
        p = Path(tmp) / "fig515.png"
        deform_figure(plan, res, p)
        out.figure_file(p, "Fig. 5.15: the plan and its trajectory (left), the displacement "
                        "field |d| with its directions (middle), the deformed map (right)",
                        alt="plan with trajectory, displacement field, deformed map")  # fmt: skip
    res_m = plan.resolution
    out.numbers({
        "path": f"{traj.length:.1f} m",
        "key poses": str(res.drawn["key_poses"]),
        "mean |d|": f"{st['mean']:.2f} px = {100 * st['mean'] * res_m:.1f} cm",
        "max |d|": f"{st['max']:.2f} px = {100 * st['max'] * res_m:.1f} cm",
        "observed": f"{100 * res.observed.mean():.0f} % of the map",
    })  # fmt: skip
    out.result("path_m", traj.length)
    out.result("key_poses", int(res.drawn["key_poses"]))
    out.result("mean_displacement_px", st["mean"])
    out.result("max_displacement_px", st["max"])
    out.result("observed_share", float(res.observed.mean()))
    out.compare("Fig. 5.15", "one example, no numbers", f"mean |d| {st['mean']:.2f} px, max "
                f"{st['max']:.2f} px over {traj.length:.0f} m",
                "the same three panels; ours also states the field's size.")  # fmt: skip
    out.comparison_table()
