"""Realism of generated SLAM maps, measured (issue #15; the thesis judged Model_AB's maps
by eye, sec. 5.1-5.2).

A generated SLAM map of a plan is *realistic* if it is as close to a simulated SLAM map of
the same plan as two independent simulated runs are to each other. On held-out plans
(the test split of a ``map2map dataset build`` dataset: plans never seen in training),
per map, on the dataset's square (``N x N`` px, thesis 4.1 preprocessing):

* ``wall_err``     mean distance (px) of the map's occupied cells to the nearest plan wall
  (the issue's "mean distance of occupied cells to plan walls"; no alignment, so drift
  counts);
* ``wall_seen``    share of plan wall pixels with an occupied cell within 2 px;
* ``free_mapped``  share of plan free pixels that are free in the map;
* ``unknown``      unknown share of the plan's known pixels;
* ``spurious``     occupied 8-connected fragments farther than 3 px from every plan wall;
* ``thickness``    wall thickness (px), :func:`map2map.maps.preprocess.wall_thickness_px`;
* ``bend``         bent-wall curvature: along the map's wall centre lines (skeleton), the
  RMS distance (px) of the centre line within a disc of radius :data:`BEND_RADIUS` px to
  its own best-fitting line (the square root of the local scatter's smaller eigenvalue),
  averaged over the centre-line pixels that lie within 3 px of a plan wall that is
  straight there (the plan's own local value below 0.25 px: corners, T-junctions and
  door jambs of the plan are left out, so only bending the map added counts; 0 for a
  straight wall).

and five statistics of SLAM errors (issue #33; exact definitions in
:mod:`map2map.experiments.realism.slam_errors`):

* ``doubled``        share of the plan's observed straight wall centre-line pixels at
  which the map shows two or more separate wall runs across the wall (a wall saved
  twice);
* ``room_rot``       per-room rotation of the map against the plan (degrees): mean
  ``|angle|`` over the plan's rooms, weighted by their occupied map cells;
* ``frontier_open``  share of the map's free border that ends in unknown more than 2 px
  from every occupied cell;
* ``frontier_rough`` that open frontier's length over its length after a closing of the
  free mask (1: smooth);
* ``streaks``        laser streaks (thin, elongated free protrusions into unknown) per
  10,000 free pixels.

Each statistic's distribution over the generated maps is compared with its distribution
over simulated run 1 (the dataset's own SLAM maps) by the 1-D Wasserstein distance, and
normalised by the same distance between simulated run 2 (:func:`map2map.datasets.rerun.
rerun_pair`: same plan, another simulation seed and the start that seed draws) and run 1:

    ratio = W(generated, run 1) / W(run 2, run 1)

Target (issue #15): every ratio <= 1.5. A ratio near 1 means the generator's maps differ
from simulated ones no more than a second simulation does. The ratio is itself noisy (a
distance between two samples over another): with a third simulated run of every plan,
:func:`null_ratios` draws what a perfect generator scores, so a generator's ratio can be
ranked among those draws (session 15: a perfect generator meets every ratio <= 1.5 in
about half the draws, at 624-662 plans).

The module needs numpy and scipy only (no torch): :func:`simulated_references` builds
the references (simulations, slow: ~10-60 s per plan), :func:`realism_table` the table,
:func:`native_seen` the generators' explorations at the plans' own resolution.

Examples
--------
>>> import numpy as np
>>> plan = np.full((32, 32), 255, np.uint8); plan[:, 0] = plan[:, -1] = 0
>>> slam = plan.copy(); slam[:, 10:] = 127
>>> s = map_stats(slam, plan)
>>> round(s["wall_seen"], 2), round(s["free_mapped"], 2), s["spurious"]
(0.5, 0.3, 0.0)
>>> rng = np.random.default_rng(0)
>>> runs = [np.stack([plan] * 4) for _ in range(3)]
>>> for r in runs[1:]:
...     r[:, rng.integers(1, 31), 5] = 0                 # a spurious dot per map
>>> rows = realism_table(runs[0], runs[1], runs[2], np.stack([plan] * 4))
>>> [(r.statistic, r.ratio) for r in rows][4]           # no dots vs dots: W = 1, ref W = 0
('spurious', inf)
"""

from __future__ import annotations

import json
import math
import os
import time
from dataclasses import asdict, dataclass
from pathlib import Path

import numpy as np
from scipy import ndimage
from scipy.stats import wasserstein_distance

from ...core.grid import FREE, OCCUPIED, UNKNOWN, OccupancyMap
from .slam_errors import SLAM_ERROR_INFO, SLAM_ERROR_STATS, line_scatter, slam_error_stats

