"""``map2map synthesize`` as a job: a CAD plan in, K SLAM-map hypotheses out
(:func:`map2map.learn.ab.synthesize.synthesize`: the robot's own scans at its particle
filter's poses by default, or Model_AB), with a JSON summary and a figure.

Every output path is checked before the plan is read; each file is written atomically.

Examples
--------
>>> import tempfile, pathlib
>>> from map2map.jobs.maps import PlanSpec, plan
>>> d = pathlib.Path(tempfile.mkdtemp())
>>> _ = plan(PlanSpec(d / "apt.yaml", seed=3))
>>> run = synthesize(SynthesizeSpec(d / "apt.yaml", d / "hyp", samples=2, figure=False))
>>> sorted(run.written), len(run.result.maps)
(['hyp00', 'hyp00_pgm', 'hyp01', 'hyp01_pgm', 'summary'], 2)
"""

from __future__ import annotations

import json
import os
import warnings
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from ..core.errors import InputError

__all__ = ["SynthesizeSpec", "SynthesizeRun", "synthesize"]


@dataclass
class SynthesizeSpec:
    """What ``map2map synthesize`` is asked to do (the parameters of
    :func:`map2map.learn.ab.synthesize.synthesize`, plus where to write).

    Parameters
    ----------
    input : path-like
        The plan (any format :func:`~map2map.maps.formats.load_map` reads).
    out : path-like
        Output folder: ``<stem>_hypNN.yaml`` (or ``.png``), ``<stem>_synthesize.json`` and
        ``<stem>_synthesize.png``.
    samples, model, seed, device, render, drift, drift_method, drift_scale, coverage,
    drift_route, traces, start
        As :func:`~map2map.learn.ab.synthesize.synthesize`.
    explore_map : {"rbpf", "grid", "oracle"} or None
        With ``model="scans"``: the map its robot explores on
        (:class:`~map2map.learn.ab.scans.ScanMapParams`; None: its default).
    pose_error : {"filter", "drawn", "learned"} or None
        With ``model="scans"``: the poses its scans are mapped at, the exploring particle
        filter's, drawn, or drawn by the learned pose-error model
        (:class:`~map2map.learn.ab.scans.ScanMapParams`; None: the filter's when exploring
        on ``rbpf``, else drawn).
    pose_model : path-like or None
        With ``pose_error="learned"``: the model file (None: the shipped one).
    format : {"ros", "png"}
        The hypotheses' file format.
    figure : bool
        Write the figure.
    read_options : MapReadOptions or None
        How the plan is read.
    """

    input: str | os.PathLike
    out: str | os.PathLike
    samples: int = 4
    model: str | os.PathLike = "scans"
    seed: int = 0
    format: str = "ros"
    render: str = "slam"
    drift: str = "rooms"
    drift_method: str = "additive"
    drift_scale: float | None = None
    coverage: str = "explore"
    drift_route: str = "tour"
    traces: str | None = None
    start: tuple[float, float, float] | None = None
    explore_map: str | None = None
    pose_error: str | None = None
    pose_model: str | os.PathLike | None = None
    device: str = "cpu"
    figure: bool = True
    read_options: Any = None


@dataclass
class SynthesizeRun:
    """What :func:`synthesize` wrote (``written``, name -> path), the plan read and the
    :class:`~map2map.learn.ab.synthesize.SynthesisResult` (maps, diversity, warnings)."""

    written: dict[str, Path]
    plan: Any
    result: Any


