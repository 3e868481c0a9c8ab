"""Thesis Table 5.3 / Fig. 5.12 as a library: does Model_BA bring SLAM maps closer to
their plans?

On held-out pairs (plans never seen in training), for every pair (plan A, SLAM map B):
``Error(sim)`` = the appendix-paper metric (:func:`map2map.evaluate.pipeline.evaluate_maps`,
the chosen chain's mean local error in px) of B against A, ``Error(gen)`` = the same, with
the same settings, of ``autocorrect(B)`` against A. ``diff = Error(sim) - Error(gen)``:
positive is improved (in the thesis's Table 5.3 15 of 20 values are positive and it
reports "75 % improved", although its text calls the negative ones the improvements).

The summary gives the share improved with its one-sided sign-test p-value
(:func:`scipy.stats.binomtest`, ties and failed alignments left out) and the guards
against an output that scores a low error by dropping walls
(:func:`map2map.evaluate.wallmetrics.wall_metrics` of B and of the output against A: wall
recall, boundary F1 at 2 px, Chamfer distance, per-class IoU); an improvement that loses
wall recall is counted apart (``improved_but_lost_recall``).

Held-out pairs come from a dataset built by ``map2map dataset build``
(:func:`heldout_pairs_from_dataset`: a split of its plans, never trained on; a running
build is read without writing to it) or from generated plans
(:func:`generated_heldout_pairs`, the parametric model of :mod:`map2map.learn.training.synthetic`).
``map2map.experiments.table53`` is the command line.

Examples
--------
>>> import numpy as np
>>> from map2map.datasets.packed import PackedPairs
>>> plan = np.full((1, 64, 64), 127, np.uint8)
>>> plan[0, 8:56, 8:56] = 255; plan[0, 8:11, 8:56] = 0; plan[0, 53:56, 8:56] = 0
>>> plan[0, 8:56, 8:11] = 0; plan[0, 8:56, 53:56] = 0; plan[0, 8:56, 30:33] = 0
>>> pairs = PackedPairs(plan, plan.copy(), ["p"], ["test"])
>>> t = run_table53(pairs, _IdentityModel(), progress=False)   # output = input
>>> t.summary["n"], t.summary["improved"], round(t.rows[0]["diff"], 6)
(1, 0, 0.0)
"""

from __future__ import annotations

import csv
import hashlib
import os
import sqlite3
import time
import warnings
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from ...core.errors import InputError
from ...core.grid import OccupancyMap
from ...datasets.packed import PackedPairs

__all__ = ["Table53", "run_table53", "heldout_pairs_from_dataset", "generated_heldout_pairs",
           "merge_pairs", "HELD_OUT_SEED", "GUARDS", "ac_options"]

#: Generated plans 100000.. are never used by ``benchmarks/train_ba.sh``.
HELD_OUT_SEED = 100_000
#: Wall-level guards reported for the SLAM map and the output (medians in the summary).
GUARDS = ("wall_recall", "boundary_f1", "chamfer_px", "iou_occupied", "iou_free",
          "iou_unknown")


def _digest(pairs: PackedPairs) -> str:
    h = hashlib.sha256()
    h.update(np.ascontiguousarray(pairs.a).tobytes())
    h.update(np.ascontiguousarray(pairs.b).tobytes())
    return h.hexdigest()[:16]


def merge_pairs(*sources: PackedPairs) -> PackedPairs:
    """Concatenate held-out sets, keeping the first pair of each plan id (two builds
    with the same generator and seed share their first plans).

    Examples
    --------
    >>> a = np.zeros((2, 4, 4), np.uint8)
    >>> p = PackedPairs(a, a, ["x", "y"], ["test", "test"])
    >>> q = PackedPairs(a, a, ["y", "z"], ["test", "val"])
    >>> merge_pairs(p, q).plan_id.tolist()
    ['x', 'y', 'z']
    """
    seen: set[str] = set()
    keep_a, keep_b, ids, splits, metas = [], [], [], [], []
    for s in sources:
        metas.append(s.meta)
        for i, pid in enumerate(s.plan_id):
            if pid in seen:
                continue
            seen.add(pid)
            keep_a.append(s.a[i])
            keep_b.append(s.b[i])
            ids.append(pid)
            splits.append(s.split[i])
    if not ids:
        shape = sources[0].a.shape[1:] if sources else (0, 0)
        return PackedPairs(np.zeros((0, *shape), np.uint8), np.zeros((0, *shape), np.uint8),
                           [], [], {"sources": metas})
    return PackedPairs(np.stack(keep_a), np.stack(keep_b), ids, splits, {"sources": metas})


