"""``map2map slam LOG --out DIR``: build a map from a recorded log with a SLAM backend."""

from __future__ import annotations

import argparse
import sys
from pathlib import Path


def register(subparsers) -> None:
    p = subparsers.add_parser(
        "slam",
        help="build a map from a recorded run (CARMEN log, simulator run, BreezySLAM log)",
        description="Replay a recorded run through a SLAM backend (GMapping-style particle "
        "filter or Karto-style graph SLAM) and write the map (ROS yaml + pgm), the estimated "
        "trajectory (CSV) and a figure. Only odometry and scans are used, never ground truth.",
    )
    p.add_argument(
        "log",
        type=Path,
        help="CARMEN log (.log, .gz allowed), a 'map2map simulate' output folder, "
        "or a BreezySLAM raw log (.dat)",
    )
    p.add_argument("--out", type=Path, required=True, help="output folder")
    p.add_argument(
        "--backend",
        choices=["rbpf", "graph"],
        default="rbpf",
        help="rbpf: GMapping-style particle filter (default); graph: Karto-style graph SLAM",
    )
    p.add_argument("--particles", type=int, default=None, help="particle count of rbpf (default 5)")
    p.add_argument(
        "--resolution", type=float, default=0.05, help="map resolution in m/px (default 0.05)"
    )
    p.add_argument(
        "--max-range",
        type=float,
        default=None,
        help="usable laser range in m (rbpf: GMapping's maxUrange, default 3 m for a 3.5 m "
        "LDS-01, 80%% of a longer sensor's range up to 10 m; graph: default the sensor "
        "maximum)",
    )
    p.add_argument("--seed", type=int, default=0, help="random seed of rbpf (default 0)")
    p.add_argument(
        "--format",
        choices=["auto", "carmen", "breezyslam", "simrun"],
        default="auto",
        help="log format (default: detected from the content)",
    )
    p.add_argument("--quiet", action="store_true", help="no progress bar")
    p.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    from ..errors import InputError
    from ..slam.logs import load_log
    from ..slam.offline import run_slam, write_slam_outputs
    from ._mapargs import check_seed

    check_seed(args.seed)
    if args.particles is not None and args.particles < 1:
        raise InputError("--particles", f"must be >= 1, got {args.particles}")
    if not args.resolution > 0:
        raise InputError("--resolution", f"must be > 0, got {args.resolution}")
    if args.max_range is not None and not args.max_range > 0:
        raise InputError("--max-range", f"must be > 0, got {args.max_range}")
    if args.out.exists() and not args.out.is_dir():
        raise InputError(args.out, "output path exists and is not a directory")
    log = load_log(args.log, args.format)  # every format problem is raised here, before output
    for note in log.notes:
        print(f"map2map: note: {args.log}: {note}", file=sys.stderr)
    res = run_slam(
        log,
        args.backend,
        particles=args.particles,
        resolution=args.resolution,
        seed=args.seed,
        max_range=args.max_range,
        progress=not args.quiet,
    )
    paths = write_slam_outputs(res, args.out, title=f"{args.log.name}: {args.backend}")
    for p in paths:
        print(p)
    return 0