__all__ = ["STATS", "STAT_INFO", "TARGET_RATIO", "map_stats", "stats_of", "stats_of_sets",
           "RealismRow",
           "realism_table", "format_realism_table", "NullRatios", "null_ratios",
           "format_null", "References", "simulated_references",
           "split_indices", "seen_on_square", "native_seen",
           "pair_square_resolution"]

STATS = ("wall_err", "wall_seen", "free_mapped", "unknown", "spurious", "thickness", "bend",
         *SLAM_ERROR_STATS)
#: What each statistic is (units).
STAT_INFO = {
    "wall_err": "mean distance of occupied cells to plan walls (px)",
    "wall_seen": "share of plan walls with an occupied cell within 2 px",
    "free_mapped": "share of plan free space mapped free",
    "unknown": "unknown share of the plan's known pixels",
    "spurious": "occupied fragments > 3 px from every plan wall (count)",
    "thickness": "wall thickness (px)",
    "bend": "bent-wall curvature: RMS px off a fragment's principal line",
    **SLAM_ERROR_INFO,
}
#: Width of the statistic column of the printed tables (the longest name).
STAT_WIDTH = max(11, *(len(s) for s in STATS))
#: Issue #15's target for every statistic's Wasserstein ratio.
TARGET_RATIO = 1.5
#: :func:`format_realism_table` puts a longer generator name on a line of its own.
NAME_WIDTH = 24
#: :func:`simulated_references` rewrites its cache at most this often (seconds).
SAVE_EVERY_S = 60.0


def map_stats(m: np.ndarray, plan: np.ndarray, rooms: np.ndarray | None = None
              ) -> dict[str, float]:
    """The statistics of the module doc for SLAM map ``m`` of ``plan`` (same square).

    Parameters
    ----------
    m, plan : (N, N) uint8
        Ternary maps in the internal convention (occupied 0, unknown 127, free 255).

    Returns
    -------
    dict
        One float per name of :data:`STATS` (``wall_err`` is NaN for a map without
        occupied cells; the SLAM-error statistics are NaN where
        :mod:`~map2map.experiments.realism.slam_errors` says).
    """
    from ...maps.preprocess import wall_thickness_px

    m, plan = np.asarray(m), np.asarray(plan)
    if m.shape != plan.shape:
        raise ValueError(f"map {m.shape} and plan {plan.shape} differ in shape")
    walls = plan == OCCUPIED
    d_wall = ndimage.distance_transform_edt(~walls) if walls.any() else np.full(m.shape, 1e9)
    occ = m == OCCUPIED
    known_plan = plan != UNKNOWN
    near = ndimage.binary_dilation(occ, iterations=2)
    lab, n = ndimage.label(occ, structure=np.ones((3, 3)))
    spurious = 0
    if n:
        mind = ndimage.minimum(d_wall, lab, np.arange(1, n + 1))
        spurious = int(np.count_nonzero(np.asarray(mind) > 3))
    bend = _bend(occ, walls, d_wall)
    free_plan = plan == FREE
    return {
        "wall_err": float(d_wall[occ].mean()) if occ.any() else float("nan"),
        "wall_seen": float(near[walls].mean()) if walls.any() else float("nan"),
        "free_mapped": float((m[free_plan] == FREE).mean()) if free_plan.any() else 0.0,
        "unknown": float((m[known_plan] == UNKNOWN).mean()) if known_plan.any() else 1.0,
        "spurious": float(spurious),
        "thickness": float(wall_thickness_px(m[None])) if occ.any() else 0.0,
        "bend": bend,
        **slam_error_stats(m, plan, rooms),
    }


#: Radius (px) of the disc over which ``bend`` fits a line to the wall centre line.
BEND_RADIUS = 4


def _local_deviation(skel: np.ndarray, radius: int = BEND_RADIUS):
    """At every pixel: the number of ``skel`` pixels in the disc around it and the RMS
    distance of those pixels to their best-fitting line (sqrt of the smaller eigenvalue
    of their scatter), by six convolutions (no loop over pixels)."""
    yy, xx = np.mgrid[-radius:radius + 1, -radius:radius + 1]
    disc = (xx**2 + yy**2 <= radius**2).astype(float)
    m = skel.astype(float)
    Y, X = np.mgrid[:m.shape[0], :m.shape[1]].astype(float)

    def conv(a):
        return ndimage.convolve(a, disc, mode="constant")

    n = conv(m)
    dev, _ = line_scatter(n, conv(m * X), conv(m * Y), conv(m * X * X), conv(m * Y * Y),
                          conv(m * X * Y))
    return n, dev


