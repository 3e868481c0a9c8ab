"""The training set, resident on the device, and the resampling to the training size.

All pairs are moved to the device once, as ``uint8`` (4,000 pairs at 256 x 256 are about
0.5 GB; at 32 x 32 about 8 MB), and each batch is a slice by index: no DataLoader, no
per-sample decoding, nothing rebuilt per epoch. The resampling to the training size
(Model_32: 256 -> 32) happens once, when the data is loaded:

* the **input** (SLAM map) by area averaging (a box filter: antialiased, every pixel of
  the full map contributes; a one-pixel wall darkens its 32-px cell instead of vanishing
  as with anime2clothing's nearest-neighbour resizing);
* the **target** (CAD plan) per class, as :func:`map2map.maps.preprocess.square_resize`
  does: a cell is occupied when walls cover at least ``0.5 / f`` of it (``f`` input
  pixels per cell side; half of what a one-pixel wall across the cell covers), so every
  wall survives the reduction; otherwise free or unknown by
  majority. The target stays a three-valued map (the thesis thickened the targets'
  walls for the same reason, sec. 4.2).

No augmentation (the thesis removed it for Model_BA); a pair is never transformed apart.

Examples
--------
>>> import numpy as np, torch
>>> m = np.full((1, 8, 8), 255, np.uint8); m[0, :, 3] = 0      # a one-pixel wall
>>> downsample_target(m, 2)[0].tolist()                        # kept as a wall
[[0, 255], [0, 255]]
>>> downsample_input(m, 2)[0].tolist()                          # area average
[[191, 255], [191, 255]]
"""

from __future__ import annotations

import os
from pathlib import Path

import numpy as np
import torch
import torch.nn.functional as F

from ...core.errors import InputError
from ...core.grid import FREE, OCCUPIED, UNKNOWN
from ...datasets.packed import PackedPairs, load_packed, merge_packed

__all__ = ["resolve_packed", "load_pairs", "downsample_input", "downsample_target",
           "reduce_input", "ResidentPairs", "FEW_TRAIN_PAIRS", "warn_about_data"]


def resolve_packed(path: str | os.PathLike) -> Path:
    """A dataset folder (``DS/packed.npz`` inside) or a packed ``.npz`` file -> the file."""
    p = Path(path)
    if p.is_dir():
        p = p / "packed.npz"
    if not p.is_file():
        raise InputError(path, "no packed dataset here (expected a dataset folder holding "
                               "packed.npz, or a .npz file written by save_packed)")
    return p


def load_pairs(data) -> PackedPairs:
    """``data`` as :class:`PackedPairs`: a path is read with :func:`load_packed`, a list of
    paths (several dataset builds) is read and merged (:func:`~map2map.datasets.packed.
    merge_packed`; one path in a list is that dataset as is)."""
    if isinstance(data, PackedPairs):
        return data
    if isinstance(data, (list, tuple)):
        if len(data) == 1:
            return load_pairs(data[0])
        return merge_packed([load_packed(resolve_packed(d)) for d in data],
                            [os.fspath(d) for d in data])
    return load_packed(resolve_packed(data))


def _pool(mask: np.ndarray, size: int) -> torch.Tensor:
    t = torch.from_numpy(np.ascontiguousarray(mask, np.float32))[:, None]
    return F.adaptive_avg_pool2d(t, size)[:, 0]


def downsample_input(maps: np.ndarray, size: int) -> np.ndarray:
    """(N, H, W) uint8 maps -> (N, size, size) uint8 by area averaging (grey values)."""
    maps = np.asarray(maps, np.uint8)
    if maps.shape[-1] == size and maps.shape[-2] == size:
        return maps.copy()
    return np.rint(_pool(maps, size).numpy()).astype(np.uint8)


def reduce_input(maps: np.ndarray, size: int, how: str = "area") -> np.ndarray:
    """The model's input at ``size``: :func:`downsample_input` (``"area"``) or
    :func:`downsample_target` (``"classes"``)."""
    if how == "area":
        return downsample_input(maps, size)
    if how == "classes":
        return downsample_target(maps, size)
    raise ValueError(f"input_reduce must be 'area' or 'classes', got {how!r}")


