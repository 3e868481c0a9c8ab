"""``map2map prep``: thesis 4.1 preprocessing of a map (square, resize, thicken, crop)."""

from __future__ import annotations

import argparse

from ._mapargs import add_input_options, read_options_from_args, say_how_read


def register(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser(
        "prep",
        help="square, resize, harmonise and thicken a map for learning (thesis 4.1)",
        description="Preprocess a map as the thesis did before training (section 4.1): "
        "pixel values to SLAM values, optional crop to the known content, pad to a square "
        "with unknown and resize to SIZE x SIZE without distorting the aspect (thin walls "
        "survive), and thicken occupied edges by K pixels. Resolution and origin are updated "
        "so the metric frame stays right.",
        epilog="example: map2map prep plan.yaml plan256.png --size 256 --thicken 1 --crop",
    )
    p.add_argument(
        "input", metavar="IN", help="input map (ROS yaml, PNG/PGM/JPG, HouseExpo JSON, DXF)"
    )
    p.add_argument("output", metavar="OUT", help="output .yaml (ROS map) or .png/.pgm")
    p.add_argument("--size", type=int, default=256, help="output side in pixels (default: 256)")
    p.add_argument(
        "--thicken", type=int, default=0, metavar="K", help="thicken walls by K pixels (default: 0)"
    )
    p.add_argument("--crop", action="store_true", help="crop to the known content first")
    p.add_argument(
        "--margin",
        type=int,
        default=4,
        metavar="PX",
        help="unknown margin (pixels of the input) kept around the content by --crop (default: 4)",
    )
    p.add_argument("--figure", help="also save a before/after picture (.png/.pdf/.svg)")
    add_input_options(p)
    p.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    from ..jobs.maps import PrepSpec, prep
    from ..maps.render import map_summary

    run = prep(
        PrepSpec(
            args.input,
            args.output,
            size=args.size,
            thicken=args.thicken,
            crop=args.crop,
            margin=args.margin,
            figure=args.figure,
            read_options=read_options_from_args(args),
        )
    )
    say_how_read(args.input, run.map)
    print(f"{args.input}: {map_summary(run.map)}\n -> {args.output}: {map_summary(run.result)}")
    return 0
