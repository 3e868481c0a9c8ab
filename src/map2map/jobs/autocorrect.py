"""``map2map autocorrect`` as a job: SLAM maps in, CAD-like plans (and DXF walls, figures)
out, with Model_BA (:mod:`map2map.learn.ba.autocorrect`) or without a network.

The model is chosen by name from :data:`MODELS` (``--model``; :data:`DEFAULT_MODEL`) or
is a Model_BA weights file or training run; every choice is a :class:`Corrector`. The
model is loaded once for all the maps; every output path is checked before any map is
read; each file is written atomically. A folder input corrects every map in it into the
output folder (same names); an image that a ROS map yaml of the folder names is that
map's image, not a map of its own, and two inputs that would write the same file are
refused before anything is written.

Examples
--------
>>> import tempfile, pathlib
>>> from map2map.jobs.maps import PlanSpec, plan
>>> d = pathlib.Path(tempfile.mkdtemp())
>>> _ = plan(PlanSpec(d / "apt.yaml", seed=3))
>>> run = autocorrect(AutocorrectSpec(d / "apt.yaml", d / "cad.yaml", dxf=d / "walls.dxf"))
>>> sorted(run.written), run.corrections[0].map.shape == run.inputs[0].shape
(['dxf', 'map', 'map_pgm'], True)
"""

from __future__ import annotations

import os
import warnings
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING, Any, Protocol, runtime_checkable

from ..core.errors import InputError

if TYPE_CHECKING:
    from ..core.grid import OccupancyMap

__all__ = ["AutocorrectSpec", "AutocorrectRun", "autocorrect", "MAP_SUFFIXES",
           "parse_thickness", "parse_draw_options", "Corrector", "ModelEntry", "MODELS",
           "DEFAULT_MODEL", "ALIASES", "corrector", "model_names_help"]


@runtime_checkable
class Corrector(Protocol):
    """What every ``--model`` is: a ``name`` (tables, messages), a ``source`` (the
    weights file, or what stands in for one) and ``correct_many``: maps in, one output
    per map in its input's frame, carrying ``meta["autocorrect"]`` (``segments_px``:
    wall segments in input pixels, ``warnings``, ``model``). ``options`` are
    :func:`~map2map.learn.ba.autocorrect.autocorrect_many`'s keywords (``straighten``,
    ``anchor``, ``thickness``, ``open_frontiers``, ``large``, ...); a corrector raises
    :class:`~map2map.core.errors.InputError` (naming ``model``) for one it has no
    meaning for."""

    name: str
    source: str

    def correct_many(self, maps: list[OccupancyMap], **options) -> list[OccupancyMap]:
        ...


@dataclass(frozen=True)
class ModelEntry:
    """A named model: ``make(device) -> Corrector`` (imports lazily: naming the models
    imports no torch) and a one-line description for ``--help``."""

    make: Callable[[str], Corrector]
    help: str
    #: whether its output goes through the plan drawer unless told (``--draw/--no-draw``)
    drawn: bool = False


def _none(device: str) -> Corrector:
    from ..learn.ba.correctors import NullCorrector

    return NullCorrector()


def _thesis(device: str) -> Corrector:
    from ..learn.ba.correctors import ThesisCorrector

    return ThesisCorrector("pretrained", device, name="thesis")


#: The models ``--model`` names (a new one is one entry here).
MODELS: dict[str, ModelEntry] = {
    "none": ModelEntry(_none, "the classical cleaning alone, no network: the input's own "
                              "walls straightened, specks and clutter removed, drawn like a "
                              "plan", drawn=True),
    "thesis": ModelEntry(_thesis, "the thesis's Model_BA (Model_32 + post-processing), "
                                  "shipped weights"),
}
#: What ``--model`` is when not given.
DEFAULT_MODEL = "none"
#: Other names of :data:`MODELS` entries (``pretrained``: the shipped weights, as before).
ALIASES = {"pretrained": "thesis"}
#: The learn extra's top-level modules: a network model that cannot import one of them
#: is refused in one line naming the extra (any other ImportError is a fault).
LEARN_MODULES = ("torch", "safetensors")


