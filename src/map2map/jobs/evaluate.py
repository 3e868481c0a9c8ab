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
"""

from __future__ import annotations

import csv
import json
import math
import os
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from ..core._io import atomic_path, ensure_output_dir
from ..core.errors import InputError, warnings_unless_error
from ..core.grid import OccupancyMap
from ..evaluate.align import check_map
from ..evaluate.anchors import Anchors, read_anchors, validate_anchors
from ..evaluate.figures import error_boxplot, error_map_figure, overlay_figure
from ..evaluate.nonrigid import warp_image
from ..evaluate.pipeline import EvaluateParams, Evaluation, evaluate_maps, register

__all__ = [
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


def run_align(
    source: str | os.PathLike,
    target: str | os.PathLike,
    out: str | os.PathLike,
    *,
    anchors: str | os.PathLike | None = None,
    points: str | os.PathLike | None = None,
    resolution: float | None = None,
    auto_anchor: bool = True,
    seed: int = 0,
    source_resolution: float | None = None,
    target_resolution: float | None = None,
    read_options=None,
) -> dict[str, Path]:
    """``map2map align``: returns ``{what: path}`` of the files written.

    ``resolution`` applies to both inputs, ``source_resolution`` and
    ``target_resolution`` to one each (they win over ``resolution``).
    ``read_options`` (:class:`~map2map.maps.formats.MapReadOptions`) say how to read
    both maps (e.g. ``occupied_thresh`` for grey walls).
    """
    check_read_options(read_options, [source, target])
    src = load_input(source, _pick(source_resolution, resolution), read_options)
    tgt = load_input(target, _pick(target_resolution, resolution), read_options)
    anch = _anchors(anchors, src, tgt)
    pts = read_points(points) if points is not None else None
    out_dir = ensure_output_dir(out)
    p = _params(src, tgt, seed, auto_anchor)
    reg = register(src.map, tgt.map, anchors=anch, params=p, names=(str(src.path), str(tgt.path)))
    al = reg.alignment
    written: dict[str, Path] = {}
    doc = {"source": str(src.path), "target": str(tgt.path), **al.to_dict()}
    doc["nonrigid"] = {
        "control_points": 0 if reg.warp is None else int(len(reg.warp.src)),
        "edge_points": int(len(reg.X)),
    }
    doc["timings_s"] = {**doc["timings_s"], **reg.timings}
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
    warped = warp_image(src.map.data, al.affine, tgt.map.shape, reg.warp)
    overlay_figure(tgt.map, warped, out_dir / "overlay.png",
                   title="SLAM map aligned to the plan (affine + nonrigid warp)")  # fmt: skip
    written["overlay"] = out_dir / "overlay.png"
    return written


def _metres_resolution(tgt: MapInput, units: str) -> float | None:
    if units == "px":
        return None
    if not tgt.resolution_known:
        raise InputError(
            tgt.path,
            "resolution unknown, so errors cannot be given in metres: pass --resolution R "
            "(metres per pixel), use a ROS yaml map, or --units px",
        )
    return tgt.map.resolution


def write_evaluation(
    ev: Evaluation, plan: OccupancyMap, out_dir: Path, resolution: float | None
) -> dict[str, Path]:
    """Write ``report.json``, ``overlay.png`` and ``error_map.png`` of an evaluation."""
    paths = {k: out_dir / f"{k}.{s}" for k, s in
             (("report", "json"), ("overlay", "png"), ("error_map", "png"),
              ("points", "csv"))}  # fmt: skip
    _write_json(paths["report"], ev.report)
    overlay_figure(plan, ev.warped[ev.chosen], paths["overlay"],
                   title=f"SLAM map aligned to the plan ({ev.chosen} chain)")  # fmt: skip
    e = ev.errors[ev.chosen]
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


def run_evaluate(
    slam: str | os.PathLike,
    plan: str | os.PathLike,
    out: str | os.PathLike,
    *,
    anchors: str | os.PathLike | None = None,
    resolution: float | None = None,
    units: str = "m",
    auto_anchor: bool = True,
    seed: int = 0,
    source_resolution: float | None = None,
    target_resolution: float | None = None,
    read_options=None,
) -> Evaluation:
    """``map2map evaluate`` for one pair; writes report.json, overlay.png, error_map.png.

    ``resolution`` applies to both maps, ``source_resolution`` (the SLAM map) and
    ``target_resolution`` (the plan) to one each. ``read_options``
    (:class:`~map2map.maps.formats.MapReadOptions`) say how to read both maps.
    """
    check_read_options(read_options, [slam, plan])
    src = load_input(slam, _pick(source_resolution, resolution), read_options)
    tgt = load_input(plan, _pick(target_resolution, resolution), read_options)
    res = _metres_resolution(tgt, units)
    anch = _anchors(anchors, src, tgt)
    out_dir = ensure_output_dir(out)
    ev = _evaluate(src, tgt, anch, res, seed, auto_anchor)
    write_evaluation(ev, tgt.map, out_dir, res)
    return ev


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


def run_pairs(
    pairs_file: str | os.PathLike,
    out: str | os.PathLike,
    *,
    resolution: float | None = None,
    units: str = "m",
    auto_anchor: bool = True,
    seed: int = 0,
    progress: bool = True,
    read_options=None,
) -> list[dict[str, Any]]:
    """``map2map evaluate --pairs``: every pair checked first, then evaluated in turn."""
    from tqdm.auto import tqdm

    pairs = read_pairs(pairs_file)
    check_read_options(read_options, [x for pair in pairs for x in pair[:2]])
    loaded = []
    for slam, plan, anchors in pairs:
        src = load_input(slam, resolution, read_options)
        tgt = load_input(plan, resolution, read_options)
        res = _metres_resolution(tgt, units)
        loaded.append((src, tgt, _anchors(anchors, src, tgt), res))
    out_dir = ensure_output_dir(out)
    rows, dists = [], {}
    unit = "px" if units == "px" else "cm"
    for i, (src, tgt, anch, res) in enumerate(tqdm(loaded, desc="evaluate", disable=not progress)):
        name = f"{i + 1:03d}_{src.path.stem}"
        ev = _evaluate(src, tgt, anch, res, seed, auto_anchor)
        pair_dir = ensure_output_dir(out_dir / name)
        write_evaluation(ev, tgt.map, pair_dir, res)
        e = ev.report["errors"]
        row = {
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
            "seconds": ev.report["timings_s"]["total"],
            "warnings": "; ".join(ev.report["warnings"]),
        }
        rows.append(row)
        ch = ev.errors[ev.chosen]
        d = ch.distances[ch.valid]
        dists[name] = d * (res * 100.0 if res else 1.0)
    path = out_dir / "pairs.csv"
    with atomic_path(path) as tmp, open(tmp, "w", newline="") as fh:
        w = csv.DictWriter(fh, fieldnames=list(rows[0]))
        w.writeheader()
        for r in rows:
            w.writerow({k: ("" if v is None else v) for k, v in r.items()})
    error_boxplot(dists, out_dir / "errors_boxplot.png", unit=unit)
    return rows
