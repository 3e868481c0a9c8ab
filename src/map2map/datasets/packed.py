"""Packed paired datasets: every (A, B) pair of a dataset in one small file.

A paired dataset for the GANs (thesis sec. 4.1, 4.2) is N pairs of square maps in the
internal convention (occupied 0, unknown 127, free 255): ``a`` the CAD plan, ``b`` the
SLAM map of it. Ternary maps carry 2 bits of information per pixel, so the file stores
them packed four pixels to a byte and deflated (``numpy.savez_compressed``): 4,000
pairs at 256x256 take a few tens of MiB, small enough to travel with the code to a GPU
machine. Loading needs numpy only (no PyTorch); the learning code wraps the arrays.

Each pair also carries its plan id and its split (``train``/``val``/``test``; a plan is
in one split only), and the file carries the dataset's identity (``meta``: how it was
built, a content digest) so that a trained model can name the data it saw.

Examples
--------
>>> import numpy as np, tempfile, pathlib
>>> rng = np.random.default_rng(0)
>>> a = rng.choice(np.array([0, 127, 255], np.uint8), size=(3, 8, 8))
>>> pairs = PackedPairs(a, a[:, ::-1].copy(), np.array(["p0", "p0", "p1"]),
...                     np.array(["train", "train", "test"]), {"seed": 0})
>>> path = pathlib.Path(tempfile.mkdtemp()) / "pairs.npz"
>>> _ = save_packed(path, pairs)
>>> back = load_packed(path)
>>> len(back), back.a.dtype, bool((back.b == pairs.b).all())
(3, dtype('uint8'), True)
>>> len(back.select("train")), back.meta["seed"]
(2, 0)
"""

from __future__ import annotations

import hashlib
import json
import os
import zipfile
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from ..core._io import atomic_path
from ..core.errors import InputError
from ..core.grid import FREE, OCCUPIED, UNKNOWN

__all__ = ["PackedPairs", "save_packed", "load_packed", "merge_packed", "pack_ternary",
           "unpack_ternary"]

#: Pixel value of each 2-bit code; the code of a value is its index here.
_VALUES = np.array([OCCUPIED, UNKNOWN, FREE], np.uint8)
SPLITS = ("train", "val", "test")
FORMAT = "map2map-packed-pairs"
VERSION = 1


@dataclass
class PackedPairs:
    """N aligned map pairs with their plan ids, splits and the dataset's identity.

    Parameters
    ----------
    a, b : ndarray, shape (N, H, W), uint8
        CAD plans and SLAM maps, values in {0, 127, 255} (the internal convention).
    plan_id : ndarray, shape (N,), str
        Plan each pair was made from (pairs of one plan share it).
    split : ndarray, shape (N,), str
        ``"train"``, ``"val"`` or ``"test"`` per pair.
    meta : dict
        JSON-serialisable description of the dataset (command, seed, counts, ...).
    """

    a: np.ndarray
    b: np.ndarray
    plan_id: np.ndarray
    split: np.ndarray
    meta: dict = field(default_factory=dict)

    def __post_init__(self):
        self.a = np.asarray(self.a, np.uint8)
        self.b = np.asarray(self.b, np.uint8)
        self.plan_id = np.asarray(self.plan_id).astype(str)
        self.split = np.asarray(self.split).astype(str)
        n = len(self.a)
        if self.a.ndim != 3 or self.a.shape != self.b.shape:
            raise ValueError(f"a and b must both be (N, H, W); got {self.a.shape}, {self.b.shape}")
        if self.plan_id.shape != (n,) or self.split.shape != (n,):
            raise ValueError("plan_id and split need one entry per pair")
        bad = set(np.unique(self.split)) - set(SPLITS)
        if bad:
            raise ValueError(f"split values must be in {SPLITS}, got {sorted(bad)}")

    def __len__(self) -> int:
        return len(self.a)

    def select(self, split: str) -> PackedPairs:
        """The pairs of one split (``"train"``, ``"val"`` or ``"test"``)."""
        keep = self.split == split
        return PackedPairs(self.a[keep], self.b[keep], self.plan_id[keep], self.split[keep],
                           dict(self.meta))

    def digest(self) -> str:
        """SHA-256 of the pixel content, plan ids and splits (the dataset's identity)."""
        h = hashlib.sha256()
        for arr in (self.a, self.b):
            h.update(np.ascontiguousarray(arr).tobytes())
        h.update("\n".join(self.plan_id).encode())
        h.update("\n".join(self.split).encode())
        return h.hexdigest()


def pack_ternary(maps: np.ndarray) -> np.ndarray:
    """Pack ternary maps (..., H, W) four pixels to a byte; raises on other values.

    Examples
    --------
    >>> m = np.array([[0, 127, 255, 0, 255]], np.uint8)
    >>> unpack_ternary(pack_ternary(m), m.shape).tolist()
    [[0, 127, 255, 0, 255]]
    """
    maps = np.asarray(maps, np.uint8)
    lut = np.full(256, 255, np.uint8)
    lut[_VALUES] = np.arange(3, dtype=np.uint8)
    codes = lut[maps].ravel()
    if codes.size and codes.max() == 255:
        bad = np.unique(maps[lut[maps] == 255])[:5].tolist()
        raise ValueError(f"maps must hold only 0, 127 and 255 (found {bad}); harmonise them first")
    pad = (-codes.size) % 4
    codes = np.concatenate([codes, np.zeros(pad, np.uint8)]).reshape(-1, 4)
    return (codes[:, 0] | codes[:, 1] << 2 | codes[:, 2] << 4 | codes[:, 3] << 6).astype(np.uint8)


