"""Thesis 4.1: the dataset path, pairs per hour and cleaning yield.

The thesis simulated every HouseExpo plan in Gazebo (TurtleBot3, GMapping, explore_lite)
for 7 minutes: 35,000 maps, 166 parallel scripts on a cluster, about 17 days (about 86
pairs/hour for the whole cluster, 8.6 per script). Cleaning kept 24,991 (stuck robots
removed), then an Extra Trees classifier and manual review kept 4,225 complete pairs.
Here: a small build with :func:`map2map.datasets.build.build_dataset` (generated
HouseExpo-like plans, the simulated TurtleBot3 and the ``rbpf`` SLAM backend, 7 simulated
minutes, 180-degree lidar, 256 x 256 pairs: the thesis's settings) into a scratch
folder, in this process; pairs/hour from the wall clock and, independent of the
machine's load, from the CPU seconds per pair; then the coverage labels and, when both
classes are present, the thesis's cleaner (:func:`map2map.datasets.clean.clean_dataset`).

Examples
--------
>>> round(THESIS_MAPS / (THESIS_DAYS * 24))        # the thesis's pairs per hour
86
"""

from __future__ import annotations

import os
import time

import numpy as np

from ._base import Context, Output, fmt

TITLE = "Thesis 4.1: dataset build rate and cleaning yield"
THESIS_MAPS, THESIS_DAYS, THESIS_SCRIPTS = 35_000, 17, 166
THESIS_CLEAN1, THESIS_CLEAN2 = 24_991, 4_225


def run(ctx: Context, out: Output) -> None:
    from map2map.core.errors import InputError
    from map2map.datasets.build import build_dataset, open_dataset
    from map2map.datasets.clean import COVERAGE_COMPLETE, clean_dataset
    from map2map.datasets.pair import BuildParams

    n = ctx.size(12, 4, 1)
    params = BuildParams() if not ctx.tiny else BuildParams(duration=60.0, size=64)
    ds = ctx.work / "dataset"
    t0, c0 = time.perf_counter(), time.process_time()
    s = build_dataset(ds, "generated", n, ctx.seed, params, workers=0, progress=False,
                      figures=False)  # fmt: skip
    wall, cpu = time.perf_counter() - t0, time.process_time() - c0
    with open_dataset(ds) as man:
        rows = list(man.rows("done"))
    done = len(rows)
    cov = np.array([r["coverage"] for r in rows if r["coverage"] is not None], float)
    complete = int((cov >= COVERAGE_COMPLETE).sum())
    per_pair_cpu = cpu / max(done, 1)
    wall_rate = done * 3600 / wall if wall > 0 else float("nan")
    cpu_rate = 3600 / per_pair_cpu if per_pair_cpu > 0 else float("nan")
    cores = os.cpu_count() or 1
    thesis_rate = THESIS_MAPS / (THESIS_DAYS * 24)
    out.table(["pair", "plan", "coverage", "SLAM wall error", "path (m)", "stop", "wall s"],
              [[r["idx"], r["plan_id"], fmt(r["coverage"]), fmt(r["wall_error"]),
                fmt(r["path_length"], 1), r["stop_reason"], fmt(r["wall_seconds"], 1)]
               for r in rows],
              caption=f"The {done} pairs built ({s.failed} failed): {params.duration:.0f} "
                      f"simulated s, {params.fov:.0f} deg lidar, {params.mapper}, "
                      f"{params.size} px")  # fmt: skip
    decisions = None
    if complete and complete < done:
        try:
            rep = clean_dataset(ds, figure=False)
            decisions = rep.decisions
        except InputError as exc:
            out.note(f"cleaner not trained: {exc}")
    else:
        out.note("the cleaner needs both complete and partial pairs to train; this build has "
                 f"{complete} complete of {done}: the yield below is the coverage label's")
    out.numbers({
        "pairs built": f"{done} in {wall:.0f} s wall, {cpu:.0f} s CPU",
        "pairs/hour (wall, this machine now)": f"{wall_rate:.0f}",
        "pairs/hour per core (CPU)": f"{cpu_rate:.0f}",
        "complete (coverage >= 0.8)": f"{complete}/{done}",
    })  # fmt: skip
    out.result("pairs", done)
    out.result("failed", s.failed)
    out.result("wall_s", wall)
    out.result("cpu_s_per_pair", per_pair_cpu)
    out.result("pairs_per_hour_wall", wall_rate)
    out.result("pairs_per_hour_per_core", cpu_rate)
    out.result("complete_share", complete / max(done, 1))
    out.result("coverage_mean", float(cov.mean()) if len(cov) else float("nan"))
    if decisions is not None:
        out.result("cleaner_decisions", decisions)
    out.compare("time per map", "7 min of Gazebo per map (one script)",
                f"{per_pair_cpu:.1f} CPU s per pair",
                f"a 2D simulator and SLAM in one process replace Gazebo + ROS: "
                f"{420 / max(per_pair_cpu, 1e-9):.0f}x less time per map than Gazebo's 7 "
                f"minutes ({params.duration:.0f} simulated s per map here).")  # fmt: skip
    out.compare("pairs per hour", f"~{thesis_rate:.0f}/h ({THESIS_SCRIPTS} scripts on a "
                f"cluster, {THESIS_MAPS:,} maps in {THESIS_DAYS} days)",
                f"{cpu_rate * cores:.0f}/h on this machine's {cores} cores "
                f"({wall_rate:.0f}/h measured now, one process, loaded machine)",
                f"35,000 pairs would take {THESIS_MAPS / max(cpu_rate * cores, 1e-9) / 24:.1f} "
                f"days on {cores} free cores instead of 17 on the cluster.")  # fmt: skip
    out.compare("cleaning yield", f"{THESIS_MAPS:,} -> {THESIS_CLEAN1:,} -> {THESIS_CLEAN2:,} "
                f"({100 * THESIS_CLEAN2 / THESIS_MAPS:.0f} % kept)",
                f"{complete}/{done} complete ({100 * complete / max(done, 1):.0f} %)"
                + ("; cleaner: " + ", ".join(f"{v} {k}" for k, v in sorted(decisions.items()))
                   if decisions else ""),
                "our robot never gets stuck at the start (the thesis's first cleaning step) "
                "and the labels come from the simulator's coverage, not by hand; a small "
                "build gives only a rough share.")  # fmt: skip
    out.comparison_table()
