"""Dataset builder throughput, Dask overhead, packed size and cleaner accuracy (issue 13).

Targets: >= 1,500 pairs/hour with 2 local workers on this 2-core machine (rbpf, 7
simulated minutes, 180-degree lidar, HouseExpo-size plans), a 2-worker speed-up >= 1.8x
over 1 worker, a Dask LocalCluster within 10 % of the local pool, a 4,000-pair 256 x 256
packed file <= 48 MiB, and a cleaner cross-validated accuracy >= 95 % against coverage
labels.

Usage::

    python3 -m benchmarks.bench_dataset                  # 8 pairs per configuration
    python3 -m benchmarks.bench_dataset --pairs 16       # steadier
    python3 -m benchmarks.bench_dataset --ds DS          # + the cleaner on a built dataset
    python3 -m benchmarks.bench_dataset --pairs 16 --repeat 2 --only-2   # Dask vs pool

Every configuration builds the same pairs (generated plans, seed 0: the default
HouseExpo-like mix of sizes) into a fresh folder. Wall-clock pairs/hour is what a user
sees and depends on the machine being free; the CPU seconds per pair of the 1-worker
run (this process's and its workers' CPU time) give the load-independent figure
``2 cores x 3600 / CPU s per pair``. The cleaner is cross-validated on ``--ds`` (a
dataset built beforehand with ``map2map dataset build``), since a few benchmark pairs
would say nothing.

Dask against the local pool: both run the same pairs back to back (``--repeat`` times,
alternating, so that a change in the machine's load hits both), 2 worker processes of
one thread each, start-up and shutdown included in both walls (what a user waits for);
the fixed cost of each backend (start, one trivial task per worker, stop) is printed
apart, with the CPU seconds per pair of every process involved (this one, with
LocalCluster's scheduler and nannies, and the workers), which the load does not change
much. Every configuration must give byte-identical pairs (checked).
"""

from __future__ import annotations

import argparse
import hashlib
import resource
import statistics
import sys
import tempfile
import time
from pathlib import Path

from map2map.datasets.build import build_dataset, open_dataset
from map2map.datasets.pair import BuildParams

MIB = 2**20


def _children_cpu() -> float:
    r = resource.getrusage(resource.RUSAGE_CHILDREN)
    return r.ru_utime + r.ru_stime


def _all_cpu() -> float:
    """CPU seconds of this process (Dask's scheduler and nannies live here) and its
    finished children (the workers)."""
    r = resource.getrusage(resource.RUSAGE_SELF)
    return r.ru_utime + r.ru_stime + _children_cpu()


def _digest(ds: Path) -> str:
    """SHA-256 over every pair file's name and bytes."""
    h = hashlib.sha256()
    for p in sorted((ds / "pairs").rglob("*")):
        if p.is_file():
            h.update(str(p.relative_to(ds)).encode())
            h.update(p.read_bytes())
    return h.hexdigest()


def one_build(root: Path, name: str, pairs: int, **kw) -> tuple[float, float, Path]:
    """Build ``pairs`` pairs; returns (wall s, CPU s of this process + children, path)."""
    ds = root / name
    c0 = _all_cpu()
    t0 = time.perf_counter()
    s = build_dataset(ds, "generated", pairs, 0, BuildParams(), progress=False, figures=False,
                      **kw)  # fmt: skip
    wall = time.perf_counter() - t0
    if s.done + s.failed != pairs:
        raise SystemExit(f"{name}: only {s.done + s.failed} of {pairs} pairs finished")
    with open_dataset(ds) as man:
        secs = [r["wall_seconds"] for r in man.rows("done")]
    print(f"  ({name}: {wall:.1f} s wall, {(_all_cpu() - c0) / pairs:.2f} CPU s per pair; wall "
          f"seconds inside a pair, mean {sum(secs) / max(len(secs), 1):.1f}: far above the CPU "
          "seconds when the machine is loaded)")  # fmt: skip
    return wall, _all_cpu() - c0, ds


class _Job:
    """A trivial task (what the fixed-cost measurement runs)."""

    def __init__(self, index: int):
        self.index = index


def _trivial(job: _Job) -> int:
    import map2map.datasets.pair  # noqa: F401  (what a real worker imports first)

    return job.index


