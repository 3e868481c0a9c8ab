"""``map2map plan``, ``convert``, ``prep`` and ``show`` as jobs: a spec in, files out.

Each job checks every output path before reading or computing anything, writes each
file atomically (temporary name, then rename) and returns what it wrote (``written``,
name -> path) with the maps it made, so the command line only parses arguments.

Examples
--------
>>> import tempfile, pathlib
>>> d = pathlib.Path(tempfile.mkdtemp())
>>> run = plan(PlanSpec(d / "apt.yaml", seed=3, meta=d / "apt.json"))
>>> sorted(run.written), run.plan.resolution
(['map', 'map_pgm', 'meta'], 0.05)
>>> conv = convert(ConvertSpec(d / "apt.json", d / "apt.png"))
>>> conv.map.shape == run.plan.shape
True
"""

from __future__ import annotations

import json
import os
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from ..core._io import atomic_path
from ..core.grid import OccupancyMap

__all__ = [
    "PlanSpec",
    "PlanRun",
    "plan",
    "ConvertSpec",
    "ConvertRun",
    "convert",
    "PrepSpec",
    "PrepRun",
    "prep",
    "ShowSpec",
    "ShowRun",
    "show",
    "FIGURE_SUFFIXES",
]

#: Suffixes of the figures the jobs write.
FIGURE_SUFFIXES = (".png", ".pdf", ".svg")


def _map_files(path: str | os.PathLike, key: str = "map") -> dict[str, Path]:
    p = Path(path)
    out = {key: p}
    if p.suffix.lower() in (".yaml", ".yml"):
        out[f"{key}_pgm"] = p.with_suffix(".pgm")
    return out


# --------------------------------------------------------------------------- plan
@dataclass
class PlanSpec:
    """What ``map2map plan`` is asked to do (see
    :func:`map2map.maps.floorplan.generate_floorplan`).

    Parameters
    ----------
    out : path-like
        The map file; its suffix picks the format (``.yaml`` writes a ``.pgm`` beside).
    seed : int
        Random seed.
    kind : {"apartment", "office"}
        Building kind.
    size : (W, H) or None
        Outer size in metres (default: random for the kind).
    resolution : float
        Metres per pixel.
    furniture : bool
        Add furniture-like obstacles.
    figure, meta : path-like or None
        Also write a labelled picture / the layout JSON (``convert`` reads it back).
    """

    out: str | os.PathLike
    seed: int = 0
    kind: str = "apartment"
    size: tuple[float, float] | None = None
    resolution: float = 0.05
    furniture: bool = False
    figure: str | os.PathLike | None = None
    meta: str | os.PathLike | None = None


@dataclass
class PlanRun:
    """What :func:`plan` wrote (name -> path) and the generated plan."""

    written: dict[str, Path]
    plan: OccupancyMap


def plan(spec: PlanSpec) -> PlanRun:
    """Generate a floor plan and write the map (+ layout JSON, + figure).

    Parameters
    ----------
    spec : PlanSpec
        Generator settings and output paths.

    Returns
    -------
    PlanRun
        ``written`` (``map``, ``map_pgm``, ``meta``, ``figure``) and the plan.

    Raises
    ------
    InputError
        A bad setting or an output path that cannot be written (checked first).
    """
    from ..maps.floorplan import generate_floorplan, plan_document, save_floorplan_figure
    from ..maps.formats import check_output_path, save_map

    check_output_path(spec.out)  # every destination before any work
    if spec.figure:
        check_output_path(spec.figure, FIGURE_SUFFIXES)
    if spec.meta:
        check_output_path(spec.meta, (".json",))
    size = None if spec.size is None else tuple(spec.size)
    m = generate_floorplan(
        spec.seed, kind=spec.kind, size=size, resolution=spec.resolution, furniture=spec.furniture
    )
    save_map(m, spec.out)
    written = _map_files(spec.out)
    if spec.meta:
        doc = plan_document(m, seed=spec.seed, kind=spec.kind, size=size, furniture=spec.furniture)
        with atomic_path(spec.meta) as tmp:
            tmp.write_text(json.dumps(doc, indent=1), encoding="utf-8")
        written["meta"] = Path(spec.meta)
    if spec.figure:
        w, h = m.meta["size_m"]
        title = f"{spec.kind} {w:g} x {h:g} m, seed {spec.seed}"
        save_floorplan_figure(m, spec.figure, title=title)
        written["figure"] = Path(spec.figure)
    return PlanRun(written, m)


