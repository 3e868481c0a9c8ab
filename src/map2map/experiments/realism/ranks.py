"""Realism judged per plan: is the generated map the odd one out among simulated runs of
its own plan? (issue #33, replacing issue #15's pooled Wasserstein ratio)

For every held-out plan there are ``K`` simulated SLAM maps (the dataset's pair, run 1,
and re-runs with other seeds, :func:`map2map.datasets.rerun.rerun_pair`) and one
generated map. For each statistic of :func:`map2map.experiments.realism.measure.map_stats`
the generated map's value is ranked among the ``K + 1`` values of its plan (rank 1 the
lowest, ``K + 1`` the highest; ties broken at random with a seed, so that equal values
favour no end). If the generator is as good as the simulator, the ``K + 1`` maps of a
plan are exchangeable and the rank is uniform on ``1 .. K + 1`` whatever the plan, the
statistic or the number of plans: that is what calibrates this test at any size (the
pooled ratio's noise shrank with the plan count, issue #33 "Why").

Per statistic, over the plans:

* ``extreme``  share of plans where the generated map is rank 1 or ``K + 1``; a perfect
  generator's expectation is ``2 / (K + 1)`` (0.5 with three runs);
* ``low - high``  ``P(rank 1) - P(rank K + 1)``: a generator that is extreme at one end
  (too many fragments, too little free space) and not the other; expectation 0;
* ``p extreme``  two-sided binomial test of the extreme count against ``2 / (K + 1)``;
* ``p ends``  two-sided sign test of the rank-1 count against the rank-``K+1`` count;
* ``p uniform``  chi-square test of all ``K + 1`` rank counts against uniform;
* ``Holm``  ``p uniform`` adjusted for testing every statistic of the table at once
  (Holm's step-down, :func:`holm`): a statistic tells the generator from the simulator at
  level ``alpha`` when its Holm value is below ``alpha``.

A plan is left out of a statistic where any of its ``K + 1`` values is NaN (a map with no
wall has no wall error).

Issue #33's target, per statistic: ``extreme <= 0.55`` and ``|low - high| <= 0.05`` on
>= 600 plans. :func:`perfect_chance` draws how often a perfect generator meets it: at 600
plans a single statistic's ``low - high`` has a standard error of about 0.029, so each
statistic misses the 0.05 band about 8 % of the time by chance alone, and a dozen
statistics all meet it only about a third of the time. The p-values (with the number of
statistics tested in mind) are the calibrated reading; the thresholds are printed as the
issue wrote them. The verdict's second line is that calibrated reading: the statistics
whose Holm-adjusted ``p uniform`` is below 0.05, which a perfect generator shows on any
statistic at all at most 5 % of the time, at any plan count (on the seed-20261201 set the
two checks of the test, three exchangeable runs, flag none of 12, where the fixed
thresholds fail 1 and 5).

Examples
--------
>>> rng = np.random.default_rng(0)
>>> runs = [{"x": rng.normal(0, 1, 400)} for _ in range(3)]
>>> fair = {"x": rng.normal(0, 1, 400)}
>>> row = rank_table(plan_ranks(fair, runs, stats=("x",)), 3)[0]
>>> abs(row.extreme - 0.5) < 0.08, row.p_extreme > 0.01
(True, True)
>>> shifted = {"x": rng.normal(2, 1, 400)}
>>> row = rank_table(plan_ranks(shifted, runs, stats=("x",)), 3)[0]
>>> row.extreme > 0.6, row.high > row.low
(True, True)
"""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass

import numpy as np
from scipy import stats as sps

from .measure import STATS

__all__ = ["EXTREME_MAX", "EXTREME_MARGIN", "ENDS_MAX", "ALPHA", "extreme_max", "plan_ranks",
           "RankRow", "rank_table", "holm", "format_rank_table", "perfect_chance",
           "shuffled_runs"]

#: Issue #33: the share of plans where the generated map is the most extreme, at most
#: (three simulated runs a plan).
EXTREME_MAX = 0.55
#: The same as a margin over a perfect generator's ``2 / (K + 1)``, for any ``K``.
EXTREME_MARGIN = 0.05
#: Issue #33: ``|P(rank 1) - P(rank K + 1)|`` at most.
ENDS_MAX = 0.05
#: Family-wise level of the calibrated verdict (Holm over the table's statistics).
ALPHA = 0.05


