"""Thesis Fig. 5.14 reproduced, with numbers: for the same plan and the same trajectory,
the simulated SLAM map, the parametric model (``deform``, additive) and Model_AB, side by
side, each with its appendix-metric error against the plan and its wall recall.

For each held-out plan (the test split of a ``map2map dataset build`` dataset, or plans
given in memory):

* **simulated SLAM map** -- the dataset's own run, re-simulated with the pair's
  ``sim_seed`` and start pose (:func:`map2map.datasets.rerun.rerun_pair`; the re-run
  gives the dataset's ``B`` pixel for pixel, checked, and its trajectory); for a plan in
  memory, a new simulation (``map2map dataset build``'s defaults: 7 simulated minutes,
  180 degree LIDAR, ``rbpf``);
* **parametric** -- :func:`map2map.parametric.pipeline.deform` (additive, thesis 3.2)
  along the *same* trajectory: the simulation's true poses at its scan times
  (:func:`map2map.datasets.rerun.parametric_on_trajectory`; the model draws its own
  odometry and LIDAR errors);
* **Model_AB** -- the generator's single output for the preprocessed plan (dropout off,
  :func:`map2map.learn.ab.synthesize.synthesize_squares`), warped along a parametric drift
  field of the plan (``drift="parametric"``, the default, :mod:`map2map.learn.ab.drift`: its
  own route and errors, not the simulation's trajectory; ``"none"``: no drift).

All three are cut and preprocessed as the dataset's ``B`` (thesis 4.1: the pair's crop
window, square, ``S`` px) and measured the same way against the preprocessed plan: the
appendix paper's metric (:func:`map2map.evaluate.evaluate_maps`, the chosen chain's mean
local error, px of the ``S`` square, default settings) and the wall recall (share of plan
wall pixels within 2 px of a map wall, :func:`map2map.evaluate.wallmetrics.wall_metrics`).
A map whose alignment fails gets NaN and says so, never a number.

Examples
--------
>>> f = Fig514(["p"], [0], np.full((1, 8, 8), 255, np.uint8),
...            {m: np.full((1, 8, 8), 255, np.uint8) for m in METHODS},
...            [{"plan": "p", "method": m, "error_px": 1.0, "wall_recall": 0.5}
...             for m in METHODS], {}, "untrained")
>>> f.summary["model_ab"]["error_px_mean"]
1.0
"""

from __future__ import annotations

import math
import os
import warnings
from collections.abc import Sequence
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from ...core.grid import OccupancyMap

__all__ = ["METHODS", "METHOD_TITLES", "Fig514", "run_fig514", "measure"]

METHODS = ("simulated", "parametric", "model_ab")
METHOD_TITLES = {"simulated": "simulated SLAM map", "parametric": "parametric (additive)",
                 "model_ab": "Model_AB"}


def measure(m: np.ndarray, plan: np.ndarray) -> dict:
    """Appendix-metric error (px, NaN when the alignment fails), wall recall and wall
    precision (2 px) of map ``m`` against ``plan`` (same square, internal convention).
    Recall alone flatters thick walls (a blurred 8 px wall covers every plan wall within
    2 px); precision, the share of the map's wall pixels within 2 px of a plan wall,
    says what they cost.

    Examples
    --------
    >>> plan = np.full((64, 64), 255, np.uint8); plan[[8, 56], 8:57] = 0
    >>> plan[8:57, [8, 56]] = 0; plan[8:40, 30] = 0
    >>> round(measure(plan, plan)["wall_recall"], 2)
    1.0
    """
    from ...evaluate.pipeline import evaluate_maps
    from ...evaluate.wallmetrics import wall_metrics

    out = {"error_px": float("nan"), "wall_recall": float("nan"),
           "wall_precision": float("nan"), "note": ""}
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            ev = evaluate_maps(OccupancyMap(m, 0.05), OccupancyMap(plan, 0.05))
        out["error_px"] = float(ev.report["chosen_errors"]["mean_px"])
    except Exception as exc:  # noqa: BLE001 - an alignment failure is a result, reported
        out["note"] = f"alignment failed: {type(exc).__name__}: {str(exc)[:80]}"
    wm = wall_metrics(m, plan)
    out["wall_recall"] = float(wm["wall_recall"])
    out["wall_precision"] = float(wm["wall_precision"])
    return out


