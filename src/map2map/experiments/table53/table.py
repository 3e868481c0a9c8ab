"""Table 5.3 with one row per model (issue #32): the SLAM maps themselves, then each
corrector measured on the same held-out maps; the rule that counts a map as improved,
the sign tests, the printed table, the CSV files and the figures.

A map is **improved** (:func:`improved`) when Error(gen) < Error(sim) -
:data:`IMPROVED_MARGIN_PX` *and* the output's wall recall is not lower than the input's:
a difference below the margin is noise of the metric's alignment, and an output that
scores a lower error by dropping walls is not better. Both variants of the appendix
metric are reported: **matched** (the points over 0.3 m from any plan wall and corners
left out, ``mean_px`` of :func:`map2map.evaluate.pipeline.evaluate_maps`) and **every
point** (Algorithm 1 as the appendix writes it, ``mean_all_px``).

Examples
--------
>>> improved([1.0, 1.0, 1.0, 1.0], [0.90, 0.97, 0.90, np.nan],
...          [0.5, 0.5, 0.5, 0.5], [0.5, 0.5, 0.4, 0.5]).tolist()
[True, False, False, False]
>>> sign_test([0.2, 0.1, 0.0, -0.1, np.nan])      # 2 better, 1 worse, 1 tie left out
{'better': 2, 'worse': 1, 'ties': 1, 'p': 0.5}
"""

from __future__ import annotations

import csv
import os
import re
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

__all__ = ["IMPROVED_MARGIN_PX", "GUARDS", "improved", "sign_test", "ModelRows", "Table53"]

#: How much lower (px) Error(gen) must be than Error(sim) for a map to count as improved
#: (``--margin``): about the metric's run-to-run scatter on one map.
IMPROVED_MARGIN_PX = 0.05
#: Wall-level guards reported for the SLAM map and the outputs (medians in the summary).
GUARDS = ("wall_recall", "boundary_f1", "chamfer_px", "iou_occupied", "iou_free",
          "iou_unknown")


def improved(error_sim, error_gen, recall_sim, recall_gen,
             margin: float = IMPROVED_MARGIN_PX) -> np.ndarray:
    """Per map: ``error_gen < error_sim - margin`` and ``recall_gen >= recall_sim``
    (False where an error is NaN: the alignment failed). Any of the arguments may be
    arrays of one length."""
    es, eg = np.asarray(error_sim, float), np.asarray(error_gen, float)
    rs, rg = np.asarray(recall_sim, float), np.asarray(recall_gen, float)
    with np.errstate(invalid="ignore"):
        return (eg < es - margin) & (rg >= rs)


def sign_test(gain) -> dict:
    """One-sided sign test that ``gain`` (e.g. Error(sim) - Error(gen) per map: positive
    is better) is positive more often than not: ``better`` / ``worse`` counts, ``ties``
    (exactly 0, left out, as NaN) and ``p`` (:func:`scipy.stats.binomtest`,
    ``alternative="greater"``; NaN when no map differs)."""
    from scipy.stats import binomtest

    g = np.asarray(gain, float)
    g = g[np.isfinite(g)]
    better, worse = int((g > 0).sum()), int((g < 0).sum())
    p = binomtest(better, better + worse, 0.5, alternative="greater").pvalue \
        if better + worse else float("nan")
    return {"better": better, "worse": worse, "ties": int((g == 0).sum()), "p": float(p)}


def _slug(name: str) -> str:
    """A file-name part for a model's name (a path gives its file or folder name)."""
    base = Path(name).stem if ("/" in name or os.sep in name) else name
    return re.sub(r"[^A-Za-z0-9_.-]+", "_", base).strip("_") or "model"


def _nanmedian(v) -> float:
    v = np.asarray(v, float)
    return float(np.nanmedian(v)) if np.isfinite(v).any() else float("nan")


