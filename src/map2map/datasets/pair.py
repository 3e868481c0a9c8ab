"""One dataset pair: (A: the plan, B: a SLAM map of it), made by one function.

:func:`make_pair` turns a :class:`PairSpec` (dataset seed, pair index, plan source,
build parameters) into a :class:`PairResult` (arrays + metadata) by calling the library
entry points directly: the plan (:func:`map2map.datasets.plans.load_plan`), the
simulated robot with a real SLAM backend (:func:`map2map.sim.runner.simulate`, thesis
sec. 4.1: TurtleBot3, 7 simulated minutes of explore_lite-style exploration, GMapping-style
``rbpf``) or the parametric model (:func:`map2map.parametric.pipeline.deform`, thesis
sec. 3.2, with its ground-truth displacement field), and the thesis 4.1 preprocessing
(:func:`map2map.maps.preprocess.preprocess`: crop, square, resize, harmonise, thicken the
plan's walls) applied with one crop window to both maps so they stay aligned.

Why not the jobs layer (:func:`map2map.jobs.simulate.simulate`,
:func:`map2map.jobs.deform.deform`), which the CLI calls: both run the same library
functions this module calls, but a job is "files in, files out". ``jobs.simulate``
writes its run folder (SLAM map, two trajectory CSVs, the CARMEN ``run.log``,
``report.json``): 3.3 MiB and 0.11 CPU s per 7-minute run (measured on a generated plan,
about 3-5 % of a pair's CPU time and 20 GiB of throw-away writes for a 6,300-pair
build). ``jobs.deform`` draws a sample's generators from an integer seed
(``SeedSequence(seed).spawn(2)``) where a pair draws them from
``SeedSequence(S, spawn_key=(0, i))``, and plans its route between start/goal or
waypoints, not the roadmap tour of ``BuildParams.tour``: using it would change every
parametric pair of existing datasets. So the builder calls the domain entry points
directly, with the same arguments the jobs pass (``simulate(plan, seed, duration, fov,
mapper, ...)``; ``make_trajectory`` + ``deform``).

Determinism: pair ``i`` of a dataset with seed ``S`` draws every random number from
``SeedSequence(S, spawn_key=(0, i))`` (its plan from ``(1, j)``, see
:mod:`~map2map.datasets.plans`): it depends on ``(S, i)`` only, never on the worker,
the order, or how often the build was interrupted. :func:`write_pair` writes the same
bytes for the same result (wall-clock times live in the manifest, not in the pair).

With ``source="both"`` pairs ``2j`` (simulated) and ``2j + 1`` (parametric) share plan
``j``; otherwise pair ``i`` uses plan ``i``.

Examples
--------
>>> import tempfile, pathlib
>>> from map2map.datasets.plans import PlanSource
>>> spec = PairSpec(0, 7, PlanSource("generated"), BuildParams(source="deform", size=64))
>>> res = make_pair(spec)
>>> res.ok, res.a_n.shape, res.kind, res.displacement is not None
(True, (64, 64), 'deform', True)
>>> folder = write_pair(res, pathlib.Path(tempfile.mkdtemp()) / "000000")
>>> sorted(p.name for p in folder.iterdir())[:4]
['A.pgm', 'A.png', 'A.yaml', 'B.pgm']
"""

from __future__ import annotations

import io
import json
import math
import os
import shutil
import time
import zipfile
from dataclasses import asdict, dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from .._version import __version__
from ..core.errors import InputError
from ..core.grid import OccupancyMap
from .pairfolder import DISPLACEMENT, META, PLAN_YAML, SLAM_YAML, write_pictures
from .plans import PlanSource, load_plan

__all__ = [
    "SOURCES",
    "BuildParams",
    "PairSpec",
    "PairResult",
    "pair_layout",
    "pair_seed",
    "make_pair",
    "run_pair",
    "write_pair",
    "read_pair_meta",
    "wall_error",
    "crop_box",
    "preprocess_pair",
    "window_resolution",
    "rerun_seed",
    "MIN_PATH_M",
]

SOURCES = ("simulate", "deform", "both")
#: A simulated robot that drove less than this (metres) "could not move": the pair fails.
MIN_PATH_M = 0.2
#: Crop margin (plan pixels) kept around the content of A and B before squaring.
CROP_MARGIN_PX = 4