def heldout_pairs_from_dataset(ds: str | os.PathLike, split: str | tuple[str, ...] = "test",
                               n: int | None = None, *, keep: tuple[str, ...] = ("complete",),
                               cleaner: str | os.PathLike | None = None) -> PackedPairs:
    """Held-out pairs of a dataset: the pairs of ``split`` (plans never trained on; a plan
    is in one split only).

    Parameters
    ----------
    ds : path-like
        A dataset folder built by ``map2map dataset build`` (its manifest is opened
        read-only, so a build still running is read as it stands, without writing to
        it), or a packed ``.npz`` (or a folder holding only ``packed.npz``: its pairs
        were selected at export).
    split : str or tuple of str
        ``"test"`` (default), ``"val"``, or several, e.g. ``("test", "val")``.
    n : int, optional
        At most this many pairs (in index order).
    keep : tuple of str
        Cleaner decisions kept when reading a dataset folder (default: ``complete``
        only, what ``dataset export`` packs); ``()`` keeps every finished pair.
    cleaner : path-like, optional
        A saved cleaner (``DS/cleaner.skops`` of another dataset) applied, in memory only,
        to the pairs of a dataset that has not been cleaned yet.

    Returns
    -------
    PackedPairs
        ``a`` plans, ``b`` SLAM maps, plan ids and splits; ``meta["heldout"]`` says what
        was read.

    Examples
    --------
    >>> import tempfile
    >>> from map2map.datasets.packed import save_packed
    >>> z = np.zeros((3, 4, 4), np.uint8)
    >>> path = Path(tempfile.mkdtemp()) / "p.npz"
    >>> _ = save_packed(path, PackedPairs(z, z, ["a", "b", "c"], ["train", "test", "val"]))
    >>> heldout_pairs_from_dataset(path, ("test", "val")).plan_id.tolist()
    ['b', 'c']
    """
    splits = (split,) if isinstance(split, str) else tuple(split)
    p = Path(ds)
    if (p / "manifest.sqlite").is_file():
        out = _from_manifest(p, splits, keep, cleaner)
    else:
        from ...learn.training.data import load_pairs

        allp = load_pairs(p)
        sel = np.flatnonzero(np.isin(allp.split, splits))
        out = PackedPairs(allp.a[sel], allp.b[sel], allp.plan_id[sel], allp.split[sel],
                          {"heldout": {"source": str(p), "splits": list(splits),
                                       "selection": "as packed"}})
    if n is not None:
        out = PackedPairs(out.a[:n], out.b[:n], out.plan_id[:n], out.split[:n], out.meta)
    return out


def _from_manifest(ds: Path, splits, keep, cleaner) -> PackedPairs:
    from ...datasets.pairfolder import pair_dir, read_pair

    try:
        db = sqlite3.connect(f"file:{ds / 'manifest.sqlite'}?mode=ro", uri=True, timeout=30)
        db.row_factory = sqlite3.Row
        rows = db.execute(
            "SELECT idx, plan_id, split, clean FROM pairs WHERE status = 'done' AND split IN "
            f"({','.join('?' * len(splits))}) ORDER BY idx", splits).fetchall()
        db.close()
    except sqlite3.DatabaseError as exc:
        raise InputError(ds / "manifest.sqlite", f"not a readable manifest ({exc})") from None
    rows = [dict(r) for r in rows]
    how = "every finished pair"
    if keep and rows:
        if all(r["clean"] is None for r in rows):
            if cleaner is None:
                raise InputError(ds, "the dataset has not been cleaned: give a cleaner "
                                     "(another dataset's cleaner.skops) or keep=()")
            from ...datasets.clean import _p_complete, dataset_features, decide, load_cleaner

            prob = _p_complete(load_cleaner(cleaner), dataset_features(ds, rows))
            for r, q in zip(rows, prob, strict=True):
                r["clean"] = decide(float(q))
            how = f"cleaner {cleaner} applied in memory: {', '.join(keep)}"
        else:
            how = f"cleaned: {', '.join(keep)}"
        rows = [r for r in rows if r["clean"] in keep]
    maps = [read_pair(pair_dir(ds, r["idx"])) for r in rows]
    meta = {"heldout": {"source": str(ds), "splits": list(splits), "selection": how,
                        "indices": [int(r["idx"]) for r in rows]}}
    if not rows:
        return PackedPairs(np.zeros((0, 0, 0), np.uint8), np.zeros((0, 0, 0), np.uint8),
                           [], [], meta)
    return PackedPairs(np.stack([a for a, _ in maps]), np.stack([b for _, b in maps]),
                       [r["plan_id"] for r in rows],
                       [r["split"] for r in rows], meta)


