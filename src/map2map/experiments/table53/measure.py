"""Thesis Table 5.3 / Fig. 5.12 as a library: do the correctors of ``map2map
autocorrect`` bring SLAM maps closer to their plans, and does the network add anything
to the classical cleaning? (issue #32)

On held-out pairs (plans never seen in training), for every pair (plan A, SLAM map B):
``Error(sim)`` = the appendix-paper metric (:func:`map2map.evaluate.pipeline.evaluate_maps`,
the chosen chain's mean local error in px) of B against A, ``Error(gen)`` = the same, with
the same settings, of each model's output against A, on both variants of the metric
(matched points; every point, Algorithm 1 as written). ``diff = Error(sim) -
Error(gen)``: positive is lower (in the thesis's Table 5.3 15 of 20 values are positive
and it reports "75 % improved", although its text calls the negative ones the
improvements).

One row per model (:class:`~map2map.experiments.table53.table.Table53`): the SLAM map
itself, then ``none`` (the classical cleaning alone, no network), ``thesis`` (Model_BA
with the shipped weights) and any further model; each with the maps improved
(:func:`~map2map.experiments.table53.table.improved`: lower by more than
:data:`IMPROVED_MARGIN_PX` and wall recall not lower), the median errors and the guards
against an output that scores a low error by dropping walls
(:func:`map2map.evaluate.wallmetrics.wall_metrics` of B and of the output against A: wall
recall, boundary F1 at 2 px, Chamfer distance, per-class IoU). The newest model (the
last) gets one-sided sign tests (:func:`scipy.stats.binomtest`, ties and failed
alignments left out) against the input and against ``none``.

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
>>> t = run_table53(pairs, [_IdentityModel()], progress=False)   # output = input
>>> s = t.model("identity").summary
>>> s["n"], s["improved"], round(t.models[0].rows[0]["diff"], 6)
(1, 0, 0.0)
"""

from __future__ import annotations

import hashlib
import os
import sqlite3
import time
import warnings
from pathlib import Path

import numpy as np

from ...core.errors import InputError
from ...core.grid import OccupancyMap
from ...datasets.packed import PackedPairs
from .table import GUARDS, IMPROVED_MARGIN_PX, ModelRows, Table53, improved, sign_test

__all__ = ["Table53", "ModelRows", "run_table53", "heldout_pairs_from_dataset",
           "generated_heldout_pairs", "merge_pairs", "HELD_OUT_SEED", "GUARDS",
           "IMPROVED_MARGIN_PX", "DEFAULT_MODELS", "improved", "sign_test", "ac_options"]

#: Generated plans 100000.. are never used by ``benchmarks/train_ba.sh``.
HELD_OUT_SEED = 100_000
#: The rows measured when no model is named: the classical cleaning alone, then the
#: thesis's Model_BA (``map2map autocorrect --model``'s names).
DEFAULT_MODELS = ("thesis", "none")


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


def _errors(src: np.ndarray, plan: np.ndarray, seed: int) -> tuple[float, float]:
    """The appendix metric of ``src`` against ``plan`` (px, chosen chain): the mean over
    the matched points and over every point (Algorithm 1 as written); NaN, NaN where the
    alignment fails (the thesis's Map 6)."""
    from ...evaluate.pipeline import EvaluateParams, evaluate_maps

    try:
        ev = evaluate_maps(OccupancyMap(src, 0.05), OccupancyMap(plan, 0.05),
                           params=EvaluateParams(seed=seed))
        e = ev.report["chosen_errors"]
        return float(e["mean_px"]), float(e["mean_all_px"])
    except Exception:  # the alignment fails on some maps
        return float("nan"), float("nan")


class _IdentityModel:
    """Stand-in "model" for tests and the example: returns its input maps."""

    name = "identity"
    source = "identity (output = input)"

    def correct(self, maps: list[np.ndarray]) -> list[np.ndarray]:
        return [m.copy() for m in maps]