@dataclass
class Fig514:
    """Fig. 5.14's maps and numbers.

    Attributes
    ----------
    plan_ids, indices : list
        Per plan: its id and its pair index (-1 for a plan given in memory).
    plans : (N, S, S) uint8
        The preprocessed plans.
    maps : dict
        ``{method: (N, S, S) uint8}`` for :data:`METHODS`.
    rows : list of dict
        Per plan and method: ``plan``, ``index``, ``method``, ``error_px`` (appendix
        metric), ``wall_recall``, ``note``.
    info : dict
        Per plan: the simulation's coverage, ATE, path length, whether the re-run gave
        the dataset's map.
    model : str
        The Model_AB weights used.
    warnings : list of str
    drift : str
        How Model_AB's maps drift (e.g. ``"parametric additive x1"``, ``"none"``).
    """

    plan_ids: list
    indices: list
    plans: np.ndarray
    maps: dict
    rows: list
    info: dict
    model: str
    warnings: list = field(default_factory=list)
    drift: str = ""

    def title(self, method: str) -> str:
        """A column's title: :data:`METHOD_TITLES`, the generated column named after the
        generator (``"scans"``: ``synthesize --model scans``)."""
        if method == "model_ab" and self.model == "scans":
            return "synthesize (scans)"
        return METHOD_TITLES[method]

    @property
    def summary(self) -> dict:
        """Per method: mean and median error (over the aligned maps), how many failed to
        align, mean wall recall; plus ``n`` and ``model``."""
        out: dict = {"n": len(self.plan_ids), "model": self.model}
        for m in METHODS:
            rs = [r for r in self.rows if r["method"] == m]
            e = np.array([r["error_px"] for r in rs], float)
            rec = np.array([r["wall_recall"] for r in rs], float)
            pre = np.array([r.get("wall_precision", np.nan) for r in rs], float)
            ok = np.isfinite(e)
            out[m] = {"error_px_mean": float(e[ok].mean()) if ok.any() else float("nan"),
                      "error_px_median": float(np.median(e[ok])) if ok.any() else float("nan"),
                      "alignment_failed": int((~ok).sum()),
                      "wall_recall_mean": float(np.nanmean(rec)) if np.isfinite(rec).any()
                      else float("nan"),
                      "wall_precision_mean": float(np.nanmean(pre)) if np.isfinite(pre).any()
                      else float("nan")}
        return out

    def table(self) -> str:
        """The rows as text, then the summary per method."""
        lines = [f"{'plan':>14} {'method':>22} {'error px':>9} {'recall':>7} {'precision':>9}"]
        for r in self.rows:
            lines.append(f"{r['plan']:>14} {self.title(r['method']):>22} "
                         f"{r['error_px']:>9.2f} {r['wall_recall']:>7.2f} "
                         f"{r.get('wall_precision', float('nan')):>9.2f}"
                         + (f"  ({r['note']})" if r.get("note") else ""))
        s = self.summary
        for m in METHODS:
            v = s[m]
            lines.append(f"{'mean':>14} {self.title(m):>22} {v['error_px_mean']:>9.2f} "
                         f"{v['wall_recall_mean']:>7.2f} {v['wall_precision_mean']:>9.2f}"
                         f"  (median error "
                         f"{v['error_px_median']:.2f}; {v['alignment_failed']} not aligned)")
        return "\n".join(lines)

    def figure(self, path: str | os.PathLike | None = None, dpi: int = 90):
        """Rows = plans; columns = plan | simulated SLAM map | parametric | Model_AB,
        each titled with its error and wall recall; saved to ``path`` (atomically) when
        given. Returns the matplotlib figure."""
        import matplotlib

        matplotlib.use("Agg")
        import matplotlib.pyplot as plt

        n = len(self.plan_ids)
        fig, axes = plt.subplots(max(n, 1), 4, figsize=(12, 3.1 * max(n, 1)), squeeze=False)
        by = {(r["plan"], r["method"]): r for r in self.rows}
        for i, pid in enumerate(self.plan_ids):
            panels = [(self.plans[i], f"{pid}: plan")]
            for m in METHODS:
                r = by.get((pid, m), {})
                e = r.get("error_px", float("nan"))
                err = f"{e:.2f} px" if math.isfinite(e) else "not aligned"
                panels.append((self.maps[m][i], f"{self.title(m)}\nerror {err}, "
                               f"recall {r.get('wall_recall', float('nan')):.2f}, "
                               f"precision {r.get('wall_precision', float('nan')):.2f}"))
            rows, cols = np.nonzero(self.plans[i] != 127)
            box = (rows.min(), rows.max(), cols.min(), cols.max()) if rows.size else None
            for ax, (img, title) in zip(axes[i], panels, strict=True):
                ax.imshow(img, cmap="gray", vmin=0, vmax=255, interpolation="nearest")
                ax.set_title(title, fontsize=8)
                ax.set_xticks([])
                ax.set_yticks([])
                if box is not None:
                    ax.set_xlim(box[2] - 3, box[3] + 3)
                    ax.set_ylim(box[1] + 3, box[0] - 3)
        import textwrap

        gen = self.title("model_ab")
        scans = self.model == "scans"
        how = f"{gen}: {self.drift.removeprefix('scans: ')}" if scans else \
            f"{gen}'s drift: {self.drift}"
        extra = textwrap.wrap(how, 130) if self.drift else []
        fig.suptitle("\n".join([
            f"Fig. 5.14 reproduced: same plan, same trajectory (appendix-metric error px of "
            f"the {self.plans.shape[-1]} px square; wall recall 2 px)"
            + ("" if scans else f"; {gen}: {Path(self.model).name}"), *extra]), fontsize=9)
        top = 0.45 + 0.3 * len(extra)
        fig.tight_layout(rect=(0, 0, 1, 1 - top / (3.1 * max(n, 1))))
        if path is not None:
            from ...core._io import atomic_path

            with atomic_path(path) as tmp:
                fig.savefig(tmp, dpi=dpi, format="png")
            plt.close(fig)
        return fig

    def write_csv(self, path: str | os.PathLike) -> None:
        """The rows as CSV (atomically)."""
        import csv

        from ...core._io import atomic_path

        keys = ["plan", "index", "method", "error_px", "wall_recall", "wall_precision", "note"]
        with atomic_path(path) as tmp:
            with open(tmp, "w", newline="") as fh:
                w = csv.DictWriter(fh, fieldnames=keys, extrasaction="ignore")
                w.writeheader()
                w.writerows(self.rows)


