"""Cleaning a paired dataset: the thesis's Extra Trees classifier, with free labels.

Thesis 4.1 removed partially explored SLAM maps: 1,468 pairs labelled by hand, an
``ExtraTreesClassifier(max_features=11, n_estimators=100)`` trained on 15 (listed: 16)
hand-made features (:mod:`map2map.datasets.features`), and the rest split by the
predicted probability of "complete": ``< 0.4`` partial (discarded), ``> 0.8`` complete
(kept), in between reviewed by hand.

Here the labels come for free: the simulator knows the free space the robot could
reach, so a pair is *complete* when its SLAM map marks at least
:data:`COVERAGE_COMPLETE` = 0.8 of it free (coverage of the reachable free space). Why
0.8: the thesis's "partial" maps (its Fig. 4.3) miss whole parts of the plan; missing a
fifth of the free space is a typical room of a 5-room plan, while a finished exploration
still loses some free space to the thick walls SLAM draws and to corners the explorer
does not enter (in a 40-pair build of generated plans, 7 simulated minutes, 180 degrees,
every run whose explorer finished reached 0.85-0.996, median 0.95; the runs cut by the
time budget on big plans spread from 0.27 to 0.94). A stricter threshold (0.9) falls
in the middle of the finished runs, where the 256 x 256 features cannot separate a few
per cent of coverage (cross-validated accuracy 85 % there against 97.5 % at 0.8 on the
same 40 pairs); pass ``coverage_threshold`` to choose another.
Manual labels (a CSV ``index,label`` with ``complete``/``partial`` or ``1``/``0``)
replace or complete them, as the thesis's were.

Accuracy is cross-validated by plan (``StratifiedGroupKFold``: no plan in both the
training and the testing fold); every pair's ``p_complete`` in the manifest is the
out-of-fold probability (a pair is never judged by a model that saw its label). The
classifier trained on all labelled pairs is saved with ``skops`` (no code runs on
load) and can be applied to any dataset or folder of pairs
(:func:`apply_cleaner`).

Examples
--------
>>> rng = np.random.default_rng(0)
>>> x = rng.normal(size=(40, 16)); y = (x[:, 2] > 0).astype(int); x[:, 2] += 3 * y
>>> model, p, acc, conf, folds = train_cleaner(x, y, np.arange(40) // 2)
>>> folds, acc > 0.9, [decide(v) for v in (0.1, 0.9)]
(5, True, ['partial', 'complete'])
"""

from __future__ import annotations

import csv
import os
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from ..core.errors import InputError
from .features import FEATURE_NAMES, pair_features
from .pairfolder import PLAN_PNG, SLAM_PNG, is_pair_folder, pair_dir, pictures, read_picture

__all__ = [
    "COVERAGE_COMPLETE",
    "P_PARTIAL",
    "P_COMPLETE",
    "RANDOM_STATE",
    "CleanReport",
    "decide",
    "read_labels",
    "dataset_features",
    "folder_pairs",
    "train_cleaner",
    "clean_dataset",
    "load_cleaner",
    "apply_cleaner",
]

#: Coverage of the reachable free space from which a simulated map counts as complete.
COVERAGE_COMPLETE = 0.8
#: Thesis thresholds on P(complete): below P_PARTIAL partial, above P_COMPLETE complete.
P_PARTIAL, P_COMPLETE = 0.4, 0.8
RANDOM_STATE = 0
CLASSES = ("partial", "complete")
#: Types a saved cleaner may contain (checked before loading it with skops).
_TRUSTED_PREFIXES = ("sklearn.", "numpy.", "builtins.")


def decide(p: float) -> str:
    """The thesis's decision on P(complete).

    Examples
    --------
    >>> decide(0.2), decide(0.5), decide(0.95)
    ('partial', 'review', 'complete')
    """
    if p < P_PARTIAL:
        return "partial"
    return "complete" if p > P_COMPLETE else "review"


def _make_model():
    from sklearn.ensemble import ExtraTreesClassifier

    return ExtraTreesClassifier(max_features=11, n_estimators=100, random_state=RANDOM_STATE)