def holm(p) -> np.ndarray:
    """Holm's step-down adjustment of the p-values ``p`` (NaN stays NaN, left out of the
    family): reject ``H_i`` at family-wise level ``alpha`` where the result is below it.

    Examples
    --------
    >>> holm([0.01, 0.04, 0.03, float("nan")]).round(3).tolist()
    [0.03, 0.06, 0.06, nan]
    """
    p = np.asarray(p, float)
    out = np.full(p.shape, np.nan)
    ok = np.flatnonzero(np.isfinite(p))
    m = len(ok)
    if m == 0:
        return out
    order = ok[np.argsort(p[ok], kind="stable")]
    adj = np.maximum.accumulate(p[order] * (m - np.arange(m)))
    out[order] = np.minimum(adj, 1.0)
    return out


def extreme_max(k: int) -> float:
    """Issue #33's bound on the extreme share with ``k`` simulated runs a plan (0.55 at
    ``k = 3``)."""
    return 2 / (k + 1) + EXTREME_MARGIN


def plan_ranks(generated: dict, runs: list[dict], *, stats=STATS, seed: int = 0
               ) -> dict[str, np.ndarray]:
    """Rank of the generated map's statistic among its plan's simulated runs.

    Parameters
    ----------
    generated : dict
        ``{statistic: (N,) values}`` of the generated maps (e.g.
        :func:`~map2map.experiments.realism.measure.stats_of`), plan ``i`` at ``i``.
    runs : list of K dicts
        The same for each of ``K >= 1`` simulated runs of the same plans.
    stats : sequence of str
        Statistics to rank.
    seed : int
        Seed of the tie-breaking (same seed, same ranks).

    Returns
    -------
    dict
        ``{statistic: (N,) int}``: 1 .. K + 1, or 0 where a value of that plan is NaN.

    Examples
    --------
    >>> plan_ranks({"x": np.array([0.0, 5.0, 2.0, np.nan])},
    ...            [{"x": np.array([1.0, 1.0, 1.0, 1.0])},
    ...             {"x": np.array([3.0, 3.0, 3.0, 3.0])}], stats=("x",))["x"]
    array([1, 3, 2, 0])
    """
    rng = np.random.default_rng(seed)
    out = {}
    for s in stats:
        g = np.asarray(generated[s], float)
        r = np.stack([np.asarray(x[s], float) for x in runs])         # (K, N)
        ok = np.isfinite(g) & np.isfinite(r).all(0)
        tie = rng.random((r.shape[0] + 1, len(g)))  # equal values: a random order
        below = (r < g) | ((r == g) & (tie[1:] < tie[0]))            # runs ranked below g
        out[s] = np.where(ok, 1 + below.sum(0), 0).astype(int)
    return out


@dataclass
class RankRow:
    """One statistic's per-plan ranks summarised (module doc)."""

    statistic: str
    plans: int
    k: int
    low: float
    high: float
    extreme: float
    p_extreme: float
    p_ends: float
    p_uniform: float
    met: bool | None
    holm: float = math.nan

    @property
    def ends(self) -> float:
        """``P(rank 1) - P(rank K + 1)``."""
        return self.low - self.high

    def as_dict(self) -> dict:
        return {**asdict(self), "ends": self.ends}


def rank_table(ranks: dict[str, np.ndarray], k: int) -> list[RankRow]:
    """:class:`RankRow` per statistic of :func:`plan_ranks` with ``k`` simulated runs.

    Examples
    --------
    >>> r = rank_table({"x": np.array([1, 1, 4, 2, 3, 0])}, 3)[0]
    >>> r.plans, r.low, r.high, r.extreme
    (5, 0.4, 0.2, 0.6)
    """
    rows = []
    for s, rk in ranks.items():
        rk = np.asarray(rk)
        rk = rk[rk > 0]
        n = len(rk)
        if n == 0:
            rows.append(RankRow(s, 0, k, *(math.nan,) * 6, None))
            continue
        counts = np.bincount(rk, minlength=k + 2)[1:k + 2]
        n1, nk = int(counts[0]), int(counts[-1])
        ext = n1 + nk
        p_ext = float(sps.binomtest(ext, n, 2 / (k + 1)).pvalue)
        p_ends = float(sps.binomtest(n1, ext, 0.5).pvalue) if ext else 1.0
        p_uni = float(sps.chisquare(counts).pvalue) if n >= 5 * (k + 1) else math.nan
        low, high, extreme = n1 / n, nk / n, ext / n
        met = bool(extreme <= extreme_max(k) + 1e-12 and abs(low - high) <= ENDS_MAX + 1e-12)
        rows.append(RankRow(s, n, k, low, high, extreme, p_ext, p_ends, p_uni, met))
    for r, h in zip(rows, holm([r.p_uniform for r in rows]), strict=True):
        r.holm = float(h)
    return rows


def _p(x: float) -> str:
    if not math.isfinite(x):
        return "-"
    return f"{x:.3f}" if x >= 0.001 else f"{x:.0e}"