def _from_dataset(ds, n, seed, split, progress):
    from ...datasets.pair import read_pair_meta, window_resolution
    from ...datasets.pairfolder import SLAM_PNG, pair_dir, read_picture
    from ...datasets.rerun import parametric_on_run, rerun_pair
    from ..realism.measure import split_indices

    idx = split_indices(ds, split)[:n]
    out = []
    for i in _bar(idx, progress, "simulate + parametric"):
        meta = read_pair_meta(pair_dir(ds, i))
        rr = rerun_pair(ds, i, sim_seed=int(meta["sim_seed"]))
        b_file = read_picture(pair_dir(ds, i) / SLAM_PNG)
        same = bool(np.array_equal(rr.b_n, b_file))
        info = {k: rr.meta.get(k) for k in ("coverage", "ate_rmse_m", "path_length_m",
                                             "stop_reason", "sim_seed")}
        info["reproduces_dataset_map"] = same
        info["square_resolution_m"] = window_resolution(rr.plan, rr.box, rr.a_n.shape[-1])
        out.append((meta["plan_id"], i, rr.a_n, rr.b_n, parametric_on_run(rr, seed=seed),
                    info, rr.plan, rr.box))
    return out


def _from_plans(plans, seed, progress, params):
    from ...datasets.pair import BuildParams, crop_box, preprocess_pair, window_resolution
    from ...datasets.rerun import parametric_on_trajectory
    from ...sim.runner import simulate

    p = params or BuildParams()
    out = []
    for k, plan in enumerate(_bar(list(plans), progress, "simulate + parametric")):
        sim = simulate(plan, seed=seed + k, duration=p.duration, fov=p.fov, mapper=p.mapper,
                       progress=False)
        box = crop_box(plan, sim.slam_map_plan)
        a_n, b_n = preprocess_pair(plan, sim.slam_map_plan, p.size, p.thicken, box=box)
        par = parametric_on_trajectory(plan, sim, box, p.size, p.thicken, p.fov,
                                       np.random.default_rng([int(seed), k]))
        rep = sim.report()
        info = {k2: rep.get(k2) for k2 in ("coverage", "ate_rmse_m", "path_length_m",
                                            "stop_reason")}
        info["square_resolution_m"] = window_resolution(plan, box, p.size)
        out.append((f"plan {k}", -1, a_n, b_n, par, info, plan, box))
    return out


