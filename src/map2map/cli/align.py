"""``map2map align``: align a SLAM map to a floor plan (similarity, affine, rigid, nonrigid)."""

from __future__ import annotations

import argparse

from ._mapargs import add_input_options, read_options_from_args


def register(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser(
        "align",
        help="align a map to another (similarity, affine, rigid and nonrigid transforms)",
        description="Align SOURCE (e.g. a SLAM map) to TARGET (e.g. a floor plan) by region "
        "decomposition and the fitness of eq. 8, refine it (affine, rigid, nonrigid warp) and "
        "write alignment.json: 3x3 matrices similarity/affine/rigid mapping SOURCE pixel "
        "coordinates (x = column, y = row, origin top-left) to TARGET pixel coordinates, plus "
        "overlay.png. Any rotation, translation and scale between 0.5 and 2. The --out "
        "folder is written whole at the end (an existing one is replaced).",
    )
    p.add_argument("source", metavar="SOURCE", help="map to align (ROS yaml, picture, JSON, DXF)")
    p.add_argument("target", metavar="TARGET", help="reference map (e.g. the floor plan)")
    p.add_argument("--out", required=True, help="output folder")
    p.add_argument(
        "--anchors",
        metavar="FILE",
        help="CSV x_source,y_source,x_target,y_target (pixels): two point pairs (eqs. 1-6)",
    )
    p.add_argument(
        "--points",
        metavar="FILE",
        help="CSV x,y of SOURCE pixels to map; writes points_aligned.csv",
    )
    p.add_argument(
        "--resolution",
        type=float,
        metavar="R",
        help="metres per pixel of picture inputs, both maps (ROS maps keep their own); "
        "without it, a picture with no stored resolution is read at 0.05 m/px with a note "
        "and has no metric scale (no scale bar; evaluate reports pixels)",
    )
    p.add_argument(
        "--source-resolution",
        type=float,
        metavar="R",
        help="metres per pixel of SOURCE only (wins over --resolution)",
    )
    p.add_argument(
        "--target-resolution",
        type=float,
        metavar="R",
        help="metres per pixel of TARGET only (wins over --resolution)",
    )
    p.add_argument(
        "--strict",
        action="store_true",
        help="exit with status 3 when the result carries a warning (doubtful alignment)",
    )
    p.add_argument(
        "--no-auto-anchors",
        action="store_true",
        help="do not look for anchor points automatically",
    )
    p.add_argument("--seed", type=int, default=0, help="random seed (default: 0)")
    add_input_options(p, resolution=False, several=True)
    p.set_defaults(func=run)


def report_warnings(warnings: list[str], strict: bool, notes: list[str] = ()) -> int:
    """Print each note and warning on stderr; the exit status: 3 with ``strict`` and a
    warning, else 0 (notes never change it)."""
    import sys

    from ._messages import as_options

    for n in notes:
        print(f"map2map: note: {as_options(n)}", file=sys.stderr)
    for w in warnings:
        print(f"map2map: warning: {as_options(w)}", file=sys.stderr)
    if warnings and strict:
        print(f"map2map: {len(warnings)} warning(s) and --strict: exit 3", file=sys.stderr)
        return 3
    return 0


def run(args: argparse.Namespace) -> int:
    from ..jobs.evaluate import AlignSpec, align

    run = align(
        AlignSpec(
            args.source,
            args.target,
            args.out,
            anchors=args.anchors,
            points=args.points,
            resolution=args.resolution,
            source_resolution=args.source_resolution,
            target_resolution=args.target_resolution,
            auto_anchor=not args.no_auto_anchors,
            seed=args.seed,
            read_options=read_options_from_args(args),
        )
    )
    doc = run.report
    print(
        f"aligned: scale {doc['scale']:.4f}, rotation {doc['rotation_deg']:.2f} deg, "
        f"translation ({doc['translation'][0]:.1f}, {doc['translation'][1]:.1f}) px, "
        f"fitness {doc['fitness']:.3f}"
    )
    for what, path in run.written.items():
        print(f"  {what:<10s} {path}")
    return report_warnings(run.warnings, args.strict, run.notes)
