"""``map2map show``: draw a map or floor plan as a picture a person can read."""

from __future__ import annotations

import argparse

from ._mapargs import add_input_options, read_options_from_args, say_how_read


def register(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser(
        "show",
        help="draw a map or floor plan (free/occupied/unknown colours, metric scale bar)",
        description="Read IN (any format convert reads) and draw it: free, occupied and "
        "unknown cells in distinct colours, a metric scale bar, a legend, and the size, "
        "resolution and free area in the title.",
        epilog="example: map2map show plan.json --out plan.png --resolution 0.05",
    )
    p.add_argument("input", metavar="IN", help="input map or floor plan")
    p.add_argument("--out", required=True, help="figure file (.png, .pdf or .svg)")
    p.add_argument("--title", help="first title line (default: the input's file name)")
    add_input_options(p)
    p.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    from ..jobs.maps import ShowSpec, show
    from ..maps.render import map_summary

    run = show(ShowSpec(args.input, args.out, args.title, read_options_from_args(args)))
    say_how_read(args.input, run.map)
    print(f"wrote {args.out}: {map_summary(run.map)}")
    return 0
