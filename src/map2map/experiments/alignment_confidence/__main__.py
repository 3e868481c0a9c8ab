"""Fit and check ``p_correct``: held-out reliability, the "doubtful" threshold, warning rates.

Usage::

    python3 -m map2map.experiments.alignment_confidence [--collect] [--cache FILE]
        [--data ../shared/data] [--plans 3] [--jobs 2] [--figure reliability.png]

Reads the labelled alignments cached by :mod:`.collect` (runs them first when the
cache is absent or with ``--collect``: about 2 min on 2 cores), then

1. refits the logistic model of :func:`map2map.evaluate.confidence.p_correct` on the
   features of :func:`~map2map.evaluate.confidence.alignment_features` with held-out
   folds grouped so that no plan or sensor map is in both a fold's training and test
   set (synthetic plans in 4 folds by plan; the Halmstad pairs and wrong-building pairs
   by the sensor map's building, E5 and HIH: every E5 sensor map is predicted by a
   model that saw none of them);
2. prints the held-out reliability (predicted vs observed share right, in bins) and
   the Brier score, and writes the reliability figure;
3. chooses the "doubtful" threshold on the held-out probabilities: the lowest that
   warns every wrong alignment if it warns at most 10% of the right ones, else the
   highest that warns at most 10% of the right ones (the figures of both are printed);
4. prints, per data set, the share of right alignments warned and of wrong ones
   warned, held out and with the library's stored coefficients (fit on all), and the
   coefficients to store in :mod:`map2map.evaluate.confidence`.

scikit-learn is needed here only (the library computes the probability with numpy).
"""

from __future__ import annotations

import argparse
import json
import sys
import time
from pathlib import Path

import numpy as np

from map2map.evaluate.confidence import (
    COEFFICIENTS,
    FEATURES,
    INTERCEPT,
    ConfidenceParams,
    alignment_features,
    alignment_warnings,
    p_correct,
)
from map2map.experiments._data import shared_data

CACHE = Path("/tmp/map2map_alignment_confidence.json")
MAX_FALSE_ALARMS = 0.10
C = 1.0
#: HouseExpo render 06a0e96d is one rectangular room: turned 180 deg it is the same
#: picture, so which of the two placements the alignment picks is a coin flip
SYMMETRIC_PLANS = ("06a0e96d",)


def subset(r: dict) -> str:
    """The data set a row is reported in: sweep, symmetric, halmstad, wrong_building."""
    if r["dataset"] != "sweep":
        return r["dataset"]
    if r["name"].startswith("symmetric") or (
        r.get("group") in SYMMETRIC_PLANS and "different" not in r.get("case", "")
    ):
        return "symmetric"
    return "sweep"


def sensor_building(r: dict) -> str:
    a, b = r["name"].split("->")
    return (a if "layout" not in a else b).split("_")[0]


def folds(rows: list[dict]) -> np.ndarray:
    """Fold of every row: synthetic plans round-robin in 4 folds, E5 = 4, HIH = 5."""
    plans = sorted({r["group"] for r in rows if r["dataset"] == "sweep"})
    out = []
    for r in rows:
        if r["dataset"] == "sweep":
            out.append(plans.index(r["group"]) % 4)
        else:
            out.append(4 if sensor_building(r) == "E5" else 5)
    return np.array(out)


def fit(X: np.ndarray, y: np.ndarray):
    from sklearn.linear_model import LogisticRegression  # experiments only, lazily

    return LogisticRegression(C=C, max_iter=5000).fit(X, y)


def held_out(X: np.ndarray, y: np.ndarray, fold: np.ndarray) -> np.ndarray:
    p = np.zeros(len(y))
    for f in np.unique(fold):
        m = fit(X[fold != f], y[fold != f])
        p[fold == f] = m.predict_proba(X[fold == f])[:, 1]
    return p


def reliability(p: np.ndarray, y: np.ndarray, bins: int = 10) -> list[tuple]:
    """(lo, hi, n, mean predicted, share right) per probability bin."""
    edges = np.linspace(0, 1, bins + 1)
    idx = np.clip(np.digitize(p, edges) - 1, 0, bins - 1)
    return [
        (edges[b], edges[b + 1], int((idx == b).sum()), float(p[idx == b].mean()),
         float(y[idx == b].mean()))
        for b in range(bins) if (idx == b).any()
    ]  # fmt: skip