def _bend(occ: np.ndarray, walls: np.ndarray, d_wall: np.ndarray) -> float:
    from skimage.morphology import skeletonize

    if not occ.any() or not walls.any():
        return 0.0
    skel = skeletonize(occ)
    n_map, dev_map = _local_deviation(skel)
    n_plan, dev_plan = _local_deviation(skeletonize(walls))
    use = skel & (d_wall <= 3) & (n_plan >= BEND_RADIUS) & (dev_plan < 0.25) & \
        (n_map >= BEND_RADIUS)
    return float(dev_map[use].mean()) if use.any() else 0.0


def stats_of(maps, plans) -> dict[str, np.ndarray]:
    """:func:`map_stats` of every ``(map, plan)``: ``{statistic: (N,) array}``."""
    rows = [map_stats(m, p) for m, p in zip(maps, plans, strict=True)]
    return {s: np.array([r[s] for r in rows], float) for s in STATS}


def stats_of_sets(sets: dict, plans) -> dict[str, dict[str, np.ndarray]]:
    """:func:`stats_of` of several map stacks of the same ``plans`` (``{name: (N, S, S)}``),
    each plan's rooms segmented once for all of them (the same values).

    Examples
    --------
    >>> plan = np.full((32, 32), 255, np.uint8); plan[:, 0] = plan[:, -1] = 0
    >>> both = stats_of_sets({"a": plan[None], "b": plan[None]}, plan[None])
    >>> both["a"]["wall_seen"].tolist() == stats_of(plan[None], plan[None])["wall_seen"].tolist()
    True
    """
    from ...learn.ab.room_drift import segment_rooms

    rows: dict[str, list] = {k: [] for k in sets}
    for i, p in enumerate(plans):
        rooms = segment_rooms(p, fill=False)   # as slam_errors.room_rotations does
        for k, maps in sets.items():
            rows[k].append(map_stats(maps[i], p, rooms))
    return {k: {s: np.array([r[s] for r in v], float) for s in STATS}
            for k, v in rows.items()}


@dataclass
class RealismRow:
    """One statistic: means over the generated maps and the two simulated runs, the
    Wasserstein distances ``W(generated, run 1)`` and ``W(run 2, run 1)``, their ratio
    and whether it meets :data:`TARGET_RATIO` (``None``: no values); ``ratio_even`` and
    ``ratio_odd``: the same ratio on the even- and the odd-numbered plans alone (NaN when
    not asked for), to show how much it moves with the plan set."""

    statistic: str
    generated: float
    sim1: float
    sim2: float
    w_generated: float
    w_sims: float
    ratio: float
    met: bool | None
    ratio_even: float = float("nan")
    ratio_odd: float = float("nan")

    def as_dict(self) -> dict:
        return asdict(self)


def _ratio(w_g: float, w_r: float) -> float:
    if w_r > 1e-12:
        return w_g / w_r
    return 1.0 if w_g <= 1e-12 else math.inf


def _w_ratio(g: np.ndarray, r1: np.ndarray, r2: np.ndarray
             ) -> tuple[float, float, float] | None:
    """``(W(g, r1), W(r2, r1), ratio)`` over the finite values of each, None when one of
    them has none: the one ratio :func:`realism_table` and :func:`null_ratios` compute."""
    g, r1, r2 = (x[np.isfinite(x)] for x in (g, r1, r2))
    if not (len(g) and len(r1) and len(r2)):
        return None
    w_g, w_r = float(wasserstein_distance(g, r1)), float(wasserstein_distance(r2, r1))
    return w_g, w_r, _ratio(w_g, w_r)


