"""Whole-process ``map2map simulate`` throughput: maps/hour with two processes at once.

Target (issue 11, item 6): >= 1,000 maps/hour on a 2-core machine running two
``python -m map2map simulate`` processes at a time on HouseExpo-size plans, each
process counted whole -- interpreter start-up, imports, numba cache loading, the
7-minute exploration with the default particle filter, and every output
(``slam_map.yaml``/``.pgm``, both trajectories, the CARMEN ``run.log``,
``report.json`` and ``figure.png``).

Usage::

    python3 -m benchmarks.bench_sim_process               # 8 runs, 2 at a time
    python3 -m benchmarks.bench_sim_process --runs 16 --jobs 2
    python3 -m benchmarks.bench_sim_process --mapper oracle

Plans: the two HouseExpo JSON plans and the HouseExpo renders (reduced to
0.05 m/px, ``benchmarks/_sim_plans.py``) from the shared data, cycled; procedural
apartments when the shared data is absent. Run ``i`` uses ``--seed i``. One
untimed run first fills the numba cache (as a user's first run would).

Printed per run: wall seconds of the process, its CPU seconds (user + system,
``os.wait4``), and the in-process simulation wall time from ``report.json``.
Summary: the batch's wall-clock maps/hour (what a user sees, but on a shared
machine it depends on everyone else's load) and the CPU figure
``cores x 3600 / mean CPU seconds per map`` (the steadier one: what two otherwise
idle cores would do).
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import tempfile
import time
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path

import numpy as np

from benchmarks._sim_plans import HOUSEEXPO, apartments, houseexpo_renders

ROOT = Path(__file__).resolve().parents[1]


def plan_files(tmp: Path, n_renders: int) -> list[Path]:
    """Plan files for the runs: HouseExpo JSON as is, renders and apartments as ROS maps."""
    from map2map.maps.formats import save_map

    if HOUSEEXPO.is_dir():
        files = sorted((HOUSEEXPO / "json").glob("*.json"))
        plans = houseexpo_renders(n_renders)
    else:
        files, plans = [], apartments(4)
    for name, plan in plans:
        path = tmp / f"{name}.yaml"
        save_map(plan, path)
        files.append(path)
    return files


def run_one(plan: Path, out: Path, seed: int, mapper: str, src: Path) -> dict:
    """One ``map2map simulate`` process; its wall and CPU seconds and report."""
    env = dict(os.environ)
    env["PYTHONPATH"] = str(src) + os.pathsep + env.get("PYTHONPATH", "")
    cmd = [sys.executable, "-m", "map2map", "simulate", str(plan), "--out", str(out)]
    cmd += ["--seed", str(seed), "--mapper", mapper, "--quiet"]
    log = out.with_suffix(".stderr")
    with open(log, "wb") as err:
        t0 = time.perf_counter()
        proc = subprocess.Popen(cmd, env=env, stdout=subprocess.DEVNULL, stderr=err)
        _, status, ru = os.wait4(proc.pid, 0)  # this child's own CPU time
        wall = time.perf_counter() - t0
    proc.returncode = os.waitstatus_to_exitcode(status)
    if proc.returncode:
        msg = log.read_text(errors="replace").strip()
        raise RuntimeError(f"{' '.join(cmd)} failed ({proc.returncode}): {msg}")
    rep = json.loads((out / "report.json").read_text())
    return {
        "plan": plan.stem[:8],
        "seed": seed,
        "wall": wall,
        "cpu": ru.ru_utime + ru.ru_stime,
        "sim_wall": rep["wall_seconds"],
        "coverage": rep["coverage"],
        "rss_mb": ru.ru_maxrss / 1024,
    }


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--runs", type=int, default=8, help="timed runs (default 8)")
    ap.add_argument("--jobs", type=int, default=2, help="processes at a time (default 2)")
    ap.add_argument("--renders", type=int, default=6, help="HouseExpo renders to use")
    ap.add_argument("--mapper", default="rbpf", help="mapping backend (default rbpf)")
    ap.add_argument(
        "--src",
        type=Path,
        default=ROOT / "src",
        help="package sources to run (default: this checkout's src; e.g. an older checkout's "
        "src for a before/after comparison)",
    )
    args = ap.parse_args()
    with tempfile.TemporaryDirectory(prefix="bench_sim_process_") as d:
        tmp = Path(d)
        plans = plan_files(tmp, args.renders)
        print(
            f"{len(plans)} plans ({'HouseExpo' if HOUSEEXPO.is_dir() else 'apartments'}), "
            f"{args.runs} runs of `map2map simulate --mapper {args.mapper}`, "
            f"{args.jobs} at a time; {os.cpu_count()} cores visible; sources {args.src}",
            flush=True,
        )
        src = args.src.resolve()
        run_one(plans[0], tmp / "warmup", 0, args.mapper, src)  # numba cache, OS file cache
        jobs = [
            (plans[i % len(plans)], tmp / f"run{i}", i, args.mapper, src) for i in range(args.runs)
        ]
        t0 = time.perf_counter()
        with ThreadPoolExecutor(max_workers=args.jobs) as pool:
            rows = list(pool.map(lambda j: run_one(*j), jobs))
        elapsed = time.perf_counter() - t0
    print(f"{'plan':<9}{'seed':>5}{'wall s':>8}{'cpu s':>7}{'sim s':>7}{'cov':>6}{'rss MB':>8}")
    for r in rows:
        print(
            f"{r['plan']:<9}{r['seed']:>5}{r['wall']:>8.2f}{r['cpu']:>7.2f}{r['sim_wall']:>7.2f}"
            f"{r['coverage']:>6.2f}{r['rss_mb']:>8.0f}"
        )
    cpu = np.array([r["cpu"] for r in rows])
    wall = np.array([r["wall"] for r in rows])
    print(
        f"per map: wall {wall.mean():.2f} s (min {wall.min():.2f}, max {wall.max():.2f}), "
        f"CPU {cpu.mean():.2f} s (min {cpu.min():.2f}, max {cpu.max():.2f})"
    )
    print(
        f"wall clock: {args.runs} maps in {elapsed:.1f} s with {args.jobs} processes -> "
        f"{args.runs * 3600 / elapsed:.0f} maps/hour (depends on the machine's other load)"
    )
    print(
        f"CPU: {args.jobs} cores x 3600 / {cpu.mean():.2f} CPU s per map -> "
        f"{args.jobs * 3600 / cpu.mean():.0f} maps/hour (target >= 1000)"
    )


if __name__ == "__main__":
    main()
