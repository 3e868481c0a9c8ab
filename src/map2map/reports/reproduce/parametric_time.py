"""Thesis Table 5.4 and Fig. 5.13: run time of the parametric model, EKF vs additive.

The thesis (section 5.2) timed its Matlab parametric model on five HouseExpo plans: the
EKF conversion (eqs. 3.54-3.80) took 15-94 s at 64 x 64 (then resized to 256 by
bilinear interpolation) and ran 7 h before running out of memory at high resolution; the
additive method of [58] (eqs. 3.81-3.90) took 2.6-3.6 s per map "even for very high
resolutions (ex: 1600x1600)". Here: generated apartments rasterised at 64, 256 and 1600
pixels (the same metric plan, only the resolution changes), one trajectory per plan
(a 5-node tour planned on the 256 px plan), :func:`map2map.parametric.deform` timed
(wall clock and CPU of this process; trajectory planning excluded) for EKF at 64 and 256
and additive at 256 and 1600, and the two conversions' displacement fields side by
side (Fig. 5.13).

Examples
--------
>>> TITLE.split(":")[0], max(v[0] for v in THESIS_TABLE54.values())   # the thesis's worst EKF
('Table 5.4 / Fig. 5.13', 94.4141)
>>> _additive_sentence(3.1, 0.03, 1.0).split(",")[0]
"at 256x256 103x faster than the thesis's mean 3.1 s"
"""

from __future__ import annotations

import tempfile
import time
from pathlib import Path

import numpy as np

from ._base import Context, Output, fmt, png_of

TITLE = "Table 5.4 / Fig. 5.13: parametric model run time, EKF vs additive"
THESIS_TABLE54 = {  # map -> (EKF low res, EKF "high res", method of [58]) seconds
    "1.2": (74.8616, 44.6421, 3.1995),
    "2.2": (15.1272, 15.5864, 2.62),
    "3.2": (20.2189, 19.3533, 2.7361),
    "4.2": (34.1854, 34.1854, 3.6313),
    "5.2": (94.4141, 94.4141, 3.225),
}
CASES = (("ekf", 64), ("ekf", 256), ("additive", 256), ("additive", 1600))


def _timed(fn, repeats: int):
    fn()  # warm-up: numba from its cache, first allocations
    wall, cpu, out = [], [], None
    for _ in range(repeats):
        t0, c0 = time.perf_counter(), time.process_time()
        out = fn()
        wall.append(time.perf_counter() - t0)
        cpu.append(time.process_time() - c0)
    return out, float(np.median(wall)), float(np.median(cpu))


