"""``map2map dataset build``, ``status``, ``clean`` and ``export`` as jobs.

* :func:`build`: build (or continue) a paired dataset (:func:`map2map.datasets.build.
  build_dataset`: resumable, local workers or a Dask cluster);
* :func:`status`: where a dataset stands (:func:`map2map.datasets.build.dataset_status`);
* :func:`clean` (thesis 4.1): label a dataset's pairs, train and save its cleaner
  (:func:`map2map.datasets.clean.clean_dataset`), or apply a saved cleaner to a dataset or
  a folder of pairs (:func:`map2map.datasets.clean.apply_cleaner`) and write the decisions;
* :func:`export`: the pairs in a training format (:func:`map2map.datasets.export.
  export_dataset`).

The cleaner needs scikit-learn and skops (``pip install 'map2map[dataset]'``); without
them the job says so in one line.

Examples
--------
>>> import tempfile, pathlib
>>> d = pathlib.Path(tempfile.mkdtemp())
>>> clean(CleanSpec(d / "missing"))  # doctest: +ELLIPSIS
Traceback (most recent call last):
...
map2map.core.errors.InputError: .../missing: not a map2map dataset (no manifest.sqlite)
"""

from __future__ import annotations

import os
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from ..core.errors import InputError

__all__ = ["BuildSpec", "build", "status", "CleanSpec", "CleanRun", "clean", "ExportSpec",
           "export"]


@dataclass
class BuildSpec:
    """What ``map2map dataset build`` is asked to do (the parameters of
    :func:`~map2map.datasets.build.build_dataset`; ``params``: the fields of
    :class:`~map2map.datasets.pair.BuildParams`, ``None`` values taking its defaults)."""

    out: str | os.PathLike
    plans: str
    count: int
    seed: int = 0
    params: dict = field(default_factory=dict)
    workers: int = 1
    scheduler: str | None = None
    resolution: float = 0.05
    plan_resolution: float | None = None
    max_attempts: int = 3
    progress: bool = True
    figures: bool = True


def build(spec: BuildSpec):
    """Build (or continue) the dataset of ``spec``; returns the
    :class:`~map2map.datasets.build.BuildSummary`."""
    from ..datasets.build import build_dataset
    from ..datasets.pair import BuildParams

    if spec.workers < 1:
        raise InputError("workers", f"must be >= 1, got {spec.workers}")
    params = BuildParams(**{k: v for k, v in spec.params.items() if v is not None})
    return build_dataset(
        spec.out, spec.plans, spec.count, spec.seed, params, workers=spec.workers,
        scheduler=spec.scheduler, resolution=spec.resolution,
        plan_resolution=spec.plan_resolution, max_attempts=spec.max_attempts,
        progress=spec.progress, figures=spec.figures)


def status(ds: str | os.PathLike) -> dict:
    """Where dataset ``ds`` stands (:func:`~map2map.datasets.build.dataset_status`)."""
    from ..datasets.build import dataset_status

    return dataset_status(ds)


@dataclass
class ExportSpec:
    """What ``map2map dataset export`` is asked to do (the parameters of
    :func:`~map2map.datasets.export.export_dataset`)."""

    ds: str | os.PathLike
    format: str
    out: str | os.PathLike | None = None
    everything: bool = False
    include_review: bool = False
    progress: bool = True


def export(spec: ExportSpec):
    """Export the dataset of ``spec``; returns the export's result (path, counts, size)."""
    from ..datasets.export import export_dataset

    return export_dataset(spec.ds, spec.format, spec.out, everything=spec.everything,
                          include_review=spec.include_review, progress=spec.progress)


@dataclass
class CleanSpec:
    """What ``map2map dataset clean`` is asked to do.

    Parameters
    ----------
    ds : path-like
        The dataset folder (or, with ``model``, a folder of pairs).
    labels : path-like or None
        Manual labels (``index,label``); None: from the simulator's coverage.
    coverage_threshold : float or None
        Coverage from which a pair is complete (None: the library's default).
    model : path-like or None
        Apply this saved cleaner instead of training one.
    out : path-like or None
        With ``model``: write the decisions (CSV) here.
    """

    ds: str | os.PathLike
    labels: str | os.PathLike | None = None
    coverage_threshold: float | None = None
    model: str | os.PathLike | None = None
    out: str | os.PathLike | None = None


@dataclass
class CleanRun:
    """A trained cleaner's report (``report``), or a saved one's decisions (``rows``:
    name, p_complete, decision) with their counts; ``written``: name -> path."""

    report: Any = None
    rows: list[dict] = field(default_factory=list)
    written: dict[str, Path] = field(default_factory=dict)

    @property
    def counts(self) -> dict[str, int]:
        out: dict[str, int] = {}
        for r in self.rows:
            out[r["decision"]] = out.get(r["decision"], 0) + 1
        return out


def clean(spec: CleanSpec) -> CleanRun:
    """Run ``map2map dataset clean`` (module docstring)."""
    from ..datasets.clean import COVERAGE_COMPLETE, apply_cleaner, clean_dataset

    try:
        import sklearn  # noqa: F401
        import skops.io  # noqa: F401
    except ImportError as exc:
        raise InputError("dataset clean", "the cleaner needs scikit-learn and skops: "
                         f"pip install 'map2map[dataset]' ({exc})") from None
    if spec.model:
        rows = apply_cleaner(spec.model, spec.ds)
        run = CleanRun(rows=rows)
        if spec.out:
            from ..core._io import atomic_path

            with atomic_path(spec.out) as tmp:
                tmp.write_text(
                    "name,p_complete,decision\n"
                    + "".join(f"{r['name']},{r['p_complete']:.4f},{r['decision']}\n"
                              for r in rows))
            run.written["decisions"] = Path(spec.out)
        return run
    thr = COVERAGE_COMPLETE if spec.coverage_threshold is None else spec.coverage_threshold
    report = clean_dataset(spec.ds, spec.labels, coverage_threshold=thr)
    return CleanRun(report=report)
