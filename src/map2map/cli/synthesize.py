"""``map2map synthesize``: K SLAM-map hypotheses for a CAD plan (the robot's own scans at
its particle filter's poses by default, or Model_AB)."""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

from ..jobs.synthesize import SynthesizeSpec
from ..learn.ab.config import POSE_ERRORS
from ._mapargs import add_input_options, read_options_from_args, say_how_read


def register(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser(
        "synthesize",
        help="CAD -> SLAM: K SLAM-map hypotheses of a plan (scans, or Model_AB)",
        description="Generate --samples SLAM-map hypotheses of a CAD plan, in the plan's "
        "frame, resolution and origin: by default each is the simulated robot's own "
        "exploration mapped at its particle filter's poses (no network); with --model "
        "pretrained or a run, Model_AB's output (test-time dropout, seeded). Writes "
        "OUT/<plan>_hypNN.yaml (+ .pgm; or .png with --format png), OUT/<plan>_synthesize.json "
        "(diversity: mean pairwise pixel disagreement) and OUT/<plan>_synthesize.png.",
    )
    d = SynthesizeSpec  # the job's defaults, read here, not written again
    p.add_argument("input", metavar="PLAN", help="CAD plan (ROS yaml, PNG, DXF, ...)")
    p.add_argument("--out", required=True, help="output folder")
    p.add_argument("--samples", type=int, default=d.samples,
                   help="number of hypotheses K (default %(default)s)")
    p.add_argument("--model", default=d.model,
                   help="'scans' (the default): no network, the robot's own exploration "
                   "mapped at its particle filter's poses (the rendering, drift, coverage "
                   "and traces "
                   "options below do not apply); 'pretrained': the shipped Model_AB weights; "
                   "or a 'train ab' run folder or weights file (default %(default)s)")
    p.add_argument("--seed", type=int, default=d.seed,
                   help="seed of every random draw: the explorations and pose errors, or "
                   "the network's dropout masks (default %(default)s)")
    p.add_argument("--start", type=float, nargs=3, metavar=("X", "Y", "YAW"),
                   default=d.start, help="scans: where the robot starts every hypothesis "
                   "(metres and radians in the plan's frame, as simulate --start; default: "
                   "each hypothesis draws its own start in the free space)")
    p.add_argument("--explore-map", choices=("rbpf", "grid", "oracle"), default=d.explore_map,
                   help="scans: the map the robot explores on: rbpf, the particle filter's "
                   "(as a simulated run's robot; the default); grid, GMapping's grid at the "
                   "true poses (faster); oracle, the simulator's perfect map")
    p.add_argument("--pose-error", choices=POSE_ERRORS, default=d.pose_error,
                   help="scans: the poses the scans are mapped at: the exploring particle "
                   "filter's own (each hypothesis is then a simulated rbpf run's map; the "
                   "default with --explore-map rbpf), learned (drawn step by step by the "
                   "pose-error model learned from rbpf runs, 'train pose-error') or drawn "
                   "(room drift, turn and jitter; the default with the other exploration "
                   "maps)")
    p.add_argument("--pose-model", default=d.pose_model, metavar="FILE",
                   help="scans, --pose-error learned: a model of 'map2map train pose-error' "
                   "(default: the shipped one)")
    p.add_argument("--format", choices=("ros", "png"), default=d.format,
                   help="ros: .yaml + .pgm; png: pictures (default %(default)s)")
    p.add_argument("--render", choices=("slam", "plain"), default=d.render,
                   help="slam: walls as a SLAM map draws them, the faces next to free space "
                   "with the training maps' wall thickness, wall interiors unknown; plain: "
                   "the network's output snapped and upsampled (nearest) (default "
                   "%(default)s)")
    p.add_argument("--drift", choices=("rooms", "parametric", "none"), default=d.drift,
                   help="rooms: one rigid transform per room chained along a walk through "
                   "the doors, blended across walls (the simulated maps' wall error, walls "
                   "kept whole), plus the parametric field smoothed; parametric: warp each "
                   "hypothesis along its own drift field of the parametric CAD->SLAM model "
                   "(thesis 3.2: a route through the plan, LIDAR + odometry errors); none: "
                   "the network's straight walls (default %(default)s)")
    p.add_argument("--drift-method", choices=("additive", "ekf"), default=d.drift_method,
                   help="the drift's odometry-to-map conversion (additive: thesis eqs. "
                   "3.81-3.90; ekf: 3.54-3.80; default %(default)s)")
    p.add_argument("--drift-scale", type=float, default=d.drift_scale,
                   help="factor on the drift field (default 1: the parametric model's "
                   "own error magnitudes; docs/synthesize.md)")
    p.add_argument("--coverage", choices=("explore", "rays", "none"), default=d.coverage,
                   help="explore: the simulator's robot explores the plan for each "
                   "hypothesis (oracle mapper, 275 s, 180 degree LIDAR, seeded; about 0.5 s "
                   "a hypothesis) and what it did not see becomes unknown, as a 7-minute run "
                   "leaves rooms unseen; rays: the same exploration, and the free space is "
                   "what its rays crossed, with the network's walls (measured, not the "
                   "default: docs/synthesize.md); none: every room the network draws "
                   "(default %(default)s)")
    p.add_argument("--traces", choices=("lidar", "none"), default=d.traces,
                   help="lidar (default with --render slam): what a LIDAR + SLAM leaves "
                   "beyond the faces, a wall band of metric width with a ragged back edge "
                   "and stray hits off the walls; none: the training maps' wall thickness")
    p.add_argument("--drift-route", choices=("tour", "explore"), default=d.drift_route,
                   help="the drift's path: tour, a roadmap tour of the plan; explore: the "
                   "hypothesis's exploration (the same one as --coverage explore) (default "
                   "%(default)s)")
    p.add_argument("--no-figure", action="store_true", help="do not write the figure")
    p.add_argument("--device", default=d.device, help="torch device (default %(default)s)")
    add_input_options(p)
    p.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    from ..jobs.synthesize import synthesize

    run = synthesize(SynthesizeSpec(
        args.input, args.out, samples=args.samples, model=args.model, seed=args.seed,
        format=args.format, render=args.render, drift=args.drift,
        drift_method=args.drift_method, drift_scale=args.drift_scale, coverage=args.coverage,
        drift_route=args.drift_route, traces=args.traces,
        start=None if args.start is None else tuple(args.start),
        explore_map=args.explore_map, pose_error=args.pose_error,
        pose_model=args.pose_model, device=args.device,
        figure=not args.no_figure, read_options=read_options_from_args(args)))
    say_how_read(args.input, run.plan)
    src, res = Path(args.input), run.result
    for w in res.warnings:
        print(f"map2map: warning: {src}: {w}", file=sys.stderr)
    print(f"{args.samples} hypotheses of {src.name} in {Path(args.out)} (mean pairwise "
          f"disagreement "
          f"{res.diversity:.2%}; model {res.model})", file=sys.stderr)
    return 0