def model_names_help() -> str:
    """``--model``'s help: the names, the default, and that a path is weights.

    >>> model_names_help().startswith("'none'")
    True
    """
    names = "; ".join(f"'{k}'{' (default)' if k == DEFAULT_MODEL else ''}: {e.help}"
                      for k, e in MODELS.items())
    return f"{names}; or a Model_BA training run folder or weights file"


def corrector(model: str | os.PathLike | Corrector | None = None,
              device: str = "cpu", *, draw: bool | None = None,
              draw_thickness: float | None = None, draw_options: Any = None) -> Corrector:
    """The :class:`Corrector` of a ``--model`` value: a name of :data:`MODELS` (or an
    alias), a Model_BA training run folder or weights file, or a corrector (returned as
    it is); None is :data:`DEFAULT_MODEL`.

    ``draw``: put the output through the plan drawer
    (:class:`~map2map.learn.ba.correctors.DrawnCorrector`: straight walls at one
    thickness, ``draw_thickness`` metres, the same segments in the DXF); None: the
    model's own choice (:attr:`ModelEntry.drawn`: ``none`` is drawn, ``thesis`` and
    weights files are the thesis's output as it is). ``draw_options``: the drawer's
    :class:`~map2map.maps.vectorize.DrawOptions` (None: its defaults;
    :func:`parse_draw_options` reads them from ``KEY=VALUE`` text).

    Examples
    --------
    >>> corrector("none").name
    'none'
    >>> corrector("no-such-model")  # doctest: +ELLIPSIS
    Traceback (most recent call last):
    ...
    map2map.core.errors.InputError: no-such-model: not a model name ('none', 'thesis') nor...
    """
    if model is None:
        model = DEFAULT_MODEL
    if not isinstance(model, str | os.PathLike):
        return model
    key = ALIASES.get(os.fspath(model), os.fspath(model))
    if key not in MODELS and not Path(model).exists():
        names = ", ".join(repr(k) for k in MODELS)
        raise InputError(model, f"not a model name ({names}) nor a Model_BA training run "
                                "folder or weights file")
    try:
        if key in MODELS:
            made, drawn = MODELS[key].make(device), MODELS[key].drawn
        else:
            from ..learn.ba.correctors import ThesisCorrector

            made, drawn = ThesisCorrector(model, device), False
    except ImportError as exc:      # a network needs the learn extra; 'none' does not
        if (getattr(exc, "name", None) or "").split(".")[0] not in LEARN_MODULES:
            raise                       # not a missing extra: a fault, shown as one
        raise InputError(os.fspath(model), f"needs PyTorch: pip install 'map2map[learn]' "
                                           f"({exc})") from None
    if draw_thickness is not None and draw_thickness <= 0:
        raise InputError("draw_thickness", f"must be > 0 metres, got {draw_thickness}")
    if draw if draw is not None else drawn:
        from ..learn.ba.correctors import DrawnCorrector

        return DrawnCorrector(made, draw_thickness, options=draw_options)
    if draw_options is not None:
        raise InputError("--draw-option", f"the {key} model's output is not drawn like a "
                                          "plan: add --draw")
    return made


def parse_draw_options(items: list[str] | None) -> Any:
    """``KEY=VALUE`` texts (``--draw-option``) -> the plan drawer's
    :class:`~map2map.maps.vectorize.DrawOptions` (its defaults for the keys not given;
    None when there are none). A value is read as the field's type: a number, ``true`` /
    ``false``, or ``none`` where the field may be None. An unknown key or a value of the
    wrong type is an :class:`~map2map.core.errors.InputError` naming it.

    Examples
    --------
    >>> o = parse_draw_options(["bridge_run=0", "lean_px=none", "two_sided=false"])
    >>> o.bridge_run, o.lean_px, o.two_sided, o.families
    (0.0, None, False, 3)
    >>> parse_draw_options(["bridge=0.2", "no_such=1"])  # doctest: +ELLIPSIS
    Traceback (most recent call last):
    ...
    map2map.core.errors.InputError: --draw-option no_such=1: not an option of the drawer (...
    """
    import dataclasses
    import types
    import typing

    from ..maps.vectorize import DrawOptions

    if not items:
        return None
    fields = typing.get_type_hints(DrawOptions)
    defaults = DrawOptions()
    values: dict[str, Any] = {}
    for item in items:
        key, eq, text = (x.strip() for x in item.partition("="))
        where = f"--draw-option {item}"
        if not eq or key not in fields:
            raise InputError(where, "not an option of the drawer ("
                             + ", ".join(fields) + "), as KEY=VALUE")
        default, low = getattr(defaults, key), text.lower()
        hint = fields[key]
        nullable = isinstance(hint, types.UnionType) and type(None) in hint.__args__
        if low == "none" and nullable:
            values[key] = None
        elif isinstance(default, bool):
            if low not in ("true", "false"):
                raise InputError(where, f"{key} is true or false, not {text!r}")
            values[key] = low == "true"
        else:
            try:
                num = float(text) if not isinstance(default, int) else int(text)
            except ValueError:
                kind = "an integer" if isinstance(default, int) else "a number"
                raise InputError(where, f"{key} is {kind}"
                                 + (" or none" if nullable else "") + f", not {text!r}"
                                 ) from None
            if not num == num or num < 0:
                raise InputError(where, f"{key} must be 0 or more, not {text!r}")
            values[key] = num
    return dataclasses.replace(defaults, **values)

