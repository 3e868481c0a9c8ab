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
    python3 -m benchmarks.bench_sim_process --held-out 8  # issue 35 item 4: as a user would
    python3 -m benchmarks.bench_sim_process --held-out 8 --sim-args "--resolution 0.01"

Plans: the two HouseExpo JSON plans and the first ``--renders`` HouseExpo renders
(cropped and reduced to 0.05 m/px, ``benchmarks/_sim_plans.py``) from the shared data,
cycled; procedural apartments when the shared data is absent. Run ``i`` uses
``--seed i``. One untimed run first fills the numba cache (as a user's first run would).

``--held-out N`` runs ``map2map simulate RENDER.png --out RUN`` exactly as a user would
on the last ``N`` HouseExpo renders in sorted name order, the files as they are
(3746x3268 at 1 cm/px, no resolution stored: ``simulate`` assumes 0.05 m/px and says
so), with every default; pass ``--sim-args`` to add options (``"--resolution 0.01"``
reads them at their true scale). No plan the simulator was tuned on is among them:
tuning used the JSON plans and the first renders. Run ``i`` is render ``i mod N`` with
``--seed i // N`` (the default seed 0 on the first pass). The untimed first run uses
the first render (not held out).

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
import shlex
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


def held_out_renders(n: int) -> list[Path]:
    """The last ``n`` HouseExpo renders in sorted name order (files as they are)."""
    return sorted((HOUSEEXPO / "renders").glob("*.png"))[-n:]


def run_one(
    plan: Path, out: Path, seed: int, mapper: str, src: Path, extra: tuple[str, ...] = ()
) -> dict:
    """One ``map2map simulate`` process; its wall and CPU seconds and report."""
    env = dict(os.environ)
    env["PYTHONPATH"] = str(src) + os.pathsep + env.get("PYTHONPATH", "")
    cmd = [sys.executable, "-m", "map2map", "simulate", str(plan), "--out", str(out)]
    cmd += ["--seed", str(seed), "--mapper", mapper, "--quiet", *extra]
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
        "cmd": cmd,
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
    ap.add_argument(
        "--held-out",
        type=int,
        default=0,
        metavar="N",
        help="run on the last N HouseExpo renders as files, as a user would (see above)",
    )
    ap.add_argument(
        "--sim-args",
        default="",
        metavar="ARGS",
        help='more options for every simulate run, e.g. "--resolution 0.01"',
    )
    args = ap.parse_args()
    extra = tuple(shlex.split(args.sim_args))
    if args.held_out and not HOUSEEXPO.is_dir():
        ap.error(f"--held-out needs the HouseExpo renders ({HOUSEEXPO})")
    with tempfile.TemporaryDirectory(prefix="bench_sim_process_") as d:
        tmp = Path(d)
        src = args.src.resolve()
        if args.held_out:
            plans = held_out_renders(args.held_out)
            warm = sorted((HOUSEEXPO / "renders").glob("*.png"))[0]
            what = f"held-out HouseExpo renders as files ({plans[0].name[:8]}..)"
            seeds = [i // len(plans) for i in range(args.runs)]
        else:
            plans = plan_files(tmp, args.renders)
            warm = plans[0]
            what = "HouseExpo" if HOUSEEXPO.is_dir() else "apartments"
            seeds = list(range(args.runs))
        print(
            f"{len(plans)} plans ({what}), {args.runs} runs of `map2map simulate PLAN --out RUN "
            f"--seed S --mapper {args.mapper} --quiet{' ' if extra else ''}{shlex.join(extra)}`, "
            f"{args.jobs} at a time; {os.cpu_count()} cores visible; sources {args.src}",
            flush=True,
        )
        run_one(warm, tmp / "warmup", 0, args.mapper, src, extra)  # numba cache, OS file cache
        jobs = [
            (plans[i % len(plans)], tmp / f"run{i}", seeds[i], args.mapper, src, extra)
            for i in range(args.runs)
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