def realism_table(generated, sim1, sim2, plans, *, halves: bool = False
                  ) -> list[RealismRow]:
    """Wasserstein ratio per statistic (module doc) of ``generated`` maps against two
    simulated runs of the same ``plans``.

    Parameters
    ----------
    generated, sim1, sim2, plans : (N, S, S) uint8 or dicts of :func:`stats_of`
        Maps in the same order (map ``i`` of each is of plan ``i``); precomputed
        statistics may be passed instead of maps.
    halves : bool
        Also the ratio on the even- and on the odd-numbered plans alone (``ratio_even``,
        ``ratio_odd``). ``W(run 2, run 1)`` is a small distance (two runs of the same
        plans agree), so a ratio from ~100 plans is noisy; two disjoint halves show how
        much (each half is noisier than the whole). Session 13 tried bootstrap intervals
        instead; both the percentile and the BCa interval of the wall-thickness ratio
        on gen900's test plans excluded the ratio itself, so they were dropped.

    Returns
    -------
    list of RealismRow
        One per :data:`STATS`. A ratio is ``inf`` when the two runs agree exactly on a
        statistic and the generated maps do not; NaN values (a map with no wall) are
        left out of that statistic.

    Examples
    --------
    >>> rng = np.random.default_rng(0)
    >>> st = [{s: rng.normal(m, 1.0, 60) for s in STATS} for m in (0.0, 0.0, 0.3)]
    >>> r = realism_table(st[2], st[0], st[1], None, halves=True)[0]
    >>> bool(np.isfinite(r.ratio_even) and np.isfinite(r.ratio_odd))
    True
    """
    st = [g if isinstance(g, dict) else stats_of(g, plans) for g in (generated, sim1, sim2)]
    rows = []
    for s in STATS:
        v = [np.asarray(x[s], float) for x in st]
        whole = _w_ratio(*v)
        if whole is None:
            rows.append(RealismRow(s, *(float("nan"),) * 6, None))
            continue
        w_g, w_r, ratio = whole
        half = [float("nan"), float("nan")]
        if halves and len({len(x) for x in v}) == 1:
            for j in (0, 1):
                part = _w_ratio(*(x[j::2] for x in v))
                if part is not None:
                    half[j] = part[2]
        means = (float(np.nanmean(x)) for x in v)
        rows.append(RealismRow(s, *means, w_g, w_r, ratio, bool(ratio <= TARGET_RATIO),
                               *half))
    return rows


def _halves(r: RealismRow) -> str:
    return " / ".join(f"{x:.2f}" if math.isfinite(x) else "-"
                      for x in (r.ratio_even, r.ratio_odd))


def format_realism_table(rows: list[RealismRow], name: str = "generated") -> str:
    """The table as text, the worst ratio and the verdict on the last line.

    Examples
    --------
    >>> r = RealismRow("unknown", 0.3, 0.2, 0.21, 0.1, 0.05, 2.0, False)
    >>> print(format_realism_table([r], "Model_AB"))  # doctest: +NORMALIZE_WHITESPACE
    statistic Model_AB  sim 1  sim 2  W(gen,1)  W(2,1)  ratio
      unknown    0.300  0.200  0.210     0.100   0.050   2.00
    worst ratio 2.00 (unknown); target <= 1.5: NOT met (1 of 1 statistics above)
    """
    out = []
    if len(name) > NAME_WIDTH:  # a long name on its own line, the column stays narrow
        out.append(f"generator: {name}")
        name = "generated"
    w = max(9, len(name))
    ci = any(math.isfinite(r.ratio_even) or math.isfinite(r.ratio_odd) for r in rows)
    out.append(f"{'statistic':>{STAT_WIDTH}} {name:>{w}} {'sim 1':>8} {'sim 2':>8} "
               f"{'W(gen,1)':>9} {'W(2,1)':>8} {'ratio':>7}"
               + (f" {'even / odd':>13}" if ci else ""))
    for r in rows:
        out.append(f"{r.statistic:>{STAT_WIDTH}} {r.generated:>{w}.3f} {r.sim1:>8.3f} "
                   f"{r.sim2:>8.3f} {r.w_generated:>9.3f} {r.w_sims:>8.3f} {r.ratio:>7.2f}"
                   + (f" {_halves(r):>13}" if ci else ""))
    valid = [r for r in rows if r.met is not None]
    if not valid:
        return "\n".join(out + ["no values"])
    worst = max(valid, key=lambda r: r.ratio)
    bad = sum(not r.met for r in valid)
    verdict = "met" if bad == 0 else f"NOT met ({bad} of {len(valid)} statistics above)"
    out.append(f"worst ratio {worst.ratio:.2f} ({worst.statistic}); target <= "
               f"{TARGET_RATIO:g}: {verdict}")
    return "\n".join(out)


