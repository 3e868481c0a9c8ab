"""``map2map simulate``: drive a simulated TurtleBot3 through a floor plan and map it."""

from __future__ import annotations

import argparse

from ..core.errors import warnings_unless_error
from ._mapargs import add_input_options, load_from_args


def register(sub: argparse._SubParsersAction) -> None:
    from ..robotlog.mappers import available_mappers

    p = sub.add_parser(
        "simulate",
        help="explore a floor plan with a simulated TurtleBot3 (LDS-01 lidar, wheel "
        "odometry) and write the SLAM map, trajectories and a CARMEN log",
        description="Simulate a TurtleBot3 Waffle Pi with an LDS-01 lidar and encoder "
        "odometry in PLAN. By default it explores frontiers like ROS explore_lite for "
        "--duration simulated seconds (7 minutes, as in the thesis); --waypoints or "
        "--trajectory make it drive a route instead. Writes slam_map.yaml/.pgm in the "
        "plan's frame, trajectory_true.csv, trajectory_estimated.csv (t,x,y,theta in the "
        "plan frame), run.log (CARMEN: ODOM, TRUEPOS, RAWLASER1), report.json and "
        "figure.png to --out. Route coordinates are in the plan's world frame (for a "
        "HouseExpo JSON plan: HouseExpo's own x, y, theta, as its trajectory files). The "
        "--out folder is written whole at the end (an existing one is replaced).",
        epilog="example: map2map simulate plan.yaml --out run1 --seed 3 --fov 180 --gif",
    )
    p.add_argument("input", metavar="PLAN", help="floor plan (any format convert reads)")
    p.add_argument("--out", required=True, help="output folder")
    p.add_argument("--seed", type=int, default=0, help="random seed (default: 0)")
    p.add_argument(
        "--duration",
        type=float,
        default=420.0,
        metavar="SECONDS",
        help="simulated time budget (default: 420 = 7 minutes)",
    )
    p.add_argument(
        "--fov",
        type=float,
        choices=[360.0, 180.0],
        default=360.0,
        metavar="{360,180}",
        help="lidar field of view in degrees (default: 360, the LDS-01's full circle; the "
        "thesis cut it to 180 to get more deformed maps, as 'dataset build' does by default)",
    )
    p.add_argument(
        "--mapper",
        default="rbpf",
        help=f"mapping backend: {', '.join(available_mappers())} (default: rbpf, the "
        "GMapping-style particle filter the thesis used; oracle maps at the true poses)",
    )
    route = p.add_mutually_exclusive_group()
    route.add_argument("--waypoints", metavar="FILE", help="drive through waypoints (x y per line)")
    route.add_argument(
        "--trajectory",
        metavar="FILE",
        help="follow a recorded trajectory CSV (x,y,theta or t,x,y,theta)",
    )
    p.add_argument(
        "--start",
        nargs=3,
        type=float,
        metavar=("X", "Y", "THETA"),
        help="true start pose in the plan frame (default: random, or the route's start)",
    )
    p.add_argument("--obstacles", type=int, default=0, metavar="N", help="random furniture boxes")
    p.add_argument("--people", type=int, default=0, metavar="N", help="people walking around")
    p.add_argument("--gif", action="store_true", help="also write exploration.gif")
    p.add_argument(
        "--bag",
        choices=["ros1", "ros2", "mcap"],
        help="also write the log's odometry and scans as a ROS bag: ros1 (run.bag), ros2 "
        "(sqlite3) or mcap (folder run_bag); needs pip install 'map2map[ros]'",
    )
    p.add_argument("--quiet", action="store_true", help="no progress bar")
    add_input_options(p)
    p.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    from ..jobs.simulate import SimulateSpec, simulate

    # a plan refused below (no free space...) is said in one line, without its warnings
    with warnings_unless_error():
        run = simulate(
            SimulateSpec(
                plan=load_from_args(args),
                plan_name=args.input,
                out=args.out,
                seed=args.seed,
                duration=args.duration,
                fov=args.fov,
                mapper=args.mapper,
                waypoints=args.waypoints,
                trajectory=args.trajectory,
                start=tuple(args.start) if args.start else None,
                obstacles=args.obstacles,
                people=args.people,
                gif=args.gif,
                progress=not args.quiet,
                bag=args.bag,
            )
        )
    rep = run.result.report()
    print(
        f"simulated {rep['simulated_seconds']:.0f} s ({rep['stop_reason']}, "
        f"{rep['fov_deg']:g} deg lidar) in "
        f"{rep['wall_seconds']:.1f} s: coverage {100 * rep['coverage']:.1f} %, "
        f"path {rep['path_length_m']:.1f} m, {rep['collisions']} collisions"
    )
    for name, path in run.written.items():
        print(f"  {name:<22s} {path}")
    return 0
