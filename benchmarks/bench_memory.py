"""Peak memory (RSS) and wall time of every map-reading command vs the map's size.

Issue 11, item 4: a 12000x12000 map exhausted 24 GB in ``evaluate`` and ``simulate``.
This script measures what each command needs per pixel, the figures from which
``map2map.core.limits`` sets each command's budget.

Usage::

    python3 -m benchmarks.bench_memory                       # sides 500 1000 2000 4000
    python3 -m benchmarks.bench_memory --sides 500 1000 --commands evaluate deform
    python3 -m benchmarks.bench_memory --timeout 300 --json mem.json

The map: one generated apartment (``map2map plan --seed 7 --size 25 25``, 500 px at
0.05 m/px) upsampled by nearest neighbour to each side, its resolution scaled so the
building keeps its metres (a finer map of the same floor, as a 12000 px scan of a
drawing is). Each command runs as its own ``python3 -m map2map`` process with
``--max-pixels 0`` (no refusal) and its peak resident memory is that process's own
``VmHWM`` at exit (``/proc/self/status``). ``align``/``evaluate`` compare the plan
with a copy of itself turned 90 degrees; ``simulate`` drives ``--duration 20`` simulated seconds;
``slam`` replays the 500 px run's CARMEN log at a resolution giving about that many
pixels across (``--resolution``); ``convert`` writes a PNG, ``prep`` resizes to 512 px,
``show`` draws the figure.

Printed: one row per command and side (megapixels, peak RSS MB, wall s), then per
command the least-squares fit ``peak = base + per_pixel * pixels`` (bytes/pixel)
over the sides that finished. Wall times are only indicative (the machine may be
shared); memory figures are not affected by the load.
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
_HAS_OVERRIDE = True
COMMANDS = ["convert", "prep", "show", "align", "evaluate", "deform", "simulate", "slam"]


def _env() -> dict:
    """The children's environment: this process's, so they run the map2map it imports (the
    installed package, or the tree ``PYTHONPATH`` names)."""
    return dict(os.environ)


_LAUNCH = (
    "import atexit, runpy, sys\n"
    "OUT = sys.argv[1]\n"
    "def _hwm():\n"
    "    for line in open('/proc/self/status'):\n"
    "        if line.startswith('VmHWM:'):\n"
    "            open(OUT, 'w').write(line.split()[1])\n"
    "atexit.register(_hwm)\n"
    "sys.argv = ['map2map'] + sys.argv[2:]\n"
    "runpy.run_module('map2map', run_name='__main__', alter_sys=True)\n"
)


def run_measured(argv: list[str], timeout: float) -> tuple[int, float, float]:
    """Run ``python3 -m map2map ARGV``: (exit status, peak RSS in MB, wall seconds).

    The peak is the child's own ``VmHWM`` (``/proc/self/status``) read at exit: the
    rusage of a forked child would start from this parent's resident size.
    """
    with tempfile.NamedTemporaryFile(prefix="m2m_hwm_", delete=False) as f:
        hwm = Path(f.name)
    t0 = time.perf_counter()
    p = subprocess.Popen(
        [sys.executable, "-c", _LAUNCH, str(hwm), *argv],
        env=_env(),
        stdout=subprocess.DEVNULL,
        stderr=subprocess.PIPE,
    )
    try:
        _, err = p.communicate(timeout=timeout)
        rc = p.returncode
    except subprocess.TimeoutExpired:
        p.kill()
        p.communicate()
        rc = -9
    wall = time.perf_counter() - t0
    text = hwm.read_text().strip()
    hwm.unlink()
    mb = int(text) / 1024 if text else float("nan")
    if rc not in (0, -9):
        lines = err.decode(errors="replace").strip().splitlines()
        print(f"    exit {rc}: {lines[-1] if lines else ''}", file=sys.stderr)
    return rc, mb, wall


def make_maps(tmp: Path, sides: list[int]) -> dict[int, tuple[Path, Path]]:
    """The plan at every side and its copy turned 90 degrees (ROS yaml + pgm)."""
    from map2map.core.grid import OccupancyMap
    from map2map.maps.floorplan import generate_floorplan
    from map2map.maps.formats import save_map

    base = generate_floorplan(seed=7, size=(25.0, 25.0), resolution=0.05)
    grid = base
    data = grid.data
    # square, 500 px
    side0 = max(data.shape)
    sq = np.full((side0, side0), 127, np.uint8)
    sq[: data.shape[0], : data.shape[1]] = data
    out = {}
    for n in sides:
        idx = (np.arange(n) * side0) // n
        up = sq[idx][:, idx]
        res = grid.resolution * side0 / n
        a = tmp / f"plan_{n}.yaml"
        b = tmp / f"turned_{n}.yaml"
        save_map(OccupancyMap(up, res, (0.0, 0.0, 0.0)), a)
        save_map(OccupancyMap(np.ascontiguousarray(np.rot90(up)), res, (0.0, 0.0, 0.0)), b)
        del up
        out[n] = (a, b)
    return out


def command_argv(cmd: str, n: int, maps, tmp: Path, log: Path | None) -> list[str] | None:
    plan, turned = maps[n]
    out = tmp / f"out_{cmd}_{n}"
    common = ["--max-pixels", "0"] if _HAS_OVERRIDE else []
    if cmd == "convert":
        return ["convert", str(plan), str(tmp / f"conv_{n}.png"), *common]
    if cmd == "prep":
        return ["prep", str(plan), str(tmp / f"prep_{n}.png"), "--size", "512", *common]
    if cmd == "show":
        return ["show", str(plan), "--out", str(tmp / f"show_{n}.png"), *common]
    if cmd == "align":
        return ["align", str(turned), str(plan), "--out", str(out), *common]
    if cmd == "evaluate":
        return ["evaluate", str(turned), str(plan), "--out", str(out), *common]
    if cmd == "deform":
        return ["deform", str(plan), "--out", str(out), "--samples", "1", "--seed", "0", *common]
    if cmd == "simulate":
        return [
            "simulate",
            str(plan),
            "--out",
            str(out),
            "--seed",
            "0",
            "--duration",
            "20",
            "--quiet",
            *common,
        ]
    if cmd == "slam":
        if log is None:
            return None
        res = 25.0 / n  # the log's map spans about the building's 25 m
        return [
            "slam",
            str(log),
            "--out",
            str(out),
            "--resolution",
            f"{res:.6f}",
            "--quiet",
            *common,
        ]
    raise ValueError(cmd)


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(
        description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter
    )
    ap.add_argument("--sides", type=int, nargs="+", default=[500, 1000, 2000, 4000])
    ap.add_argument("--commands", nargs="+", choices=COMMANDS, default=COMMANDS)
    ap.add_argument("--timeout", type=float, default=400.0, help="seconds per run (default 400)")
    ap.add_argument("--json", type=Path, help="also write the rows as JSON")
    args = ap.parse_args(argv)
    global _HAS_OVERRIDE
    helptext = subprocess.run(
        [sys.executable, "-m", "map2map", "convert", "--help"],
        env=_env(),
        capture_output=True,
        text=True,
    ).stdout
    _HAS_OVERRIDE = "--max-pixels" in helptext
    rows = []
    with tempfile.TemporaryDirectory(prefix="m2m_mem_") as t:
        tmp = Path(t)
        maps = make_maps(tmp, sorted(set(args.sides) | {500}))
        log = None
        if "slam" in args.commands:
            rc, _, _ = run_measured(command_argv("simulate", 500, maps, tmp, None), args.timeout)
            cand = tmp / "out_simulate_500" / "run.log"
            log = cand if rc == 0 and cand.exists() else None
        # the interpreter + imports alone, for reference
        rc, base_mb, base_s = run_measured(["--version"], 60)
        print(f"{'python -m map2map --version':32s} {base_mb:8.0f} MB {base_s:7.1f} s")
        print(f"{'command':10s} {'side':>6s} {'MP':>7s} {'peak MB':>9s} {'wall s':>8s}")
        for cmd in args.commands:
            for n in args.sides:
                cargv = command_argv(cmd, n, maps, tmp, log)
                if cargv is None:
                    continue
                rc, mb, s = run_measured(cargv, args.timeout)
                status = "ok" if rc == 0 else ("timeout" if rc == -9 else f"exit {rc}")
                print(
                    f"{cmd:10s} {n:6d} {n * n / 1e6:7.2f} {mb:9.0f} {s:8.1f} {status}", flush=True
                )
                rows.append(
                    dict(command=cmd, side=n, pixels=n * n, peak_mb=mb, wall_s=s, status=status)
                )
                if rc == -9:
                    break  # larger sides would time out too
    print("\nfit peak = base + per_pixel * pixels (runs that finished):")
    for cmd in args.commands:
        r = [x for x in rows if x["command"] == cmd and x["status"] == "ok"]
        if len(r) < 2:
            continue
        px = np.array([x["pixels"] for x in r], float)
        mb = np.array([x["peak_mb"] for x in r], float) * 2**20
        A = np.stack([np.ones_like(px), px], 1)
        (b0, b1), *_ = np.linalg.lstsq(A, mb, rcond=None)
        print(f"  {cmd:10s} base {b0 / 2**20:7.0f} MB   {b1:7.1f} bytes/pixel")
    if args.json:
        args.json.write_text(json.dumps(rows, indent=1))
    return 0


if __name__ == "__main__":
    sys.exit(main())