@dataclass
class NullRatios:
    """What a perfect generator scores: :func:`realism_table`'s ratio per statistic for
    ``draws`` random relabellings of simulated runs (:func:`null_ratios`).

    Attributes
    ----------
    ratios : (draws, len(STATS)) float
        One row per draw, columns in :data:`STATS` order.
    runs : int
        Simulated runs per plan the draws came from.
    plans : int
    """

    ratios: np.ndarray
    runs: int
    plans: int

    def quantiles(self, q=(0.5, 0.9, 0.95, 0.99)) -> dict[str, np.ndarray]:
        """Quantiles ``q`` of each statistic's ratio and of the worst (key ``"worst"``)."""
        with np.errstate(invalid="ignore"):  # inf ratios (runs that agree exactly)
            out = {s: np.quantile(self.ratios[:, j], q) for j, s in enumerate(STATS)}
            out["worst"] = np.quantile(self.ratios.max(1), q)
        return out

    def p_within(self, target: float = TARGET_RATIO) -> dict[str, float]:
        """Share of draws whose ratio is ``<= target``, per statistic and for every
        statistic at once (``"worst"``): the chance a perfect generator meets it."""
        out = {s: float(np.mean(self.ratios[:, j] <= target)) for j, s in enumerate(STATS)}
        out["worst"] = float(np.mean(self.ratios.max(1) <= target))
        return out

    def rank(self, statistic: str, ratio: float) -> float:
        """Share of draws with a ratio below ``ratio`` for ``statistic`` ("worst": the
        worst of every statistic): near 1, no perfect generator scores that badly."""
        col = self.ratios.max(1) if statistic == "worst" else \
            self.ratios[:, STATS.index(statistic)]
        return float(np.mean(col < ratio))


def null_ratios(runs, *, draws: int = 2000, seed: int = 0) -> NullRatios:
    """The ratios of :func:`realism_table` a generator exactly as good as the simulator
    gets, from ``K >= 3`` simulated runs of the same plans.

    Per plan and per draw, three of the ``K`` runs are picked in random order as the
    "generated" map, run 1 and run 2, and every statistic's ratio
    ``W(generated, run 1) / W(run 2, run 1)`` is computed over the plans. If the runs of
    a plan are exchangeable (independent simulations of it), the draws are the ratio's
    distribution for a perfect generator on these plans: its spread is the benchmark's
    own noise. Both numerator and denominator are distances between two finite samples,
    so the ratio scatters around 1 at any number of plans (issue #15's "every ratio <=
    1.5" is met by about half the draws at 662 plans, session 15).

    Parameters
    ----------
    runs : sequence of K dicts of :func:`stats_of`
        The runs' statistics, plan ``i`` at position ``i`` of each.
    draws : int
    seed : int
        Seed of the relabelling (same seed, same draws).

    Returns
    -------
    NullRatios

    Examples
    --------
    >>> rng = np.random.default_rng(1)
    >>> runs = [{s: rng.normal(0.0, 1.0, 200) for s in STATS} for _ in range(3)]
    >>> null = null_ratios(runs, draws=200)
    >>> null.ratios.shape == (200, len(STATS)), 0.7 < float(np.median(null.ratios)) < 1.4
    (True, True)
    """
    runs = list(runs)
    if len(runs) < 3:
        raise ValueError(f"a null needs >= 3 simulated runs per plan, got {len(runs)}")
    if not isinstance(runs[0], dict):
        raise ValueError("pass stats_of() dicts (the plans are needed for map stacks)")
    k = len(runs)
    vals = {s: np.stack([np.asarray(r[s], float) for r in runs]) for s in STATS}
    n = vals[STATS[0]].shape[1]
    rng = np.random.default_rng(seed)
    cols = np.arange(n)
    out = np.empty((draws, len(STATS)))
    for d in range(draws):
        roles = np.argsort(rng.random((k, n)), axis=0)[:3]  # per plan: 3 runs, in order
        for j, s in enumerate(STATS):
            got = _w_ratio(*(vals[s][roles[i], cols] for i in range(3)))
            out[d, j] = np.nan if got is None else got[2]
    return NullRatios(out, k, n)


def format_null(null: NullRatios, target: float = TARGET_RATIO) -> str:
    """:class:`NullRatios` as a table: quantiles of each ratio and the chance to meet
    ``target``.

    Examples
    --------
    >>> r = np.ones((4, len(STATS))); r[0] = 2.0
    >>> print(format_null(NullRatios(r, 3, 10)).splitlines()[-1])  # doctest: +NORMALIZE_WHITESPACE
    worst 1.00 1.70 1.85 1.97 0.750
    """
    q = null.quantiles()
    p = null.p_within(target)
    out = [f"{'statistic':>{STAT_WIDTH}} {'median':>6} {'90 %':>6} {'95 %':>6} {'99 %':>6} "
           f"{f'P(<={target:g})':>7}"]
    for s in (*STATS, "worst"):
        out.append(f"{s:>{STAT_WIDTH}} " + " ".join(f"{x:>6.2f}" for x in q[s])
                   + f" {p[s]:>7.3f}")
    return "\n".join(out)


