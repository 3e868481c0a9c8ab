"""``map2map deform``: model SLAM maps of a floor plan with the parametric model (thesis 3.2)."""

from __future__ import annotations

import argparse
import dataclasses
import sys
from pathlib import Path

from ._mapargs import add_input_options, read_options_from_args


def register(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser(
        "deform",
        help="model SLAM maps of a floor plan (parametric LIDAR + odometry error model)",
        description=(
            "Drive a TurtleBot3 along a trajectory through PLAN and model the SLAM map it "
            "would build (thesis section 3.2): LIDAR errors (eqs. 3.8-3.30) and odometry "
            "errors (3.31-3.53) converted to map errors by the additive method the thesis "
            "takes from its reference [58] (3.81-3.90: errors growing linearly with the "
            "distance driven and angle turned, added up at every re-observation of a "
            "pixel) or by EKF-SLAM (3.54-3.80). Writes per sample: slam_map.yaml + "
            "slam_map.pgm (the plan's resolution and origin), displacement.npz (dx, dy in "
            "pixels, float32: plan content at pixel p appears at p + d(p); x = columns "
            "right, y = rows down), trajectory.csv (t,x,y,theta,v,omega), params.yaml "
            "(everything needed to repeat the run) and figure.png. With --samples K > 1 "
            "they go to sample_000/, sample_001/, ...; sample k uses seed N + k. "
            "Coordinates (--start, --goal, waypoints, trajectories) are metres in the "
            "plan's frame (ROS maps: the ROS world frame; HouseExpo JSON: HouseExpo's x, "
            "y, as simulate takes them; see --route-frame), headings radians "
            "counter-clockwise. The --out folder is written whole at the end (an "
            "existing one is replaced)."
        ),
    )
    p.add_argument(
        "plan", metavar="PLAN", help="floor plan (ROS yaml, PNG/PGM/JPG, HouseExpo JSON, DXF)"
    )
    p.add_argument("--out", required=True, metavar="DIR", help="output folder")
    p.add_argument(
        "--method",
        choices=["additive", "ekf"],
        default="additive",
        help="odometry-to-map conversion: the additive method of the thesis's ref. [58] "
        "(fast, default) or EKF",
    )
    p.add_argument("--seed", type=int, default=0, help="random seed of sample 0 (default: 0)")
    p.add_argument(
        "--samples", type=int, default=1, metavar="K", help="number of maps (default: 1)"
    )
    p.add_argument("--start", type=float, nargs=2, metavar=("X", "Y"), help="start point [m]")
    p.add_argument("--goal", type=float, nargs=2, metavar=("X", "Y"), help="goal point [m]")
    p.add_argument(
        "--waypoints",
        metavar="FILE",
        help="text file of 'x y' world points [m], one per line; the path visits them in order",
    )
    p.add_argument(
        "--trajectory",
        metavar="FILE",
        help="recorded trajectory CSV (x,y,theta or t,x,y,theta[,v,omega]) to drive instead",
    )
    p.add_argument(
        "--fov", type=int, choices=[360, 180], help="LIDAR field of view in degrees (default 360)"
    )
    p.add_argument("--params", metavar="FILE.yaml", help="model parameters (YAML) to override")
    p.add_argument(
        "--resolution", type=float, metavar="R", help="metres per pixel, for pictures without one"
    )
    p.add_argument(
        "--route-frame",
        choices=["plan", "world"],
        default="plan",
        help="frame of --start/--goal/--waypoints/--trajectory: the plan's own (default; for "
        "a HouseExpo JSON plan HouseExpo's x, y with y down, as simulate takes them) or the "
        "map's ROS world frame (what a sample's trajectory.csv is written in)",
    )
    p.add_argument("--quiet", action="store_true", help="no progress bar")
    add_input_options(p, resolution=False)
    p.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    from ..jobs.deform import DeformSpec, deform

    run = deform(
        DeformSpec(
            plan=Path(args.plan),
            out=Path(args.out),
            method=args.method,
            seed=args.seed,
            samples=args.samples,
            start=tuple(args.start) if args.start else None,
            goal=tuple(args.goal) if args.goal else None,
            waypoints=Path(args.waypoints) if args.waypoints else None,
            trajectory=Path(args.trajectory) if args.trajectory else None,
            fov=args.fov,
            params=Path(args.params) if args.params else None,
            resolution=args.resolution,
            read_options=dataclasses.replace(read_options_from_args(args), resolution=None),
            route_frame=args.route_frame,
            progress=not args.quiet,
        )
    )
    for s in run.samples:
        print(
            f"{s.folder}: |d| mean {s.stats['mean']:.2f} px, max {s.stats['max']:.2f} px "
            f"({s.stats['method']}, {s.stats['seconds']:.1f} s)"
        )
    sys.stdout.flush()
    return 0