def synthesize(spec: SynthesizeSpec) -> SynthesizeRun:
    """Run ``map2map synthesize`` (module docstring); the result's warnings are not issued."""
    from ..core._io import atomic_path, ensure_output_dir
    from ..maps.formats import check_output_path, load_map, save_map

    try:
        from ..learn.ab.synthesize import SCANS, save_synthesis_figure
        from ..learn.ab.synthesize import synthesize as synthesize_maps
    except ImportError as exc:
        raise InputError("synthesize", f"needs PyTorch: pip install 'map2map[learn]' ({exc})"
                         ) from None
    if spec.samples < 1:
        raise InputError("samples", f"must be >= 1, got {spec.samples}")
    src = Path(spec.input)
    if not src.exists():
        raise InputError(src, "file not found")
    out = Path(spec.out)
    suffix = ".yaml" if spec.format == "ros" else ".png"
    names = [out / f"{src.stem}_hyp{k:02d}{suffix}" for k in range(spec.samples)]
    for path in names:
        check_output_path(path)
    scans = None
    chosen = {k: v for k, v in (("explore_map", spec.explore_map),
                                ("pose_error", spec.pose_error),
                                ("pose_model", spec.pose_model)) if v is not None}
    if "pose_model" in chosen:
        if spec.pose_error != "learned":
            raise InputError("pose_model", "applies to --pose-error learned only")
        if not Path(chosen["pose_model"]).is_file():
            raise InputError(chosen["pose_model"], "no pose-error model there")
        chosen["pose_model"] = str(chosen["pose_model"])
    if chosen:
        if str(spec.model) != SCANS:
            raise InputError(next(iter(chosen)), f"applies to model '{SCANS}' only")
        from ..learn.ab.scans import ScanMapParams

        scans = ScanMapParams(**chosen)
    plan = load_map(src, spec.read_options)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        try:
            res = synthesize_maps(
                plan, spec.model, samples=spec.samples, seed=spec.seed, device=spec.device,
                render=spec.render, drift=spec.drift, drift_method=spec.drift_method,
                drift_scale=spec.drift_scale, coverage=spec.coverage,
                drift_route=spec.drift_route, traces=spec.traces, start=spec.start,
                scans=scans)
        except InputError as exc:       # the plan's problems (a start in a wall) name it
            if exc.source not in (None, "plan"):
                raise
            raise InputError(src, exc.problem) from None
    ensure_output_dir(out)
    written: dict[str, Path] = {}
    for k, (path, m) in enumerate(zip(names, res.maps, strict=True)):
        save_map(m, path)
        written[f"hyp{k:02d}"] = path
        if suffix == ".yaml":
            written[f"hyp{k:02d}_pgm"] = path.with_suffix(".pgm")
    meta = res.maps[0].meta["synthesize"]
    if meta["model"] == "scans":          # no network: its own settings, per hypothesis
        summary = {"plan": str(src), "seed": spec.seed, "scans": meta["scans"],
                   **({"start": list(spec.start)} if spec.start is not None else {}),
                   "hypotheses": [m.meta["synthesize"]["hypothesis"] for m in res.maps],
                   "files": [p.name for p in names], **res.summary()}
    else:
        summary = _network_summary(spec, src, names, meta, res)
    written["summary"] = out / f"{src.stem}_synthesize.json"
    with atomic_path(written["summary"]) as tmp:
        tmp.write_text(json.dumps(summary, indent=2))
    if spec.figure:
        written["figure"] = out / f"{src.stem}_synthesize.png"
        what = "Model_AB hypotheses" if meta["model"] != "scans" else "hypotheses (scans)"
        save_synthesis_figure(plan, res, written["figure"],
                              title=f"{src.name}: {spec.samples} {what} (seed {spec.seed})")
    return SynthesizeRun(written, plan, res)


def _network_summary(spec: SynthesizeSpec, src: Path, names, meta: dict, res) -> dict:
    """The JSON summary of a Model_AB network's hypotheses."""
    return {"plan": str(src), "seed": spec.seed, "render": spec.render, "drift": spec.drift,
            **({"coverage": spec.coverage, "drift_route": spec.drift_route}
               if (spec.coverage, spec.drift_route) != ("none", "tour") else {}),
            "drift_params": meta.get("drift_params"),
            **({"traces": meta["traces"]} if "traces" in meta else {}),
            "files": [p.name for p in names], **res.summary()}