# --------------------------------------------------------------------------- convert
@dataclass
class ConvertSpec:
    """What ``map2map convert`` is asked to do: read ``input`` (with ``read_options``, a
    :class:`~map2map.maps.formats.MapReadOptions`) and write ``output`` (format by
    suffix: ROS ``.yaml``, ``.png``/``.pgm``, ``.dxf``)."""

    input: str | os.PathLike
    output: str | os.PathLike
    read_options: Any = None


@dataclass
class ConvertRun:
    """What :func:`convert` wrote and the map read (its ``meta`` says what was assumed)."""

    written: dict[str, Path]
    map: OccupancyMap


def convert(spec: ConvertSpec) -> ConvertRun:
    """Convert a map between formats; the output path is checked before reading.

    Parameters
    ----------
    spec : ConvertSpec
        Input, output and reading options.

    Returns
    -------
    ConvertRun
        ``written`` (``map``, and ``map_pgm`` for a ROS yaml) and the map.
    """
    from ..maps.formats import check_output_path, load_map, save_map

    check_output_path(spec.output)  # before reading: fail fast, write nothing
    m = load_map(spec.input, spec.read_options)
    save_map(m, spec.output)
    return ConvertRun(_map_files(spec.output), m)


# --------------------------------------------------------------------------- prep
@dataclass
class PrepSpec:
    """What ``map2map prep`` is asked to do (thesis sec. 4.1, see
    :func:`map2map.maps.preprocess.preprocess`): square, resize to ``size``, thicken
    walls by ``thicken`` pixels, optionally crop to the content (``margin`` pixels)."""

    input: str | os.PathLike
    output: str | os.PathLike
    size: int = 256
    thicken: int = 0
    crop: bool = False
    margin: int = 4
    figure: str | os.PathLike | None = None
    read_options: Any = None


@dataclass
class PrepRun:
    """What :func:`prep` wrote, the map read (``map``) and the preprocessed one (``result``)."""

    written: dict[str, Path]
    map: OccupancyMap
    result: OccupancyMap


def prep(spec: PrepSpec) -> PrepRun:
    """Preprocess a map as the thesis did before training; outputs checked first.

    Parameters
    ----------
    spec : PrepSpec
        Input, output, preprocessing settings.

    Returns
    -------
    PrepRun
        ``written`` (``map``, ``map_pgm``, ``figure``), the input and the result.

    Raises
    ------
    InputError
        A bad setting, input or output path.
    """
    from ..core.errors import InputError
    from ..maps.formats import check_output_path, load_map, save_map
    from ..maps.preprocess import preprocess, save_preprocess_figure

    if spec.size < 1:
        raise InputError("size", f"output size must be >= 1 pixel, got {spec.size}")
    if spec.thicken < 0:
        raise InputError("thicken", f"K must be >= 0, got {spec.thicken}")
    if spec.margin < 0:
        raise InputError("margin", f"margin must be >= 0, got {spec.margin}")
    check_output_path(spec.output)  # before reading: fail fast, write nothing
    if spec.figure:
        check_output_path(spec.figure, FIGURE_SUFFIXES)
    m = load_map(spec.input, spec.read_options)
    out = preprocess(m, size=spec.size, thicken=spec.thicken, crop=spec.crop, margin=spec.margin)
    save_map(out, spec.output)
    written = _map_files(spec.output)
    if spec.figure:
        steps = f"size {spec.size}, thicken {spec.thicken}" + (", crop" if spec.crop else "")
        save_preprocess_figure(m, out, spec.figure, title=f"{spec.input}: {steps}")
        written["figure"] = Path(spec.figure)
    return PrepRun(written, m, out)


# --------------------------------------------------------------------------- show
@dataclass
class ShowSpec:
    """What ``map2map show`` is asked to do: draw ``input`` into figure ``out``
    (``.png``/``.pdf``/``.svg``) with an optional first title line."""

    input: str | os.PathLike
    out: str | os.PathLike
    title: str | None = None
    read_options: Any = None


@dataclass
class ShowRun:
    """What :func:`show` wrote and the map drawn."""

    written: dict[str, Path]
    map: OccupancyMap


def show(spec: ShowSpec) -> ShowRun:
    """Draw a map as a readable figure (:func:`map2map.maps.render.save_map_figure`).

    Parameters
    ----------
    spec : ShowSpec
        Input, figure path, title, reading options.

    Returns
    -------
    ShowRun
        ``written`` (``figure``) and the map.
    """
    from ..maps.formats import check_output_path, load_map
    from ..maps.render import save_map_figure

    check_output_path(spec.out, FIGURE_SUFFIXES)
    m = load_map(spec.input, spec.read_options)
    save_map_figure(m, spec.out, title=spec.title)
    return ShowRun({"figure": Path(spec.out)}, m)