def _correct(model, b: np.ndarray, options: dict) -> np.ndarray:
    """The outputs of ``model`` on the SLAM maps ``b`` (N, H, W): a corrector's
    ``correct_many`` on 0.05 m maps, or a stand-in's ``correct`` on the arrays."""
    if not len(b):
        return b.copy()
    if hasattr(model, "correct_many"):
        outs = model.correct_many([OccupancyMap(x, 0.05) for x in b], **options)
        return np.stack([o.data for o in outs])
    return np.stack(model.correct(list(b)))


def run_table53(pairs: PackedPairs, models=DEFAULT_MODELS, *, seed: int = 0,
                progress: bool = True, margin: float = IMPROVED_MARGIN_PX,
                straighten: bool = True, anchor: bool = True,
                autocorrect_kw: dict | None = None) -> Table53:
    """Table 5.3 of each of ``models`` on held-out ``pairs``, one row per model beside
    the SLAM maps themselves (module docstring, :mod:`~map2map.experiments.table53.table`).

    Parameters
    ----------
    pairs : PackedPairs
        Held-out pairs (``a`` plans, ``b`` SLAM maps), from
        :func:`heldout_pairs_from_dataset` or :func:`generated_heldout_pairs`.
    models : sequence, or one model
        Each a name of ``map2map autocorrect --model`` (``"none"``, ``"thesis"``;
        ``"pretrained"`` is ``"thesis"``; :data:`map2map.jobs.autocorrect.MODELS`), a
        Model_BA weights file or run folder, a
        :class:`~map2map.jobs.autocorrect.Corrector`, or a stand-in with
        ``correct(list of uint8 maps) -> list of maps``, ``name`` and ``source``. The
        last is the newest model: its sign tests go in ``Table53.tests``. Default
        :data:`DEFAULT_MODELS`.
    seed : int
        Seed of the metric's point subsampling (``EvaluateParams.seed``), the same for
        every map of a pair.
    progress : bool
        tqdm progress bar over the maps.
    margin : float
        Error(gen) must be this much lower than Error(sim) for a map to count as
        improved (:data:`IMPROVED_MARGIN_PX`; :func:`~.table.improved`).
    straighten, anchor : bool
        Passed to every model but ``none`` (which is the anchored, straightened
        post-processing alone); ``anchor=False`` adds " (anchor off)" to their names.
    autocorrect_kw : dict, optional
        More keyword arguments of
        :func:`~map2map.learn.ba.autocorrect.autocorrect_many` (``thickness``,
        ``open_frontiers``, ...), for every model.

    Returns
    -------
    Table53
    """
    from tqdm import tqdm

    from ...evaluate.wallmetrics import wall_metrics
    from ...jobs.autocorrect import corrector

    if isinstance(models, str | os.PathLike) or not isinstance(models, list | tuple):
        models = [models]
    a, b = pairs.a, pairs.b
    base = dict(autocorrect_kw or {})
    if not straighten:
        base["straighten"] = False
    if not anchor:
        base["anchor"] = False
    runs = []
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        for spec in models:
            model = spec if hasattr(spec, "correct") else corrector(spec)
            name = getattr(model, "name", None) or str(spec)
            opts = base
            if name == "none":
                opts = {k: v for k, v in base.items() if k not in ("anchor", "straighten")}
            elif opts.get("anchor") is False:
                name += " (anchor off)"
            t0 = time.perf_counter()
            gen = _correct(model, b, opts)
            dt = time.perf_counter() - t0
            runs.append((name, str(model.source), gen, dt))
    sim, gens = [], [[] for _ in runs]
    for i in tqdm(range(len(a)), desc="Table 5.3", disable=not progress):
        sim.append((*_errors(b[i], a[i], seed), wall_metrics(b[i], a[i])))
        for k, (_, _, gen, _) in enumerate(runs):
            gens[k].append((*_errors(gen[i], a[i], seed), wall_metrics(gen[i], a[i])))
    rows_of = []
    for (name, source, gen, dt), g in zip(runs, gens, strict=True):
        rows = []
        for i, ((es, esa, ws), (eg, ega, wg)) in enumerate(zip(sim, g, strict=True)):
            rows.append({
                "map": i + 1, "plan_id": str(pairs.plan_id[i]), "error_sim": es,
                "error_gen": eg, "diff": es - eg, "error_sim_all": esa, "error_gen_all": ega,
                "diff_all": esa - ega,
                "improved": bool(improved(es, eg, ws["wall_recall"], wg["wall_recall"],
                                          margin)),
                "improved_all": bool(improved(esa, ega, ws["wall_recall"], wg["wall_recall"],
                                              margin)),
                **{f"sim_{k}": v for k, v in ws.items()},
                **{f"gen_{k}": v for k, v in wg.items()}})
        rows_of.append(ModelRows(name, source, rows, _model_summary(rows, margin, len(b), dt),
                                 gen))
    summary = {"n": len(a), "seed": seed, "margin_px": margin,
               "median_error_sim": _nanmedian([s[0] for s in sim]),
               "median_error_sim_all": _nanmedian([s[1] for s in sim])}
    for k in GUARDS:
        summary[f"median_sim_{k}"] = _nanmedian([s[2][k] for s in sim])
    source = pairs.meta.get("heldout", {}).get("source", "") if pairs.meta else ""
    return Table53(rows_of, summary, _newest_tests(rows_of, margin), b, a, str(source),
                   _digest(pairs))


