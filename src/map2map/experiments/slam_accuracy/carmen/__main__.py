"""SLAM on the two real CARMEN logs of ``../shared/data/carmen``, against their corrected poses.

Usage::

    python3 -m map2map.experiments.slam_accuracy.carmen  # oracle, rbpf:5, rbpf, rbpf:30, graph
    python3 -m map2map.experiments.slam_accuracy.carmen --backends rbpf --logs aces
    python3 -m map2map.experiments.slam_accuracy.carmen --backends rbpf --seeds 0-7
    python3 -m map2map.experiments.slam_accuracy.carmen --backends rbpf:20 --no-close-loops
    python3 -m map2map.experiments.slam_accuracy.carmen --figure docs/carmen_real.png

The logs are read from ``$MAP2MAP_SHARED_DATA/carmen`` or ``../shared/data/carmen``
(beside the working folder).

The logs (Radish ``aces-corrected``, ``fhw-corrected``) are "corrected": the pose of
each ``FLASER`` line is a SLAM-corrected pose, and the ``ODOM`` stream is re-anchored
at it after every scan. :func:`map2map.robotlog.carmen.read_carmen` rebuilds the raw wheel
odometry from the ``ODOM`` increments; the backends see only that and the scans.

The **reference** is the raster of every scan's endpoints at its corrected pose
(:func:`map2map.slam.quality.scan_endpoint_map`, 5 cm cells, readings below 50 m).
Our map is placed in the reference frame by the rigid transform that best fits our
trajectory to the corrected one (Umeyama), then refined by the rigid transform
minimising the Huber-robust distances of our occupied cells to the reference's
(:func:`map2map.slam.quality.wall_distances` with ``align=True``, the appendix
paper's ``E_rigid,opt``). Printed per log and backend:

* ``mean`` / ``median``: distance (cm) of our occupied cells to the nearest
  reference endpoint cell, after that rigid alignment (the two figures of the issue);
* ``placed``: the mean with our map placed by the first corrected pose only (the map
  frame starts there; a heading error early in the run rotates the whole map and
  counts in full);
* ``p90``: 90th percentile after alignment;
* ``ATE``: RMSE (cm) of our trajectory against the corrected poses (rigidly aligned),
  and ``odo``: the same for the raw odometry;
* ``cells``: occupied cells of our map, ``s``: CPU seconds of the SLAM run.

``rbpf`` is ``map2map slam``'s default for a recorded log
(:data:`map2map.slam.offline.RECORDED_LOG_PARTICLES` particles, then loop closure,
:mod:`map2map.slam.loops`), ``rbpf:N`` N particles (with loop closure too;
``--no-close-loops``: without); ``--seeds 0-7`` repeats every rbpf run with each seed (the filter is
stochastic: one seed is one draw).

The floor of the metric -- the corrected poses' own map, made by the ``oracle``
mapper through the same pipeline -- is printed as backend ``oracle``.
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

import numpy as np

from map2map.experiments._data import shared_data

DATA = shared_data() / "carmen"


def relative_to_first(poses: np.ndarray) -> np.ndarray:
    from map2map.slam.rbpf import absolute_difference

    return absolute_difference(poses, np.repeat(poses[:1], len(poses), 0))


def _at_times(log, times: np.ndarray) -> np.ndarray:
    """Scan index of each trajectory time (graph SLAM reports keyframes only)."""
    t = np.array([s.t for s in log.scans])
    return np.clip(np.searchsorted(t, times - 1e-6), 0, len(t) - 1)


def evaluate_log(name, backend, particles=None, max_range=None, seed=0, **options):
    from map2map.core.geometry import fit_rigid
    from map2map.robotlog.carmen import replay
    from map2map.robotlog.logs import load_log
    from map2map.robotlog.mappers import make_mapper
    from map2map.slam.offline import run_slam
    from map2map.slam.quality import (
        ate_rmse,
        scan_endpoint_map,
        wall_distances,
    )

    log = load_log(DATA / f"{name}-corrected.log.gz")
    ref_poses = log.logged_poses
    reference = scan_endpoint_map(log.scans, ref_poses, 0.05)
    t0 = time.process_time()
    if backend == "oracle":
        from map2map.robotlog.carmen import CarmenLog

        truth_log = CarmenLog(log.odometry, log.scans, ref_poses, log.params)
        mapper = replay(truth_log, make_mapper("oracle", resolution=0.05))
        slam_map = mapper.get_map()
        traj = relative_to_first(ref_poses)
        times = np.array([s.t for s in log.scans])
    else:
        res = run_slam(log, backend, particles=particles, max_range=max_range, seed=seed, **options)
        slam_map, traj, times = res.map, res.trajectory[:, 1:4], res.trajectory[:, 0]
    cpu = time.process_time() - t0
    start = ref_poses[0]  # every map frame starts at the first pose
    placed = wall_distances(slam_map, reference, start)
    truth = relative_to_first(ref_poses)
    # rigid placement of the whole map: our trajectory fitted to the corrected one
    # (Umeyama), then the Huber ICP of our occupied cells onto the reference
    T = fit_rigid(traj[:, :2], ref_poses[_at_times(log, times)][:, :2])
    fit = (T[0, 2], T[1, 2], float(np.arctan2(T[1, 0], T[0, 0])))
    aligned = wall_distances(slam_map, reference, fit, align=True)
    odo = np.array([(o.x, o.y, o.theta) for o in log.odometry])
    row = {
        "log": name,
        "backend": backend,
        "mean": 100 * float(np.mean(aligned)),
        "median": 100 * float(np.median(aligned)),
        "p90": 100 * float(np.quantile(aligned, 0.9)),
        "placed": 100 * float(np.mean(placed)),
        "ate": 100 * ate_rmse(traj, truth[_at_times(log, times)]),
        "odo": 100 * ate_rmse(relative_to_first(odo), truth),
        "cells": int(slam_map.occupied.sum()),
        "cpu": cpu,
    }
    return row, slam_map, reference, fit


def figure(results, path: Path) -> None:
    """Our maps (red) over the reference endpoints (black), one panel per run."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from map2map.slam.quality import map_to_plan_points

    n = len(results)
    fig, axes = plt.subplots(1, n, figsize=(4.2 * n, 4.4), squeeze=False)
    for ax, (row, slam_map, reference, start) in zip(axes[0], results, strict=True):
        rr, cc = np.nonzero(reference.occupied)
        rx, ry = reference.pixel_to_world(rr, cc)
        ax.scatter(rx, ry, s=0.05, c="k", lw=0, label="reference (corrected poses)")
        p = map_to_plan_points(slam_map, start)
        ax.scatter(p[:, 0], p[:, 1], s=0.05, c="tab:red", lw=0, label=f"{row['backend']} map")
        ax.set_aspect("equal")
        ax.set_title(
            f"{row['log']} {row['backend']}: {row['mean']:.1f} / {row['median']:.1f} cm",
            fontsize=9,
        )
        ax.tick_params(labelsize=7)
    axes[0][0].legend(loc="lower left", fontsize=7, markerscale=40)
    fig.tight_layout()
    fig.savefig(path, dpi=80)
    plt.close(fig)