@dataclass(frozen=True)
class BuildParams:
    """What every pair of a dataset is made with (part of the dataset's identity).

    Parameters
    ----------
    source : {"simulate", "deform", "both"}
        Simulated robot + SLAM, parametric model (thesis 3.2), or one of each per plan.
    fov : float
        Lidar field of view in degrees (thesis: 180).
    size : int
        Side of the preprocessed square maps (thesis: 256).
    duration : float
        Simulated seconds of exploration (thesis: 420 = 7 minutes).
    mapper : str
        SLAM backend of :func:`map2map.robotlog.mappers.make_mapper` (default ``rbpf``).
    thicken : int
        Pixels by which the plan's walls grow after resizing (thesis 4.1).
    method : {"additive", "ekf"}
        Parametric model's odometry-to-map conversion.
    tour : int
        Roadmap nodes the parametric model's trajectory visits.
    """

    source: str = "simulate"
    fov: float = 180.0
    size: int = 256
    duration: float = 420.0
    mapper: str = "rbpf"
    thicken: int = 1
    method: str = "additive"
    tour: int = 12

    def __post_init__(self):
        for name in ("fov", "duration"):  # 60 and 60.0 are the same dataset
            value = getattr(self, name)
            if isinstance(value, int | float) and not isinstance(value, bool):
                object.__setattr__(self, name, float(value))
        if self.source not in SOURCES:
            raise InputError("source", f"must be one of {', '.join(SOURCES)}, got {self.source!r}")
        if self.fov not in (180.0, 360.0):
            raise InputError("fov", f"must be 180 or 360 degrees, got {self.fov}")
        if not (isinstance(self.size, int) and 16 <= self.size <= 4096):
            raise InputError("size", f"must be an integer in [16, 4096], got {self.size!r}")
        if not (math.isfinite(self.duration) and self.duration > 0):
            raise InputError("duration", f"must be > 0 seconds, got {self.duration}")
        if not (isinstance(self.thicken, int) and 0 <= self.thicken <= 16):
            raise InputError("thicken", f"must be an integer in [0, 16], got {self.thicken!r}")


@dataclass(frozen=True)
class PairSpec:
    """Everything one pair depends on: dataset seed, pair index, plans, parameters."""

    index: int
    seed: int
    plans: PlanSource
    params: BuildParams = BuildParams()


@dataclass
class PairResult:
    """A made pair (``ok``) or the reason it could not be made.

    Attributes
    ----------
    index, plan_id, kind : int, str, str
        Pair index, plan id, ``"simulate"`` or ``"deform"``.
    a, b : OccupancyMap
        Plan and SLAM map at full resolution, in the plan's frame.
    a_n, b_n : (N, N) uint8
        The thesis 4.1 preprocessed pair.
    displacement : DisplacementField or None
        Ground-truth field of a parametric pair (pixels of ``a``).
    meta : dict
        Deterministic metadata (written to ``meta.json``).
    wall_seconds : float
        Time taken (kept in the manifest, not in the pair's files).
    reason : str or None
        Why the pair failed (``None`` when ``ok``).
    """

    index: int
    plan_id: str
    kind: str
    a: OccupancyMap | None = None
    b: OccupancyMap | None = None
    a_n: np.ndarray | None = None
    b_n: np.ndarray | None = None
    displacement: Any = None
    meta: dict = field(default_factory=dict)
    wall_seconds: float = 0.0
    reason: str | None = None

    @property
    def ok(self) -> bool:
        return self.reason is None


def pair_layout(index: int, source: str) -> tuple[str, int]:
    """``(kind, plan index)`` of pair ``index``.

    Examples
    --------
    >>> pair_layout(5, "both"), pair_layout(5, "simulate")
    (('deform', 2), ('simulate', 5))
    """
    if source == "both":
        return ("simulate", "deform")[index % 2], index // 2
    return source, index


def pair_seed(seed: int, index: int) -> np.random.SeedSequence:
    """The seed sequence of pair ``index`` of a dataset with ``seed``."""
    return np.random.SeedSequence(int(seed), spawn_key=(0, int(index)))


def wall_error(a: OccupancyMap, b: OccupancyMap) -> tuple[float | None, float | None]:
    """Mean and 95th percentile distance (m) of B's wall pixels from A's nearest wall.

    A simple map error in the plan frame (no alignment: a SLAM map's drift counts).
    ``(None, None)`` when either map has no wall.

    Examples
    --------
    >>> d = np.full((20, 20), 255, np.uint8); d[:, 5] = 0
    >>> e = d.copy(); e[:, 5] = 255; e[:, 7] = 0
    >>> wall_error(OccupancyMap(d, 0.1), OccupancyMap(e, 0.1))
    (0.2, 0.2)
    """
    import cv2

    if not a.occupied.any() or not b.occupied.any():
        return None, None
    dist = cv2.distanceTransform((~a.occupied).astype(np.uint8), cv2.DIST_L2, 5)
    d = dist[b.occupied].astype(float) * a.resolution
    return round(float(d.mean()), 6), round(float(np.percentile(d, 95)), 6)


