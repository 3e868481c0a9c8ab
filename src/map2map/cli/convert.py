"""``map2map convert``: any supported map or floor plan to a ROS map or a picture."""

from __future__ import annotations

import argparse
from pathlib import Path

from ._mapargs import add_input_options, load_from_args


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
    from ..maps.formats import check_output_path, save_map
    from ..maps.render import map_summary

    check_output_path(args.output)  # before reading: fail fast, write nothing
    m = load_from_args(args)
    save_map(m, args.output)
    written = str(args.output)
    if Path(args.output).suffix.lower() in (".yaml", ".yml"):
        written += f" and {Path(args.output).with_suffix('.pgm')}"
    print(f"wrote {written}: {map_summary(m)}")
    return 0
