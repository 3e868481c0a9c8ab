"""Files of ``map2map align`` and ``map2map evaluate``: inputs checked first, outputs atomic.

Every input (maps, anchors, points, pair lists, resolutions) is read and checked
before anything is written; every output goes through :func:`map2map.core._io.atomic_path`.

* ``align``: ``alignment.json`` (3x3 ``similarity``, ``affine``, ``rigid`` mapping
  source pixels (x = column, y = row, origin top-left) to target pixels, fitness),
  ``overlay.png``, and with points ``points_aligned.csv``
  (``x_similarity, y_similarity, x_nonrigid, y_nonrigid`` in target pixels).
* ``evaluate``: the same plus ``report.json`` (errors of both chains in px and m,
  chosen chain, IoU, ICP, warnings, timings), ``error_map.png`` and ``points.csv``
  (every SLAM wall point: ``x, y`` in plan pixels, ``error_px``, ``error_m``, ``class``
  = wall / corner / unmatched).
* ``evaluate --pairs``: one folder per pair, ``pairs.csv`` (one row per pair) and
  ``errors_boxplot.png``.

:func:`align` takes an :class:`AlignSpec` and returns an :class:`AlignRun` (``written``,
the in-memory :class:`~map2map.evaluate.align.Alignment` and the ``alignment.json``
document); :func:`evaluate` takes an :class:`EvaluateSpec` (one pair or a pairs file)
and returns an :class:`EvaluateRun` (``written``, the
:class:`~map2map.evaluate.pipeline.Evaluation` of each pair, the pairs table). The output
folder is checked before any work and written whole at the end
(:func:`map2map.core._io.atomic_dir`: an existing folder is replaced). ``run_align``,
``run_evaluate`` and ``run_pairs`` are the older call forms.

Examples
--------
>>> import numpy as np, tempfile, pathlib
>>> from map2map.maps.floorplan import generate_floorplan
>>> from map2map.maps.formats import save_map
>>> d = pathlib.Path(tempfile.mkdtemp())
>>> save_map(generate_floorplan(3, size=(8, 6)), d / "plan.yaml")
>>> run = evaluate(EvaluateSpec(d / "plan.yaml", d / "plan.yaml", d / "ev", figures=False))
>>> sorted(run.written), run.evaluation.chosen in ("rigid", "nonrigid")
(['points', 'report'], True)
"""

from __future__ import annotations

import csv
import json
import math
import os
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from ..core._io import atomic_dir, atomic_path, check_output_dir, ensure_output_dir
from ..core.errors import InputError, warnings_unless_error
from ..core.grid import OccupancyMap
from ..evaluate.align import Alignment, check_map
from ..evaluate.anchors import Anchors, read_anchors, validate_anchors
from ..evaluate.figures import error_boxplot, error_map_figure, overlay_figure
from ..evaluate.nonrigid import warp_image
from ..evaluate.pipeline import EvaluateParams, Evaluation, Registration, evaluate_maps, register
from ._common import check_positive, check_seed, final_paths

__all__ = [
    "AlignSpec",
    "AlignRun",
    "align",
    "EvaluateSpec",
    "EvaluateRun",
    "evaluate",
    "MapInput",
    "load_input",
    "read_points",
    "run_align",
    "run_evaluate",
    "read_pairs",
    "run_pairs",
    "write_evaluation",
]


@dataclass
class MapInput:
    """A loaded map, its path, and whether its resolution is known (not assumed)."""

    path: Path
    map: OccupancyMap
    resolution_known: bool


def load_input(path: str | os.PathLike, resolution: float | None = None, options=None) -> MapInput:
    """Load a map with :func:`map2map.maps.formats.load_map` and check it can be aligned.

    ``resolution`` applies to formats without their own (pictures, HouseExpo, DXF);
    a ROS map keeps the resolution of its yaml. ``options``
    (:class:`~map2map.maps.formats.MapReadOptions`: thresholds, ``negate``, DXF
    layers...) apply where the file's format takes them.
    """
    from ..maps.formats import MapReadOptions, load_map, map_kind

    p = Path(path)
    kind = map_kind(p)
    res = resolution if kind != "ros" else None
    opts = (options or MapReadOptions()).applicable(kind)
    with warnings_unless_error():  # a refused map: the error alone
        m = load_map(p, opts, resolution=res)
        check_map(m.data, str(p))
    known = not m.meta.get("resolution_assumed", False)
    return MapInput(p, m, known)