def crop_box(a: OccupancyMap, b: OccupancyMap) -> tuple[int, int, int, int] | None:
    """The window :func:`preprocess_pair` cuts (before its margin): the union of both
    maps' content boxes ``(r0, r1, c0, c1)``, ``None`` when both are empty."""
    return _union_box(a, b)


def _union_box(a: OccupancyMap, b: OccupancyMap) -> tuple[int, int, int, int] | None:
    boxes = [m.content_bbox() for m in (a, b)]
    boxes = [x for x in boxes if x is not None]
    if not boxes:
        return None
    r0 = min(x[0] for x in boxes)
    r1 = max(x[1] for x in boxes)
    c0 = min(x[2] for x in boxes)
    c1 = max(x[3] for x in boxes)
    return r0, r1, c0, c1


def _window(m: OccupancyMap, box, k: int) -> OccupancyMap:
    r0, r1, c0, c1 = box
    out = m.crop(max(0, r0 - k), min(m.height, r1 + k), max(0, c0 - k), min(m.width, c1 + k))
    return out.pad(top=max(0, k - r0), bottom=max(0, r1 + k - m.height),
                   left=max(0, k - c0), right=max(0, c1 + k - m.width))  # fmt: skip


def preprocess_pair(a: OccupancyMap, b: OccupancyMap, size: int, thicken: int, box=None):
    """Thesis 4.1 preprocessing of an aligned pair: one crop window (the union of both
    maps' content plus :data:`CROP_MARGIN_PX`), square, resize to ``size``, harmonise;
    the plan's walls thickened by ``thicken`` pixels. Returns ``(a_n, b_n)`` uint8.

    ``box`` (``(r0, r1, c0, c1)``, default :func:`crop_box` of ``a`` and ``b``) forces the
    window: a second SLAM map of a dataset's plan cut with the pair's own window lands
    on the same pixels as the pair's ``B``."""
    from ..maps.preprocess import preprocess

    if box is None:
        box = _union_box(a, b)
    if box is not None:
        a, b = _window(a, box, CROP_MARGIN_PX), _window(b, box, CROP_MARGIN_PX)
    a_n = preprocess(a, size=size, thicken=thicken, crop=False)
    b_n = preprocess(b, size=size, thicken=0, crop=False)
    return a_n.data, b_n.data


def window_resolution(a: OccupancyMap, box, size: int) -> float:
    """Metres per pixel of the ``size`` px squares :func:`preprocess_pair` makes of map
    ``a`` (and its partner) cut with ``box`` (``None``: the whole map): the window's side,
    margins included, over ``size`` times ``a``'s resolution (thesis 4.1's square + resize
    keeps the aspect ratio, :func:`map2map.maps.preprocess.square_resize`).

    Examples
    --------
    >>> a = OccupancyMap(np.full((100, 300), 255, np.uint8), 0.05)
    >>> window_resolution(a, (10, 60, 20, 220), 256) == 0.05 * (200 + 2 * CROP_MARGIN_PX) / 256
    True
    >>> window_resolution(a, None, 100)
    0.15
    """
    if box is None:
        side = max(a.shape)
    else:
        r0, r1, c0, c1 = box
        side = max(r1 - r0, c1 - c0) + 2 * CROP_MARGIN_PX
    return float(a.resolution) * side / int(size)


def _reachable(plan: OccupancyMap, start) -> np.ndarray:
    from ..sim.runner import REACH_MARGIN
    from ..sim.world import World

    radius = 0.2
    world = World.build(plan, start=start, robot_radius=radius, rng=np.random.default_rng(0))
    return world.reachable_cells(start, radius, REACH_MARGIN)


def rerun_seed(sim_seed: int, run: int) -> int:
    """Simulation seed of run ``run`` (>= 2) of a simulated pair whose run 1 had
    ``sim_seed`` (its ``meta.json``): independent of run 1, a pure function of both.

    Examples
    --------
    >>> rerun_seed(4088532484, 2) == rerun_seed(4088532484, 2) != rerun_seed(4088532484, 3)
    True
    """
    return int(np.random.SeedSequence([int(sim_seed), int(run)]).generate_state(1)[0])