def _bar(items, progress, desc):
    if not progress:
        return items
    from tqdm.auto import tqdm

    return tqdm(items, desc=desc, unit="plan")


def run_fig514(source: str | os.PathLike | Sequence[OccupancyMap], n: int = 6,
               model="pretrained", seed: int = 0, *, split: str = "test",
               params=None, progress: bool = True, render: str = "slam",
               drift="parametric", drift_method: str | None = None,
               drift_scale: float | None = None, coverage: str = "none",
               drift_route: str = "tour", traces="none",
               explore_at: str = "square") -> Fig514:
    """Fig. 5.14 for ``n`` held-out plans (module doc).

    Parameters
    ----------
    source : path or sequence of OccupancyMap
        A ``map2map dataset build`` folder (its ``split`` pairs, by index) or plans.
    n : int
        Number of plans (the first ``n`` of the split; all given plans otherwise).
    model : "pretrained", "scans", run folder, weights file or ABModel
        Model_AB, or ``"scans"``: ``synthesize``'s default, the robot's own scans at
        its particle filter's poses (:mod:`map2map.learn.ab.scans`; hypothesis 0 with
        seed ``seed`` + the pair's index; the Model_AB options below do not apply).
    seed : int
        Seeds the parametric model (and the simulations of plans given in memory).
    split : str
        The dataset split (``"test"``: plans never seen in training).
    params : BuildParams, optional
        For plans in memory: simulation and preprocessing (default ``map2map dataset
        build``'s: 420 s, 180 degrees, ``rbpf``, 256 px, walls thickened by 1).
    progress : bool
    render : {"slam", "plain"}
        How Model_AB's output is raised to the plans' size
        (:func:`~map2map.learn.ab.synthesize.synthesize_squares`).
    drift, drift_method, drift_scale
        Model_AB's drift (:func:`~map2map.learn.ab.synthesize.synthesize_squares`; each
        square at its metric resolution, ``info[plan]["square_resolution_m"]``).
    coverage, drift_route
        Model_AB's coverage from its own exploration and the drift's route
        (:func:`~map2map.learn.ab.synthesize.synthesize_squares`, :mod:`map2map.learn.ab.coverage`).
    traces : {"none", "lidar"} or TraceParams
        What a LIDAR leaves beyond the faces (:class:`~map2map.learn.ab.render.
        TraceParams`; ``render="slam"`` only).
    explore_at : {"square", "native"}
        Where ``coverage="explore"``'s robot explores: the preprocessed square, or each
        plan at its own resolution, as :func:`~map2map.learn.ab.synthesize.synthesize` does
        (:func:`~map2map.experiments.realism.measure.seen_on_square`; needs ``drift_route="tour"``).
        ``drift="rooms", coverage="explore", traces="lidar", explore_at="native"`` is
        what ``map2map synthesize`` makes (its defaults).

    Returns
    -------
    Fig514
        ``.rows``, ``.summary``, ``.figure()``, ``.table()``.
    """
    if isinstance(source, str | os.PathLike):
        made = _from_dataset(Path(source), int(n), int(seed), split, progress)
    else:
        made = _from_plans(list(source)[:int(n)], int(seed), progress, params)
    if not made:
        from ...core.errors import InputError

        raise InputError(source if isinstance(source, str | os.PathLike) else None,
                         f"no simulated '{split}' pairs to draw")
    if explore_at not in ("square", "native"):
        raise ValueError(f"explore_at must be 'square' or 'native', got {explore_at!r}")
    plans = np.stack([m[2] for m in made])
    if model == "scans":
        gen, source, warns, how = _scans_squares(made, plans.shape[-1], seed, progress)
        given = {"render": (render, "slam"), "drift": (drift, "parametric"),
                 "drift_method": (drift_method, None), "drift_scale": (drift_scale, None),
                 "coverage": (coverage, "none"), "drift_route": (drift_route, "tour"),
                 "traces": (traces, "none"), "explore_at": (explore_at, "square")}
        unused = [k for k, (v, d) in given.items() if v != d]
        if unused:
            warns.append(f"{', '.join(unused)}: Model_AB's options, not used by scans")
    else:
        gen, source, warns, how = _network_squares(
            made, plans, model, seed, render=render, drift=drift, drift_method=drift_method,
            drift_scale=drift_scale, coverage=coverage, drift_route=drift_route,
            traces=traces, explore_at=explore_at)
    maps = {"simulated": np.stack([m[3] for m in made]),
            "parametric": np.stack([m[4] for m in made]), "model_ab": gen}
    rows = []
    for i, (pid, idx, *_rest) in enumerate(_bar(made, progress, "evaluate")):
        for m in METHODS:
            rows.append({"plan": pid, "index": int(idx), "method": m,
                         **measure(maps[m][i], plans[i])})
    info = {m[0]: m[5] for m in made}
    bad = [pid for pid, v in info.items() if v.get("reproduces_dataset_map") is False]
    if bad:
        warns.append(f"the re-run of {len(bad)} pair(s) ({', '.join(bad[:4])}) did not give "
                     "the dataset's map; the figure shows the re-run (whose trajectory the "
                     "parametric model follows)")
    return Fig514([m[0] for m in made], [int(m[1]) for m in made], plans, maps, rows, info,
                  source, warns, how)