def generated_heldout_pairs(n: int = 100, *, seed: int = HELD_OUT_SEED, size: int = 256,
                            cache: str | os.PathLike | None = None) -> PackedPairs:
    """``n`` generated held-out pairs (plans seeded ``seed..seed+n-1``, SLAM maps from the
    parametric model: :func:`map2map.learn.training.synthetic.make_pairs`), cached in ``cache``
    (a ``.npz``) so that several models are compared on the same maps."""
    from ...datasets.packed import load_packed, save_packed
    from ...learn.training.synthetic import make_pairs

    if cache is not None and Path(cache).is_file():
        return load_packed(cache)
    pairs = make_pairs(n, size, seed=seed)
    pairs.meta.setdefault("heldout", {"source": f"generated pairs, seeds {seed}.."
                                                f"{seed + n - 1}"})
    if cache is not None:
        save_packed(cache, pairs)
    return pairs


@dataclass
class Table53:
    """Table 5.3 on a held-out set (see the module docstring).

    Attributes
    ----------
    rows : list of dict
        Per map: ``map`` (1-based), ``plan_id``, ``error_sim``, ``error_gen``, ``diff``,
        and ``sim_<guard>`` / ``gen_<guard>`` for every guard of :data:`GUARDS` (plus wall
        precision).
    summary : dict
        ``n`` (evaluated), ``failed`` (alignment failed), ``improved``, ``worse``,
        ``share_improved``, ``sign_test_p``, ``median_error_sim``, ``median_error_gen``,
        ``improved_but_lost_recall``, ``median_sim_<guard>``/``median_gen_<guard>``,
        ``maps_per_s`` (end-to-end inference).
    inputs, outputs, plans : ndarray (N, H, W) uint8
        SLAM maps, auto-corrected maps, plans.
    model, source : str
        Which model and which held-out pairs.
    """

    rows: list[dict]
    summary: dict
    inputs: np.ndarray
    outputs: np.ndarray
    plans: np.ndarray
    model: str = ""
    source: str = ""
    digest: str = field(default="", repr=False)

    def format(self) -> str:
        """The table and its summary as text."""
        s = self.summary
        lines = [f"Table 5.3 on {len(self.rows)} held-out maps ({self.source}); "
                 f"model {self.model}",
                 f"{'map':>4} {'Error(sim)':>10} {'Error(gen)':>10} {'sim-gen':>8} "
                 f"{'recall s/g':>11} {'F1 s/g':>11}"]
        for r in self.rows:
            lines.append(f"{r['map']:>4} {r['error_sim']:>10.3f} {r['error_gen']:>10.3f} "
                         f"{r['diff']:>8.3f} {r['sim_wall_recall']:>5.2f}/"
                         f"{r['gen_wall_recall']:<5.2f} {r['sim_boundary_f1']:>5.2f}/"
                         f"{r['gen_boundary_f1']:<5.2f}")
        lines += [
            f"evaluated: {s['n']} (alignment failed: {s['failed']})",
            f"improved (Error(sim) - Error(gen) > 0): {s['improved']}/{s['n']} = "
            f"{s['share_improved']:.1%} (thesis: 15/20 = 75%; target >= 95%); "
            f"sign test p = {s['sign_test_p']:.3g}",
            f"improved but lost wall recall: {s['improved_but_lost_recall']}",
            f"median Error(sim) {s['median_error_sim']:.3f} px, "
            f"Error(gen) {s['median_error_gen']:.3f} px",
        ]
        for k in GUARDS:
            lines.append(f"median {k:<13} SLAM {s[f'median_sim_{k}']:7.3f}  "
                         f"auto-corrected {s[f'median_gen_{k}']:7.3f}")
        if s.get("maps_per_s"):
            lines.append(f"inference: {s['maps_per_s']:.1f} maps/s, batched, network + "
                         "post-processing (one cold pass, CPU)")
        return "\n".join(lines)

    def to_csv(self, path: str | os.PathLike) -> Path:
        """Write :attr:`rows` as CSV (atomically)."""
        from ...core._io import atomic_path

        path = Path(path)
        with atomic_path(path) as tmp, open(tmp, "w", newline="") as fh:
            w = csv.DictWriter(fh, fieldnames=list(self.rows[0]) if self.rows else ["map"])
            w.writeheader()
            w.writerows(self.rows)
        return path

    def _diff(self) -> np.ndarray:
        return np.array([r["diff"] for r in self.rows], float)

    def figure(self, path: str | os.PathLike | None = None):
        """Fig. 5.12: box plot of ``Error(sim) - Error(gen)`` (px); saved to ``path`` when
        given. Returns the matplotlib figure."""
        from ...core.viz import plt
        d = self._diff()
        ok = np.isfinite(d)
        fig, ax = plt.subplots(figsize=(4, 5))
        ax.boxplot(d[ok])
        ax.axhline(0, color="grey", lw=0.8)
        ax.set(ylabel="Error(sim) - Error(gen) [px]",
               title=f"Fig. 5.12: {self.summary['improved']}/{self.summary['n']} improved")
        fig.tight_layout()
        if path is not None:
            from ...core.viz import save_figure

            save_figure(fig, path, dpi=100)
        return fig

    def examples_figure(self, path: str | os.PathLike | None = None, k: int = 3):
        """The ``k`` worst and ``k`` best maps: SLAM map | auto-corrected | plan."""
        from ...core.viz import plt
        d = self._diff()
        ok = np.isfinite(d)
        worst = [int(i) for i in np.argsort(np.where(ok, d, np.inf))[:k] if ok[i]]
        best = [int(i) for i in np.argsort(np.where(ok, -d, np.inf))[:k] if ok[i]]
        picks = worst + [i for i in best if i not in worst]
        fig, axes = plt.subplots(max(1, len(picks)), 3, figsize=(7.5, 2.5 * max(1, len(picks))),
                                 squeeze=False)
        for row, i in enumerate(picks):
            for col, (img, name) in enumerate(((self.inputs[i], "SLAM map"),
                                               (self.outputs[i], "auto-corrected"),
                                               (self.plans[i], "plan"))):
                ax = axes[row, col]
                ax.imshow(img, cmap="gray", vmin=0, vmax=255, interpolation="nearest")
                ax.set_xticks([])
                ax.set_yticks([])
                if col == 0:
                    ax.set_ylabel(f"map {i + 1}: {d[i]:+.2f} px", fontsize=8)
                if row == 0:
                    ax.set_title(name, fontsize=9)
        fig.suptitle("worst (top) and best (bottom) Error(sim) - Error(gen)", fontsize=9)
        fig.tight_layout()
        if path is not None:
            from ...core.viz import save_figure

            save_figure(fig, path, dpi=90)
        return fig