def choose_threshold(p, y, amb, sub) -> tuple[float, float, str]:
    """(threshold, threshold that warns every wrong one, why).

    An alignment is warned when ``p < threshold`` or ``amb`` (its runner-up fits as
    well). False alarms are counted per data set ``sub`` (at most 10% of the right
    alignments of each), leaving out the symmetric plans: right there by a coin flip,
    they are warned by design.
    """
    grid = np.round(np.arange(0.01, 1.01, 0.01), 2)
    sets = [s for s in np.unique(sub) if s != "symmetric" and (y & (sub == s)).any()]

    def worst_false_alarms(t):
        w = (p < t) | amb
        return max(w[y & (sub == s)].mean() for s in sets)

    every = float(min(t for t in grid if ((p[~y] < t) | amb[~y]).all()))
    if worst_false_alarms(every) <= MAX_FALSE_ALARMS:
        return every, every, "warns every wrong alignment and at most 10% of the right ones"
    # the highest threshold warning at most 10% of the right ones of each data set
    ok = [t for t in grid if worst_false_alarms(t) <= MAX_FALSE_ALARMS]
    t = float(max(ok)) if ok else 0.0
    return t, every, (
        "no threshold does both: the highest warning at most 10% of the right alignments of "
        "each data set"
    )


def rates(rows, warned, y) -> list[str]:
    out = [f"  {'data set':<15s} {'right':>5s} {'warned':>7s} {'wrong':>6s} {'warned':>7s}"]
    sub = np.array([subset(r) for r in rows])
    for s in ("sweep", "symmetric", "halmstad", "wrong_building", "all"):
        m = np.ones(len(y), bool) if s == "all" else sub == s
        nr, nw = int((m & y).sum()), int((m & ~y).sum())
        wr, ww = int((m & y & warned).sum()), int((m & ~y & warned).sum())
        fr = f"{wr:3d} ({100 * wr / nr:3.0f}%)" if nr else "      -"
        fw = f"{ww:3d} ({100 * ww / nw:3.0f}%)" if nw else "      -"
        out.append(f"  {s:<15s} {nr:5d} {fr:>10s} {nw:4d} {fw:>10s}")
    return out


