"""``map2map dataset``: build, inspect, clean and export paired CAD/SLAM datasets."""

from __future__ import annotations

import argparse
import json

from ..datasets.build import MAX_COUNT
from ..datasets.pair import BuildParams
from ..jobs.dataset import BuildSpec


def register(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser(
        "dataset",
        help="paired CAD/SLAM datasets at scale: build (local or Dask), status, clean, export",
        description="Build a paired dataset of (A: plan, B: SLAM map) the way thesis sec. 4.1 "
        "did with Gazebo, in one resumable command; clean it with the thesis's Extra Trees "
        "classifier; export it for pix2pix or as one packed file.",
    )
    cmds = p.add_subparsers(dest="dataset_command", metavar="ACTION")
    cmds.required = True

    b = cmds.add_parser(
        "build",
        help="make (or continue making) the pairs of a dataset",
        description="Make pairs 0..N-1 of dataset --out. Pair i depends only on (--seed, i): "
        "the same command gives byte-identical pairs whatever --workers and however often "
        "it was interrupted; rerun it after a crash or kill to continue. Bad plans are "
        "recorded as failed and the build goes on.",
        epilog="example: map2map dataset build --out DS --plans generated --count 40 --seed 0 "
        "--workers 2",
    )
    job, pair = BuildSpec, BuildParams  # the defaults, read here, not written again
    b.add_argument("--out", required=True, metavar="DS", help="dataset folder")
    b.add_argument(
        "--plans",
        required=True,
        metavar="SOURCE",
        help="'generated' (procedural plans, HouseExpo-like sizes), or a folder of HouseExpo "
        "JSON files/renders or ROS/image maps",
    )
    b.add_argument("--count", required=True, type=int, metavar="N",
                   help=f"number of pairs (at most {MAX_COUNT})")
    b.add_argument("--seed", type=int, default=job.seed, help="dataset seed (default: %(default)s)")
    where = b.add_mutually_exclusive_group()
    where.add_argument(
        "--workers", type=int, default=None, metavar="K",
        help="local worker processes (default: 1; with --scheduler local: LocalCluster size)",
    )  # fmt: skip
    b.add_argument(
        "--scheduler",
        metavar="ADDR",
        help="run on a dask.distributed cluster: tcp://host:8786, or 'local' for a "
        "LocalCluster of --workers processes (needs the 'dask' extra)",
    )
    b.add_argument(
        "--source", choices=["simulate", "deform", "both"], default=pair.source,
        help="simulated robot + SLAM (simulate), the parametric model (deform), or one of "
        "each per plan (default: %(default)s)",
    )  # fmt: skip
    b.add_argument(
        "--fov",
        type=float,
        choices=[180.0, 360.0],
        default=pair.fov,
        metavar="{180,360}",
        help="lidar field of view (default: %(default)g, the thesis's: fewer features seen "
        "per scan, more deformed maps; simulate's default is 360, the LDS-01's full circle)",
    )
    b.add_argument("--size", type=int, default=pair.size,
                   help="preprocessed map side (default: %(default)s)")
    b.add_argument("--duration", type=float, default=pair.duration, metavar="SECONDS",
                   help="simulated exploration time (default: %(default)g s)")
    b.add_argument("--mapper", default=pair.mapper, help="SLAM backend (default: %(default)s)")
    b.add_argument("--thicken", type=int, default=pair.thicken, metavar="PX",
                   help="pixels the plan's walls grow after resizing (default: %(default)s)")
    b.add_argument("--resolution", type=float, default=job.resolution, metavar="R",
                   help="working resolution of the plans in m/px (default: %(default)g)")
    b.add_argument("--plan-resolution", type=float, metavar="R",
                   help="m/px of picture plans (HouseExpo renders: 0.01; default: stored, "
                   "else 0.05)")  # fmt: skip
    b.add_argument("--max-attempts", type=int, default=job.max_attempts, metavar="N",
                   help="runs of a pair whose worker died before it counts as failed "
                   "(default: %(default)s)")
    b.add_argument("--no-figures", action="store_true", help="skip the contact sheet/histograms")
    b.add_argument("--quiet", action="store_true", help="no progress bar")
    b.set_defaults(func=run_build)

    s = cmds.add_parser("status", help="counts, failures with their reasons, cleaner, splits")
    s.add_argument("ds", metavar="DS", help="dataset folder")
    s.add_argument("--json", action="store_true", help="print the status as JSON")
    s.set_defaults(func=run_status)

    c = cmds.add_parser(
        "clean",
        help="thesis 4.1 cleaner: 16 features, Extra Trees, split by P(complete)",
        description="Label pairs complete/partial from the simulator's coverage of the "
        "reachable free space (or --labels), cross-validate and train the thesis's "
        "ExtraTreesClassifier(max_features=11, n_estimators=100), and mark each pair "
        "complete (P > 0.8), partial (P < 0.4) or review. With --model, apply a saved "
        "classifier to a dataset or a folder of pairs instead.",
    )
    c.add_argument("ds", metavar="DS", help="dataset folder (or, with --model, a folder of pairs)")
    c.add_argument("--labels", metavar="CSV", help="manual labels: index,label (complete/partial)")
    c.add_argument("--coverage-threshold", type=float, default=None, metavar="C",
                   help="coverage from which a pair is complete (default: 0.8)")  # fmt: skip
    c.add_argument("--model", metavar="FILE.skops", help="apply this saved classifier")
    c.add_argument("--out", metavar="CSV", help="with --model: write the decisions here")
    c.set_defaults(func=run_clean)

    e = cmds.add_parser("export", help="pix2pix A|B layout, A/ B/ folders, or DS/packed.npz")
    e.add_argument("ds", metavar="DS", help="dataset folder")
    e.add_argument("--format", required=True, choices=["pix2pix", "folders", "packed"])
    e.add_argument("--out", metavar="DIR", help="output folder (default: DS/export/FORMAT)")
    e.add_argument("--all", action="store_true", help="every done pair, cleaned or not")
    e.add_argument("--include-review", action="store_true",
                   help="also the pairs the cleaner left for review")  # fmt: skip
    e.add_argument("--quiet", action="store_true", help="no progress bar")
    e.set_defaults(func=run_export)


def run_build(args: argparse.Namespace) -> int:
    from ..jobs.dataset import BuildSpec, build

    summary = build(BuildSpec(
        args.out, args.plans, args.count, args.seed,
        dict(source=args.source, fov=args.fov, size=args.size, duration=args.duration,
             mapper=args.mapper, thicken=args.thicken),
        workers=1 if args.workers is None else args.workers, scheduler=args.scheduler,
        resolution=args.resolution, plan_resolution=args.plan_resolution,
        max_attempts=args.max_attempts, progress=not args.quiet,
        figures=not args.no_figures))
    print("\n".join(summary.lines()))
    return 0


def run_status(args: argparse.Namespace) -> int:
    from ..jobs.dataset import status

    st = status(args.ds)
    if args.json:
        print(json.dumps(st, indent=1, default=str))
        return 0
    ident = st["identity"]
    c = st["counts"]
    print(f"{args.ds}: {c.get('done', 0)}/{st['count']} done, {c.get('failed', 0)} failed, "
          f"{c.get('crashed', 0)} waiting for a retry after a worker died")  # fmt: skip
    print(
        f"  plans {ident['plans']}, seed {ident['seed']}, "
        + ", ".join(f"{k} {v}" for k, v in ident["params"].items())
    )
    if st["splits"]:
        print("  splits: " + ", ".join(f"{k} {v}" for k, v in sorted(st["splits"].items())))
    if st["last_build"]:
        lb = st["last_build"]
        print(f"  last build: {lb['made']} made, {lb['failed']} failed in {lb['seconds']:.0f} s "
              f"({lb['pairs_per_hour']:.0f} pairs/h)")  # fmt: skip
    if st["cleaner"]:
        cl = st["cleaner"]
        print(
            f"  cleaner: accuracy {100 * cl['cv_accuracy']:.1f} % ({cl['folds']}-fold), "
            + ", ".join(f"{k} {v}" for k, v in sorted(st["clean"].items()))
        )
    for idx, plan, reason in st["failed"]:
        print(f"  failed {idx:6d} ({plan}): {reason}")
    for idx, n, reason in st["crashed"]:
        print(f"  retry  {idx:6d}: {reason} ({n} attempt{'s' if n > 1 else ''})")
    return 0


def run_clean(args: argparse.Namespace) -> int:
    from ..jobs.dataset import CleanSpec, clean

    run = clean(CleanSpec(args.ds, labels=args.labels,
                          coverage_threshold=args.coverage_threshold, model=args.model,
                          out=args.out))
    if args.model:
        print(f"{args.ds}: {len(run.rows)} pairs: "
              + ", ".join(f"{k} {v}" for k, v in sorted(run.counts.items())))
        return 0
    print("\n".join(run.report.lines()))
    return 0


def run_export(args: argparse.Namespace) -> int:
    from ..jobs.dataset import ExportSpec, export

    res = export(ExportSpec(args.ds, args.format, args.out, everything=args.all,
                            include_review=args.include_review, progress=not args.quiet))
    print(
        f"{res.path}: {res.count} pairs ("
        + ", ".join(f"{k} {v}" for k, v in res.splits.items())
        + f"), {res.bytes / 2**20:.2f} MiB"
    )
    return 0