@dataclass
class ModelRows:
    """One model on the held-out maps.

    Attributes
    ----------
    name, source : str
        What the table calls it (``none``, ``thesis``, a path) and its weights file (or
        what stands in for one).
    rows : list of dict
        Per map: ``map`` (1-based), ``plan_id``, ``error_sim``, ``error_gen``, ``diff``
        (matched points), ``error_sim_all``, ``error_gen_all``, ``diff_all`` (every
        point), ``improved`` / ``improved_all`` (:func:`improved` on each variant),
        ``sim_<guard>`` / ``gen_<guard>`` for every guard (plus wall precision).
    summary : dict
        ``n`` (evaluated), ``failed`` (alignment failed), ``improved``,
        ``share_improved``, ``improved_all``, ``share_improved_all``,
        ``improved_any`` (Error(gen) < Error(sim) by any amount, the rule before
        issue #32), ``improved_but_lost_recall``, ``sign_test_p`` (against the input,
        matched points), ``median_error_gen``, ``median_error_gen_all``,
        ``median_gen_<guard>``, ``maps_per_s``.
    outputs : ndarray (N, H, W) uint8
        The corrected maps.
    """

    name: str
    source: str
    rows: list[dict]
    summary: dict
    outputs: np.ndarray


@dataclass
class Table53:
    """Table 5.3 on a held-out set, one row per model (module docstring).

    Attributes
    ----------
    models : list of ModelRows
        The models in the order given; the last is the newest (its sign tests are in
        :attr:`tests`).
    summary : dict
        The SLAM maps themselves: ``n``, ``median_error_sim``, ``median_error_sim_all``,
        ``median_sim_<guard>``, ``seed``, ``margin_px``.
    tests : dict
        The newest model's one-sided sign tests (:func:`sign_test`; ties left out):
        ``vs_input`` / ``vs_input_all`` (matched points / every point), and when a
        ``none`` row precedes it ``vs_none`` / ``vs_none_all`` and ``beats_none`` /
        ``share_beats_none`` (maps where its Error(gen) is lower than ``none``'s by more
        than the margin, matched points).
    inputs, plans : ndarray (N, H, W) uint8
        SLAM maps, plans.
    source : str
        Which held-out pairs.
    """

    models: list[ModelRows]
    summary: dict
    tests: dict
    inputs: np.ndarray
    plans: np.ndarray
    source: str = ""
    digest: str = field(default="", repr=False)

    def model(self, name: str) -> ModelRows:
        """The row of the model called ``name``."""
        for m in self.models:
            if m.name == name:
                return m
        raise KeyError(f"no model {name!r} in this table ({[m.name for m in self.models]})")

    @property
    def newest(self) -> ModelRows:
        return self.models[-1]

    def format(self, per_map: bool = True) -> str:
        """The table as text: per map (with ``per_map``) the matched Error(sim) and each
        model's Error(gen); one row per model; the newest model's sign tests."""
        s, margin = self.summary, self.summary["margin_px"]
        names = [m.name for m in self.models]
        short = [n if len(n) <= 14 else _slug(n)[:14] for n in names]
        lines = [f"Table 5.3 on {s['n']} held-out maps ({self.source}); improved = "
                 f"Error(gen) < Error(sim) - {margin:g} px and wall recall not lower"]
        if per_map and self.models:
            lines.append("per map, Error px (matched points):")
            lines.append(f"{'map':>4} {'input':>8} " + " ".join(f"{n:>14}" for n in short))
            for i, r in enumerate(self.models[0].rows):
                lines.append(f"{r['map']:>4} {r['error_sim']:>8.3f} " + " ".join(
                    f"{m.rows[i]['error_gen']:>14.3f}" for m in self.models))
        head = (f"{'model':<14} {'improved':>14} {'improved all':>14} {'Error px':>8} "
                f"{'Error all':>9} {'recall':>6} {'F1':>5} {'Chamfer':>7} {'p vs input':>10}")
        lines += ["", "improved: matched points / every point (Algorithm 1 as written); "
                      "Error: median", head, "-" * len(head)]
        lines.append(f"{'input':<14} {'-':>14} {'-':>14} {s['median_error_sim']:>8.3f} "
                     f"{s['median_error_sim_all']:>9.3f} {s['median_sim_wall_recall']:>6.2f} "
                     f"{s['median_sim_boundary_f1']:>5.2f} {s['median_sim_chamfer_px']:>7.2f} "
                     f"{'-':>10}")
        for m, n in zip(self.models, short, strict=True):
            q = m.summary
            lines.append(
                f"{n:<14} {_count(q['improved'], q['n']):>14} "
                f"{_count(q['improved_all'], q['n_all']):>14} {q['median_error_gen']:>8.3f} "
                f"{q['median_error_gen_all']:>9.3f} {q['median_gen_wall_recall']:>6.2f} "
                f"{q['median_gen_boundary_f1']:>5.2f} {q['median_gen_chamfer_px']:>7.2f} "
                f"{q['sign_test_p']:>10.2g}")
        lines.append("")
        for m in self.models:
            q = m.summary
            lines.append(f"{m.name}: {m.source}; alignment failed on {q['failed']}; "
                         f"better by any amount {q['improved_any']}/{q['n']}; better by > "
                         f"{margin:g} px but lost wall recall {q['improved_but_lost_recall']}"
                         + (f"; {q['maps_per_s']:.1f} maps/s (CPU, batched)"
                            if np.isfinite(q.get("maps_per_s", np.nan)) else ""))
        t = self.tests
        if t:
            lines.append(f"newest model ({self.newest.name}), one-sided sign tests, ties left "
                         "out:")
            pairs = [("vs input", t["vs_input"], t["vs_input_all"])]
            vs = t.get("vs") or ({"none": {"matched": t["vs_none"], "all": t["vs_none_all"]}}
                                 if "vs_none" in t else {})
            pairs += [(f"vs {k}", v["matched"], v["all"]) for k, v in vs.items()]
            for what, a, b in pairs:
                lines.append(f"  {what:<9} matched: better {a['better']}, worse "
                             f"{a['worse']}, ties {a['ties']}, p = {a['p']:.3g}; every "
                             f"point: better {b['better']}, worse {b['worse']}, ties "
                             f"{b['ties']}, p = {b['p']:.3g}")
            for k, v in (t.get("vs") or {}).items():
                lines.append(f"  beats {k} by > {margin:g} px (matched) on {v['beats']}"
                             f"/{v['n']} maps = {v['share_beats']:.1%}")
            if "beats_none" in t and not t.get("vs"):
                lines.append(f"  beats none by > {margin:g} px (matched) on {t['beats_none']}"
                             f"/{t['n_vs_none']} maps = {t['share_beats_none']:.1%}")
        return "\n".join(lines)

    def summary_rows(self) -> list[dict]:
        """One dict per row of the printed table (input first)."""
        s = self.summary
        out = [{"model": "input", "source": self.source, "n": s["n"],
                "median_error_px": s["median_error_sim"],
                "median_error_all_px": s["median_error_sim_all"],
                **{f"median_{k}": s[f"median_sim_{k}"] for k in GUARDS}}]
        for m in self.models:
            q = m.summary
            out.append({"model": m.name, "source": m.source, "n": q["n"],
                        "median_error_px": q["median_error_gen"],
                        "median_error_all_px": q["median_error_gen_all"],
                        **{f"median_{k}": q[f"median_gen_{k}"] for k in GUARDS},
                        "improved": q["improved"], "share_improved": q["share_improved"],
                        "improved_all": q["improved_all"],
                        "share_improved_all": q["share_improved_all"],
                        "improved_any": q["improved_any"],
                        "improved_but_lost_recall": q["improved_but_lost_recall"],
                        "sign_test_p": q["sign_test_p"], "failed": q["failed"],
                        "maps_per_s": q["maps_per_s"]})
        return out

    def to_csv(self, out: str | os.PathLike) -> list[Path]:
        """Write ``out/table53.csv`` (one row per model, input first) and
        ``out/table53_<model>.csv`` (per map, one file per model), atomically; returns
        the paths."""
        out = Path(out)
        out.mkdir(parents=True, exist_ok=True)
        paths = [_write_csv(out / "table53.csv", self.summary_rows())]
        seen: set[str] = set()
        for m in self.models:
            slug = _slug(m.name)
            while slug in seen:
                slug += "_"
            seen.add(slug)
            paths.append(_write_csv(out / f"table53_{slug}.csv", m.rows))
        return paths

    def figure(self, path: str | os.PathLike | None = None):
        """Fig. 5.12 per model: box plots of Error(sim) - Error(gen) (px), matched points
        (left) and every point (right); saved to ``path`` when given."""
        from ...core.viz import plt

        fig, axes = plt.subplots(1, 2, figsize=(3 + 1.3 * len(self.models), 4.5),
                                 sharey=True, squeeze=False)
        for ax, key, what in ((axes[0, 0], "diff", "matched points"),
                              (axes[0, 1], "diff_all", "every point")):
            data = []
            for m in self.models:
                d = np.array([r[key] for r in m.rows], float)
                data.append(d[np.isfinite(d)] if np.isfinite(d).any() else [np.nan])
            ax.boxplot(data)
            ax.set_xticks(range(1, len(self.models) + 1),
                          [_slug(m.name) for m in self.models], fontsize=8)
            ax.axhline(0, color="grey", lw=0.8)
            ax.set_title(what, fontsize=9)
        axes[0, 0].set_ylabel("Error(sim) - Error(gen) [px]")
        fig.suptitle("Fig. 5.12 per model: above 0 the model lowered the error", fontsize=9)
        fig.tight_layout()
        if path is not None:
            from ...core.viz import save_figure

            save_figure(fig, path, dpi=100)
        return fig

    def examples_figure(self, path: str | os.PathLike | None = None, k: int = 3):
        """The newest model's ``k`` worst and ``k`` best maps (matched Error(sim) -
        Error(gen)): input | every model | plan, side by side."""
        from ...core.viz import plt

        d = np.array([r["diff"] for r in self.newest.rows], float) if self.models \
            else np.zeros(0)
        ok = np.isfinite(d)
        worst = [int(i) for i in np.argsort(np.where(ok, d, np.inf))[:k] if ok[i]]
        best = [int(i) for i in np.argsort(np.where(ok, -d, np.inf))[:k] if ok[i]]
        picks = worst + [i for i in best if i not in worst]
        cols = [("input (SLAM map)", self.inputs)] + \
            [(m.name if len(m.name) <= 20 else _slug(m.name), m.outputs) for m in self.models] \
            + [("plan", self.plans)]
        fig, axes = plt.subplots(max(1, len(picks)), len(cols),
                                 figsize=(2.5 * len(cols), 2.5 * max(1, len(picks))),
                                 squeeze=False)
        for row, i in enumerate(picks):
            for col, (name, imgs) in enumerate(cols):
                ax = axes[row, col]
                ax.imshow(imgs[i], cmap="gray", vmin=0, vmax=255, interpolation="nearest")
                ax.set_xticks([])
                ax.set_yticks([])
                if 0 < col < len(cols) - 1:
                    e = self.models[col - 1].rows[i]["error_gen"]
                    ax.set_xlabel(f"{e:.2f} px", fontsize=8)
                elif col == 0:
                    ax.set_xlabel(f"{self.newest.rows[i]['error_sim']:.2f} px", fontsize=8)
                    ax.set_ylabel(f"map {i + 1}: {d[i]:+.2f} px", fontsize=8)
                if row == 0:
                    ax.set_title(name, fontsize=9)
        fig.suptitle(f"{self.newest.name if self.models else ''}: worst (top) and best "
                     "(bottom) Error(sim) - Error(gen); Error (matched) under each map",
                     fontsize=9)
        fig.tight_layout()
        if path is not None:
            from ...core.viz import save_figure

            save_figure(fig, path, dpi=90)
        return fig


def _count(k: int, n: int) -> str:
    return f"{k}/{n} {k / n:.0%}" if n else "-"


def _write_csv(path: Path, rows: list[dict]) -> Path:
    from ...core._io import atomic_path

    with atomic_path(path) as tmp, open(tmp, "w", newline="") as fh:
        keys = list(dict.fromkeys(k for r in rows for k in r)) or ["map"]
        w = csv.DictWriter(fh, fieldnames=keys, restval="")
        w.writeheader()
        w.writerows(rows)
    return path
