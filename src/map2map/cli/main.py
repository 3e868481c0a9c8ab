"""Entry point of the ``map2map`` console script.

Each command lives in its own module of this package and exposes
``register(subparsers)``, which adds its parser and sets ``func`` to a function
``func(args) -> int`` that only calls library functions. Adding a command means
adding its module name to :data:`COMMANDS`.
"""

from __future__ import annotations

import argparse
import importlib
import sys
import warnings

from .._version import __version__
from ..core.errors import EXIT_BAD_INPUT, InputError, MapWarning
from ..core.limits import for_command
from ._messages import as_options

#: Command modules, in the order ``--help`` lists them.
COMMANDS = [
    "demo",
    "plan",
    "convert",
    "prep",
    "show",
    "deform",
    "simulate",
    "slam",
    "align",
    "evaluate",
    "dataset",
    "train",
    "autocorrect",
    "synthesize",
    "reproduce",
]


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(
        prog="map2map",
        description="Move robot maps between CAD floor plans and SLAM occupancy maps, "
        "in both directions, and measure how far apart they are.",
    )
    parser.add_argument("--version", action="version", version=f"map2map {__version__}")
    parser.add_argument(
        "--debug", action="store_true", help="show the full traceback when something fails"
    )
    sub = parser.add_subparsers(dest="command", metavar="COMMAND")
    sub.required = True
    for name in COMMANDS:
        importlib.import_module(f"{__package__}.{name}").register(sub)
    return parser


def _as_flags(exc: InputError, args: argparse.Namespace) -> str:
    """The error as the command line says it: a library parameter name becomes its flag.

    The library names parameters (``max_range``); when the command has an option of
    that name, the message names the option (``--max-range``). Parameters named in the
    problem (`` `resolution` ``) become options too (:func:`~map2map.cli._messages.as_options`).
    """
    name, problem = exc.source, as_options(exc.problem)
    if name and name.isidentifier() and name in vars(args) and name != "func":
        return f"--{name.replace('_', '-')}: {problem}"
    return problem if name is None else f"{name}: {problem}"


def main(argv: list[str] | None = None) -> int:
    argv = sys.argv[1:] if argv is None else list(argv)
    parser = build_parser()
    args = parser.parse_args(argv)
    budget = for_command(args.command, getattr(args, "max_pixels", None))  # core.limits
    try:
        with warnings.catch_warnings(), budget:
            warnings.simplefilter("always", MapWarning)
            shown = warnings.showwarning

            def show(message, category, *rest, **kw):  # our warnings: one plain line
                if issubclass(category, MapWarning):
                    print(f"map2map: warning: {as_options(str(message))}", file=sys.stderr)
                else:
                    shown(message, category, *rest, **kw)

            warnings.showwarning = show
            return int(args.func(args) or 0)
    except InputError as exc:
        if args.debug:
            raise
        print(f"map2map: error: {_as_flags(exc, args)}", file=sys.stderr)
        return EXIT_BAD_INPUT
    except KeyboardInterrupt:
        print("map2map: interrupted", file=sys.stderr)
        return 130


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