def _error(src: np.ndarray, plan: np.ndarray, seed: int) -> float:
    from ...evaluate.pipeline import EvaluateParams, evaluate_maps

    try:
        ev = evaluate_maps(OccupancyMap(src, 0.05), OccupancyMap(plan, 0.05),
                           params=EvaluateParams(seed=seed))
        return float(ev.report["chosen_errors"]["mean_px"])
    except Exception:  # the alignment fails on some maps (the thesis's Map 6)
        return float("nan")


class _IdentityModel:
    """Stand-in "model" for tests and the example: returns its input maps."""

    source = "identity (output = input)"

    def correct(self, maps: list[np.ndarray]) -> list[np.ndarray]:
        return [m.copy() for m in maps]


def run_table53(pairs: PackedPairs, model="pretrained", *, seed: int = 0,
                progress: bool = True, baseline: Table53 | None = None,
                straighten: bool = True, anchor: bool = True,
                autocorrect_kw: dict | None = None) -> Table53:
    """Table 5.3 of ``model`` on held-out ``pairs`` (module docstring).

    Parameters
    ----------
    pairs : PackedPairs
        Held-out pairs (``a`` plans, ``b`` SLAM maps), from
        :func:`heldout_pairs_from_dataset` or :func:`generated_heldout_pairs`.
    model : "pretrained", run folder, weights file, BAModel, or a corrector
        The Model_BA to measure (:func:`map2map.learn.ba.autocorrect.load_model`); or any
        object with ``correct(list of uint8 maps) -> list of maps`` and a ``source``
        string (a baseline or an ablation measured the same way).
    seed : int
        Seed of the metric's point subsampling (``EvaluateParams.seed``), the same for
        both maps of a pair.
    progress : bool
        tqdm progress bar over the maps.
    baseline : Table53, optional
        A previous table on the same pairs with the same seed: its ``Error(sim)`` and SLAM
        guards are reused instead of recomputed (they do not depend on the model).
    straighten, anchor : bool
        Passed to :func:`~map2map.learn.ba.autocorrect.autocorrect_many`.
    autocorrect_kw : dict, optional
        More keyword arguments of it (``thickness``, ``open_frontiers``, ...).

    Returns
    -------
    Table53
    """
    from scipy.stats import binomtest
    from tqdm import tqdm

    from ...evaluate.wallmetrics import wall_metrics

    a, b = pairs.a, pairs.b
    digest = _digest(pairs)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        if hasattr(model, "correct"):
            t0 = time.perf_counter()
            gen = np.stack(model.correct(list(b))) if len(b) else b.copy()
            name = model.source
        else:
            from ...learn.ba.autocorrect import autocorrect_many
            from ...learn.ba.model import load_model

            net = load_model(model)
            name = net.source
            t0 = time.perf_counter()
            res = autocorrect_many([OccupancyMap(x, 0.05) for x in b], net,
                                   straighten=straighten, anchor=anchor,
                                   **(autocorrect_kw or {}))
            gen = np.stack([r.map.data for r in res]) if res else b.copy()
        dt = time.perf_counter() - t0
    reuse = baseline is not None and baseline.digest == digest \
        and baseline.summary.get("seed") == seed
    rows = []
    for i in tqdm(range(len(a)), desc="Table 5.3", disable=not progress):
        if reuse:
            old = baseline.rows[i]
            e_sim = old["error_sim"]
            ws = {k[4:]: v for k, v in old.items() if k.startswith("sim_")}
        else:
            e_sim = _error(b[i], a[i], seed)
            ws = wall_metrics(b[i], a[i])
        e_gen = _error(gen[i], a[i], seed)
        wg = wall_metrics(gen[i], a[i])
        rows.append({"map": i + 1, "plan_id": str(pairs.plan_id[i]), "error_sim": e_sim,
                     "error_gen": e_gen, "diff": e_sim - e_gen,
                     **{f"sim_{k}": v for k, v in ws.items()},
                     **{f"gen_{k}": v for k, v in wg.items()}})
    diff = np.array([r["diff"] for r in rows], float)
    ok = np.isfinite(diff)
    improved, worse = int((diff[ok] > 0).sum()), int((diff[ok] < 0).sum())
    p = binomtest(improved, improved + worse, 0.5, alternative="greater").pvalue \
        if improved + worse else float("nan")
    lost = sum(1 for r in rows if np.isfinite(r["diff"]) and r["diff"] > 0
               and r["gen_wall_recall"] < r["sim_wall_recall"])
    n = int(ok.sum())
    summary = {
        "n": n, "failed": int((~ok).sum()), "improved": improved, "worse": worse,
        "share_improved": improved / n if n else float("nan"), "sign_test_p": float(p),
        "median_error_sim": _nanmedian([r["error_sim"] for r in rows]),
        "median_error_gen": _nanmedian([r["error_gen"] for r in rows]),
        "improved_but_lost_recall": lost, "seed": seed,
        "maps_per_s": len(b) / dt if dt > 0 and len(b) else float("nan"),
    }
    for k in GUARDS:
        summary[f"median_sim_{k}"] = _nanmedian([r[f"sim_{k}"] for r in rows])
        summary[f"median_gen_{k}"] = _nanmedian([r[f"gen_{k}"] for r in rows])
    source = pairs.meta.get("heldout", {}).get("source", "") if pairs.meta else ""
    if not hasattr(model, "correct") and not anchor:
        name += " (anchor off)"
    return Table53(rows, summary, b, gen, a, name, str(source), digest)


def _nanmedian(v) -> float:
    v = np.asarray(v, float)
    return float(np.nanmedian(v)) if np.isfinite(v).any() else float("nan")


def ac_options(items: list[str]) -> dict:
    """``KEY=VALUE`` strings -> keyword arguments of ``autocorrect_many`` (true/false,
    numbers, else strings): the scripts' ``--ac`` option.

    Examples
    --------
    >>> ac_options(["anchor=false", "thickness=3", "large=tile"])
    {'anchor': False, 'thickness': 3.0, 'large': 'tile'}
    """
    out = {}
    for item in items:
        k, _, v = item.partition("=")
        low = v.strip().lower()
        if low in ("true", "false"):
            out[k.strip()] = low == "true"
            continue
        try:
            out[k.strip()] = float(v)
        except ValueError:
            out[k.strip()] = v.strip()
    return out
