"""Exporting a dataset for training: pix2pix layout, A/B folders, or one packed file.

Formats (the preprocessed N x N pairs; values 0 occupied, 127 unknown, 255 free):

``pix2pix``
    ``OUT/{train,val,test}/<index>.png``: A and B side by side (N x 2N, A left), the
    aligned layout that pytorch-CycleGAN-and-pix2pix's ``--dataset_mode aligned`` reads
    (``--dataroot OUT``).
``folders``
    ``OUT/A/<split>/<index>.png`` and ``OUT/B/<split>/<index>.png`` with matching names
    (the input layout of that project's ``datasets/combine_A_and_B.py``).
``packed``
    ``DS/packed.npz`` written by :func:`map2map.datasets.packed.save_packed` (2 bits per
    pixel, deflated; loads with numpy only: :func:`~map2map.datasets.packed.load_packed`).

Which pairs: those the cleaner kept (``complete``; with ``include_review`` also those it
left for review), or every done pair with ``everything``. The split of each pair is the
one recorded in the manifest at build time (by plan: no plan in two splits). Folder
exports are written to a temporary folder and renamed into place.

Examples
--------
>>> import tempfile
>>> from map2map.datasets.build import build_dataset
>>> from map2map.datasets.pair import BuildParams
>>> ds = build_dataset(tempfile.mkdtemp(), "generated", 2, 0, BuildParams(source="deform",
...                    size=32), workers=0, progress=False, figures=False).out
>>> res = export_dataset(ds, "pix2pix", everything=True, progress=False)
>>> res.count, sorted(p.name for p in res.path.iterdir())
(2, ['train'])
"""

from __future__ import annotations

import os
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from ..core._io import atomic_dir, check_output_dir
from ..core.errors import InputError

__all__ = ["FORMATS", "ExportResult", "select_rows", "export_dataset"]

FORMATS = ("pix2pix", "folders", "packed")


@dataclass
class ExportResult:
    """Where the export went and what it holds."""

    path: Path
    format: str
    count: int
    splits: dict[str, int]
    bytes: int


def select_rows(man, *, everything: bool = False, include_review: bool = False) -> list:
    """Done pairs to export (see the module docstring)."""
    rows = man.rows("done")
    if everything:
        return rows
    if rows and all(r["clean"] is None for r in rows):
        raise InputError(
            man.path.parent,
            "the dataset has not been cleaned: run 'map2map dataset clean' first, "
            "or export every pair with `everything`",
        )
    keep = {"complete", "review"} if include_review else {"complete"}
    return [r for r in rows if r["clean"] in keep]


def _load(ds: Path, idx: int) -> tuple[np.ndarray, np.ndarray]:
    from .pairfolder import pair_dir, read_pair

    return read_pair(pair_dir(ds, idx))


def _png(path: Path, img: np.ndarray) -> None:
    import cv2

    ok, buf = cv2.imencode(".png", img)
    if not ok:
        raise OSError(f"PNG encoding failed for {path}")
    path.write_bytes(buf.tobytes())


def _tree_bytes(path: Path) -> int:
    if path.is_file():
        return path.stat().st_size
    return sum(p.stat().st_size for p in path.rglob("*") if p.is_file())


def export_dataset(
    ds: str | os.PathLike,
    fmt: str,
    out: str | os.PathLike | None = None,
    *,
    everything: bool = False,
    include_review: bool = False,
    progress: bool = True,
) -> ExportResult:
    """Export dataset ``ds`` in format ``fmt``.

    Parameters
    ----------
    ds : path-like
        The dataset.
    fmt : {"pix2pix", "folders", "packed"}
        Output format (module docstring).
    out : path-like, optional
        Output folder of ``pix2pix``/``folders`` (default ``DS/export/<fmt>``; checked
        before any work, written whole and replacing an existing one); the
        packed file is always ``DS/packed.npz``.
    everything, include_review : bool
        Export every done pair / also the pairs the cleaner left for review.
    progress : bool
        Show a tqdm bar.

    Returns
    -------
    ExportResult

    Raises
    ------
    InputError
        Unknown format, not a dataset, not cleaned (without ``everything``), nothing to
        export.
    """
    from tqdm.auto import tqdm

    from .build import open_dataset

    if fmt not in FORMATS:
        raise InputError("format", f"must be one of {', '.join(FORMATS)}, got {fmt!r}")
    ds = Path(ds)
    if fmt != "packed":  # an unwritable output is found before any work
        path = Path(out) if out else ds / "export" / fmt
        check_output_dir(path, protect=(ds,))
    with open_dataset(ds) as man:
        rows = select_rows(man, everything=everything, include_review=include_review)
        if not rows:
            raise InputError(ds, "no pairs to export (none done, or the cleaner kept none)")
        ident = man.get_info("identity")
        splits = {s: sum(1 for r in rows if r["split"] == s) for s in ("train", "val", "test")}
        bar = tqdm(rows, desc=f"export {fmt}", unit="pair", disable=not progress)
        if fmt == "packed":
            from .packed import PackedPairs, save_packed

            a = np.stack([_load(ds, r["idx"])[0] for r in bar])
            b = np.stack([_load(ds, r["idx"])[1] for r in rows])
            meta = {
                "dataset": str(ds.resolve()),
                "identity": ident,
                "indices": [int(r["idx"]) for r in rows],
                "selection": "all" if everything else
                ("complete+review" if include_review else "complete"),
            }  # fmt: skip
            path = save_packed(ds / "packed.npz", PackedPairs(
                a, b, np.array([r["plan_id"] for r in rows]),
                np.array([r["split"] for r in rows]), meta))  # fmt: skip
        else:
            with atomic_dir(path, protect=(ds,)) as tmp:
                for r in bar:
                    a, b = _load(ds, r["idx"])
                    name = f"{r['idx']:06d}.png"
                    if fmt == "pix2pix":
                        d = tmp / r["split"]
                        d.mkdir(parents=True, exist_ok=True)
                        _png(d / name, np.concatenate([a, b], axis=1))
                    else:
                        for side, img in (("A", a), ("B", b)):
                            d = tmp / side / r["split"]
                            d.mkdir(parents=True, exist_ok=True)
                            _png(d / name, img)
        bar.close()
        exports = man.get_info("exports", {})
        exports[fmt] = {"path": str(path), "count": len(rows), "splits": splits}
        man.set_info("exports", exports)
    return ExportResult(path, fmt, len(rows), splits, _tree_bytes(path))