@dataclass
class References:
    """Held-out plans of a dataset with two simulated SLAM maps each and the parametric
    model's map on run 2's trajectory.

    Attributes
    ----------
    indices : (N,) int
        Pair indices in the dataset.
    plan_ids : list of str
    a : (N, S, S) uint8
        Preprocessed plans (the dataset's ``A.png``).
    sim1, sim2 : (N, S, S) uint8
        Run 1 (the dataset's ``B.png``) and run 2 (:func:`~map2map.datasets.rerun.
        rerun_pair`), same pixels; run 2 starts where :func:`simulated_references`'s
        ``start`` says.
    parametric : (N, S, S) uint8
        :func:`map2map.parametric.pipeline.deform` (additive) driven along run 2's true
        trajectory, cut and preprocessed as the pair's ``B``.
    meta : list of dict
        Per plan: run 2's coverage, ATE, path length, seed.
    resolution : (N,) float
        Metres per pixel of each square (:func:`~map2map.datasets.pair.window_resolution`
        of the pair's crop window), for the metric drift model of
        :func:`~map2map.learn.ab.synthesize.synthesize_squares`.
    """

    indices: np.ndarray
    plan_ids: list
    a: np.ndarray
    sim1: np.ndarray
    sim2: np.ndarray
    parametric: np.ndarray
    meta: list
    resolution: np.ndarray | None = None

    def only(self, indices) -> References:
        """The same references for those of ``indices`` (pair indices) they hold, in
        their order (e.g. the plans two :func:`simulated_references` calls share)."""
        keep = np.flatnonzero(np.isin(self.indices, np.asarray(indices, int)))
        return References(self.indices[keep], [self.plan_ids[k] for k in keep],
                          self.a[keep], self.sim1[keep], self.sim2[keep],
                          self.parametric[keep], [self.meta[k] for k in keep],
                          None if self.resolution is None else self.resolution[keep])


def split_indices(ds: str | os.PathLike, split: str = "test") -> list[int]:
    """Indices of the simulated pairs of ``split`` in dataset ``ds``, sorted (``"all"``:
    every split, for a dataset whose plans no model was trained on)."""
    from ...datasets.build import open_dataset

    with open_dataset(ds) as man:
        rows = man.rows("done")
    return sorted(int(r["idx"]) for r in rows
                  if split in ("all", r["split"]) and r["kind"] == "simulate")


def _reference(item) -> tuple[int, dict | str]:
    """Run ``run`` of pair ``index`` (``item = (ds, index, run, start)``) as
    :func:`simulated_references` keeps it, or the reason it failed (a worker's task)."""
    from ...core.errors import InputError
    from ...datasets import rerun

    ds, i, run, start = item
    try:
        rr = rerun.rerun_pair(ds, i, run, start=start)
    except InputError as exc:
        return i, exc.problem
    return i, {"sim2": rr.b_n, "parametric": rerun.parametric_on_run(rr),
               "meta": {k: rr.meta.get(k) for k in (
                   "sim_seed", "coverage", "ate_rmse_m", "path_length_m", "stop_reason",
                   "wall_error_m", "plan_id", "start_pose")}}