#: Files of a folder input that are read as maps.
MAP_SUFFIXES = (".yaml", ".yml", ".png", ".pgm", ".jpg", ".jpeg", ".tif", ".tiff", ".json")


@dataclass
class AutocorrectSpec:
    """What ``map2map autocorrect`` is asked to do.

    Parameters
    ----------
    input : path-like
        A SLAM map (any format :func:`~map2map.maps.formats.load_map` reads) or a folder
        of them.
    out : path-like
        The output map, or folder (folder input).
    model : str, path-like or Corrector
        A name of :data:`MODELS` (``"none"``, ``"thesis"``; ``"pretrained"`` is
        ``"thesis"``), a Model_BA training run folder or weights file, or a corrector;
        None: :data:`DEFAULT_MODEL`.
    dxf, figure : path-like or None
        Also write the walls as DXF lines (and arcs) / a before-after figure (folder input:
        folders).
    straighten, anchor : bool
        :func:`~map2map.learn.ba.autocorrect.autocorrect`'s options.
    thickness : str, float or None
        ``"shrink"``, ``"resolution"``, ``"input"``, a number of pixels (or its text);
        None: the library's default.
    open_frontiers : bool or None
        None: the library's default (on for a map corrected in tiles).
    large : {"resize", "tile", "refuse"} or None
        None: the library's default.
    device : str
        Torch device.
    read_options : MapReadOptions or None
        How the input maps are read.
    draw : bool or None
        Draw the output like a plan (:func:`corrector`); None: the model's choice.
    draw_thickness : float or None
        Metres of every wall the plan drawer draws; None: the plans' convention
        (:func:`map2map.maps.vectorize.default_wall_thickness`: 0.20 m plus a pixel on
        each side for a wall seen from one side, interior walls as measured).
    draw_options : DrawOptions or None
        The plan drawer's tolerances (:func:`parse_draw_options`); None: its defaults.
    workers : int or None
        Threads for the per-map work and processes for the plan drawer (from 16 maps
        on); None: one per CPU core (at most 8); 1: this process only. The outputs do not
        depend on it.
    """

    input: str | os.PathLike
    out: str | os.PathLike
    model: str | os.PathLike | Corrector | None = None
    dxf: str | os.PathLike | None = None
    figure: str | os.PathLike | None = None
    straighten: bool = True
    anchor: bool = True
    thickness: str | float | None = None
    open_frontiers: bool | None = None
    large: str | None = None
    device: str = "cpu"
    read_options: Any = None
    draw: bool | None = None
    draw_thickness: float | None = None
    draw_options: Any = None
    workers: int | None = None


@dataclass
class AutocorrectRun:
    """What :func:`autocorrect` did: the files (``written``: the last map's; ``files``:
    per input, name -> path), the input maps, the corrections (map, world segments,
    warnings) and the model's source."""

    inputs: list
    corrections: list
    sources: list[Path]
    model: str
    files: list[dict[str, Path]] = field(default_factory=list)

    @property
    def written(self) -> dict[str, Path]:
        return self.files[-1] if self.files else {}