def _simulate(spec: PairSpec, plan: OccupancyMap, ss: np.random.SeedSequence,
              sim_seed: int | None = None, start=None, keep: list | None = None):
    """The simulated pair's SLAM map, field (None) and metadata; ``sim_seed`` and
    ``start`` override the pair's (a re-run); ``keep`` receives the SimResult."""
    from ..sim.runner import simulate

    p = spec.params
    if sim_seed is None:
        sim_seed = int(ss.generate_state(1)[0])
    res = simulate(plan, seed=sim_seed, duration=p.duration, fov=p.fov, mapper=p.mapper,
                   start=start, progress=False, source=f"plan {spec.index}")  # fmt: skip
    if keep is not None:
        keep.append(res)
    rep = res.report()
    if res.path_length < MIN_PATH_M:
        raise InputError(None, f"the robot could not move (drove {res.path_length:.2f} m)")
    meta = {
        "sim_seed": sim_seed,
        "coverage": rep["coverage"],
        "coverage_strict": rep.get("coverage_strict"),
        "ate_rmse_m": rep["ate_rmse_m"],
        "path_length_m": rep["path_length_m"],
        "stop_reason": rep["stop_reason"],
        "collisions": rep["collisions"],
        "simulated_seconds": rep["simulated_seconds"],
        "scans": rep["scans"],
        "reachable_free_m2": rep["reachable_free_m2"],
        "start_pose": rep["start_pose"],
        "mapper": rep["mapper"],
    }
    return res.slam_map_plan, None, meta


def _deform(spec: PairSpec, plan: OccupancyMap, ss: np.random.SeedSequence):
    from ..parametric.params import ParametricParams
    from ..parametric.pipeline import deform, make_trajectory

    p = spec.params
    traj_rng, model_rng = (np.random.default_rng(s) for s in ss.spawn(2))
    params = ParametricParams(fov_deg=float(p.fov))
    traj, _ = make_trajectory(plan, params, traj_rng, tour=p.tour)
    res = deform(plan, traj, p.method, params, model_rng)
    start = (float(traj.x[0]), float(traj.y[0]), float(traj.theta[0]))
    reach = _reachable(plan, start)
    n = int(reach.sum())
    cov = float((res.map.free & reach).sum() / n) if n else 0.0
    stats = res.field.stats(res.observed)
    path = float(np.hypot(np.diff(traj.x), np.diff(traj.y)).sum())
    meta = {
        "coverage": round(cov, 6),
        "ate_rmse_m": None,
        "path_length_m": round(path, 4),
        "stop_reason": "route done",
        "method": p.method,
        "tour": p.tour,
        "displacement_mean_px": round(stats["mean"], 6),
        "displacement_max_px": round(stats["max"], 6),
        "drawn": res.drawn,
        "start_pose": [round(v, 6) for v in start],
    }
    return res.map, res.field, meta


def make_pair(spec: PairSpec) -> PairResult:
    """Make pair ``spec.index`` (see the module docstring).

    Parameters
    ----------
    spec : PairSpec
        Dataset seed, pair index, plan source and build parameters.

    Returns
    -------
    PairResult
        The pair; its ``meta`` holds seed, plan id, coverage of the reachable free space,
        ATE, path length, stop reason and the parameters.

    Raises
    ------
    InputError
        An unreadable or degenerate plan (no free space, too small for the robot, the
        robot could not move).
    """
    t0 = time.perf_counter()
    kind, plan_index = pair_layout(spec.index, spec.params.source)
    plan_id, plan = load_plan(spec.plans, spec.seed, plan_index)
    if not plan.free.any():
        raise InputError(plan_id, "plan has no free space")
    ss = pair_seed(spec.seed, spec.index)
    if kind == "simulate":
        b, disp, info = _simulate(spec, plan, ss)
    else:
        b, disp, info = _deform(spec, plan, ss)
    a_n, b_n = preprocess_pair(plan, b, spec.params.size, spec.params.thicken)
    err, err95 = wall_error(plan, b)
    plan_info = {k: plan.meta[k] for k in ("kind", "size_m", "room_num", "file", "seed")
                 if k in plan.meta}  # fmt: skip
    meta = {
        "index": int(spec.index),
        "seed": int(spec.seed),
        "pair_seed": {"entropy": int(spec.seed), "spawn_key": [0, int(spec.index)]},
        "plan_id": plan_id,
        "plan_index": int(plan_index),
        "plan": plan_info,
        "kind": kind,
        "resolution": plan.resolution,
        "full_shape": list(plan.shape),
        "wall_error_m": err,
        "wall_error_p95_m": err95,
        "params": asdict(spec.params),
        "map2map_version": __version__,
        **info,
    }
    return PairResult(spec.index, plan_id, kind, plan, b, a_n, b_n, disp, meta,
                      time.perf_counter() - t0)  # fmt: skip