def read_labels(path: str | os.PathLike) -> dict[str, int]:
    """A labels CSV: header ``index,label`` (or ``name,label``); label ``complete``/``1`` or
    ``partial``/``0``. Returns key (as text) -> 1 complete / 0 partial.

    Examples
    --------
    >>> import tempfile, pathlib
    >>> p = pathlib.Path(tempfile.mkdtemp()) / "labels.csv"
    >>> _ = p.write_text("index,label\\n3,complete\\n4,0\\n")
    >>> read_labels(p)
    {'3': 1, '4': 0}
    """
    path = Path(path)
    values = {"complete": 1, "1": 1, "partial": 0, "0": 0}
    try:
        with open(path, newline="") as fh:
            rows = list(csv.reader(fh))
    except FileNotFoundError:
        raise InputError(path, "file not found") from None
    except (OSError, UnicodeDecodeError, csv.Error) as exc:
        raise InputError(path, f"unreadable labels file ({exc})") from None
    if not rows or [c.strip().lower() for c in rows[0][:2]] not in (
        ["index", "label"],
        ["name", "label"],
    ):
        raise InputError(path, "labels need the header 'index,label' (or 'name,label')")
    out = {}
    for k, row in enumerate(rows[1:], start=2):
        if not row or not "".join(row).strip():
            continue
        if len(row) < 2 or row[1].strip().lower() not in values:
            raise InputError(path, f"line {k}: label must be complete/partial or 1/0, got {row}")
        out[row[0].strip()] = values[row[1].strip().lower()]
    return out


def _read_png(path: Path) -> np.ndarray:
    """A pair picture, harmonised to the three map values (a folder of pairs from
    elsewhere may hold grey levels)."""
    from ..maps.preprocess import harmonise

    return harmonise(read_picture(path))


def dataset_features(ds: str | os.PathLike, rows) -> np.ndarray:
    """Features (rows x 16) of the done pairs ``rows`` of dataset ``ds``."""
    out = np.zeros((len(rows), len(FEATURE_NAMES)))
    for k, r in enumerate(rows):
        a, b = pictures(pair_dir(ds, r["idx"]))
        out[k] = pair_features(_read_png(a), _read_png(b))
    return out


def folder_pairs(folder: str | os.PathLike) -> list[tuple[str, Path, Path]]:
    """``(name, A picture, B picture)`` of a folder of pairs: ``A/`` and ``B/`` holding
    pictures with matching names (searched recursively, e.g. an ``export --format
    folders`` output), or one sub-folder per pair holding ``A.png`` and ``B.png``."""
    folder = Path(folder)
    out = []
    if (folder / "A").is_dir() and (folder / "B").is_dir():
        for a in sorted((folder / "A").rglob("*.png")):
            rel = a.relative_to(folder / "A")
            b = folder / "B" / rel
            if b.is_file():
                out.append((str(rel.with_suffix("")), a, b))
    else:
        for sub in sorted(p for p in folder.iterdir() if p.is_dir()):
            if is_pair_folder(sub):
                out.append((sub.name, *pictures(sub)))
    if not out:
        raise InputError(folder, "no pairs found (expected A/ and B/ with matching names, "
                                 f"or sub-folders holding {PLAN_PNG} and {SLAM_PNG})")
    return out


@dataclass
class CleanReport:
    """What :func:`clean_dataset` found."""

    n_labelled: int
    n_complete: int
    cv_accuracy: float
    confusion: list[list[int]]
    importances: dict[str, float]
    decisions: dict[str, int]
    model_path: Path
    figure: Path | None = None
    labels_from: str = ""
    folds: int = 0
    warnings: list[str] = field(default_factory=list)

    def as_dict(self) -> dict:
        return {
            "n_labelled": self.n_labelled,
            "n_complete": self.n_complete,
            "cv_accuracy": self.cv_accuracy,
            "confusion": self.confusion,
            "classes": list(CLASSES),
            "importances": self.importances,
            "decisions": self.decisions,
            "model": str(self.model_path),
            "labels_from": self.labels_from,
            "folds": self.folds,
            "warnings": self.warnings,
        }

    def lines(self) -> list[str]:
        out = [
            f"labelled pairs: {self.n_labelled} ({self.n_complete} complete; {self.labels_from})",
            f"cross-validated accuracy ({self.folds}-fold by plan): {100 * self.cv_accuracy:.1f} %",
            "confusion (rows label partial/complete, columns predicted): "
            f"{self.confusion}",
            "decisions: " + ", ".join(f"{k} {v}" for k, v in sorted(self.decisions.items())),
            "top features: " + ", ".join(
                f"{k} {v:.2f}" for k, v in sorted(self.importances.items(),
                                                  key=lambda kv: -kv[1])[:5]),
            f"classifier: {self.model_path}",
        ]  # fmt: skip
        out += [f"warning: {w}" for w in self.warnings]
        if self.figure:
            out.append(f"figure: {self.figure}")
        return out


