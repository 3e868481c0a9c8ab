"""``map2map autocorrect``: turn SLAM maps into CAD-like plans with Model_BA (or, with
``--model none``, with the classical cleaning alone)."""

from __future__ import annotations

import argparse
import sys

from ._mapargs import add_input_options, read_options_from_args, say_how_read


def register(sub: argparse._SubParsersAction) -> None:
    from ..jobs.autocorrect import model_names_help

    p = sub.add_parser(
        "autocorrect",
        help="SLAM -> CAD auto-correct (classical, or --model thesis: Model_BA)",
        description="Auto-correct a SLAM map into a CAD-like plan (straight walls, no noise) "
        "(--model: the classical cleaning drawn like a plan by default, or the thesis's "
        "Model_BA), in the input's frame, resolution and origin. INPUT may be "
        "a folder: "
        "every map in it is corrected into the --out folder (same names).",
    )
    p.add_argument("input", metavar="INPUT", help="SLAM map (ROS yaml, PNG, ...) or a folder")
    p.add_argument("--out", required=True, help="output map (.yaml/.png/.pgm) or folder")
    p.add_argument("--model", default=None, metavar="NAME|PATH",
                   help="which corrector: " + model_names_help().replace("%", "%%")
                        + " ('pretrained' is 'thesis')")
    p.add_argument("--dxf", metavar="FILE", help="also write the walls as DXF lines (curved walls: "
                   "arcs; with a folder INPUT: a folder)")
    p.add_argument("--figure", metavar="PNG", help="before/after figure (folder INPUT: folder)")
    p.add_argument("--no-straighten", action="store_true",
                   help="only upsample and snap the output (no straight walls)")
    p.add_argument("--no-anchor", action="store_true",
                   help="place the walls where the network's low-resolution output says, "
                        "not on the input's observed wall faces (the default anchors them)")
    p.add_argument("--thickness", default=None, metavar="RULE",
                   help="thickness of the walls drawn behind a face seen from one side: "
                        "'shrink' (the training plans' walls scaled with the map's size), "
                        "'resolution' (their metres at the map's resolution), 'input' (from "
                        "the input's own walls) or a number of pixels (default: "
                        "map2map.learn.ba.autocorrect.THICKNESS)")
    p.add_argument("--open-frontiers", action=argparse.BooleanOptionalAction, default=None,
                   help="leave out the network's walls at the edge of the known area or "
                        "beyond it (partial maps; default: "
                        "map2map.learn.ba.autocorrect.OPEN_FRONTIERS, on for a map "
                        "corrected in tiles)")
    p.add_argument("--large", choices=("resize", "tile", "refuse"), default=None,
                   help="maps more than 2.5x the training maps' size: resized whole, "
                        "corrected in overlapping tiles at the training scale, or returned "
                        "uncorrected (default: map2map.learn.ba.autocorrect.LARGE)")
    p.add_argument("--draw", action=argparse.BooleanOptionalAction, default=None,
                   help="draw the output like a plan: straight walls at the map's dominant "
                        "angle, pieces of a wall joined unless free space passes through "
                        "(a door), corners closed, one thickness, the same segments in the "
                        "DXF (default: on for 'none', off for 'thesis' and weights files, "
                        "the thesis's output as it is)")
    p.add_argument("--draw-thickness", type=float, default=None, metavar="M",
                   help="metres of every wall a drawn output draws (default: the "
                        "plans' convention, 0.20 m plus a pixel on each side; "
                        "map2map.maps.vectorize.default_wall_thickness)")
    p.add_argument("--draw-option", action="append", default=[], metavar="KEY=VALUE",
                   help="a tolerance of the plan drawer (repeatable), a field of "
                        "map2map.maps.vectorize.DrawOptions, e.g. bridge_run=0 (no "
                        "bridges), lean_px=none (every wall straight in its direction)")
    p.add_argument("--device", default="cpu", help="torch device (default cpu)")
    p.add_argument("--workers", type=int, default=None, metavar="N",
                   help="CPU threads for the per-map work and processes for drawing a "
                        "folder of 16 maps or more (default: one per core, at most 8; 1: "
                        "this process only); the outputs are the same")
    add_input_options(p)
    p.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    from ..jobs.autocorrect import AutocorrectSpec, autocorrect, parse_draw_options

    run = autocorrect(AutocorrectSpec(
        args.input, args.out, model=args.model, dxf=args.dxf, figure=args.figure,
        straighten=not args.no_straighten, anchor=not args.no_anchor,
        thickness=args.thickness, open_frontiers=args.open_frontiers, large=args.large,
        device=args.device, read_options=read_options_from_args(args), draw=args.draw,
        draw_thickness=args.draw_thickness,
        draw_options=parse_draw_options(args.draw_option), workers=args.workers))
    for f, m in zip(run.sources, run.inputs, strict=True):
        say_how_read(f, m)
    for f, r in zip(run.sources, run.corrections, strict=True):
        for w in r.warnings:
            print(f"map2map: warning: {f}: {w}", file=sys.stderr)
    print(f"auto-corrected {len(run.corrections)} map(s) with {run.model}", file=sys.stderr)
    return 0
