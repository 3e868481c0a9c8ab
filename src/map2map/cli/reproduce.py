"""``map2map reproduce``: re-run the thesis's results, write a report beside theirs."""

from __future__ import annotations

import argparse
import shlex
import sys


def register(sub: argparse._SubParsersAction) -> None:
    from ..reports.reproduce.runner import EXIT_SECTION_FAILED, SECTIONS

    p = sub.add_parser(
        "reproduce",
        help="re-run every thesis table and figure, ours beside theirs (HTML + Markdown)",
        description="Re-run every quantitative result of the thesis and its appendix paper "
        "with this project's code and write OUT/report.html (self-contained), "
        "OUT/report.md (+ report_files/) and OUT/results.json. A section that fails is "
        "shown in the report and the run goes on; the exit status is then "
        f"{EXIT_SECTION_FAILED}. Sections: {', '.join(SECTIONS)}.",
    )
    p.add_argument("--out", required=True, help="report folder (files in it are replaced)")
    p.add_argument("--quick", action="store_true",
                   help="reduced sizes: under 5 minutes on 2 cores")  # fmt: skip
    p.add_argument("--only", default="", metavar="SECTION,...",
                   help="run only these sections (comma-separated keys)")  # fmt: skip
    p.add_argument("--seed", type=int, default=0, help="random seed (default: 0)")
    p.add_argument("--data", default=None,
                   help="real data folder (default: $MAP2MAP_SHARED_DATA or ../shared/data)")
    p.add_argument("--quiet", action="store_true", help="no progress lines")
    p.add_argument("--tiny", action="store_true", help=argparse.SUPPRESS)  # tests only
    p.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    from ..reports.reproduce import reproduce

    only = [s.strip() for s in args.only.split(",") if s.strip()] or None
    s = reproduce(args.out, quick=args.quick, sections=only, seed=args.seed, data=args.data,
                  tiny=args.tiny, progress=not args.quiet,
                  command="map2map " + shlex.join(sys.argv[1:]))  # fmt: skip
    for line in s.lines():
        print(line)
    sys.stdout.flush()
    return s.exit_code