def unpack_ternary(packed: np.ndarray, shape: tuple[int, ...]) -> np.ndarray:
    """Inverse of :func:`pack_ternary` for maps of the given shape."""
    packed = np.asarray(packed, np.uint8)
    codes = np.stack([(packed >> s) & 3 for s in (0, 2, 4, 6)], axis=1).ravel()
    n = int(np.prod(shape))
    return _VALUES[codes[:n]].reshape(shape)


def save_packed(path: str | os.PathLike, pairs: PackedPairs) -> Path:
    """Write ``pairs`` to one compressed ``.npz`` file, atomically; returns its path.

    ``meta`` gains ``format``, ``version``, ``count``, ``shape``, per-split counts and
    ``digest`` (:meth:`PackedPairs.digest`).
    """
    path = Path(path)
    meta = dict(pairs.meta)
    meta.update(
        format=FORMAT,
        version=VERSION,
        count=len(pairs),
        shape=list(pairs.a.shape[1:]),
        splits={s: int((pairs.split == s).sum()) for s in SPLITS},
        digest=pairs.digest(),
    )
    with atomic_path(path) as tmp, open(tmp, "wb") as fh:
        np.savez_compressed(
            fh,
            a=pack_ternary(pairs.a),
            b=pack_ternary(pairs.b),
            plan_id=pairs.plan_id.astype("U"),
            split=pairs.split.astype("U"),
            meta=np.array(json.dumps(meta, sort_keys=True)),
        )
    return path


def load_packed(path: str | os.PathLike) -> PackedPairs:
    """Read a file written by :func:`save_packed` (no pickle: nothing runs on load).

    Raises :class:`~map2map.core.errors.InputError` naming the file when it is missing,
    corrupt, or not a packed-pairs file.
    """
    path = Path(path)
    try:
        with np.load(path, allow_pickle=False) as z:
            meta = json.loads(str(z["meta"]))
            if meta.get("format") != FORMAT:
                raise InputError(path, "not a map2map packed-pairs file")
            shape = (int(meta["count"]), *map(int, meta["shape"]))
            pairs = PackedPairs(
                unpack_ternary(z["a"], shape),
                unpack_ternary(z["b"], shape),
                z["plan_id"],
                z["split"],
                meta,
            )
    except FileNotFoundError:
        raise InputError(path, "file not found") from None
    except (OSError, KeyError, ValueError, zipfile.BadZipFile) as exc:
        if isinstance(exc, InputError):
            raise
        raise InputError(path, f"not a readable packed-pairs file ({exc})") from None
    if pairs.digest() != meta.get("digest"):
        raise InputError(path, "content digest mismatch (file corrupt or edited)")
    return pairs


def merge_packed(parts, sources=None) -> PackedPairs:
    """Several packed datasets as one training set (``map2map train --data DS1 DS2 ...``).

    The pairs are concatenated in the order given, each keeping its split; plan ids get
    the part's index as a prefix (``"0:"``, ``"1:"``, ...), since two builds with other
    seeds may name different plans alike. ``meta["merged"]`` lists every part's source,
    identity, digest and split counts, so a model trained on the merge names its data.

    Examples
    --------
    >>> a = np.zeros((2, 4, 4), np.uint8)
    >>> one = PackedPairs(a, a, np.array(["p0", "p1"]), np.array(["train", "val"]), {"seed": 1})
    >>> two = PackedPairs(a[:1], a[:1], np.array(["p0"]), np.array(["train"]), {"seed": 2})
    >>> m = merge_packed([one, two], ["DS1", "DS2"])
    >>> len(m), m.plan_id.tolist(), [p["source"] for p in m.meta["merged"]]
    (3, ['0:p0', '0:p1', '1:p0'], ['DS1', 'DS2'])
    """
    parts = list(parts)
    sources = [str(s) for s in (sources or [f"part {k}" for k in range(len(parts))])]
    if not parts or len(sources) != len(parts):
        raise ValueError("merge_packed needs one source name per part, and at least one part")
    odd = [s for s, p in zip(sources, parts, strict=True) if p.a.shape[1:] != parts[0].a.shape[1:]]
    if odd:
        raise InputError(odd[0], f"maps of another size than {sources[0]}'s "
                         f"{parts[0].a.shape[1:]}; build them with the same --size")
    keys = ("dataset", "identity", "digest", "count", "splits")
    meta = {"merged": [{"source": s, **{k: p.meta[k] for k in keys if k in p.meta}}
                       for s, p in zip(sources, parts, strict=True)]}
    return PackedPairs(np.concatenate([p.a for p in parts]),
                       np.concatenate([p.b for p in parts]),
                       np.concatenate([np.char.add(f"{k}:", p.plan_id.astype(str))
                                       for k, p in enumerate(parts)]),
                       np.concatenate([p.split for p in parts]), meta)
