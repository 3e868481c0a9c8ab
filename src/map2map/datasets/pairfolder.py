"""The pair folder: one place that knows how a dataset stores a pair on disk.

A dataset ``DS`` holds pair ``i`` in ``DS/pairs/<i:06d>/`` (:func:`pair_dir`):

* ``A.png`` / ``B.png`` -- the plan and the SLAM map preprocessed to N x N (0 occupied,
  127 unknown, 255 free), what the models train on (:data:`PLAN_PNG`, :data:`SLAM_PNG`);
* ``A.yaml`` + ``A.pgm`` / ``B.yaml`` + ``B.pgm`` -- both maps at full resolution, in the
  plan's frame (ROS map_server files);
* ``displacement.npz`` (the parametric model's field, when it made the map) and
  ``meta.json``.

Every reader and writer of pairs goes through these functions.

Examples
--------
>>> import tempfile, pathlib
>>> import numpy as np
>>> d = pair_dir(pathlib.Path(tempfile.mkdtemp()), 7)
>>> d.name
'000007'
>>> a = np.full((8, 8), 255, np.uint8); a[0] = 0
>>> write_pictures(d, a, a.T)
>>> is_pair_folder(d), [x.tolist() == y.tolist() for x, y in zip(read_pair(d), (a, a.T))]
(True, [True, True])
"""

from __future__ import annotations

import os
from pathlib import Path

import numpy as np

from ..core.errors import InputError

__all__ = ["PLAN_PNG", "SLAM_PNG", "PLAN_YAML", "SLAM_YAML", "META", "DISPLACEMENT",
           "pair_dir", "pictures", "is_pair_folder", "read_picture", "read_pair",
           "write_pictures"]

#: The preprocessed plan and SLAM map of a pair (N x N, three values).
PLAN_PNG, SLAM_PNG = "A.png", "B.png"
#: The full-resolution plan and SLAM map (ROS yaml, a ``.pgm`` beside each).
PLAN_YAML, SLAM_YAML = "A.yaml", "B.yaml"
#: The pair's record and the parametric model's displacement field.
META, DISPLACEMENT = "meta.json", "displacement.npz"


def pair_dir(ds: str | os.PathLike, index: int) -> Path:
    """Folder of pair ``index`` in dataset ``ds``."""
    return Path(ds) / "pairs" / f"{int(index):06d}"


def pictures(folder: str | os.PathLike) -> tuple[Path, Path]:
    """The paths of a pair folder's preprocessed plan and SLAM map (``A.png``, ``B.png``)."""
    folder = Path(folder)
    return folder / PLAN_PNG, folder / SLAM_PNG


def is_pair_folder(folder: str | os.PathLike) -> bool:
    """Whether ``folder`` holds both preprocessed pictures of a pair."""
    return all(p.is_file() for p in pictures(folder))


def read_picture(path: str | os.PathLike) -> np.ndarray:
    """One pair picture as a grey uint8 array; a missing or unreadable one is an
    :class:`~map2map.core.errors.InputError` naming the file."""
    import cv2

    img = cv2.imread(str(path), cv2.IMREAD_GRAYSCALE)
    if img is None:
        raise InputError(path, "missing or unreadable pair picture")
    return img


def read_pair(folder: str | os.PathLike) -> tuple[np.ndarray, np.ndarray]:
    """The preprocessed plan and SLAM map of a pair folder."""
    a, b = pictures(folder)
    return read_picture(a), read_picture(b)


def write_pictures(folder: str | os.PathLike, a: np.ndarray, b: np.ndarray) -> None:
    """Write the preprocessed plan ``a`` and SLAM map ``b`` into ``folder`` (created):
    PNG, compression 6."""
    import cv2

    folder = Path(folder)
    folder.mkdir(parents=True, exist_ok=True)
    for path, arr in zip(pictures(folder), (a, b), strict=True):
        ok, buf = cv2.imencode(".png", np.asarray(arr, np.uint8),
                               [cv2.IMWRITE_PNG_COMPRESSION, 6])
        if not ok:
            raise OSError(f"PNG encoding of {path.name} failed")
        path.write_bytes(buf.tobytes())
