"""Building a paired dataset: deterministic, resumable, local or on a Dask cluster.

:func:`build_dataset` makes pairs ``0 .. count-1`` of a dataset (thesis sec. 4.1, without
Gazebo: the simulated robot + SLAM of :mod:`map2map.sim`, and/or the parametric model)
into a folder ``DS``::

    DS/manifest.sqlite          the manifest (map2map.datasets.manifest)
    DS/pairs/000123/            one folder per pair (map2map.datasets.pair.write_pair)
    DS/figures/contact_sheet.png, DS/figures/histograms.png

Every pair depends only on (seed, index); workers only compute, this process writes
(each pair into a temporary folder renamed into place, then one manifest transaction),
so the pairs are byte-identical whatever the worker count, the backend (local pool or
Dask) and however often the build was interrupted. Running the same command again
continues where it stopped; with other settings on an existing ``DS`` it refuses
(``count`` alone may change: pair ``i`` does not depend on it). A bad plan is recorded
``failed`` with its reason and the build goes on; a pair whose worker died is run again,
at most ``max_attempts`` times, then recorded failed.

Splits: a plan goes to ``train``, ``val`` or ``test`` by a hash of its id (80/10/10), so no
plan is in two splits, the split never depends on the order of work, and a plan keeps
its split across datasets built from the same folder. It is recorded per pair.
"""

from __future__ import annotations

import contextlib
import dataclasses
import hashlib
import math
import os
import shutil
import time
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from ..core.errors import InputError
from .manifest import Manifest
from .pair import BuildParams, PairResult, PairSpec, pair_layout, run_pair, write_pair
from .pairfolder import pair_dir
from .plans import PlanSource, source_digest

__all__ = [
    "FORMAT",
    "MAX_COUNT",
    "SPLIT_FRACTIONS",
    "BuildSummary",
    "build_dataset",
    "split_for_plan",
    "open_dataset",
    "dataset_status",
]

FORMAT = "map2map-dataset"
VERSION = 1
#: train / val / test shares of the plans.
SPLIT_FRACTIONS = (0.8, 0.1, 0.1)
#: The most pairs a dataset holds: pairs and generated plans are numbered with six digits
#: (``pairs/000000`` .. ``pairs/999999``, ``gen-SEED-000000``).
MAX_COUNT = 1_000_000


def split_for_plan(plan_id: str, fractions=SPLIT_FRACTIONS) -> str:
    """The split of a plan: a function of its id only.

    Examples
    --------
    >>> split_for_plan("gen-0-000001"), split_for_plan("gen-0-000001")
    ('train', 'train')
    """
    u = int.from_bytes(hashlib.sha256(plan_id.encode()).digest()[:8], "big") / 2.0**64
    if u < fractions[0]:
        return "train"
    return "val" if u < fractions[0] + fractions[1] else "test"


@dataclass
class BuildSummary:
    """What a build did (this session) and where the dataset stands."""

    out: Path
    count: int
    done: int
    failed: int
    pending: int
    made_now: int
    failed_now: int
    seconds: float
    pairs_per_hour: float
    failures: list[tuple[int, str, str]] = field(default_factory=list)
    figures: list[Path] = field(default_factory=list)
    coverage_mean: float | None = None
    extended_from: int | None = None

    def lines(self) -> list[str]:
        """The human summary the CLI prints."""
        out = [
            f"{self.out}: {self.done}/{self.count} pairs done, {self.failed} failed, "
            f"{self.pending} pending",
            f"this run: {self.made_now} made, {self.failed_now} failed in {self.seconds:.0f} s "
            f"({self.pairs_per_hour:.0f} pairs/h)",
        ]
        if self.extended_from is not None:
            out.append(f"extended from {self.extended_from} to {self.count} pairs")
        if self.coverage_mean is not None:
            out.append(f"mean coverage of reachable free space {100 * self.coverage_mean:.1f} %")
        for idx, plan, why in self.failures[:10]:
            out.append(f"  failed {idx:6d} ({plan}): {why}")
        if len(self.failures) > 10:
            out.append(f"  ... {len(self.failures) - 10} more (map2map dataset status)")
        out += [f"figure: {p}" for p in self.figures]
        return out