def check_read_options(options, paths) -> None:
    """Refuse a reading option that applies to none of the maps ``paths`` (one line)."""
    from ..maps.formats import map_kind

    if options is None:
        return
    kinds = [map_kind(p) for p in paths]
    for name in options.given():
        if name == "resolution":
            continue
        if not any(name in options.applicable(k).given() for k in kinds):
            flag = "--" + name.replace("_", "-")
            raise InputError(flag, f"does not apply to any input ({', '.join(map(str, paths))})")


def read_points(path: str | os.PathLike, shape: tuple[int, int] | None = None) -> np.ndarray:
    """(N, 2) points from a CSV with header ``x,y`` (source pixels)."""
    try:
        with open(path, newline="") as fh:
            rows = [r for r in csv.reader(fh) if any(c.strip() for c in r)]
    except OSError as exc:
        raise InputError(path, f"cannot read points file ({exc.strerror})") from None
    except UnicodeDecodeError:
        raise InputError(path, "points file is not a text CSV file") from None
    if not rows or [c.strip() for c in rows[0]] != ["x", "y"]:
        raise InputError(path, "points file must start with the header x,y")
    pts = []
    for i, r in enumerate(rows[1:], start=2):
        try:
            if len(r) != 2:
                raise ValueError
            x, y = float(r[0]), float(r[1])
        except ValueError:
            raise InputError(path, f"line {i}: expected two numbers x,y") from None
        if not (math.isfinite(x) and math.isfinite(y)):
            raise InputError(path, f"line {i}: values must be finite")
        pts.append((x, y))
    if not pts:
        raise InputError(path, "points file has no points")
    return np.array(pts, float)


def _pick(own: float | None, shared: float | None) -> float | None:
    return own if own is not None else shared


def _anchors(path, src: MapInput, tgt: MapInput) -> Anchors | None:
    if path is None:
        return None
    a = read_anchors(path)
    validate_anchors(a, src.map.shape, tgt.map.shape, path)
    return a


def _rigid_scale(src: MapInput, tgt: MapInput) -> float:
    """Target pixels per source pixel for the same length (1 unless both resolutions known)."""
    if src.resolution_known and tgt.resolution_known:
        return src.map.resolution / tgt.map.resolution
    return 1.0


def _params(src: MapInput, tgt: MapInput, seed: int, auto_anchor: bool) -> EvaluateParams:
    p = EvaluateParams(seed=seed)
    p.align.rigid_scale = _rigid_scale(src, tgt)
    if src.resolution_known and tgt.resolution_known:  # the metric scale is known: a prior
        p.align.metric_scale = p.align.rigid_scale
    p.align.seed = seed
    p.align.auto_anchor = auto_anchor
    return p


def _write_json(path: Path, obj: Any) -> None:
    with atomic_path(path) as tmp:
        tmp.write_text(json.dumps(obj, indent=2, default=_json_default) + "\n")


def _json_default(o):
    if isinstance(o, np.generic):
        return o.item()
    if isinstance(o, np.ndarray):
        return o.tolist()
    raise TypeError(f"not JSON serialisable: {type(o).__name__}")


