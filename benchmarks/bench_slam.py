"""SLAM throughput: simulated 7-minute explorations per hour, per backend and particle count.

Target (issue 5): ``map2map simulate`` with the default particle filter on HouseExpo-size
plans (7 simulated minutes each) reaches >= 1,000 maps/hour on a 2-core machine running
one process per core, i.e. <= 7.2 s per map per core, simulation included.

Usage::

    python3 -m benchmarks.bench_slam            # 2 plans per configuration
    python3 -m benchmarks.bench_slam --plans 4  # more plans, steadier figures

For each configuration the script simulates procedural apartments (about 8 x 13 m at
0.05 m/px, the size of HouseExpo plans) for 420 simulated seconds and prints wall and CPU
seconds per map and the implied maps/hour with one process per core
(``cores * 3600 / seconds per map``). CPU time is the steadier figure on a shared
machine; wall time is what a user sees. The default configuration is then run with two
processes at once to measure the real two-core throughput. The ``oracle`` row is the
simulator alone (no SLAM), for reference.

Then the same on real HouseExpo plans from the shared data (skipped when absent): the
two JSON plans and the first ``--houseexpo`` renders reduced to 0.05 m/px
(``benchmarks/_sim_plans.py``), per backend.
"""

from __future__ import annotations

import argparse
import os
import time
from concurrent.futures import ProcessPoolExecutor

from benchmarks._sim_plans import HOUSEEXPO, houseexpo_json, houseexpo_renders

CONFIGS = [
    ("oracle", {}),
    ("rbpf", {}),  # the default: 5 particles
    ("rbpf", {"particles": 10}),
    ("rbpf", {"particles": 30}),
    ("rbpf", {"particles": 100}),  # TurtleBot3's GMapping configuration
    ("graph", {}),
]


def one_plan(backend, options, plan, seed):
    """Simulate a given plan for 7 minutes; returns (wall s, cpu s, coverage)."""
    from map2map.robotlog.mappers import make_mapper
    from map2map.sim.runner import simulate

    mapper = make_mapper(backend, resolution=plan.resolution, seed=seed, **options)
    t0, c0 = time.perf_counter(), time.process_time()
    res = simulate(plan, seed=seed, mapper=mapper, duration=420.0, progress=False)
    return time.perf_counter() - t0, time.process_time() - c0, res.coverage


def one_map(args):
    """Simulate the procedural apartment of ``seed``; returns (wall s, cpu s, coverage)."""
    from map2map.maps.floorplan import generate_floorplan

    backend, options, seed = args
    return one_plan(backend, options, generate_floorplan(seed, kind="apartment"), seed)


def bench_houseexpo(n_renders: int, cores: int) -> None:
    """CPU s per 7-minute map on HouseExpo plans, per backend (one process)."""
    if not HOUSEEXPO.is_dir():
        print(f"HouseExpo data not found at {HOUSEEXPO}: skipped")
        return
    plans = houseexpo_json() + houseexpo_renders(n_renders)
    areas = [float(p.free.sum()) * p.resolution**2 for _, p in plans]
    print(
        f"\nHouseExpo: {len(plans)} plans ({min(areas):.0f}-{max(areas):.0f} m2 free, "
        "0.05 m/px), 420 simulated s each"
    )
    print(f"{'configuration':<26}{'wall s/map':>11}{'cpu s/map':>11}{'maps/h (cpu)':>14}{'cov':>6}")
    for backend, options in (("oracle", {}), ("rbpf", {}), ("graph", {})):
        r = [one_plan(backend, options, p, seed) for seed, (_, p) in enumerate(plans)]
        w = sum(x[0] for x in r) / len(r)
        c = sum(x[1] for x in r) / len(r)
        cov = sum(x[2] for x in r) / len(r)
        print(
            f"{label(backend, options):<26}{w:>11.2f}{c:>11.2f}{cores * 3600 / c:>14.0f}"
            f"{cov:>6.2f}",
            flush=True,
        )
    # the issue's figure: default rbpf, one process per core, on HouseExpo-size plans
    jobs = [("rbpf", {}, p, seed) for seed, (_, p) in enumerate(plans)]
    t0 = time.perf_counter()
    with ProcessPoolExecutor(max_workers=cores) as pool:
        list(pool.map(_one_plan_job, jobs))
    elapsed = time.perf_counter() - t0
    print(
        f"default rbpf on HouseExpo, {cores} processes: {len(jobs)} maps in {elapsed:.1f} s "
        f"wall -> {len(jobs) * 3600 / elapsed:.0f} maps/hour (target >= 1000)"
    )


def _one_plan_job(job):
    return one_plan(*job)


def label(backend, options):
    return backend + "".join(f" {k}={v}" for k, v in options.items())


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--plans", type=int, default=2, help="plans per configuration")
    ap.add_argument(
        "--skip", default="", help="comma-separated labels to skip, e.g. 'rbpf particles=100'"
    )
    ap.add_argument("--houseexpo", type=int, default=4, help="HouseExpo renders (0: none)")
    args = ap.parse_args()
    skip = {s.strip() for s in args.skip.split(",") if s.strip()}
    cores = 2
    print(f"machine: {os.cpu_count()} cores visible; figures assume {cores} processes")
    one_map(("rbpf", {"particles": 2}, 99))  # numba warm-up (compiled kernels are cached)
    one_map(("graph", {}, 99))
    print(f"{'configuration':<26}{'wall s/map':>11}{'cpu s/map':>11}{'maps/h (cpu)':>14}")
    for backend, options in CONFIGS:
        name = label(backend, options)
        if name in skip:
            continue
        walls, cpus = [], []
        for seed in range(args.plans):
            w, c, _ = one_map((backend, options, seed))
            walls.append(w)
            cpus.append(c)
        w, c = sum(walls) / len(walls), sum(cpus) / len(cpus)
        print(f"{name:<26}{w:>11.2f}{c:>11.2f}{cores * 3600 / c:>14.0f}", flush=True)
    # the real thing: two processes, one per core, default particle filter
    jobs = [("rbpf", {}, seed) for seed in range(2 * args.plans)]
    t0 = time.perf_counter()
    with ProcessPoolExecutor(max_workers=cores) as pool:
        list(pool.map(one_map, jobs))
    elapsed = time.perf_counter() - t0
    print(
        f"default rbpf, {cores} processes: {len(jobs)} maps in {elapsed:.1f} s wall "
        f"-> {len(jobs) * 3600 / elapsed:.0f} maps/hour (target >= 1000)"
    )
    if args.houseexpo >= 0:
        bench_houseexpo(args.houseexpo, cores)


if __name__ == "__main__":
    main()