def _scans_squares(made, size: int, seed: int, progress: bool):
    """``synthesize --model scans``'s first hypothesis of every plan (seed ``seed`` + its
    row, as per_plan's), cut with the pair's window: ``(maps, source, warnings, how)``."""
    from ...datasets.pair import preprocess_pair
    from ...learn.ab.scans import ScanMapParams
    from ...learn.ab.synthesize import SCANS, synthesize

    out = []
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        for j, m in enumerate(_bar(made, progress, "synthesize --model scans")):
            idx = int(m[1]) if int(m[1]) >= 0 else j
            res = synthesize(m[6], SCANS, samples=1, seed=int(seed) + idx)
            out.append(preprocess_pair(m[6], res.maps[0], size, 0, m[7])[1])
    sp = ScanMapParams()
    how = ("scans: the robot's own scans at its particle filter's poses"
           if sp.pose_error == "filter" else
           f"scans: the robot's own scans at drifted poses (rooms {sp.room_order}, "
           f"{sp.rooms.rot_deg:g} deg a room step; jitter {100 * sp.jitter_m:g} cm / "
           f"{sp.jitter_deg:g} deg)")
    return np.stack(out), SCANS, sorted({str(w.message) for w in caught}), how


def _network_squares(made, plans, model, seed, *, render, drift, drift_method, drift_scale,
                     coverage, drift_route, traces, explore_at):
    """Model_AB's map of every plan (:func:`~map2map.learn.ab.synthesize.synthesize_squares`):
    ``(maps, source, warnings, how)``."""
    from ...learn.ab.drift import drift_params
    from ...learn.ab.model import load_ab_model
    from ...learn.ab.room_drift import RoomDriftParams
    from ...learn.ab.synthesize import synthesize_squares

    net = load_ab_model(model)
    seen = None
    unexplored = []
    if explore_at == "native" and coverage == "explore":
        from ...learn.ab.coverage import explore_rng
        from ..realism.measure import seen_on_square

        seen = np.ones(plans.shape, bool)           # a plan not explored: nothing hidden
        for j, m in enumerate(made):
            sq = seen_on_square(m[6], m[7], plans.shape[-1], explore_rng(seed, j))
            if sq is None:
                unexplored.append(m[0])
            else:
                seen[j] = sq
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        gen = synthesize_squares(net, plans, seed=seed, render=render, drift=drift,
                                 drift_method=drift_method, drift_scale=drift_scale,
                                 resolution=[m[5]["square_resolution_m"] for m in made],
                                 coverage=coverage, drift_route=drift_route,
                                 traces=traces, seen=seen)
    warns = []
    if "PROVISIONAL" in str(net.header.get("note", "")):
        warns.append("Model_AB weights are provisional (their note says so)")
    if unexplored:
        warns.append(f"the robot could not explore {len(unexplored)} plan(s) "
                     f"({', '.join(unexplored[:4])}): Model_AB's map there hides nothing")
    warns += sorted({str(w.message) for w in caught})
    dp = drift_params(drift, drift_method, drift_scale)
    how = "none" if dp is None else dp.describe() if isinstance(dp, RoomDriftParams) else \
        f"parametric ({dp.describe()})"
    if coverage != "none" or (drift_route != "tour" and dp is not None):
        how += f"; own exploration: coverage {coverage}, drift route {drift_route}"
        if coverage == "explore":
            how += f", explored at {explore_at} resolution"
    if traces not in ("none", None):
        how += "; LIDAR traces"
    return gen, net.source, warns, how