@dataclass
class AlignSpec:
    """What ``map2map align`` is asked to do.

    Parameters
    ----------
    source, target : path-like
        The map to align (e.g. a SLAM map) and the reference (e.g. the plan).
    out : path-like
        Output folder (replaced whole if it exists).
    anchors, points : path-like or None
        Two anchor point pairs (paper eqs. 1-6); source pixels to map.
    resolution, source_resolution, target_resolution : float or None
        Metres per pixel of both / one input (the own one wins; ROS maps keep theirs).
    auto_anchor : bool
        Look for anchor points automatically.
    seed : int
        Random seed.
    read_options : MapReadOptions or None
        How to read both maps (e.g. ``occupied_thresh`` for grey walls).
    figures : bool
        Write ``overlay.png``.
    """

    source: str | os.PathLike
    target: str | os.PathLike
    out: str | os.PathLike
    anchors: str | os.PathLike | None = None
    points: str | os.PathLike | None = None
    resolution: float | None = None
    source_resolution: float | None = None
    target_resolution: float | None = None
    auto_anchor: bool = True
    seed: int = 0
    read_options: Any = None
    figures: bool = True


@dataclass
class AlignRun:
    """What :func:`align` wrote (name -> path), the alignment, and ``alignment.json``'s
    document (``report``: scale, rotation, translation, fitness, warnings...)."""

    written: dict[str, Path]
    alignment: Alignment
    report: dict[str, Any]
    registration: Registration | None = None

    @property
    def warnings(self) -> list[str]:
        """Why the alignment is doubtful (empty when it is not)."""
        return list(self.report.get("warnings", []))

    @property
    def notes(self) -> list[str]:
        """Facts that limit what the alignment's numbers describe (no doubt on it)."""
        return list(self.report.get("notes", []))


def _check_common(seed, resolutions: dict[str, float | None]) -> None:
    check_seed(seed)
    for name, value in resolutions.items():
        check_positive(value, name)


def align(spec: AlignSpec) -> AlignRun:
    """Run ``map2map align``: every input and the output folder checked before any work.

    Parameters
    ----------
    spec : AlignSpec
        Maps, options and output folder.

    Returns
    -------
    AlignRun
        ``written`` (``alignment``, ``overlay``, ``points``), the
        :class:`~map2map.evaluate.align.Alignment` and the ``alignment.json`` document.

    Raises
    ------
    InputError
        A bad map, option, anchors or points file, or output folder (nothing written).
    """
    _check_common(spec.seed, {"resolution": spec.resolution,
                              "source_resolution": spec.source_resolution,
                              "target_resolution": spec.target_resolution})  # fmt: skip
    inputs = (spec.source, spec.target, spec.anchors, spec.points)
    check_output_dir(spec.out, protect=inputs)
    check_read_options(spec.read_options, [spec.source, spec.target])
    src = load_input(spec.source, _pick(spec.source_resolution, spec.resolution),
                     spec.read_options)  # fmt: skip
    tgt = load_input(spec.target, _pick(spec.target_resolution, spec.resolution),
                     spec.read_options)  # fmt: skip
    anch = _anchors(spec.anchors, src, tgt)
    pts = read_points(spec.points) if spec.points is not None else None
    p = _params(src, tgt, spec.seed, spec.auto_anchor)
    reg = register(src.map, tgt.map, anchors=anch, params=p, names=(str(src.path), str(tgt.path)))
    al = reg.alignment
    doc = {"source": str(src.path), "target": str(tgt.path), **al.to_dict()}
    doc["nonrigid"] = {
        "control_points": 0 if reg.warp is None else int(len(reg.warp.src)),
        "edge_points": int(len(reg.X)),
    }
    doc["timings_s"] = {**doc["timings_s"], **reg.timings}
    written: dict[str, Path] = {}
    with atomic_dir(spec.out, protect=inputs) as out_dir:
        _write_json(out_dir / "alignment.json", doc)
        written["alignment"] = out_dir / "alignment.json"
        if pts is not None:
            sim, nonrigid = reg.map_points(pts)
            path = out_dir / "points_aligned.csv"
            with atomic_path(path) as tmp, open(tmp, "w", newline="") as fh:
                w = csv.writer(fh)
                w.writerow(["x_similarity", "y_similarity", "x_nonrigid", "y_nonrigid"])
                for a, b in zip(sim, nonrigid, strict=True):
                    w.writerow([f"{a[0]:.4f}", f"{a[1]:.4f}", f"{b[0]:.4f}", f"{b[1]:.4f}"])
            written["points"] = path
        if spec.figures:
            warped = warp_image(src.map.data, al.affine, tgt.map.shape, reg.warp)
            title = "SLAM map aligned to the plan (affine + nonrigid warp)"
            overlay_figure(tgt.map, warped, out_dir / "overlay.png", title=title)
            written["overlay"] = out_dir / "overlay.png"
    return AlignRun(final_paths(written, out_dir, spec.out), al, doc, reg)