def _identity(src: PlanSource, seed: int, params: BuildParams) -> dict[str, Any]:
    return {
        "format": FORMAT,
        "version": VERSION,
        "seed": int(seed),
        "plans": src.kind,
        "plans_digest": source_digest(src),
        "resolution": src.resolution,
        "plan_resolution": src.plan_resolution,
        "params": dataclasses.asdict(params),
        "splits": list(SPLIT_FRACTIONS),
    }


def _describe_diff(old: dict, new: dict) -> str:
    diffs = []
    for k in sorted(set(old) | set(new)):
        if k == "params":
            for pk in sorted(set(old.get(k, {})) | set(new.get(k, {}))):
                a, b = old.get(k, {}).get(pk), new.get(k, {}).get(pk)
                if a != b:
                    diffs.append(f"{pk} {a!r} -> {b!r}")
        elif old.get(k) != new.get(k):
            if k == "plans_digest":
                diffs.append("the plan folder's files changed")
            else:
                diffs.append(f"{k} {old.get(k)!r} -> {new.get(k)!r}")
    return ", ".join(diffs)


@contextlib.contextmanager
def _build_lock(ds: Path):
    """Hold ``ds/.build.lock`` (an exclusive flock) while a build runs; the file is removed
    when the build ends, finished or interrupted, while it is still locked. A build that
    opened the file just before it was removed gets the lock of a file no longer in
    ``ds``: it notices (another inode, or none, at the path) and takes a fresh one, so
    two builds never both hold the lock."""
    import fcntl

    path = ds / ".build.lock"
    while True:
        fh = open(path, "w")
        try:
            fcntl.flock(fh, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except BlockingIOError:
            fh.close()
            raise InputError(ds, "another build is running on this dataset") from None
        try:
            if os.stat(path).st_ino == os.fstat(fh.fileno()).st_ino:
                break
        except FileNotFoundError:
            pass
        fh.close()  # the build that held it has just ended and removed it: try again
    try:
        yield
    finally:
        with contextlib.suppress(FileNotFoundError):
            path.unlink()
        fh.close()


def open_dataset(ds: str | os.PathLike) -> Manifest:
    """The manifest of an existing dataset (:class:`InputError` if ``ds`` is not one)."""
    ds = Path(ds)
    path = ds / "manifest.sqlite"
    if not path.is_file():
        raise InputError(ds, "not a map2map dataset (no manifest.sqlite)")
    m = Manifest(path)
    ident = m.get_info("identity")
    if not ident or ident.get("format") != FORMAT:
        m.close()
        raise InputError(path, "not a map2map dataset manifest")
    return m


def _tidy(ds: Path, done: set[int]) -> int:
    """Remove left-over temporary folders and pair folders the manifest does not know."""
    removed = 0
    pairs = ds / "pairs"
    if not pairs.is_dir():
        return 0
    for p in pairs.iterdir():
        if p.name.startswith(".tmp-") or (p.name.isdigit() and int(p.name) not in done):
            shutil.rmtree(p, ignore_errors=True)
            removed += 1
    return removed


def build_dataset(
    out: str | os.PathLike,
    plans: str | PlanSource,
    count: int,
    seed: int,
    params: BuildParams | None = None,
    *,
    workers: int = 1,
    scheduler: str | None = None,
    resolution: float = 0.05,
    plan_resolution: float | None = None,
    max_attempts: int = 3,
    progress: bool = True,
    figures: bool = True,
    task: Callable[[PairSpec], PairResult] = run_pair,
    start_method: str = "spawn",
) -> BuildSummary:
    """Build (or continue) dataset ``out``.

    Parameters
    ----------
    out : path-like
        Dataset folder (created; an existing dataset is continued).
    plans : str or PlanSource
        ``"generated"``, a folder of plans, or a :class:`PlanSource`.
    count : int
        Number of pairs (indices ``0 .. count - 1``), at most :data:`MAX_COUNT`.
    seed : int
        Dataset seed; pair ``i`` depends on ``(seed, i)`` only.
    params : BuildParams
        How pairs are made (source, fov, size, duration, ...).
    workers : int
        Local worker processes (or LocalCluster workers with ``scheduler="local"``).
        ``0`` runs in this process (no isolation from a crashing pair).
    scheduler : str, optional
        ``"local"`` (a Dask LocalCluster) or a Dask scheduler address.
    resolution, plan_resolution : float
        Working resolution of plans; metres per pixel of picture plans.
    max_attempts : int
        Runs of a pair whose worker died before it is recorded failed.
    progress, figures : bool
        Show a tqdm bar (pairs/h, ETA); write the contact sheet and histograms.
    task : callable
        What makes one pair (default :func:`~map2map.datasets.pair.run_pair`); it must be
        importable by name in worker processes.
    start_method : str
        multiprocessing start method of the local pool.

    Returns
    -------
    BuildSummary

    Raises
    ------
    InputError
        Bad arguments, ``out`` holding a dataset built with other settings (or not a
        dataset), another build running on it, an unreachable scheduler.
    """
    from tqdm.auto import tqdm

    if isinstance(count, bool) or not isinstance(count, int) or count < 1:
        raise InputError("count", f"must be an integer >= 1, got {count!r}")
    if count > MAX_COUNT:
        raise InputError("count", f"must be at most {MAX_COUNT} (pairs are numbered with six "
                         f"digits: pairs/000000 .. pairs/999999), got {count}")
    if isinstance(seed, bool) or not isinstance(seed, int) or seed < 0:
        raise InputError("seed", f"must be an integer >= 0, got {seed!r}")
    if workers < 0:
        raise InputError("workers", f"must be >= 0, got {workers}")
    if max_attempts < 1:
        raise InputError("max_attempts", f"must be >= 1, got {max_attempts}")
    params = params or BuildParams()
    from ..robotlog.mappers import available_mappers

    if params.mapper not in available_mappers():
        raise InputError(
            "mapper", f"unknown mapper {params.mapper!r} ({', '.join(available_mappers())})"
        )
    src = plans if isinstance(plans, PlanSource) else PlanSource.from_arg(
        plans, resolution, plan_resolution)  # fmt: skip
    ds = Path(out)
    if ds.exists() and not ds.is_dir():
        raise InputError(ds, "output exists and is not a folder")
    if ds.is_dir() and any(ds.iterdir()) and not (ds / "manifest.sqlite").is_file():
        raise InputError(ds, "folder is not empty and holds no dataset; choose a new `out`")
    ds.mkdir(parents=True, exist_ok=True)
    (ds / "pairs").mkdir(exist_ok=True)
    ident = _identity(src, seed, params)
    with _build_lock(ds), Manifest(ds / "manifest.sqlite") as man:
        old = man.get_info("identity")
        extended_from = None
        if old is None:
            man.set_info("identity", ident)
            man.set_info("plans", {"kind": src.kind, "files": list(src.files)})
        elif old != ident:
            raise InputError(
                ds,
                f"holds a dataset built with other settings ({_describe_diff(old, ident)}); "
                "rerun with its original arguments or choose a new `out`",
            )
        old_count = man.get_info("count")
        if old_count is not None and old_count != count:
            extended_from = old_count
        man.set_info("count", max(count, old_count or 0))
        finished = man.finished()
        _tidy(ds, {r["idx"] for r in man.rows("done")})
        n_todo = count - sum(1 for i in finished if i < count)
        # made one at a time as workers take them; each task carries only its own plan file
        # (load_plan gives the same plan)
        specs = (
            PairSpec(i, seed, src.only(pair_layout(i, params.source)[1]), params)
            for i in range(count) if i not in finished
        )
        made = failed = 0
        failures: list[tuple[int, str, str]] = []
        t0 = time.perf_counter()
        bar = tqdm(total=count, initial=count - n_todo, unit="pair", desc="dataset",
                   disable=not progress, dynamic_ncols=True)  # fmt: skip

        def tick() -> None:
            el = time.perf_counter() - t0
            rate = (made + failed) * 3600.0 / el if el > 0 else 0.0
            bar.set_postfix_str(f"{rate:.0f} pairs/h, {failed} failed", refresh=False)
            bar.update(1)

        def on_result(spec: PairSpec, res: PairResult, worker: str) -> None:
            nonlocal made, failed
            split = split_for_plan(res.plan_id)
            if res.ok:
                write_pair(res, pair_dir(ds, spec.index))
                man.record_done(spec.index, res.plan_id, res.kind, res.meta, split=split,
                                wall_seconds=res.wall_seconds, worker=worker)  # fmt: skip
                made += 1
            else:
                man.record_failed(spec.index, res.plan_id, res.kind, res.reason, split=split,
                                  wall_seconds=res.wall_seconds, worker=worker)  # fmt: skip
                failures.append((spec.index, res.plan_id, res.reason))
                failed += 1
            tick()

        def on_crash(spec: PairSpec, reason: str) -> bool:
            nonlocal failed
            kind, plan_index = pair_layout(spec.index, params.source)
            plan_id = f"plan {plan_index}"
            n = man.record_crash(spec.index, plan_id, kind, reason, split="")
            if reason.startswith("dask"):  # Dask has retried already and says how often
                why = reason
            elif n < max_attempts:
                return True
            else:
                why = f"{reason}; gave up after {n} attempt{'s' if n > 1 else ''}"
            man.record_failed(spec.index, plan_id, kind, why, split="")
            failures.append((spec.index, plan_id, why))
            failed += 1
            tick()
            return False

        try:
            if not n_todo:
                pass
            elif scheduler:
                from .dask_backend import run_dask

                key = hashlib.sha256(repr(sorted(ident.items())).encode()).hexdigest()[:12]
                run_dask(specs, task, scheduler, workers=max(1, workers), on_result=on_result,
                         on_crash=on_crash, key_prefix=f"map2map-pair-{key}")  # fmt: skip
            elif workers == 0:
                for spec in specs:
                    on_result(spec, task(spec), "main")
            else:
                from .pool import run_pool

                run_pool(specs, task, min(workers, n_todo), on_result=on_result,
                         on_crash=on_crash, start_method=start_method)  # fmt: skip
        finally:
            bar.close()
        seconds = time.perf_counter() - t0
        counts = man.counts()
        done_rows = man.rows("done")
        covs = [r["coverage"] for r in done_rows if r["coverage"] is not None]
        summary = BuildSummary(
            out=ds,
            count=count,
            done=sum(1 for r in done_rows if r["idx"] < count),
            failed=sum(1 for r in man.rows("failed") if r["idx"] < count),
            pending=0,
            made_now=made,
            failed_now=failed,
            seconds=seconds,
            pairs_per_hour=(made + failed) * 3600.0 / seconds if seconds > 0 else 0.0,
            failures=failures,
            coverage_mean=float(sum(covs) / len(covs)) if covs else None,
            extended_from=extended_from,
        )
        summary.pending = count - summary.done - summary.failed
        man.set_info("last_build", {
            "made": made, "failed": failed, "seconds": round(seconds, 3),
            "pairs_per_hour": round(summary.pairs_per_hour, 1), "workers": workers,
            "scheduler": scheduler, "counts": counts,
        })  # fmt: skip
        if figures and done_rows:
            from .figures import contact_sheet, histograms

            summary.figures = [
                contact_sheet(ds, done_rows, ds / "figures" / "contact_sheet.png"),
                histograms(done_rows, ds / "figures" / "histograms.png"),
            ]
    return summary


def dataset_status(ds: str | os.PathLike) -> dict[str, Any]:
    """Where dataset ``ds`` stands: identity, counts, failures, cleaner, splits, timing.

    Examples
    --------
    >>> import tempfile
    >>> s = build_dataset(tempfile.mkdtemp(), "generated", 1, 0,
    ...                   BuildParams(source="deform", size=32), workers=0,
    ...                   progress=False, figures=False)
    >>> st = dataset_status(s.out)
    >>> st["counts"], st["count"]
    ({'done': 1}, 1)
    """
    with open_dataset(ds) as man:
        rows = man.rows()
        done = [r for r in rows if r["status"] == "done"]
        secs = [r["wall_seconds"] for r in done if r["wall_seconds"]]
        splits: dict[str, int] = {}
        for r in done:
            splits[r["split"]] = splits.get(r["split"], 0) + 1
        clean: dict[str, int] = {}
        for r in done:
            if r["clean"]:
                clean[r["clean"]] = clean.get(r["clean"], 0) + 1
        return {
            "identity": man.get_info("identity"),
            "count": man.get_info("count"),
            "counts": man.counts(),
            "failed": [
                (r["idx"], r["plan_id"], r["reason"]) for r in rows if r["status"] == "failed"
            ],  # fmt: skip
            "crashed": [
                (r["idx"], r["attempts"], r["reason"]) for r in rows if r["status"] == "crashed"
            ],  # fmt: skip
            "splits": splits,
            "clean": clean,
            "cleaner": man.get_info("cleaner"),
            "last_build": man.get_info("last_build"),
            "mean_wall_seconds": (sum(secs) / len(secs)) if secs else math.nan,
        }