def train_cleaner(x: np.ndarray, y: np.ndarray, groups: np.ndarray):
    """Cross-validate (by group) and fit the thesis's classifier.

    Returns ``(model fitted on all, out-of-fold P(complete), accuracy, confusion, folds)``.
    ``folds`` is 0 when there are too few labels of a class to cross-validate (then the
    out-of-fold probabilities are the fitted model's own and accuracy is NaN).
    """
    from sklearn.metrics import confusion_matrix
    from sklearn.model_selection import StratifiedGroupKFold, cross_val_predict

    y = np.asarray(y, int)
    model = _make_model()
    minority = int(min((y == 0).sum(), (y == 1).sum()))
    n_groups = len(np.unique(groups))
    folds = min(5, minority, n_groups)
    if folds >= 2:
        cv = StratifiedGroupKFold(n_splits=folds, shuffle=True, random_state=RANDOM_STATE)
        proba = cross_val_predict(model, x, y, groups=groups, cv=cv, method="predict_proba")
        p = proba[:, 1]
        pred = (p >= 0.5).astype(int)
        acc = float((pred == y).mean())
        conf = confusion_matrix(y, pred, labels=[0, 1]).tolist()
    else:
        folds, acc, conf = 0, float("nan"), [[0, 0], [0, 0]]
    model.fit(x, y)
    if folds == 0:
        p = _p_complete(model, x)
    return model, p, acc, conf, folds


def _p_complete(model, x: np.ndarray) -> np.ndarray:
    proba = model.predict_proba(x)
    classes = list(model.classes_)
    if 1 not in classes:
        return np.zeros(len(x))
    return proba[:, classes.index(1)]


def clean_dataset(
    ds: str | os.PathLike,
    labels: str | os.PathLike | None = None,
    *,
    coverage_threshold: float = COVERAGE_COMPLETE,
    model_path: str | os.PathLike | None = None,
    figure: bool = True,
) -> CleanReport:
    """Label, cross-validate, train and apply the cleaner on dataset ``ds``.

    Parameters
    ----------
    ds : path-like
        A dataset built by :func:`map2map.datasets.build.build_dataset`.
    labels : path-like, optional
        Manual labels CSV (``index,label``); they override coverage labels.
    coverage_threshold : float
        Coverage of the reachable free space from which a pair is labelled complete.
    model_path : path-like, optional
        Where to save the classifier (default ``DS/cleaner.skops``).
    figure : bool
        Write ``DS/figures/cleaner.png`` (confusion matrix, feature importances).

    Returns
    -------
    CleanReport
        Also stored in the manifest (``info.cleaner``); each pair gets ``p_complete``,
        its label and its decision (``complete``/``review``/``partial``).

    Raises
    ------
    InputError
        Not a dataset, no done pairs, labels of one class only, a bad labels file.
    """
    import skops.io as sio

    from ..core._io import atomic_path
    from .build import open_dataset

    if not 0.0 < coverage_threshold <= 1.0:
        raise InputError("coverage_threshold", f"must be in (0, 1], got {coverage_threshold}")
    ds = Path(ds)
    manual = read_labels(labels) if labels else {}
    with open_dataset(ds) as man:
        rows = man.rows("done")
        if not rows:
            raise InputError(ds, "no finished pairs to clean")
        unknown = sorted(set(manual) - {str(r["idx"]) for r in rows})
        if unknown:
            raise InputError(labels, f"labels for pairs the dataset does not have: "
                                     f"{', '.join(unknown[:5])}")  # fmt: skip
        x = dataset_features(ds, rows)
        y = np.full(len(rows), -1)
        for k, r in enumerate(rows):
            if str(r["idx"]) in manual:
                y[k] = manual[str(r["idx"])]
            elif r["coverage"] is not None:
                y[k] = int(r["coverage"] >= coverage_threshold)
        lab = y >= 0
        if len(np.unique(y[lab])) < 2:
            raise InputError(ds, f"the labels are all of one class ({int(lab.sum())} labelled "
                                 f"pairs): the classifier needs complete and partial examples; "
                                 "build more pairs or add manual labels")  # fmt: skip
        groups = np.array([r["plan_id"] for r in rows])
        model, p_lab, acc, conf, folds = train_cleaner(x[lab], y[lab], groups[lab])
        p = np.zeros(len(rows))
        p[lab] = p_lab
        if (~lab).any():
            p[~lab] = _p_complete(model, x[~lab])
        decisions = [decide(v) for v in p]
        man.set_clean([(r["idx"], p[k], (CLASSES[y[k]] if y[k] >= 0 else None), decisions[k])
                       for k, r in enumerate(rows)])  # fmt: skip
        model_path = Path(model_path) if model_path else ds / "cleaner.skops"
        with atomic_path(model_path) as tmp:
            sio.dump(model, tmp)
        source = (f"{len(manual)} manual labels" if manual else "") + (
            (" + " if manual else "") + f"coverage >= {coverage_threshold:g} of reachable free "
            "space" if (lab.sum() > len(manual)) else "")  # fmt: skip
        warnings = []
        if folds == 0:
            warnings.append("too few labels of one class to cross-validate: accuracy unknown")
        elif lab.sum() < 100:
            warnings.append(f"only {int(lab.sum())} labelled pairs: the accuracy is a rough "
                            "estimate")  # fmt: skip
        report = CleanReport(
            n_labelled=int(lab.sum()),
            n_complete=int((y == 1).sum()),
            cv_accuracy=acc,
            confusion=conf,
            importances={n: round(float(v), 4)
                         for n, v in zip(FEATURE_NAMES, model.feature_importances_, strict=True)},
            decisions={d: decisions.count(d) for d in sorted(set(decisions))},
            model_path=model_path,
            labels_from=source,
            folds=folds,
            warnings=warnings,
        )  # fmt: skip
        if figure:
            from .figures import cleaner_figure

            report.figure = cleaner_figure(report.as_dict(), ds / "figures" / "cleaner.png")
        man.set_info("cleaner", report.as_dict())
    return report