def parse_thickness(value: str | float | None) -> str | float | None:
    """``thickness`` as the library takes it: a rule name, a number of pixels or None.

    >>> parse_thickness("input"), parse_thickness("2.5"), parse_thickness(None)
    ('input', 2.5, None)
    """
    if value is None or value in ("shrink", "resolution", "input"):
        return value
    try:
        return float(value)
    except ValueError:
        raise InputError("thickness", "'shrink', 'resolution', 'input' or a number of "
                         f"pixels, not {value!r}") from None


def _plan_paths(spec: AutocorrectSpec) -> tuple[list[Path], list[dict[str, Path]]]:
    src = Path(spec.input)
    if src.is_dir():
        files = sorted(f for f in src.iterdir() if f.suffix.lower() in MAP_SUFFIXES)
        images = _yaml_images(files)            # a yaml's image is not a map of its own
        files = [f for f in files if f.resolve() not in images]
        if not files:
            raise InputError(src, "no maps in this folder")
        out = [{"map": Path(spec.out) / f.name} for f in files]
        for f, o in zip(files, out, strict=True):
            if spec.dxf:
                o["dxf"] = Path(spec.dxf) / (f.stem + ".dxf")
            if spec.figure:
                o["figure"] = Path(spec.figure) / (f.stem + ".png")
        _refuse_shared_outputs(files, out)
        return files, out
    if not src.exists():
        raise InputError(src, "file not found")
    o = {"map": Path(spec.out)}
    if spec.dxf:
        o["dxf"] = Path(spec.dxf)
    if spec.figure:
        o["figure"] = Path(spec.figure)
    return [src], [o]


def _yaml_images(files: list[Path]) -> set[Path]:
    """The images that the ROS map yamls among ``files`` name (resolved paths)."""
    from ..maps.ros import read_ros_yaml

    out = set()
    for f in files:
        if f.suffix.lower() in (".yaml", ".yml"):
            try:
                out.add(Path(read_ros_yaml(f)["image"]).resolve())
            except InputError:
                pass                   # not a map yaml: reported when it is read
    return out


def _refuse_shared_outputs(files: list[Path], outs: list[dict[str, Path]]) -> None:
    """One line (InputError) when two inputs would write the same file."""
    seen: dict[Path, Path] = {}
    for f, o in zip(files, outs, strict=True):
        paths = list(o.values())
        if o["map"].suffix.lower() in (".yaml", ".yml"):
            paths.append(o["map"].with_suffix(".pgm"))
        for p in paths:
            other = seen.setdefault(p.resolve(), f)
            if other != f:
                raise InputError(f, f"would write {p}, as {other.name} does: rename one of "
                                    "them or correct them apart")


def autocorrect(spec: AutocorrectSpec) -> AutocorrectRun:
    """Run ``map2map autocorrect`` (module docstring); the warnings of each correction are
    in ``run.corrections[i].warnings`` (not issued)."""
    from ..learn.ba.correction import Correction
    from ..learn.training.figures import save_before_after
    from ..maps.formats import check_output_path, load_map, save_map

    thickness = parse_thickness(spec.thickness)
    files, outs = _plan_paths(spec)
    for o in outs:
        check_output_path(o["map"])
    maps = [load_map(f, spec.read_options) for f in files]
    model = corrector(spec.model, spec.device, draw=spec.draw,
                      draw_thickness=spec.draw_thickness, draw_options=spec.draw_options)
    if spec.workers is not None and spec.workers < 1:
        raise InputError("workers", f"must be at least 1, got {spec.workers}")
    options = dict(straighten=spec.straighten, anchor=spec.anchor, thickness=thickness,
                   open_frontiers=spec.open_frontiers, large=spec.large,
                   workers=spec.workers)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        results = [Correction.of(o) for o in model.correct_many(maps, **options)]
    written = []
    for f, m, r, o in zip(files, maps, results, outs, strict=True):
        w = dict(o)
        save_map(r.map, o["map"])
        if o["map"].suffix.lower() in (".yaml", ".yml"):
            w["map_pgm"] = o["map"].with_suffix(".pgm")
        if "dxf" in o:
            r.save_dxf(o["dxf"])
        if "figure" in o:
            save_before_after(m, r.map, o["figure"], r.map.meta["autocorrect"]["segments_px"],
                              title=f"{f.name} -> {o['map'].name} ({Path(model.source).name})",
                              label="Model_BA" if model.name == "thesis" else model.name)
        written.append(w)
    return AutocorrectRun(maps, results, files, model.source, written)