def _model_summary(rows: list[dict], margin: float, n_maps: int, dt: float) -> dict:
    """:attr:`ModelRows.summary` of one model's rows."""
    diff = np.array([r["diff"] for r in rows], float)
    diff_all = np.array([r["diff_all"] for r in rows], float)
    ok, ok_all = np.isfinite(diff), np.isfinite(diff_all)
    n, n_all = int(ok.sum()), int(ok_all.sum())
    imp = sum(r["improved"] for r in rows)
    imp_all = sum(r["improved_all"] for r in rows)
    out = {
        "n": n, "n_all": n_all, "failed": int((~ok).sum()), "margin_px": margin,
        "improved": imp, "share_improved": imp / n if n else float("nan"),
        "improved_all": imp_all, "share_improved_all": imp_all / n_all if n_all
        else float("nan"),
        "improved_any": int((diff[ok] > 0).sum()), "worse": int((diff[ok] < 0).sum()),
        "improved_but_lost_recall": sum(1 for r in rows if r["diff"] > margin
                                        and r["gen_wall_recall"] < r["sim_wall_recall"]),
        "sign_test_p": sign_test(diff)["p"],
        "median_error_gen": _nanmedian([r["error_gen"] for r in rows]),
        "median_error_gen_all": _nanmedian([r["error_gen_all"] for r in rows]),
        "maps_per_s": n_maps / dt if dt > 0 and n_maps else float("nan"),
    }
    for k in GUARDS:
        out[f"median_gen_{k}"] = _nanmedian([r[f"gen_{k}"] for r in rows])
    return out


def _newest_tests(models: list[ModelRows], margin: float) -> dict:
    """The last model's sign tests against the input and against every earlier row
    (``vs``: name -> tests; a ``none`` row also as ``vs_none``, ``beats_none``)."""
    if not models:
        return {}
    new = models[-1]
    out = {"model": new.name,
           "vs_input": sign_test([r["diff"] for r in new.rows]),
           "vs_input_all": sign_test([r["diff_all"] for r in new.rows]), "vs": {}}
    for other in models[:-1]:
        gain = np.array([q["error_gen"] - r["error_gen"]
                         for q, r in zip(other.rows, new.rows, strict=True)], float)
        gain_all = [q["error_gen_all"] - r["error_gen_all"]
                    for q, r in zip(other.rows, new.rows, strict=True)]
        ok = np.isfinite(gain)
        beats = int((gain[ok] > margin).sum())
        t = {"matched": sign_test(gain), "all": sign_test(gain_all), "beats": beats,
             "n": int(ok.sum()), "share_beats": beats / ok.sum() if ok.any() else float("nan")}
        out["vs"][other.name] = t
        if other.name == "none":
            out.update(vs_none=t["matched"], vs_none_all=t["all"], beats_none=beats,
                       n_vs_none=t["n"], share_beats_none=t["share_beats"])
    return out


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