def simulated_references(ds: str | os.PathLike, *, split: str = "test", n: int | None = None,
                         run: int = 2, cache: str | os.PathLike | None = None,
                         progress: bool = True, start: str = "own",
                         workers: int | None = 1) -> References:
    """Two simulated SLAM maps (and the parametric model's) of the ``split`` plans of
    dataset ``ds`` (see :class:`References`).

    Parameters
    ----------
    ds : path
        A ``map2map dataset build`` folder (read only).
    split : str
        Which plans (``"test"``: never seen in training).
    n : int, optional
        The first ``n`` pairs of the split (by index).
    run : int
        Run number of the second simulation (:func:`~map2map.datasets.pair.rerun_seed`).
    cache : path, optional
        An ``.npz`` kept between calls (written atomically at most every
        :data:`SAVE_EVERY_S` seconds and at the end): plans already there are not
        simulated again. Tied to the dataset's folder, ``run`` and ``start``.
    progress : bool
        tqdm bar over the plans.
    start : {"own", "pair"}
        Where the second run starts (:func:`~map2map.datasets.rerun.rerun_pair`):
        ``"own"`` (default), drawn from its seed as the build drew run 1's, so the
        dataset's run and the re-runs are exchangeable and a generator that draws its
        own start is compared with runs that do; ``"pair"``, at run 1's start pose (the
        protocol until 2026-11-28; compare a generator started there too).
    workers : int, optional
        Worker processes (:func:`map2map.core.parallel.process_map`; None: one per
        core). Each plan is simulated alone from its seeds, so the maps do not depend on
        it.

    Returns
    -------
    References
        Without the plans whose second simulation failed (e.g. a robot that cannot move
        from its start with that seed), with a warning naming them; the failures are
        cached too.
    """
    from ...core._io import atomic_path
    from ...core.errors import InputError
    from ...core.parallel import default_workers, process_map
    from ...datasets.pairfolder import pair_dir, read_pair
    from ...datasets.rerun import STARTS

    if start not in STARTS:
        raise InputError("start", f"must be one of {', '.join(STARTS)}, got {start!r}")
    ds = Path(ds)
    idx = split_indices(ds, split)
    if n is not None:
        idx = idx[:n]
    have: dict[int, dict] = {}
    failed: dict[int, str] = {}
    key = {"dataset": str(ds.resolve()), "run": int(run), "version": 1}
    if start != "pair":         # a cache made before the option started at the pair's
        key["start"] = start
    if cache is not None and Path(cache).is_file():
        with np.load(cache, allow_pickle=False) as z:
            if json.loads(str(z["key"])) == key:
                # each z[name] decompresses the whole array: once per array, not per plan
                # (a view per plan of its own copy kept 2 x N copies alive: 22 GB at 411)
                sim2, par, meta = z["sim2"], z["parametric"], z["meta"]
                for j, i in enumerate(z["indices"]):
                    have[int(i)] = {"sim2": sim2[j], "parametric": par[j],
                                    "meta": json.loads(str(meta[j]))}
                if "failed" in z.files:
                    failed = {int(k): v for k, v in json.loads(str(z["failed"])).items()}

    def save():
        if cache is None or not (have or failed):
            return
        ks = sorted(have)
        with atomic_path(cache) as tmp:
            with open(tmp, "wb") as fh:
                # np.array, not np.stack: a cache of failures only holds no map at all
                np.savez_compressed(
                    fh, key=json.dumps(key), indices=np.array(ks, int),
                    sim2=np.array([have[i]["sim2"] for i in ks], np.uint8),
                    parametric=np.array([have[i]["parametric"] for i in ks], np.uint8),
                    meta=np.array([json.dumps(have[i]["meta"]) for i in ks]),
                    failed=json.dumps({str(k): v for k, v in failed.items()}))

    todo = [i for i in idx if i not in have and i not in failed]
    bar = None
    if progress and todo:
        from tqdm.auto import tqdm

        bar = tqdm(total=len(todo), desc=f"simulating run {run}", unit="plan")
    last = time.monotonic()
    nw = default_workers() if workers is None else max(1, int(workers))
    step = 1 if nw == 1 else 4 * nw       # a few plans a worker between saves
    for c in range(0, len(todo), step):
        chunk = [(str(ds), i, int(run), start) for i in todo[c:c + step]]
        for i, got in process_map(_reference, chunk, workers=nw, min_items=2):
            if isinstance(got, str):
                failed[i] = got
            else:
                have[i] = got
        # the whole cache is rewritten each time: every minute, not every plan
        if time.monotonic() - last > SAVE_EVERY_S or c + step >= len(todo):
            save()
            last = time.monotonic()
        if bar is not None:
            bar.update(len(chunk))
    if bar is not None:
        bar.close()
    gone = [i for i in idx if i in failed]
    if gone:
        import warnings

        warnings.warn(f"{len(gone)} of {len(idx)} plans left out: their run {run} failed ("
                      + "; ".join(f"pair {i}: {failed[i]}" for i in gone[:5])
                      + ("; ..." if len(gone) > 5 else "") + ")", stacklevel=2)
        idx = [i for i in idx if i not in failed]
    if not idx:
        raise InputError(ds, f"no {split!r} plan has a simulated run {run}")
    a, sim1 = (np.stack(m) for m in zip(*(read_pair(pair_dir(ds, i)) for i in idx),
                                          strict=True))
    return References(np.array(idx, int), [have[i]["meta"]["plan_id"] for i in idx], a, sim1,
                      np.stack([have[i]["sim2"] for i in idx]),
                      np.stack([have[i]["parametric"] for i in idx]),
                      [have[i]["meta"] for i in idx],
                      np.array([pair_square_resolution(ds, i, a.shape[-1]) for i in idx]))


