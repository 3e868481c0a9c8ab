"""``map2map plan``: generate a procedural floor plan (apartment or office)."""

from __future__ import annotations

import argparse


def register(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser(
        "plan",
        help="generate a random apartment or office floor plan",
        description="Generate a seeded floor plan like HouseExpo's (rooms, corridors, doors "
        "0.7-1.0 m, outer and interior walls) whose free space is one connected component for "
        "a 0.2 m robot, and save it as a map (ROS yaml+pgm, PNG, ... by the suffix of --out).",
    )
    p.add_argument("--seed", type=int, default=0, help="random seed (default: 0)")
    p.add_argument(
        "--out", required=True, help="output map, format from the suffix (e.g. plan.yaml)"
    )
    p.add_argument(
        "--size",
        nargs=2,
        type=float,
        metavar=("W", "H"),
        help="outer size of the building in metres (default: random for the kind; >= 4 m)",
    )
    p.add_argument(
        "--resolution", type=float, default=0.05, help="metres per pixel (default: 0.05)"
    )
    p.add_argument(
        "--kind", choices=("apartment", "office"), default="apartment", help="building kind"
    )
    p.add_argument(
        "--furniture", action="store_true", help="add furniture-like obstacles inside rooms"
    )
    p.add_argument(
        "--figure", help="also save a picture with room labels and doors (.png/.pdf/.svg)"
    )
    p.add_argument(
        "--meta",
        help="also save the layout (rooms, doors, furniture) as .json; 'map2map convert' "
        "reads it back as the plan (at any --resolution)",
    )
    p.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    from ..jobs.maps import PlanSpec, plan

    run = plan(
        PlanSpec(
            args.out,
            seed=args.seed,
            kind=args.kind,
            size=None if args.size is None else tuple(args.size),
            resolution=args.resolution,
            furniture=args.furniture,
            figure=args.figure,
            meta=args.meta,
        )
    )
    m = run.plan
    written = [args.out] + [f for f in (args.meta, args.figure) if f]
    print(
        f"{args.kind}: {len(m.meta['rooms'])} rooms, {len(m.meta['doors'])} doors, "
        f"{m.width}x{m.height} px at {m.resolution:g} m/px -> {', '.join(written)}"
    )
    return 0