def run_align(
    source: str | os.PathLike,
    target: str | os.PathLike,
    out: str | os.PathLike,
    **options: Any,
) -> dict[str, Path]:
    """The older call form of :func:`align` (``options`` are :class:`AlignSpec`'s
    fields); returns ``{what: path}`` of the files written."""
    return align(AlignSpec(source, target, out, **options)).written


def _metres_resolution(tgt: MapInput, units: str) -> float | None:
    if units == "px":
        return None
    if not tgt.resolution_known:
        raise InputError(
            tgt.path,
            "resolution unknown, so errors cannot be given in metres: pass `resolution=R` "
            "(metres per pixel), use a ROS yaml map, or `units=px`",
        )
    return tgt.map.resolution


def write_evaluation(
    ev: Evaluation,
    plan: OccupancyMap,
    out_dir: Path,
    resolution: float | None,
    *,
    figures: bool = True,
) -> dict[str, Path]:
    """Write ``report.json``, ``points.csv`` and (with ``figures``) ``overlay.png`` and
    ``error_map.png`` of an evaluation into the existing folder ``out_dir``."""
    paths = {k: out_dir / f"{k}.{s}" for k, s in
             (("report", "json"), ("overlay", "png"), ("error_map", "png"),
              ("points", "csv"))}  # fmt: skip
    if not figures:
        del paths["overlay"], paths["error_map"]
    _write_json(paths["report"], ev.report)
    e = ev.errors[ev.chosen]
    if figures:
        overlay_figure(plan, ev.warped[ev.chosen], paths["overlay"],
                       title=f"SLAM map aligned to the plan ({ev.chosen} chain)")  # fmt: skip
        error_map_figure(plan, e.X_rigid, e.distances, paths["error_map"],
                         resolution=resolution, excluded=e.corner, unmatched=e.unmatched,
                         title=f"Local error, {ev.chosen} chain (Algorithm 1)")  # fmt: skip
    with atomic_path(paths["points"]) as tmp, open(tmp, "w", newline="") as fh:
        w = csv.writer(fh)
        w.writerow(["x", "y", "error_px", "error_m", "class"])
        for (x, y), d, c in zip(e.X_rigid, e.distances, e.classes(), strict=True):
            m = "" if resolution is None else f"{d * resolution:.4f}"
            w.writerow([f"{x:.2f}", f"{y:.2f}", f"{d:.3f}", m, c])
    return paths


@dataclass
class EvaluateSpec:
    """What ``map2map evaluate`` is asked to do: one pair (``slam``, ``plan``) or a
    pairs file (``pairs``, with ``slam`` and ``plan`` None).

    Parameters
    ----------
    slam, plan : path-like or None
        The SLAM (as-built) map and the floor plan (as-planned).
    out : path-like
        Output folder (replaced whole if it exists).
    pairs : path-like or None
        CSV ``slam,plan[,anchors]`` (paths relative to it) instead of one pair.
    anchors : path-like or None
        Two anchor point pairs (paper eqs. 1-6); one pair only.
    resolution, source_resolution, target_resolution : float or None
        Metres per pixel of both maps / the SLAM map / the plan (one pair only).
    units : {"auto", "m", "px"}
        Errors in metres (needs the plan's metric scale: a ROS yaml, a picture with a
        stored resolution, HouseExpo JSON, DXF, or ``resolution``) or pixels; ``"auto"``
        (default): metres when every plan has a metric scale, else pixels, with a note.
    auto_anchor : bool
        Look for anchor points automatically.
    seed : int
        Random seed.
    read_options : MapReadOptions or None
        How to read the maps.
    figures, progress : bool
        Write the figures; show a tqdm bar over pairs.
    """

    slam: str | os.PathLike | None
    plan: str | os.PathLike | None
    out: str | os.PathLike
    pairs: str | os.PathLike | None = None
    anchors: str | os.PathLike | None = None
    resolution: float | None = None
    source_resolution: float | None = None
    target_resolution: float | None = None
    units: str = "auto"
    auto_anchor: bool = True
    seed: int = 0
    read_options: Any = None
    figures: bool = True
    progress: bool = True