def seen_on_square(plan: OccupancyMap, box, size: int, rng: np.random.Generator,
                   params=None) -> np.ndarray | None:
    """Cells an exploration of ``plan`` (at its own resolution) sees, cut and resized as
    :func:`~map2map.datasets.pair.preprocess_pair` cuts a pair with window ``box``
    (``None``: the whole map) to ``size`` px: a square pixel is seen when seen plan cells
    cover at least ``0.5 / f`` of it (the rule that keeps thin walls).

    Parameters
    ----------
    plan : OccupancyMap
        The plan at its own resolution (a pair's ``A.yaml``).
    box : (r0, r1, c0, c1) or None
        The pair's crop window (:func:`~map2map.datasets.pair.crop_box`).
    size : int
        Side of the pair's squares.
    rng : numpy.random.Generator
        Draws the exploration's seed (:func:`~map2map.learn.ab.coverage.explore_rng`).
    params : ExploreParams, optional

    Returns
    -------
    (size, size) bool or None
        ``None`` when the robot cannot explore the plan (no free space, too small).

    Examples
    --------
    >>> from map2map.maps.floorplan import generate_floorplan
    >>> from map2map.learn.ab.coverage import ExploreParams, explore_rng
    >>> plan = generate_floorplan(3, size=(10, 8))
    >>> s = seen_on_square(plan, None, 64, explore_rng(0, 0), ExploreParams(duration=20.0))
    >>> s.shape, s.dtype.name, bool(0.0 < s.mean() < 1.0)
    ((64, 64), 'bool', True)
    """
    from ...core.errors import InputError
    from ...datasets.pair import preprocess_pair
    from ...learn.ab.coverage import explore_plan
    from ...maps.preprocess import preprocess

    try:
        ex = explore_plan(plan, rng, params)
    except InputError:
        return None
    m = plan.copy(data=np.where(ex.seen, OCCUPIED, UNKNOWN).astype(np.uint8))
    sq = preprocess(m, size=int(size), crop=False).data if box is None else \
        preprocess_pair(m, m, int(size), 0, box)[0]
    return sq == OCCUPIED


def native_seen(ds: str | os.PathLike, indices, size: int, *, seed: int = 0,
                params=None, progress: bool = True) -> np.ndarray:
    """Cells seen by an exploration of each pair's plan at its own resolution, on the
    pair's ``size`` px square: ``seen=`` of
    :func:`~map2map.learn.ab.synthesize.synthesize_squares`.

    :func:`~map2map.learn.ab.synthesize.synthesize` explores the plan it is given at the
    plan's resolution; exploring a dataset's preprocessed square instead (0.04-0.12 m a
    pixel, walls thickened by the build) blocks doors the dataset's 0.05 m robot passes.
    Pair ``indices[j]``'s plan (``A.yaml``) is explored with
    :func:`~map2map.learn.ab.coverage.explore_rng` ``(seed, j)`` (the stream
    ``synthesize_squares`` gives square ``j``) and its seen cells are put on the pair's
    square by :func:`seen_on_square` with the pair's window.

    Parameters
    ----------
    ds : path
        A ``map2map dataset build`` folder.
    indices : sequence of int
        Pair indices (:attr:`References.indices`).
    size : int
        Side of the pair's squares.
    seed : int
    params : ExploreParams, optional
    progress : bool

    Returns
    -------
    (N, size, size) bool
        A plan the robot cannot explore is all seen (nothing hidden), with a warning.
    """
    import warnings

    from ...datasets.pair import crop_box
    from ...datasets.pairfolder import PLAN_YAML, SLAM_YAML, pair_dir
    from ...learn.ab.coverage import explore_rng
    from ...maps.formats import load_map

    out = np.ones((len(indices), int(size), int(size)), bool)
    it = enumerate(indices)
    if progress:
        from tqdm.auto import tqdm

        it = tqdm(it, total=len(indices), desc="exploring plans", unit="plan")
    for j, i in it:
        folder = pair_dir(ds, int(i))
        a, b = load_map(folder / PLAN_YAML), load_map(folder / SLAM_YAML)
        sq = seen_on_square(a, crop_box(a, b), size, explore_rng(seed, j), params)
        if sq is None:
            warnings.warn(f"pair {i}: the robot cannot explore its plan; nothing hidden",
                          stacklevel=2)
            continue
        out[j] = sq
    return out


def pair_square_resolution(ds: str | os.PathLike, index: int, size: int) -> float:
    """Metres per pixel of pair ``index``'s ``size`` px squares (``A.png``, ``B.png``): its
    crop window (the union of the plan's and run 1's content, as the build and
    :func:`~map2map.datasets.rerun.rerun_pair` cut it) over ``size``."""
    from ...datasets.pair import crop_box, window_resolution
    from ...datasets.pairfolder import PLAN_YAML, SLAM_YAML, pair_dir
    from ...maps.formats import load_map

    folder = pair_dir(ds, index)
    a, b = load_map(folder / PLAN_YAML), load_map(folder / SLAM_YAML)
    return window_resolution(a, crop_box(a, b), size)
