"""``map2map evaluate``: how far apart a SLAM map and a floor plan are, where, in centimetres."""

from __future__ import annotations

import argparse
from pathlib import Path

from ._mapargs import add_input_options, read_options_from_args


def register(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser(
        "evaluate",
        help="local error between a SLAM map and its floor plan (Algorithm 1)",
        description="Align SLAM_MAP to PLAN, optimise the rigid and nonrigid chains (eq. 7) and "
        "measure the local error of every wall point (Algorithm 1), in pixels and metres; "
        "write report.json (both chains, the chosen one, IoU, vanilla ICP, timings), "
        "overlay.png and error_map.png. With --pairs, evaluate every pair of a CSV list "
        "(header slam,plan[,anchors]) and write pairs.csv and errors_boxplot.png. The --out "
        "folder is written whole at the end (an existing one is replaced).",
    )
    p.add_argument("slam", metavar="SLAM_MAP", nargs="?", help="the SLAM (as-built) map")
    p.add_argument("plan", metavar="PLAN", nargs="?", help="the floor plan (as-planned)")
    p.add_argument("--out", required=True, help="output folder")
    p.add_argument("--pairs", metavar="FILE", help="CSV list of map pairs instead of one pair")
    p.add_argument(
        "--anchors",
        metavar="FILE",
        help="CSV x_source,y_source,x_target,y_target (pixels): two point pairs (eqs. 1-6)",
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
        help="metres per pixel of SLAM_MAP only (wins over --resolution)",
    )
    p.add_argument(
        "--target-resolution",
        type=float,
        metavar="R",
        help="metres per pixel of PLAN only (wins over --resolution)",
    )
    p.add_argument(
        "--strict",
        action="store_true",
        help="exit with status 3 when the result carries a warning (doubtful alignment)",
    )
    p.add_argument(
        "--units",
        choices=("auto", "m", "px"),
        default="auto",
        help="report errors in metres or pixels; auto (default): metres when PLAN has a "
        "metric scale (a ROS yaml, a picture with a stored resolution, HouseExpo JSON, DXF, "
        "or --resolution), else pixels, with a note",
    )
    p.add_argument(
        "--report",
        metavar="HTML",
        help="also write an as-built inspection report: HTML (self-contained, prints to PDF), "
        "its Markdown twin and a CSV of every plan wall segment with pass / fail / not "
        "observed (with --pairs: one report per pair, HTML_<pair>.html); a relative path "
        "is inside --out",
    )
    p.add_argument(
        "--tolerance",
        type=float,
        metavar="M",
        help="largest acceptable wall deviation for --report, metres (default: 0.05)",
    )
    p.add_argument("--no-auto-anchors", action="store_true", help="do not look for anchor points")
    p.add_argument("--seed", type=int, default=0, help="random seed (default: 0)")
    add_input_options(p, resolution=False, several=True)
    p.add_argument("--quiet", action="store_true", help="no progress bar")
    p.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    from ..core.errors import InputError
    from ..evaluate.metric import summary_lines
    from ..jobs.evaluate import EvaluateSpec, evaluate
    from .align import report_warnings

    tolerance = 0.05
    if args.report is not None:  # checked before any work
        from ..evaluate.walls import check_tolerance
        from ..reports.inspection import check_report_path

        if args.tolerance is not None:
            tolerance = check_tolerance(args.tolerance)
        if args.units == "px":
            raise InputError("--report", "the inspection report needs errors in metres, "
                             "not --units px")  # fmt: skip
        check_report_path(_report_path(args), "--report")
    elif args.tolerance is not None:
        raise InputError("--tolerance", "applies to the inspection report: add --report FILE")
    run = evaluate(
        EvaluateSpec(
            args.slam,
            args.plan,
            args.out,
            pairs=args.pairs,
            anchors=args.anchors,
            resolution=args.resolution,
            source_resolution=args.source_resolution,
            target_resolution=args.target_resolution,
            units="m" if args.report is not None and args.units == "auto" else args.units,
            auto_anchor=not args.no_auto_anchors,
            seed=args.seed,
            read_options=read_options_from_args(args),
            progress=not args.quiet,
        )
    )
    if args.pairs:
        unit = run.units
        for r in run.rows:
            print(
                f"{r['pair']:<24s} {r['chosen_chain']:<8s} wall mean {r['mean_' + unit]:.4g} "
                f"{unit}, wall max {r['max_' + unit]:.4g} {unit}"
                + ("  (WARNING)" if r["warnings"] else "")
            )
        print(f"wrote {args.out}/pairs.csv and {args.out}/errors_boxplot.png")
        _inspection(run, args, tolerance)
        return report_warnings(run.warnings, args.strict, run.notes)
    for line in summary_lines(run.evaluation.report):
        print(line)
    print(f"wrote report.json, overlay.png, error_map.png in {args.out}")
    _inspection(run, args, tolerance)
    return report_warnings(run.warnings, args.strict, run.notes)


def _report_path(args: argparse.Namespace) -> Path:
    """``--report``: inside ``--out`` unless absolute."""
    p = Path(args.report)
    return p if p.is_absolute() else Path(args.out) / p


def _inspection(run, args: argparse.Namespace, tolerance: float) -> None:
    """Write the inspection report(s) of ``--report`` and say what they found."""
    if args.report is None:
        return
    from ..reports.inspection import write_run_inspections

    for f in write_run_inspections(run, _report_path(args), tolerance=tolerance):
        print(f"wrote {f.html}, {f.md.name} and {f.csv.name}: walls {f.summary()}")