def fixed_costs(workers: int = 2) -> tuple[float, float]:
    """Wall seconds to start ``workers`` processes, run one trivial task on each and stop:
    (local pool, Dask LocalCluster)."""
    from map2map.datasets.dask_backend import run_dask
    from map2map.datasets.pool import run_pool

    jobs = [_Job(i) for i in range(workers)]
    noop = dict(on_result=lambda t, r, w: None, on_crash=lambda t, why: False)
    t0 = time.perf_counter()
    run_pool(jobs, _trivial, workers, **noop)
    t1 = time.perf_counter()
    run_dask(jobs, _trivial, "local", workers=workers, **noop)
    return t1 - t0, time.perf_counter() - t1


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--pairs", type=int, default=8, help="pairs per configuration (default 8)")
    ap.add_argument("--ds", type=Path, help="a built dataset to cross-validate the cleaner on")
    ap.add_argument("--no-dask", action="store_true", help="skip the LocalCluster run")
    ap.add_argument("--repeat", type=int, default=1,
                    help="alternating local-pool / Dask runs with 2 workers (default 1)")
    ap.add_argument("--only-2", action="store_true",
                    help="skip the 1-worker run and the packed size (Dask vs pool only)")
    args = ap.parse_args()
    n = args.pairs
    print(f"{n} pairs per configuration: generated plans (HouseExpo-like sizes), rbpf, 420 s, "
          "180 deg, 256 x 256; wall-clock figures depend on the machine's load")  # fmt: skip
    with tempfile.TemporaryDirectory() as tmp:
        root = Path(tmp)
        # warm-up: numba caches compiled, one tiny pair
        build_dataset(root / "warm", "generated", 1, 99, BuildParams(duration=20.0, size=64),
                      progress=False, figures=False)  # fmt: skip
        digests = {}
        if not args.only_2:
            w1, cpu1, ds1 = one_build(root, "w1", n, workers=1)
            digests["local, 1 worker"] = _digest(ds1)
        local2, dask2 = [], []
        for r in range(args.repeat):
            w2, _, ds2 = one_build(root, f"w2-{r}", n, workers=2)
            local2.append(w2)
            digests[f"local, 2 workers #{r}"] = _digest(ds2)
            if args.no_dask:
                continue
            try:
                wd, _, dsd = one_build(root, f"dask-{r}", n, workers=2, scheduler="local")
            except Exception as exc:  # dask missing
                print(f"Dask LocalCluster: skipped ({exc})")
                args.no_dask = True
                continue
            dask2.append(wd)
            digests[f"Dask LocalCluster #{r}"] = _digest(dsd)
        w2 = statistics.median(local2)
        print(f"{'configuration':<24}{'wall s':>9}{'pairs/h':>10}")
        if not args.only_2:
            cpu_pair = cpu1 / n
            print(f"{'local, 1 worker':<24}{w1:>9.1f}{n * 3600 / w1:>10.0f}")
        print(f"{'local, 2 workers':<24}{w2:>9.1f}{n * 3600 / w2:>10.0f}"
              + (f"   speed-up {w1 / w2:.2f}x (target >= 1.8x)" if not args.only_2 else "")
              + (f"   runs {', '.join(f'{w:.1f}' for w in local2)}" if len(local2) > 1 else ""))
        if not args.only_2:
            print(f"CPU per pair (1 worker): {cpu_pair:.1f} s -> {2 * 3600 / cpu_pair:.0f} "
                  "pairs/h on 2 free cores (target >= 1,500)")  # fmt: skip
        if dask2:
            wd = statistics.median(dask2)
            rel = 100 * (wd / w2 - 1)
            pairs_rel = [f"{100 * (d / w - 1):+.1f} %" for w, d in zip(local2, dask2, strict=False)]
            print(f"{'Dask LocalCluster, 2':<24}{wd:>9.1f}{n * 3600 / wd:>10.0f}"
                  f"   {rel:+.1f} % wall vs local pool (target within 10 %)"
                  + (f"   runs {', '.join(pairs_rel)}" if len(dask2) > 1 else ""))  # fmt: skip
            fp, fd = fixed_costs(2)
            print(f"fixed cost (start 2 workers, one trivial task each, stop): local pool "
                  f"{fp:.1f} s, Dask LocalCluster {fd:.1f} s (Dask already imported)")
        same = len(set(digests.values())) == 1
        print(f"pairs byte-identical across {len(digests)} builds: {'yes' if same else 'NO'}")
        if not same:
            for k, v in digests.items():
                print(f"  {k}: {v[:16]}")
        if args.only_2:
            return 0 if same else 1
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