def run_pair(spec: PairSpec) -> PairResult:
    """:func:`make_pair`, with a bad plan or an unexpected error turned into a failed
    result (``reason`` says why) so that a build goes on. What workers run."""
    t0 = time.perf_counter()
    try:
        return make_pair(spec)
    except InputError as exc:
        reason = str(exc)
    except Exception as exc:  # a bug must not stop a 4,000-pair build; it is recorded
        reason = f"internal error: {type(exc).__name__}: {exc}"
    kind, plan_index = pair_layout(spec.index, spec.params.source)
    plan_id = f"plan {plan_index}"
    try:
        if not spec.plans.generated:
            plan_id = Path(spec.plans.files[plan_index % len(spec.plans.files)]).stem
        else:
            plan_id = f"gen-{int(spec.seed)}-{int(plan_index):06d}"
    except Exception:
        pass
    return PairResult(spec.index, plan_id, kind, reason=reason,
                      wall_seconds=time.perf_counter() - t0)  # fmt: skip


# ------------------------------------------------------------------- files
def _write_npz(path: Path, **arrays: np.ndarray) -> None:
    """A deflated .npz with fixed zip timestamps (same arrays -> same bytes)."""
    with zipfile.ZipFile(path, "w", compression=zipfile.ZIP_DEFLATED) as zf:
        for name, arr in arrays.items():
            buf = io.BytesIO()
            np.lib.format.write_array(buf, np.ascontiguousarray(arr), allow_pickle=False)
            info = zipfile.ZipInfo(f"{name}.npy", date_time=(1980, 1, 1, 0, 0, 0))
            info.compress_type = zipfile.ZIP_DEFLATED
            info.external_attr = 0o644 << 16
            zf.writestr(info, buf.getvalue())


def _fsync_dir(path: Path) -> None:
    try:
        fd = os.open(path, os.O_RDONLY)
    except OSError:
        return
    try:
        os.fsync(fd)
    except OSError:
        pass
    finally:
        os.close(fd)


def write_pair(res: PairResult, folder: str | os.PathLike) -> Path:
    """Write a made pair into ``folder`` atomically (a temporary folder beside it, renamed).

    Files: ``A.yaml``/``A.pgm`` and ``B.yaml``/``B.pgm`` (full resolution, the plan's
    frame), ``A.png``/``B.png`` (preprocessed N x N: 0 occupied, 127 unknown, 255 free),
    ``meta.json`` and, for parametric pairs, ``displacement.npz`` (``dx``, ``dy`` float32
    pixels of A: A's content at ``p`` appears in B at ``p + d(p)``). An existing
    ``folder`` is replaced. The same result always gives the same bytes.
    """

    from ..maps.ros import save_ros_map

    if not res.ok:
        raise ValueError("cannot write a failed pair")
    folder = Path(folder)
    tmp = folder.parent / f".tmp-{folder.name}-{os.getpid()}"
    if tmp.exists():
        shutil.rmtree(tmp)
    tmp.mkdir(parents=True)
    try:
        save_ros_map(res.a, tmp / PLAN_YAML)
        save_ros_map(res.b, tmp / SLAM_YAML)
        write_pictures(tmp, res.a_n, res.b_n)
        if res.displacement is not None:
            _write_npz(tmp / DISPLACEMENT, dx=res.displacement.dx.astype(np.float32),
                       dy=res.displacement.dy.astype(np.float32))  # fmt: skip
        text = json.dumps(res.meta, indent=1, sort_keys=True, default=_json_default)
        (tmp / META).write_text(text + "\n")
        for p in tmp.iterdir():
            with open(p, "rb") as fh:
                os.fsync(fh.fileno())
        if folder.exists():
            shutil.rmtree(folder)
        os.rename(tmp, folder)
        _fsync_dir(folder.parent)
    finally:
        if tmp.exists():
            shutil.rmtree(tmp, ignore_errors=True)
    return folder


def _json_default(o):
    if isinstance(o, np.integer):
        return int(o)
    if isinstance(o, np.floating):
        return float(o)
    if isinstance(o, np.ndarray):
        return o.tolist()
    raise TypeError(f"not JSON serialisable: {type(o).__name__}")


def read_pair_meta(folder: str | os.PathLike) -> dict:
    """The ``meta.json`` of a pair folder (:class:`InputError` naming it if unreadable)."""
    path = Path(folder) / META
    try:
        return json.loads(path.read_text())
    except FileNotFoundError:
        raise InputError(path, "file not found") from None
    except (OSError, ValueError) as exc:
        raise InputError(path, f"unreadable pair metadata ({exc})") from None
