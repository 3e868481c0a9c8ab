"""Map-reading options shared by every command that reads a map.

``convert``, ``prep``, ``show``, ``simulate``, ``deform``, ``align`` and ``evaluate``
all take the same options (:func:`add_input_options`) and turn them into one
:class:`map2map.maps.formats.MapReadOptions` (:func:`read_options_from_args`).
``align``, ``evaluate`` and ``deform`` keep their own ``--resolution`` flag.
"""

from __future__ import annotations

import argparse
import sys

from ..maps.ros import MODES
from ..maps.units import UNITS


def add_input_options(
    p: argparse.ArgumentParser, *, resolution: bool = True, several: bool = False
) -> None:
    """Add the options of :func:`map2map.maps.formats.load_map` to a parser.

    ``resolution=False`` leaves ``--resolution`` to the command itself; ``several``
    says the command reads several maps (each option then applies to the inputs of
    the formats it names).
    """
    g = p.add_argument_group(
        "reading the input maps" if several else "reading the input",
        "Each option applies to the input formats it names; an option that applies to "
        "no input is refused."
        if several
        else "Options apply only to the formats named; others are refused.",
    )
    if resolution:
        g.add_argument(
            "--resolution",
            type=float,
            metavar="R",
            help="metres per pixel for pictures, HouseExpo JSON and DXF (default: stored in "
            "the picture, else 0.05 with a note; such a picture has no metric scale: no "
            "scale bar, sizes in pixels)",
        )
    g.add_argument(
        "--occupied-thresh",
        type=float,
        metavar="P",
        help="ROS yaml / picture: occupancy above which a pixel is occupied (default 0.65)",
    )
    g.add_argument(
        "--free-thresh",
        type=float,
        metavar="P",
        help="ROS yaml / picture: occupancy below which a pixel is free (default 0.196)",
    )
    g.add_argument(
        "--negate",
        action="store_true",
        default=None,
        help="ROS yaml / picture: white is occupied, black free",
    )
    g.add_argument("--mode", choices=MODES, help="ROS yaml: override the map_server mode")
    g.add_argument(
        "--layers",
        action="append",
        metavar="NAMES",
        help="DXF: layers to draw, comma-separated or repeated (default: all)",
    )
    g.add_argument(
        "--wall-thickness",
        type=float,
        metavar="T",
        help="DXF: wall thickness in metres (default 0.1)",
    )
    g.add_argument(
        "--max-pixels",
        type=int,
        metavar="N",
        help="largest map (pixels) to accept; default: what the command's memory budget "
        "allows (docs/memory.md); 0: no limit",
    )
    # evaluate has its own --units (of the report): there only --dxf-units
    flags = [f for f in ("--units", "--dxf-units") if f not in p._option_string_actions]
    g.add_argument(
        *flags,
        dest="dxf_units",
        choices=sorted(UNITS),
        help="DXF: drawing units (default: from $INSUNITS)",
    )


def _split_layers(values: list[str] | None) -> list[str] | None:
    if values is None:
        return None
    names = [name.strip() for value in values for name in value.split(",")]
    return [name for name in names if name]


def read_options_from_args(args: argparse.Namespace):
    """The :class:`~map2map.maps.formats.MapReadOptions` of :func:`add_input_options`."""
    from ..maps.formats import MapReadOptions

    layers = _split_layers(args.layers)
    return MapReadOptions(
        resolution=getattr(args, "resolution", None),
        occupied_thresh=args.occupied_thresh,
        free_thresh=args.free_thresh,
        negate=args.negate,
        mode=args.mode,
        layers=None if layers is None else tuple(layers),
        wall_thickness=args.wall_thickness,
        units=args.dxf_units,
    )


def load_from_args(args: argparse.Namespace):
    """Load ``args.input`` with the options of :func:`add_input_options` and say how it
    was read (:func:`say_how_read`)."""
    from ..maps.formats import load_map

    m = load_map(args.input, read_options_from_args(args))
    say_how_read(args.input, m)
    return m


def say_how_read(path, m) -> None:
    """Print what reading ``path`` assumed or left out (from the map's ``meta``)."""
    if m.meta.get("resolution_assumed"):
        print(
            f"map2map: note: {path}: no resolution given or stored; assuming "
            f"{m.resolution:g} m/px (use --resolution)",
            file=sys.stderr,
        )
    if "entities" in m.meta:  # DXF: say what was drawn and what was left out
        drawn = ", ".join(f"{n} {k}" for k, n in sorted(m.meta["entities"].items()))
        left = ", ".join(f"{n} {k}" for k, n in sorted(m.meta.get("skipped_entities", {}).items()))
        layers = m.meta.get("layers", [])
        doors = sum(m.meta.get("door_entities", {}).values())
        print(
            f"read {path}: {drawn} on layer{'s' if len(layers) > 1 else ''} "
            f"{', '.join(layers)}" + (f"; ignored {left}" if left else "")
            + (f"; left out {doors} entities drawing door swings and leaves" if doors else "")
            + (f"; left out {m.meta['floor_hatches']} pattern hatches as wide as a room "
               "(floors)" if m.meta.get("floor_hatches") else "")
        )
    if m.meta.get("units_assumed"):
        print(
            f"map2map: note: {path}: the drawing has no units; reading it as metres (use --units)",
            file=sys.stderr,
        )
