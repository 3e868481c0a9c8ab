"""Dataset builder throughput, Dask overhead, packed size and cleaner accuracy (issue 13).

Targets: >= 1,500 pairs/hour with 2 local workers on this 2-core machine (rbpf, 7
simulated minutes, 180-degree lidar, HouseExpo-size plans), a 2-worker speed-up >= 1.8x
over 1 worker, a Dask LocalCluster within 10 % of the local pool, a 4,000-pair 256 x 256
packed file <= 48 MiB, and a cleaner cross-validated accuracy >= 95 % against coverage
labels.

Usage::

    python3 benchmarks/bench_dataset.py                  # 8 pairs per configuration
    python3 benchmarks/bench_dataset.py --pairs 16       # steadier
    python3 benchmarks/bench_dataset.py --ds DS          # + the cleaner on a built dataset

Every configuration builds the same pairs (generated plans, seed 0: the default
HouseExpo-like mix of sizes) into a fresh folder. Wall-clock pairs/hour is what a user
sees and depends on the machine being free; the CPU seconds per pair of the 1-worker
run (the worker processes' CPU time) give the load-independent figure
``2 cores x 3600 / CPU s per pair``. The cleaner is cross-validated on ``--ds`` (a
dataset built beforehand with ``map2map dataset build``), since a few benchmark pairs
would say nothing.
"""

from __future__ import annotations

import argparse
import resource
import sys
import tempfile
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "src"))

from map2map.datasets.build import build_dataset, open_dataset  # noqa: E402
from map2map.datasets.pair import BuildParams  # noqa: E402

MIB = 2**20


def _children_cpu() -> float:
    r = resource.getrusage(resource.RUSAGE_CHILDREN)
    return r.ru_utime + r.ru_stime


def one_build(root: Path, name: str, pairs: int, **kw) -> tuple[float, float, Path]:
    """Build ``pairs`` pairs; returns (wall s, children CPU s, dataset path)."""
    ds = root / name
    c0 = _children_cpu()
    t0 = time.perf_counter()
    s = build_dataset(ds, "generated", pairs, 0, BuildParams(), progress=False, figures=False,
                      **kw)  # fmt: skip
    wall = time.perf_counter() - t0
    if s.done + s.failed != pairs:
        raise SystemExit(f"{name}: only {s.done + s.failed} of {pairs} pairs finished")
    with open_dataset(ds) as man:
        secs = [r["wall_seconds"] for r in man.rows("done")]
    print(f"  ({name}: wall seconds inside a pair, mean {sum(secs) / max(len(secs), 1):.1f}: "
          "far above the CPU seconds when the machine is loaded)")  # fmt: skip
    return wall, _children_cpu() - c0, ds


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--pairs", type=int, default=8, help="pairs per configuration (default 8)")
    ap.add_argument("--ds", type=Path, help="a built dataset to cross-validate the cleaner on")
    ap.add_argument("--no-dask", action="store_true", help="skip the LocalCluster run")
    args = ap.parse_args()
    n = args.pairs
    print(f"{n} pairs per configuration: generated plans (HouseExpo-like sizes), rbpf, 420 s, "
          "180 deg, 256 x 256; wall-clock figures depend on the machine's load")  # fmt: skip
    with tempfile.TemporaryDirectory() as tmp:
        root = Path(tmp)
        # warm-up: numba caches compiled, one tiny pair
        build_dataset(root / "warm", "generated", 1, 99, BuildParams(duration=20.0, size=64),
                      progress=False, figures=False)  # fmt: skip
        w1, cpu1, ds1 = one_build(root, "w1", n, workers=1)
        w2, _, _ = one_build(root, "w2", n, workers=2)
        cpu_pair = cpu1 / n
        print(f"{'configuration':<24}{'wall s':>9}{'pairs/h':>10}")
        print(f"{'local, 1 worker':<24}{w1:>9.1f}{n * 3600 / w1:>10.0f}")
        print(f"{'local, 2 workers':<24}{w2:>9.1f}{n * 3600 / w2:>10.0f}"
              f"   speed-up {w1 / w2:.2f}x (target >= 1.8x)")  # fmt: skip
        print(f"CPU per pair (1 worker): {cpu_pair:.1f} s -> {2 * 3600 / cpu_pair:.0f} pairs/h "
              "on 2 free cores (target >= 1,500)")  # fmt: skip
        if not args.no_dask:
            try:
                wd, _, _ = one_build(root, "dask", n, workers=2, scheduler="local")
            except Exception as exc:  # dask missing
                print(f"Dask LocalCluster: skipped ({exc})")
            else:
                rel = 100 * (wd / w2 - 1)
                print(f"{'Dask LocalCluster, 2':<24}{wd:>9.1f}{n * 3600 / wd:>10.0f}"
                      f"   {rel:+.1f} % wall vs local pool (target within 10 %)")  # fmt: skip
        # packed size: this build's pairs, extrapolated to 4,000
        from map2map.datasets.export import export_dataset

        res = export_dataset(ds1, "packed", everything=True, progress=False)
        per = res.bytes / res.count
        print(f"packed: {res.count} pairs {res.bytes / 1024:.1f} KiB = {per / 1024:.2f} KiB/pair "
              f"-> 4,000 pairs {4000 * per / MIB:.1f} MiB (target <= 48 MiB)")  # fmt: skip
    if args.ds:
        import numpy as np

        from map2map.datasets.clean import COVERAGE_COMPLETE, dataset_features, train_cleaner

        with open_dataset(args.ds) as man:
            rows = [r for r in man.rows("done") if r["coverage"] is not None]
        x = dataset_features(args.ds, rows)
        g = np.array([r["plan_id"] for r in rows])
        for thr in (COVERAGE_COMPLETE, 0.9):
            y = np.array([r["coverage"] >= thr for r in rows], int)
            _, _, acc, conf, folds = train_cleaner(x, y, g)
            print(f"cleaner on {args.ds} ({len(rows)} pairs, labels coverage >= {thr:g}: "
                  f"{int(y.sum())} complete): {folds}-fold by plan accuracy {100 * acc:.1f} % "
                  f"(target >= 95 %), confusion {conf}")  # fmt: skip
    else:
        print("cleaner: skipped (give --ds DS, a dataset built with map2map dataset build)")
    return 0


if __name__ == "__main__":
    sys.exit(main())