def parse_seeds(text: str) -> list[int]:
    """Seeds from ``"0,3"`` or ``"0-7"``.

    Examples
    --------
    >>> parse_seeds("0-2"), parse_seeds("4,1")
    ([0, 1, 2], [4, 1])
    """
    seeds: list[int] = []
    for part in text.split(","):
        a, sep, b = part.partition("-")
        seeds += list(range(int(a), int(b) + 1)) if sep else [int(a)]
    return seeds


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(
        prog="python3 -m map2map.experiments.slam_accuracy.carmen",
        description=__doc__.splitlines()[0],
    )
    ap.add_argument("--logs", default="aces,fhw")
    ap.add_argument(
        "--backends",
        default="oracle,rbpf:5,rbpf,rbpf:30,graph",
        help="rbpf:N = N particles; rbpf = map2map slam's default for a recorded log",
    )
    ap.add_argument("--particles", type=int, default=None)
    ap.add_argument("--max-range", type=float, default=None)
    ap.add_argument(
        "--seeds",
        default="0",
        help="seeds of the rbpf runs, comma-separated or a range A-B (default 0); "
        "rbpf is stochastic: check a setting on several",
    )
    ap.add_argument(
        "--close-loops",
        action=argparse.BooleanOptionalAction,
        default=None,
        help="rbpf: loop closure after the filter (default: map2map slam's for a recorded "
        "log, on); --no-close-loops: the filter's own map",
    )
    ap.add_argument("--figure", type=Path, help="PNG of the maps over the references")
    args = ap.parse_args(argv)
    seeds = parse_seeds(args.seeds)
    if not DATA.is_dir():
        print(f"no CARMEN data at {DATA} (set $MAP2MAP_SHARED_DATA)", file=sys.stderr)
        return 1
    print(
        f"{'log':<5} {'backend':<7} {'seed':>4} {'mean':>6} {'median':>6} {'p90':>6} "
        f"{'placed':>7} {'ATE':>6} {'odo':>6} {'cells':>6} {'s':>6}   (cm; s = CPU seconds)"
    )
    results = []
    for name in args.logs.split(","):
        for spec in args.backends.split(","):
            backend, _, count = spec.partition(":")  # rbpf:30 = 30 particles
            # only rbpf draws random numbers: one run of the others
            for seed in seeds if backend == "rbpf" else seeds[:1]:
                n = int(count) if count else args.particles
                opts = {"close_loops": args.close_loops} if backend == "rbpf" else {}
                r = evaluate_log(name, backend, n, args.max_range, seed, **opts)
                r[0]["backend"] = spec
                r[0]["seed"] = seed
                results.append(r)
                row = r[0]
                print(
                    f"{row['log']:<5} {row['backend']:<7} {seed:4d} {row['mean']:6.1f} "
                    f"{row['median']:6.1f} {row['p90']:6.1f} {row['placed']:7.1f} "
                    f"{row['ate']:6.1f} {row['odo']:6.1f} {row['cells']:6d} {row['cpu']:6.1f}",
                    flush=True,
                )
    if args.figure:
        figure([r for r in results if r[0]["backend"] != "oracle"], args.figure)
        print(f"wrote {args.figure}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