def load_cleaner(path: str | os.PathLike):
    """Load a classifier saved by :func:`clean_dataset`, refusing unexpected types.

    Only scikit-learn, numpy and builtin types are accepted (skops lists every type in
    the file before anything is built; nothing executes on load).
    """
    import skops.io as sio

    path = Path(path)
    try:
        untrusted = sio.get_untrusted_types(file=path)
    except FileNotFoundError:
        raise InputError(path, "file not found") from None
    except Exception as exc:
        raise InputError(path, f"not a skops classifier file ({exc})") from None
    bad = [t for t in untrusted if not t.startswith(_TRUSTED_PREFIXES)]
    if bad:
        raise InputError(path, f"refusing to load unexpected types: {', '.join(bad[:5])}")
    try:
        return sio.load(path, trusted=untrusted)
    except Exception as exc:
        raise InputError(path, f"cannot load the classifier ({exc})") from None


def apply_cleaner(model_path: str | os.PathLike, target: str | os.PathLike) -> list[dict]:
    """Apply a saved cleaner to a dataset (updating its manifest) or a folder of pairs.

    Returns one ``{"name", "p_complete", "decision"}`` per pair.
    """
    from .build import open_dataset

    model = load_cleaner(model_path)
    target = Path(target)
    out = []
    if (target / "manifest.sqlite").is_file():
        with open_dataset(target) as man:
            rows = man.rows("done")
            if not rows:
                raise InputError(target, "no finished pairs")
            p = _p_complete(model, dataset_features(target, rows))
            man.set_clean([(r["idx"], p[k], r["label"], decide(p[k]))
                           for k, r in enumerate(rows)])  # fmt: skip
            out = [{"name": f"{r['idx']:06d}", "p_complete": float(p[k]),
                    "decision": decide(p[k])} for k, r in enumerate(rows)]  # fmt: skip
        return out
    if not target.is_dir():
        raise InputError(target, "not a dataset or a folder of pairs")
    pairs = folder_pairs(target)
    x = np.stack([pair_features(_read_png(a), _read_png(b)) for _, a, b in pairs])
    p = _p_complete(model, x)
    return [{"name": n, "p_complete": float(p[k]), "decision": decide(p[k])}
            for k, (n, _, _) in enumerate(pairs)]  # fmt: skip