def run(ctx: Context, out: Output) -> None:
    from map2map.maps.floorplan import generate_floorplan
    from map2map.maps.preprocess import preprocess
    from map2map.parametric import ParametricParams, deform, make_trajectory

    n_plans = ctx.size(5, 2, 1)
    repeats = ctx.size(3, 1, 1)
    sizes = sorted({n for _, n in CASES})
    if ctx.tiny:
        sizes = [64, 256]
    params = ParametricParams()
    rows, times, fields = [], {c: [] for c in CASES}, []
    for k in range(n_plans):
        seed = ctx.seed + k
        fp = generate_floorplan(seed, kind="apartment")
        plans = {n: preprocess(fp, n) for n in sizes}
        traj, _ = make_trajectory(plans[256], params, np.random.default_rng(seed), tour=5)
        row = [f"apartment {seed}", f"{fp.width * fp.resolution:.1f} x "
               f"{fp.height * fp.resolution:.1f}", f"{traj.length:.0f}"]  # fmt: skip
        res_by = {}
        for method, n in CASES:
            if n not in plans:
                row.append("-")
                continue
            res, wall, cpu = _timed(
                lambda m=plans[n], method=method, t=traj, s=seed: deform(
                    m, t, method, params, np.random.default_rng(s)),
                repeats,
            )  # fmt: skip
            res_by[(method, n)] = res
            times[(method, n)].append((wall, cpu))
            row.append(f"{wall:.2f} ({cpu:.2f})")
        rows.append(row)
        for n in (64, 256):
            for method in ("ekf", "additive"):
                r = res_by.get((method, n)) or deform(plans[n], traj, method, params,
                                                      np.random.default_rng(seed))  # fmt: skip
                st = r.field.stats(r.observed)
                fields.append((seed, n, method, st["mean"] * plans[n].resolution,
                               st["max"] * plans[n].resolution))  # fmt: skip
        if k == 0:
            first = (plans, res_by, traj)
    out.table(["plan", "size (m)", "path (m)"] + [f"{m} {n}x{n} s" for m, n in CASES], rows,
              caption="Wall seconds (CPU seconds) of one deform run, median of "
                      f"{repeats} after a warm-up; trajectory planning excluded")  # fmt: skip
    out.table(["seed", "pixels", "method", "mean |d| (m)", "max |d| (m)"],
              [[s, f"{n}x{n}", m, fmt(a, 3), fmt(b, 3)] for s, n, m, a, b in fields],
              caption="Fig. 5.13 in numbers: the displacement field of each conversion on "
                      "the same plan and trajectory (observed pixels)")  # fmt: skip

    med = {f"{m}_{n}": {"wall_s": float(np.median([w for w, _ in v])),
                        "cpu_s": float(np.median([c for _, c in v])),
                        "max_wall_s": float(np.max([w for w, _ in v]))}
           for (m, n), v in times.items() if v}  # fmt: skip
    out.result("run_time", med)
    out.result("plans", n_plans)
    ekf_mean = float(np.mean([r[3] for r in fields if r[2] == "ekf" and r[1] == 256]))
    add_mean = float(np.mean([r[3] for r in fields if r[2] == "additive" and r[1] == 256]))
    out.result("mean_displacement_m_256", {"ekf": ekf_mean, "additive": add_mean})
    ekf = [THESIS_TABLE54[k][0] for k in THESIS_TABLE54]
    add = [THESIS_TABLE54[k][2] for k in THESIS_TABLE54]
    e64 = med["ekf_64"]
    out.numbers({
        "EKF 64x64": f"{e64['wall_s']:.2f} s (thesis {min(ekf):.0f}-{max(ekf):.0f} s)",
        "additive 256x256": f"{med['additive_256']['wall_s']:.2f} s",
        **({"additive 1600x1600": f"{med['additive_1600']['wall_s']:.2f} s "
            f"(thesis {min(add):.1f}-{max(add):.1f} s)"} if "additive_1600" in med else {}),
        "EKF 256x256": f"{med['ekf_256']['wall_s']:.2f} s (thesis: 7 h, out of memory)",
    })  # fmt: skip
    out.compare("EKF at 64x64 (Table 5.4)", f"{min(ekf):.0f}-{max(ekf):.0f} s",
                f"{e64['wall_s']:.2f} s wall ({e64['cpu_s']:.2f} s CPU)",
                "decimated landmarks, one stacked update per key pose and numba kernels "
                "instead of Matlab with a landmark per pixel: orders of magnitude faster "
                "(different machines, too).")  # fmt: skip
    out.compare("EKF at high resolution", "7 h, then out of memory",
                f"{med['ekf_256']['wall_s']:.2f} s wall ({med['ekf_256']['cpu_s']:.2f} s CPU) "
                "at 256x256",
                "the thesis made every observed pixel a landmark (a 2HW state); ours are "
                "the wall pixels decimated to at most ekf_max_landmarks, so the state does "
                "not grow with the resolution.")  # fmt: skip
    if "additive_1600" in med:
        out.compare("additive (method of [58])", f"{min(add):.1f}-{max(add):.1f} s per map",
                    f"{med['additive_256']['cpu_s']:.2f} s CPU at 256, "
                    f"{med['additive_1600']['cpu_s']:.2f} s CPU at 1600 (wall "
                    f"{med['additive_256']['wall_s']:.2f} and "
                    f"{med['additive_1600']['wall_s']:.2f} s)",
                    _additive_sentence(float(np.mean(add)), med["additive_256"]["cpu_s"],
                                       med["additive_1600"]["cpu_s"]))
    out.compare("EKF vs additive deformation (Fig. 5.13)", "\"the deformations are similar\"",
                f"mean |d| EKF {100 * ekf_mean:.1f} cm, additive {100 * add_mean:.1f} cm "
                "(256x256)",
                "ours differ: the EKF corrects re-observed landmarks, so its drift stays "
                "smaller than the additive sum of odometry errors; the thesis judged by eye.")
    _houseexpo(ctx, out, params, repeats)
    out.comparison_table()
    _figure(out, *first)


HOUSEEXPO_ID = "0a1b29dba355df2ab02630133187bfab"


