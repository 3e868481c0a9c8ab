"""``map2map slam LOG --out DIR``: build a map from a recorded log with a SLAM backend."""

from __future__ import annotations

import argparse
import sys
from pathlib import Path


def register(subparsers) -> None:
    from ..slam.offline import RECORDED_LOG_PARTICLES

    p = subparsers.add_parser(
        "slam",
        help="build a map from a recorded run (CARMEN log, simulator run, BreezySLAM log, ROS bag)",
        description="Replay a recorded run through a SLAM backend (GMapping-style particle "
        "filter or Karto-style graph SLAM) and write the map (ROS yaml + pgm), the estimated "
        "trajectory (CSV) and a figure. Only odometry and scans are used, never ground truth. "
        "The --out folder is written whole at the end (an existing one is replaced).",
    )
    p.add_argument(
        "log",
        type=Path,
        help="CARMEN log (.log, .gz allowed), a 'map2map simulate' output folder, "
        "a BreezySLAM raw log (.dat), or a ROS bag: a ROS 1 .bag file or a ROS 2 bag "
        "folder (sqlite3 or mcap; needs pip install 'map2map[ros]')",
    )
    p.add_argument("--out", type=Path, required=True, help="output folder")
    p.add_argument(
        "--backend",
        choices=["rbpf", "graph"],
        default="rbpf",
        help="rbpf: GMapping-style particle filter (default; for a recorded log followed by "
        "loop closure, see --close-loops); graph: Karto-style graph SLAM",
    )
    p.add_argument(
        "--particles",
        type=int,
        default=None,
        help=f"particle count of rbpf (default {RECORDED_LOG_PARTICLES} for a recorded log: "
        "CARMEN, BreezySLAM, ROS bag, with loop closure, see --close-loops; 5 for a "
        "'map2map simulate' run, the simulator's speed default)",
    )
    p.add_argument(
        "--close-loops",
        action=argparse.BooleanOptionalAction,
        default=None,
        help="rbpf: after the filter, close the loops of its best trajectory with a pose "
        "graph (filter steps that disagree with the odometry re-matched, earlier places "
        "found again by scan matching, the graph optimised) and draw the map again from "
        "the corrected poses (default: on for a recorded log, off for a 'map2map "
        "simulate' run; docs/slam.md)",
    )
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
        choices=["auto", "carmen", "breezyslam", "simrun", "rosbag"],
        default="auto",
        help="log format (default: detected from the content)",
    )
    p.add_argument(
        "--scan-topic",
        metavar="TOPIC",
        help="ROS bag: the sensor_msgs/LaserScan topic (default: the bag's only one)",
    )
    p.add_argument(
        "--odom-topic",
        metavar="TOPIC",
        help="ROS bag: the nav_msgs/Odometry topic, or /tf for the odom -> base transform "
        "(default: the bag's only Odometry topic, else /tf)",
    )
    p.add_argument("--quiet", action="store_true", help="no progress bar")
    p.add_argument(
        "--max-memory",
        type=float,
        metavar="GIB",
        help="largest peak memory to plan for, GiB; a log whose estimate (the map tiles "
        "within range of its path, docs/slam.md) exceeds it is refused before mapping "
        "(default 4, or the machine's RAM if less; 0: no limit)",
    )
    p.add_argument(
        "--max-pixels",
        type=int,
        metavar="N",
        help="largest map (pixels) a reader decodes (a simulator run's plan); "
        "default: the memory budget's (docs/memory.md); 0: no limit",
    )
    p.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    from ..jobs.slam import SlamSpec, slam

    run = slam(
        SlamSpec(
            log=args.log,
            out=args.out,
            backend=args.backend,
            particles=args.particles,
            close_loops=args.close_loops,
            resolution=args.resolution,
            max_range=args.max_range,
            seed=args.seed,
            format=args.format,
            scan_topic=args.scan_topic,
            odom_topic=args.odom_topic,
            progress=not args.quiet,
            max_memory=args.max_memory,
        )
    )
    for note in run.notes:
        print(f"map2map: note: {args.log}: {note}", file=sys.stderr)
    for p in run.written.values():
        print(p)
    return 0