@dataclass
class EvaluateRun:
    """What :func:`evaluate` wrote (name -> path; ``PAIR/name`` for a pairs file), the
    :class:`~map2map.evaluate.pipeline.Evaluation` of every pair (``evaluation``: the
    only one of a single pair), for a pairs file its table (``rows``), and the plan
    each pair was evaluated against (``plans``, as read: resolution and origin)."""

    written: dict[str, Path]
    evaluations: list[Evaluation] = field(default_factory=list)
    rows: list[dict[str, Any]] = field(default_factory=list)
    plans: list[OccupancyMap] = field(default_factory=list)
    #: the units the errors were given in, ``"m"`` or ``"px"`` (``"auto"`` resolved)
    units: str = "m"

    @property
    def evaluation(self) -> Evaluation | None:
        """The evaluation of a single pair (``None`` for a pairs file)."""
        return self.evaluations[0] if len(self.evaluations) == 1 and not self.rows else None

    @property
    def warnings(self) -> list[str]:
        """Every warning (prefixed by the pair's name for a pairs file)."""
        if not self.rows:
            return [w for ev in self.evaluations for w in ev.report["warnings"]]
        return [f"{r['pair']}: {w}" for r in self.rows for w in r["warnings"].split("; ") if w]

    @property
    def notes(self) -> list[str]:
        """Every note (prefixed by the pair's name for a pairs file)."""
        if not self.rows:
            return [w for ev in self.evaluations for w in ev.report.get("notes", [])]
        return [f"{r['pair']}: {w}" for r in self.rows for w in r["notes"].split("; ") if w]


def _check_evaluate(spec: EvaluateSpec) -> None:
    _check_common(spec.seed, {"resolution": spec.resolution,
                              "source_resolution": spec.source_resolution,
                              "target_resolution": spec.target_resolution})  # fmt: skip
    if spec.units not in ("auto", "m", "px"):
        raise InputError("units", f"must be auto, m or px, got {spec.units!r}")
    if spec.pairs is not None:
        if spec.slam is not None or spec.plan is not None:
            raise InputError("pairs", "give either the slam and plan maps or pairs, not both")
        if spec.anchors is not None:
            raise InputError("anchors", "with pairs, give anchors in the pairs file")
        if spec.source_resolution is not None or spec.target_resolution is not None:
            raise InputError("pairs", "with pairs, give one resolution for all pictures")
    elif spec.slam is None or spec.plan is None:
        raise InputError(None, "give the slam and plan maps, or a pairs file")


def evaluate(spec: EvaluateSpec) -> EvaluateRun:
    """Run ``map2map evaluate``: every input and the output folder checked before any work.

    Parameters
    ----------
    spec : EvaluateSpec
        One pair or a pairs file, options, output folder.

    Returns
    -------
    EvaluateRun
        ``written``, the evaluations and (pairs file) one row per pair.

    Raises
    ------
    InputError
        A bad map, option, anchors or pairs file, or output folder (nothing written).
    """
    _check_evaluate(spec)
    if spec.pairs is not None:
        return _evaluate_pairs(spec)
    inputs = (spec.slam, spec.plan, spec.anchors)
    check_output_dir(spec.out, protect=inputs)
    check_read_options(spec.read_options, [spec.slam, spec.plan])
    src = load_input(spec.slam, _pick(spec.source_resolution, spec.resolution),
                     spec.read_options)  # fmt: skip
    tgt = load_input(spec.plan, _pick(spec.target_resolution, spec.resolution),
                     spec.read_options)  # fmt: skip
    units = _units(spec.units, [tgt])
    res = _metres_resolution(tgt, units)
    anch = _anchors(spec.anchors, src, tgt)
    ev = _evaluate(src, tgt, anch, res, spec.seed, spec.auto_anchor)
    _note_units(ev, spec.units, units)
    with atomic_dir(spec.out, protect=inputs) as out_dir:
        written = write_evaluation(ev, tgt.map, out_dir, res, figures=spec.figures)
    return EvaluateRun(final_paths(written, out_dir, spec.out), [ev], plans=[tgt.map],
                       units=units)


