"""``map2map demo``: run every stage on the embedded default floor plan."""

from __future__ import annotations

import argparse
import sys


def register(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser(
        "demo",
        help="run every stage on a generated floor plan (no downloads)",
        description="Generate a floor plan and run every map2map stage on it, "
        "writing maps and figures to --out.",
    )
    p.add_argument("--out", default="demo_out", help="output folder (default: demo_out)")
    p.add_argument("--seed", type=int, default=0, help="random seed (default: 0)")
    p.add_argument("--quiet", action="store_true", help="no progress bar")
    p.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    from ..demo import run_demo

    ctx = run_demo(args.out, seed=args.seed, progress=not args.quiet)
    print(f"map2map demo finished in {sum(ctx.timings.values()):.1f} s; wrote:")
    for what, path in ctx.written:
        print(f"  {what:<40s} {path}")
    figures = [str(p) for _, p in ctx.written if p.suffix in {".png", ".gif"}]
    if figures:
        print("pictures: " + ", ".join(figures))
    print(f"index of the folder (what each step did, its numbers, its files): "
          f"{ctx.out / 'index.html'} and README.md")  # fmt: skip
    sys.stdout.flush()
    return 0