def downsample_target(maps: np.ndarray, size: int) -> np.ndarray:
    """(N, H, W) ternary maps -> (N, size, size) ternary maps, walls kept (module doc)."""
    maps = np.asarray(maps, np.uint8)
    if maps.shape[-1] == size and maps.shape[-2] == size:
        return maps.copy()
    f = maps.shape[-1] / size
    occ, free, unk = (_pool(maps == v, size).numpy() for v in (OCCUPIED, FREE, UNKNOWN))
    out = np.where(free >= unk, FREE, UNKNOWN).astype(np.uint8)
    out[occ >= 0.5 / f - 1e-6] = OCCUPIED
    return out


class ResidentPairs:
    """Inputs ``x`` and targets ``y`` of one split as uint8 (N, 1, s, s) device tensors.

    Parameters
    ----------
    inputs, targets : ndarray (N, H, W) uint8
        SLAM maps (the input of Model_BA) and CAD plans (its target).
    size : int
        Training resolution.
    device : torch.device
    channels_last : bool
        Batches in channels-last memory format (CUDA).
    input_reduce : {"area", "classes"}
        See :func:`reduce_input`.
    target_size : int, optional
        Resolution of the targets when it differs from ``size`` (the inputs').

    Examples
    --------
    >>> import numpy as np, torch
    >>> a = np.zeros((4, 8, 8), np.uint8)
    >>> data = ResidentPairs(a, a, 4, torch.device("cpu"))
    >>> x, y = data.batch(torch.tensor([0, 2]))
    >>> tuple(x.shape), float(x.min())
    ((2, 1, 4, 4), -1.0)
    """

    def __init__(self, inputs: np.ndarray, targets: np.ndarray, size: int,
                 device: torch.device, channels_last: bool = False,
                 input_reduce: str = "area", target_size: int | None = None):
        if len(inputs) != len(targets):
            raise ValueError("inputs and targets differ in length")
        if inputs.shape[-1] < size:
            raise InputError(None, f"dataset maps are {inputs.shape[-1]} px, smaller than "
                                   f"the training size {size}")
        self.x = torch.from_numpy(reduce_input(inputs, size, input_reduce))[:, None].to(device)
        ts = size if target_size is None else target_size
        self.y = torch.from_numpy(downsample_target(targets, ts))[:, None].to(device)
        self.channels_last = channels_last

    def __len__(self) -> int:
        return len(self.x)

    def batch(self, idx: torch.Tensor) -> tuple[torch.Tensor, torch.Tensor]:
        """Float batches in [-1, 1] of the pairs ``idx``."""
        idx = idx.to(self.x.device)
        x = self.x[idx].float() / 127.5 - 1.0
        y = self.y[idx].float() / 127.5 - 1.0
        if self.channels_last:
            x = x.contiguous(memory_format=torch.channels_last)
            y = y.contiguous(memory_format=torch.channels_last)
        return x, y


#: Fewer training pairs than this get a warning: pix2pix's smallest training set (CMP
#: Facades, Isola et al. 2017) had 400 pairs, the thesis's 4,224.
FEW_TRAIN_PAIRS = 400


def warn_about_data(src, n_train: int, n_val: int) -> None:
    """Warn of a training set too small to generalize from, and of no 'val' pairs (the
    sample grids then show training pairs).

    Examples
    --------
    >>> import warnings
    >>> with warnings.catch_warnings(record=True) as got:
    ...     warnings.simplefilter("always")
    ...     warn_about_data("ds", 1, 0)
    >>> [str(w.message)[:40] for w in got]
    ['ds: only 1 training pair: fewer than 400', "ds: no 'val' pairs: the sample grids (sa"]
    """
    import warnings

    from ...core.errors import MapWarning

    where = f"{src}: " if src is not None else ""
    if n_train < FEW_TRAIN_PAIRS:
        warnings.warn(
            f"{where}only {n_train} training pair{'s' if n_train != 1 else ''}: fewer than "
            f"{FEW_TRAIN_PAIRS} (pix2pix's smallest training set; the thesis trained on "
            "4,224), so the model will learn these pairs rather than maps in general",
            MapWarning, stacklevel=3)  # fmt: skip
    if n_val == 0:
        warnings.warn(
            f"{where}no 'val' pairs: the sample grids (samples/epoch_NNNN.png) show training "
            "pairs, which tell how well the model fits them, not how it does on new maps",
            MapWarning, stacklevel=3)  # fmt: skip