#: Why errors come in pixels under ``units="auto"``.
PIXELS_NOTE = ("errors in pixels: the plan has no metric scale (a picture without a stored "
               "resolution); give `resolution=R` for metres")


def _units(units: str, plans: list[MapInput]) -> str:
    """``units`` with ``"auto"`` resolved: metres when every plan has a metric scale.

    >>> import numpy as np
    >>> m = OccupancyMap(np.zeros((2, 2), np.uint8), 0.05)
    >>> yaml, png = MapInput(Path("a.yaml"), m, True), MapInput(Path("a.png"), m, False)
    >>> _units("auto", [yaml]), _units("auto", [yaml, png]), _units("m", [png])
    ('m', 'px', 'm')
    """
    if units != "auto":
        return units
    return "m" if all(p.resolution_known for p in plans) else "px"


def _note_units(ev: Evaluation, asked: str, units: str) -> None:
    if asked == "auto" and units == "px":
        ev.report.setdefault("notes", []).append(PIXELS_NOTE)


def run_evaluate(
    slam: str | os.PathLike, plan: str | os.PathLike, out: str | os.PathLike, **options: Any
) -> Evaluation:
    """The older call form of :func:`evaluate` for one pair (``options`` are
    :class:`EvaluateSpec`'s fields); returns the evaluation."""
    return evaluate(EvaluateSpec(slam, plan, out, **options)).evaluations[0]


def _evaluate(src, tgt, anch, res, seed, auto_anchor) -> Evaluation:
    p = _params(src, tgt, seed, auto_anchor)
    return evaluate_maps(
        src.map, tgt.map, anchors=anch, params=p, resolution=res,
        names=(str(src.path), str(tgt.path)),
    )  # fmt: skip


def read_pairs(path: str | os.PathLike) -> list[tuple[Path, Path, Path | None]]:
    """Pairs CSV: header ``slam,plan`` (optionally ``,anchors``), paths relative to the CSV."""
    p = Path(path)
    try:
        with open(p, newline="") as fh:
            rows = [r for r in csv.reader(fh) if any(c.strip() for c in r)]
    except OSError as exc:
        raise InputError(p, f"cannot read pairs file ({exc.strerror})") from None
    except UnicodeDecodeError:
        raise InputError(p, "pairs file is not a text CSV file") from None
    head = [c.strip() for c in rows[0]] if rows else []
    if head not in (["slam", "plan"], ["slam", "plan", "anchors"]):
        raise InputError(
            p, "pairs file must start with the header slam,plan (or slam,plan,anchors)"
        )
    pairs = []
    for i, r in enumerate(rows[1:], start=2):
        if len(r) != len(head):
            raise InputError(p, f"line {i}: expected {len(head)} columns, got {len(r)}")
        cells = [c.strip() for c in r]
        paths = [(p.parent / c) if c else None for c in cells]
        if paths[0] is None or paths[1] is None:
            raise InputError(p, f"line {i}: slam and plan paths are required")
        pairs.append((paths[0], paths[1], paths[2] if len(paths) > 2 else None))
    if not pairs:
        raise InputError(p, "pairs file lists no pairs")
    return pairs