def _houseexpo(ctx: Context, out: Output, params, repeats: int) -> None:
    """A real HouseExpo plan (the thesis's source) with its recorded trajectory, if present."""
    from map2map.maps.houseexpo import houseexpo_to_world, load_houseexpo
    from map2map.parametric import deform
    from map2map.trajectory import read_trajectory
    from map2map.trajectory.timing import trajectory_from_poses

    folder = None if ctx.data is None else ctx.data / "houseexpo" / "json"
    if folder is None or not (folder / f"{HOUSEEXPO_ID}_trajectory.csv").is_file():
        out.note("The real HouseExpo plan with a recorded trajectory (../shared/data) is not "
                 "on this machine: its row is left out.")  # fmt: skip
        return
    plan = load_houseexpo(folder / f"{HOUSEEXPO_ID}.json", resolution=0.05)
    rec = read_trajectory(folder / f"{HOUSEEXPO_ID}_trajectory.csv")
    traj = trajectory_from_poses(*houseexpo_to_world(rec.x, rec.y, rec.theta))
    rows, res = [], {}
    for method in ("ekf", "additive"):
        r, wall, cpu = _timed(lambda m=method: deform(plan, traj, m, params,
                                                      np.random.default_rng(ctx.seed)),
                              repeats)  # fmt: skip
        st = r.field.stats(r.observed)
        res[method] = {"wall_s": wall, "cpu_s": cpu, "mean_displacement_px": st["mean"]}
        rows.append([method, f"{plan.width}x{plan.height}", f"{wall:.2f}", f"{cpu:.2f}",
                     r.drawn["key_poses"], fmt(st["mean"])])  # fmt: skip
    out.table(["method", "pixels (0.05 m)", "wall s", "CPU s", "key poses", "mean |d| px"],
              rows, caption=f"HouseExpo {HOUSEEXPO_ID[:8]} (a plan of the thesis's dataset) "
                            f"with its recorded {traj.length:.0f} m trajectory")  # fmt: skip
    out.result("houseexpo", res)
    out.compare("a real HouseExpo plan", "Table 5.4: 15-94 s (EKF), 2.6-3.6 s (additive)",
                f"EKF {res['ekf']['cpu_s']:.2f} s, additive {res['additive']['cpu_s']:.2f} s "
                "CPU", "the same speed-up on a plan of the thesis's own dataset.")


def _figure(out: Output, plans, res_by, traj) -> None:
    """Fig. 5.13: the same plan deformed by each conversion, side by side."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from map2map.core.viz import draw_map
    from map2map.parametric.figures import deform_figure, draw_trajectory

    cases = [c for c in CASES if c in res_by]
    fig, axes = plt.subplots(1, len(cases) + 1, figsize=(3.2 * (len(cases) + 1), 3.6))
    draw_map(axes[0], plans[256], title="plan 256x256 + trajectory")
    draw_trajectory(axes[0], plans[256], traj)
    for ax, (m, n) in zip(axes[1:], cases, strict=True):
        r = res_by[(m, n)]
        draw_map(ax, r.map, title=f"{m} {n}x{n}", scale_bar=False)
    fig.suptitle("Fig. 5.13: odometry-to-map conversions on the same plan and trajectory",
                 fontsize=10)  # fmt: skip
    fig.tight_layout()
    out.figure(png_of(fig), "Fig. 5.13: the modelled SLAM map of one plan by each conversion "
               "and resolution (same trajectory, same noise seed)",
               alt="plan and four modelled SLAM maps")  # fmt: skip
    with tempfile.TemporaryDirectory() as tmp:
        for m in ("ekf", "additive"):
            p = Path(tmp) / f"{m}.png"
            deform_figure(plans[256], res_by[(m, 256)], p, title=f"modelled SLAM map ({m})")
            out.figure_file(p, f"Displacement field of the {m} conversion at 256x256 "
                            "(|d| in pixels, arrows: direction)",
                            alt=f"{m} displacement field")  # fmt: skip


def _additive_sentence(thesis_mean: float, t256: float, t1600: float) -> str:
    """One sentence on the additive method's run time against the thesis's mean."""
    def rel(t):
        r = thesis_mean / max(t, 1e-9)
        return f"{r:.0f}x faster" if r >= 1.5 else ("about the same" if r > 0.67 else
                                                    f"{1 / r:.1f}x slower")
    return (f"at 256x256 {rel(t256)} than the thesis's mean {thesis_mean:.1f} s, at "
            f"1600x1600 {rel(t1600)} (39x the pixels of a 256x256 map; CPU seconds, as the "
            "wall clock depends on the machine's load).")
