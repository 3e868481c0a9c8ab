"""Speed of ``map2map autocorrect`` (issue #32's two speed targets), in one command.

Usage::

    python3 -m benchmarks.bench_autocorrect [--data DS] [--maps 320] [--model none]
        [--repeat 3] [--workers N] [--no-single] [--folder]

* **Batched**: ``corrector(model).correct_many(maps)`` (what ``autocorrect`` does with a
  folder or a list of maps: the cleaning and the plan drawer in worker processes, one per
  core) on ``--maps`` SLAM maps at 256 px, at each pair's own resolution. The first
  batch of the process (the worker pool starting, each worker importing numba, scipy and
  the drawer) and then ``--repeat`` warm batches. Target: >= 50 maps/s on the 2 cores.
* **One map, whole process**: ``map2map autocorrect MAP --out OUT`` in a fresh
  interpreter, wall-clock seconds (interpreter start and imports included; the target,
  < 2 s, is "after import", so this figure is an upper bound).
* **A folder, whole process** (``--folder``): the same maps written as ROS yaml + pgm and
  ``map2map autocorrect FOLDER --out OUT`` run on them, maps per second end to end
  (interpreter start, reading, the pool's start, correcting and writing: what a user
  waits for).

The maps are the simulated SLAM maps (``B.png``) of a ``map2map dataset build`` folder
(``--data``), every split, cycled to ``--maps``. Without ``--data`` a small build (24
pairs, seed 0, ``rbpf``) is made first in a temporary folder, about a minute on 2 cores.

Timings are only meaningful on a quiet machine: the line before the figures prints the
load average, which should be well under the core count. Figures of this benchmark on
this project's 2-core CPU are in docs/autocorrect.md ("Speed").
"""

from __future__ import annotations

import argparse
import os
import statistics
import subprocess
import sys
import tempfile
import time
import warnings
from pathlib import Path

from map2map.core.grid import OccupancyMap
from map2map.core.parallel import default_workers
from map2map.jobs.autocorrect import corrector


def _maps(ds: Path, n: int) -> list[OccupancyMap]:
    from benchmarks.bench_drawing import _dataset

    items = _dataset(ds, None)
    if not items:
        raise SystemExit(f"{ds}: no finished pairs")
    return [OccupancyMap(items[i % len(items)][2], items[i % len(items)][3])
            for i in range(n)]


def _build(out: Path) -> None:
    print("building 24 pairs (seed 0) to take maps from ...", flush=True)
    t0 = time.perf_counter()
    subprocess.run([sys.executable, "-m", "map2map", "dataset", "build", "--out", str(out),
                    "--plans", "generated", "--count", "24", "--seed", "0", "--workers",
                    str(default_workers())], check=True, stdout=subprocess.DEVNULL)
    print(f"built in {time.perf_counter() - t0:.0f} s", flush=True)


def _batched(maps: list[OccupancyMap], model: str, repeat: int, workers: int | None) -> None:
    c = corrector(model)
    rates = []
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        for _ in range(1 + repeat):
            t0 = time.perf_counter()
            c.correct_many(maps, workers=workers)
            rates.append(len(maps) / (time.perf_counter() - t0))
    w = default_workers() if workers is None else workers
    print(f"batched, {len(maps)} maps, --model {model}, {w} worker(s): first batch "
          f"{rates[0]:.1f} maps/s (pool start and imports included); warm "
          f"{', '.join(f'{r:.1f}' for r in rates[1:])} maps/s, median "
          f"{statistics.median(rates[1:]):.1f} (target >= 50 maps/s on 2 cores)", flush=True)


def _single(m: OccupancyMap, model: str) -> None:
    from map2map.maps.formats import save_map

    with tempfile.TemporaryDirectory() as tmp:
        src = Path(tmp) / "map.yaml"
        save_map(m, src)
        cmd = [sys.executable, "-m", "map2map", "autocorrect", str(src), "--out",
               str(Path(tmp) / "out.yaml"), "--model", model]
        times = []
        for _ in range(3):
            t0 = time.perf_counter()
            subprocess.run(cmd, check=True, stdout=subprocess.DEVNULL,
                           stderr=subprocess.DEVNULL)
            times.append(time.perf_counter() - t0)
    print(f"one {m.shape[1]} x {m.shape[0]} map, whole process (`map2map autocorrect`, "
          f"interpreter start and imports included): {', '.join(f'{t:.2f}' for t in times)}"
          f" s (target < 2 s after import)", flush=True)


def _folder(maps: list[OccupancyMap], model: str) -> None:
    from map2map.maps.formats import save_map

    with tempfile.TemporaryDirectory() as tmp:
        src = Path(tmp) / "in"
        src.mkdir()
        for i, m in enumerate(maps):
            save_map(m, src / f"{i:06d}.yaml")
        times = []
        for k in range(2):
            t0 = time.perf_counter()
            subprocess.run([sys.executable, "-m", "map2map", "autocorrect", str(src), "--out",
                            str(Path(tmp) / f"out{k}"), "--model", model], check=True,
                           stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
            times.append(time.perf_counter() - t0)
    print(f"a folder of {len(maps)} maps, whole process (`map2map autocorrect FOLDER`: "
          f"start, reading, pool, correcting, writing): "
          f"{', '.join(f'{t:.2f} s ({len(maps) / t:.1f} maps/s)' for t in times)}", flush=True)


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--data", type=Path, help="a dataset build (default: build 24 pairs)")
    ap.add_argument("--maps", type=int, default=320, help="maps per batch (cycled)")
    ap.add_argument("--model", default="none", help="an autocorrect --model name")
    ap.add_argument("--repeat", type=int, default=3, help="warm batches")
    ap.add_argument("--workers", type=int, help="worker processes (default: one a core)")
    ap.add_argument("--no-single", action="store_true", help="skip the one-map process")
    ap.add_argument("--folder", action="store_true",
                    help="also time `map2map autocorrect FOLDER` on the maps, end to end")
    args = ap.parse_args(argv)
    load = os.getloadavg()[0]
    print(f"load average {load:.2f} on {os.cpu_count()} cores"
          f"{' (loaded: figures not meaningful)' if load > 0.5 * (os.cpu_count() or 1) else ''}",
          flush=True)
    with tempfile.TemporaryDirectory() as tmp:
        ds = args.data
        if ds is None:
            ds = Path(tmp) / "ds"
            _build(ds)
        maps = _maps(ds, max(1, args.maps))
    _batched(maps, args.model, max(1, args.repeat), args.workers)
    if not args.no_single:
        _single(maps[0], args.model)
    if args.folder:
        _folder(maps, args.model)
    return 0


if __name__ == "__main__":
    sys.exit(main())