def _evaluate_pairs(spec: EvaluateSpec) -> EvaluateRun:
    """``map2map evaluate --pairs``: every pair checked first, then evaluated in turn."""
    from tqdm.auto import tqdm

    pairs = read_pairs(spec.pairs)
    inputs = (spec.pairs, *(x for pair in pairs for x in pair))
    check_output_dir(spec.out, protect=inputs)
    check_read_options(spec.read_options, [x for pair in pairs for x in pair[:2]])
    read = []
    for slam, plan, anchors in pairs:
        src = load_input(slam, spec.resolution, spec.read_options)
        tgt = load_input(plan, spec.resolution, spec.read_options)
        read.append((src, tgt, anchors))
    units = _units(spec.units, [tgt for _, tgt, _ in read])
    loaded = [(src, tgt, _anchors(anchors, src, tgt), _metres_resolution(tgt, units))
              for src, tgt, anchors in read]
    rows, dists, evs = [], {}, []
    written: dict[str, Path] = {}
    unit = "px" if units == "px" else "cm"
    with atomic_dir(spec.out, protect=inputs) as out_dir:
        bar = tqdm(loaded, desc="evaluate", disable=not spec.progress)
        for i, (src, tgt, anch, res) in enumerate(bar):
            name = f"{i + 1:03d}_{src.path.stem}"
            ev = _evaluate(src, tgt, anch, res, spec.seed, spec.auto_anchor)
            _note_units(ev, spec.units, units)
            evs.append(ev)
            pair_dir = ensure_output_dir(out_dir / name)
            paths = write_evaluation(ev, tgt.map, pair_dir, res, figures=spec.figures)
            written.update({f"{name}/{k}": v for k, v in paths.items()})
            rows.append(_pair_row(name, src, tgt, ev))
            ch = ev.errors[ev.chosen]
            d = ch.distances[ch.valid]
            dists[name] = d * (res * 100.0 if res else 1.0)
        path = out_dir / "pairs.csv"
        with atomic_path(path) as tmp, open(tmp, "w", newline="") as fh:
            w = csv.DictWriter(fh, fieldnames=list(rows[0]))
            w.writeheader()
            for r in rows:
                w.writerow({k: ("" if v is None else v) for k, v in r.items()})
        written["pairs"] = path
        if spec.figures:
            error_boxplot(dists, out_dir / "errors_boxplot.png", unit=unit)
            written["boxplot"] = out_dir / "errors_boxplot.png"
    plans = [tgt.map for _, tgt, _, _ in loaded]
    return EvaluateRun(final_paths(written, out_dir, spec.out), evs, rows, plans, units)


def _pair_row(name: str, src: MapInput, tgt: MapInput, ev: Evaluation) -> dict[str, Any]:
    e = ev.report["errors"]
    return {
        "pair": name,
        "slam": str(src.path),
        "plan": str(tgt.path),
        "chosen_chain": ev.chosen,
        "mean_px": e[ev.chosen]["mean_px"],
        "max_px": e[ev.chosen]["max_px"],
        "mean_m": e[ev.chosen]["mean_m"],
        "max_m": e[ev.chosen]["max_m"],
        "rigid_mean_px": e["rigid"]["mean_px"],
        "rigid_max_px": e["rigid"]["max_px"],
        "nonrigid_mean_px": e["nonrigid"]["mean_px"],
        "nonrigid_max_px": e["nonrigid"]["max_px"],
        "iou_free": ev.report["iou"][ev.chosen]["free"],
        "icp_mean_px": ev.report["icp"]["from_identity"]["mean_px"],
        "fitness": ev.report["alignment"]["fitness"],
        "p_correct": ev.report.get("p_correct"),
        "seconds": ev.report["timings_s"]["total"],
        "warnings": "; ".join(ev.report["warnings"]),
        "notes": "; ".join(ev.report.get("notes", [])),
    }


def run_pairs(
    pairs_file: str | os.PathLike, out: str | os.PathLike, **options: Any
) -> list[dict[str, Any]]:
    """The older call form of :func:`evaluate` with a pairs file (``options`` are
    :class:`EvaluateSpec`'s fields); returns one row per pair."""
    return evaluate(EvaluateSpec(None, None, out, pairs=pairs_file, **options)).rows
