"""``map2map convert``: any supported map or floor plan to a ROS map or a picture."""

from __future__ import annotations

import argparse

from ._mapargs import add_input_options, read_options_from_args, say_how_read


def register(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser(
        "convert",
        help="convert a map or floor plan (ROS yaml, PNG/PGM/JPG, HouseExpo JSON, DXF) "
        "to a ROS map, a picture or a DXF drawing",
        description="Read IN (ROS map_server .yaml, a .png/.pgm/.jpg picture, a HouseExpo "
        ".json plan or a .dxf drawing) and write OUT: a ROS map (.yaml, with a .pgm of the "
        "same name beside it, as map_saver writes it), a picture (.png/.pgm with 0 "
        "occupied, 127 unknown, 255 free) or a DXF drawing of the walls (.dxf, metres).",
        epilog="example: map2map convert plan.dxf plan.yaml --layers WALLS --units mm",
    )
    p.add_argument("input", metavar="IN", help="input map or floor plan")
    p.add_argument("output", metavar="OUT", help="output .yaml (ROS map), .png/.pgm or .dxf")
    add_input_options(p)
    p.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    from ..jobs.maps import ConvertSpec, convert
    from ..maps.render import map_summary

    run = convert(ConvertSpec(args.input, args.output, read_options_from_args(args)))
    say_how_read(args.input, run.map)
    print(f"wrote {' and '.join(map(str, run.written.values()))}: {map_summary(run.map)}")
    return 0