def figure(path: Path, p: np.ndarray, y: np.ndarray, rows: list[dict], t: float) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, (a, b) = plt.subplots(1, 2, figsize=(10, 4.2))
    rel = reliability(p, y)
    a.plot([0, 1], [0, 1], color="0.6", lw=1, ls="--", label="perfect calibration")
    a.plot([r[3] for r in rel], [r[4] for r in rel], "o-", color="C0", label="held out")
    for r in rel:
        a.annotate(str(r[2]), (r[3], r[4]), textcoords="offset points", xytext=(4, -10),
                   fontsize=7)  # fmt: skip
    a.set(xlabel="predicted p_correct (bin mean)", ylabel="share of alignments right",
          title="Reliability (held-out folds; n per bin)", xlim=(0, 1), ylim=(0, 1.02))  # fmt: skip
    a.legend(loc="upper left", fontsize=8)
    sub = np.array([subset(r) for r in rows])
    bins = np.linspace(0, 1, 21)
    for s, c in (("sweep", "C0"), ("symmetric", "C4"), ("halmstad", "C2"),
                 ("wrong_building", "C3")):  # fmt: skip
        for right in (True, False):
            m = (sub == s) & (y == right)
            if m.any():
                b.hist(p[m], bins=bins, histtype="step", color=c, lw=1.5,
                       ls="-" if right else ":",
                       label=f"{s} {'right' if right else 'wrong'} ({m.sum()})")  # fmt: skip
    b.set_yscale("log")
    b.axvline(t, color="k", lw=1)
    b.text(t, 0.7, f" doubtful < {t:.2f}", fontsize=8, va="bottom")
    b.set(xlabel="held-out p_correct", ylabel="alignments (log scale)",
          title="Held-out p_correct by data set", ylim=(0.7, 300))  # fmt: skip
    b.legend(fontsize=7, loc="upper left", ncol=2)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(
        prog="python3 -m map2map.experiments.alignment_confidence",
        description=__doc__.splitlines()[0],
    )
    ap.add_argument("--data", default=str(shared_data()),
                    help="real-data folder (default: $MAP2MAP_SHARED_DATA or ../shared/data)")
    ap.add_argument("--cache", default=str(CACHE), help=f"labelled alignments (default {CACHE})")
    ap.add_argument("--collect", action="store_true", help="rerun the alignments into the cache")
    ap.add_argument("--plans", type=int, default=3, help="synthetic plans of each kind (3)")
    ap.add_argument("--jobs", type=int, default=2, help="processes for --collect (2)")
    ap.add_argument("--figure", default="alignment_confidence_reliability.png",
                    help="reliability figure (PNG)")
    args = ap.parse_args(argv)
    cache = Path(args.cache)
    if args.collect or not cache.is_file():
        from .collect import collect

        rows = collect(Path(args.data), args.plans, args.jobs)
        cache.write_text(json.dumps(rows))
    rows = [r for r in json.loads(cache.read_text()) if "error" not in r]
    t0 = time.perf_counter()
    X = np.array([alignment_features(r["quality"]) for r in rows])
    y = np.array([bool(r["right"]) for r in rows])
    fold = folds(rows)
    p = held_out(X, y, fold)
    print(f"{len(rows)} labelled alignments ({y.sum()} right, {(~y).sum()} wrong) from {cache}")
    for s in ("sweep", "symmetric", "halmstad", "wrong_building"):
        m = np.array([subset(r) == s for r in rows])
        print(f"  {s:<15s} {m.sum():4d}: {int((m & y).sum())} right, {int((m & ~y).sum())} wrong")
    brier = float(((p - y) ** 2).mean())
    base = float(((y.mean() - y) ** 2).mean())
    print(f"\nheld-out reliability (6 folds: 4 of synthetic plans, E5, HIH); Brier {brier:.3f} "
          f"(a constant {y.mean():.2f} scores {base:.3f})")  # fmt: skip
    print(f"  {'p bin':<10s} {'n':>4s} {'mean p':>7s} {'right':>6s}")
    for lo, hi, n, mp, obs in reliability(p, y):
        print(f"  {lo:.1f}-{hi:.1f}    {n:4d} {mp:7.2f} {obs:6.2f}")
    amb = ConfidenceParams().ambiguity
    r_up = np.array([r["quality"].get("runner_up_ratio") or 0.0 for r in rows])
    sub = np.array([subset(r) for r in rows])
    t, every, why = choose_threshold(p, y, r_up >= amb, sub)
    w_every = (p < every) | (r_up >= amb)
    print(f"\nthreshold {t:.2f} ({why}); warning every wrong one needs < {every:.2f}, which "
          "warns, of the right alignments held out, "
          + ", ".join(f"{s} {100 * w_every[y & (sub == s)].mean():.0f}%"
                      for s in ("sweep", "symmetric", "halmstad")))  # fmt: skip
    warned = (p < t) | (r_up >= amb)
    print(f"\nwarning rates held out (doubtful when p_correct < {t:.2f} or the runner-up fits "
          f"{amb} as well or better):")  # fmt: skip
    print("\n".join(rates(rows, warned, y)))
    print(f"  (p_correct alone: {int((y & (p < t)).sum())}/{y.sum()} right and "
          f"{int((~y & (p < t)).sum())}/{(~y).sum()} wrong warned)")  # fmt: skip
    missed = sorted((float(p[i]), rows[i]["name"]) for i in np.flatnonzero(~y & ~warned))
    if missed:
        print("  wrong alignments not warned (held-out p): "
              + "; ".join(f"{n} {v:.2f}" for v, n in missed[::-1]))  # fmt: skip
    final = fit(X, y)
    coef = [round(float(c), 4) for c in final.coef_[0]]
    icpt = round(float(final.intercept_[0]), 4)
    print(f"\nfit on all {len(rows)}: COEFFICIENTS = {tuple(coef)}  INTERCEPT = {icpt}"
          f"  (features {', '.join(FEATURES)})")  # fmt: skip
    lib_t = ConfidenceParams().doubtful_below
    q_lib = [{**r["quality"], "p_correct": None} for r in rows]
    p_lib = np.array([p_correct(q) for q in q_lib])
    doubt = np.array([any(w.startswith("doubtful") for w in alignment_warnings(q)) for q in q_lib])
    same = np.allclose(COEFFICIENTS, coef, atol=1e-3) and abs(INTERCEPT - icpt) < 1e-3
    print(f"library: COEFFICIENTS = {COEFFICIENTS}  INTERCEPT = {INTERCEPT}  doubtful below "
          f"{lib_t}" + ("" if same else "  (differ from this fit: store the new ones)"))
    print("warning rates of the library (alignment_warnings with the stored coefficients, "
          "fit on all: in-sample), doubtful:")  # fmt: skip
    print("\n".join(rates(rows, doubt, y)))
    # any alignment warning: doubtful, scale mismatch, and the search's own (the scale the
    # resolutions give fits far worse, no hypothesis passed), as cached
    search = ("the maps fit far better", "no alignment hypothesis passed")
    anyw = np.array([bool(alignment_warnings(q)) or any(w.startswith(search) for w in r["warnings"])
                     for q, r in zip(q_lib, rows, strict=True)])  # fmt: skip
    print("any alignment warning (doubtful, scale mismatch, the search's own):")
    print("\n".join(rates(rows, anyw, y)))
    brier_lib = float(((p_lib - y) ** 2).mean())
    print(f"  in-sample Brier {brier_lib:.3f}")
    missed = [f"{r['name']} {v:.2f}" for r, v, d in zip(rows, p_lib, doubt, strict=True)
              if not r["right"] and not d]  # fmt: skip
    if missed:
        print("  wrong alignments not warned (library p): " + "; ".join(missed))
    if args.figure:
        figure(Path(args.figure), p, y, rows, t)
        print(f"\nreliability figure: {args.figure}")
    print(f"fit and checks: {time.perf_counter() - t0:.1f} s")
    return 0


if __name__ == "__main__":
    sys.exit(main())