def format_rank_table(rows: list[RankRow], name: str = "generated") -> str:
    """The rank table as text: one line per statistic and a verdict line.

    Examples
    --------
    >>> rows = rank_table({"x": np.array([1, 2, 3, 4] * 50)}, 3)
    >>> print(format_rank_table(rows, "perfect"))  # doctest: +NORMALIZE_WHITESPACE
    perfect: rank among 3 simulated runs of its plan, 200 plans
       statistic  P(low) P(high) extreme low-high p extreme  p ends p uniform    Holm
               x   0.250   0.250   0.500    0.000     1.000   1.000     1.000   1.000
    issue #33 (extreme <= 0.55, |low-high| <= 0.05): met on 1 of 1 statistics
    calibrated (Holm over 1 statistics, family-wise 0.05): told apart on 0 of 1
    """
    valid = [r for r in rows if r.met is not None]
    n = max((r.plans for r in valid), default=0)
    k = valid[0].k if valid else 0
    out = [f"{name}: rank among {k} simulated runs of its plan, {n} plans",
           f"{'statistic':>14} {'P(low)':>7} {'P(high)':>7} {'extreme':>7} {'low-high':>8} "
           f"{'p extreme':>9} {'p ends':>7} {'p uniform':>9} {'Holm':>7}"]
    for r in rows:
        if r.met is None:
            out.append(f"{r.statistic:>14}   (no plan with every value)")
            continue
        flag = "" if r.met else "  *"
        out.append(f"{r.statistic:>14} {r.low:>7.3f} {r.high:>7.3f} {r.extreme:>7.3f} "
                   f"{r.ends:>8.3f} {_p(r.p_extreme):>9} {_p(r.p_ends):>7} "
                   f"{_p(r.p_uniform):>9} {_p(r.holm):>7}{flag}")
    good = sum(r.met for r in valid)
    out.append(f"issue #33 (extreme <= {extreme_max(k):.2f}, |low-high| <= {ENDS_MAX:g}): "
               f"met on {good} of {len(valid)} statistics"
               + (" (* not met)" if good < len(valid) else ""))
    tested = [r for r in valid if math.isfinite(r.holm)]
    apart = [r.statistic for r in tested if r.holm < ALPHA]
    out.append(f"calibrated (Holm over {len(tested)} statistics, family-wise {ALPHA:g}): "
               f"told apart on {len(apart)} of {len(tested)}"
               + (f": {', '.join(apart)}" if apart else ""))
    return "\n".join(out)


def perfect_chance(plans: int, k: int = 3, stats: int = len(STATS), *, draws: int = 20000,
                   seed: int = 0) -> tuple[float, float]:
    """How often a perfect generator meets issue #33's thresholds at ``plans`` plans.

    Ranks uniform on ``1 .. k + 1``, statistics independent (the real ones are
    correlated, so the all-statistics chance is a lower bound of sorts).

    Returns
    -------
    (float, float)
        The chance for one statistic and for all ``stats`` statistics at once.

    Examples
    --------
    >>> one, every = perfect_chance(600, 3, 12, draws=4000)
    >>> 0.85 < one < 0.95, every < 0.5
    (True, True)
    """
    rng = np.random.default_rng(seed)
    c = rng.multinomial(plans, [1 / (k + 1)] * (k + 1), size=draws)
    low, high = c[:, 0] / plans, c[:, -1] / plans
    ok = (low + high <= extreme_max(k) + 1e-12) & (np.abs(low - high) <= ENDS_MAX + 1e-12)
    one = float(ok.mean())
    return one, one ** stats


def shuffled_runs(runs: list[dict], *, seed: int = 0) -> tuple[dict, list[dict]]:
    """A perfect generator from ``K + 1 >= 2`` simulated runs: per plan, one run picked at
    random plays the generated map and the others the runs (for checking the test).

    Examples
    --------
    >>> runs = [{"x": np.arange(4.0) + 10 * j} for j in range(3)]
    >>> g, rest = shuffled_runs(runs, seed=1)
    >>> len(rest), sorted(float(v) for v in np.r_[g["x"][:1], [r["x"][0] for r in rest]])
    (2, [0.0, 10.0, 20.0])
    """
    keys = list(runs[0])
    vals = {s: np.stack([np.asarray(r[s], float) for r in runs]) for s in keys}
    n = vals[keys[0]].shape[1]
    order = np.argsort(np.random.default_rng(seed).random((len(runs), n)), axis=0)
    cols = np.arange(n)
    pick = [{s: vals[s][order[j], cols] for s in keys} for j in range(len(runs))]
    return pick[0], pick[1:]
