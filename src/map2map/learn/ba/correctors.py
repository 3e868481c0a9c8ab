"""The correctors ``map2map autocorrect --model`` chooses between (issue #32): the same
pipeline (:mod:`~map2map.learn.ba.autocorrect`: content square, deskew, post-processing,
back to the input's frame) with or without a network inside.

* :class:`NullCorrector` (``none``): the classical cleaning alone. The anchored
  post-processing (:func:`~map2map.learn.ba.postprocess.postprocess`, step 4b) runs with
  :class:`NullNetwork` in the network's place, an output that draws no wall and calls
  everything free: the input's own walls straightened on the median of their faces,
  pieces of one wall line put on one line, two-sided walls grown to the plan's
  thickness, free specks made unknown, and every input wall pixel that no straight wall
  explains dropped as clutter (the network keeps those it draws a wall near). No
  weights are read: it runs where the shipped file is missing or unreadable.
* :class:`ThesisCorrector` (``thesis``, and any weights file or training run): the
  thesis's Model_BA, Model_32 (the generator of eqs. 3.1-3.7) followed by the same
  post-processing; ``"pretrained"`` is the shipped weights.

Both follow the protocol of :class:`map2map.jobs.autocorrect.Corrector`: a ``name``,
a ``source`` and ``correct_many(maps, **options) -> list[OccupancyMap]``, each output
in its input's frame with ``meta["autocorrect"]`` (wall segments, warnings, ``model``);
``options`` are those of :func:`~map2map.learn.ba.autocorrect.autocorrect_many`.
Measured side by side by ``python -m map2map.experiments.table53 --models none thesis``.

Examples
--------
>>> import numpy as np
>>> from map2map.core.grid import OccupancyMap
>>> data = np.full((90, 140), 127, np.uint8)
>>> data[10:80, 10:130] = 255; data[10, 10:130] = 0; data[79, 10:130] = 0
>>> data[10:80, 10] = 0; data[10:80, 129] = 0
>>> out = NullCorrector().correct_many([OccupancyMap(data, 0.05)])[0]
>>> out.shape, out.meta["autocorrect"]["model"]
((90, 140), 'none')
"""

from __future__ import annotations

import os
from dataclasses import dataclass, field

import numpy as np

from ...core.errors import InputError
from ...core.grid import FREE, OccupancyMap

__all__ = ["NullNetwork", "NullCorrector", "ThesisCorrector", "PLAN_WALL_PX"]

#: Thickness (pixels at the dataset's 256 px) of the training plans' walls, what the
#: shipped weights' header says (``target_wall_px``, measured on gen6400's train plans):
#: how thick :class:`NullNetwork` has the walls seen from one side drawn, as Model_BA does.
PLAN_WALL_PX = 5.528186639013267


@dataclass
class NullNetwork:
    """A stand-in for Model_BA's generator that draws no wall: every output cell free.

    It has what :func:`~map2map.learn.ba.autocorrect.autocorrect_many` reads of a network
    (``size``, ``data_size``, ``target_wall_px``, ``header``, ``source``, ``predict``)
    and no weights; ``learnt`` is False, so no warning speaks of what a model learnt.

    Examples
    --------
    >>> NullNetwork().predict(np.zeros((2, 256, 256), np.uint8)).shape
    (2, 64, 64)
    """

    size: int = 64
    data_size: int = 256
    target_wall_px: float = PLAN_WALL_PX
    header: dict = field(default_factory=lambda: {
        "dataset": {"identity": {"resolution": 0.05}}})
    source: str = "none"
    learnt: bool = False

    def predict(self, inputs: np.ndarray, batch: int = 256) -> np.ndarray:
        """(N, ...) maps -> (N, size, size) float32 outputs, all free (255)."""
        return np.full((len(inputs), self.size, self.size), float(FREE), np.float32)


class NullCorrector:
    """``none``: the post-processing with :class:`NullNetwork` inside (module docstring).

    Only the anchored, straightened pipeline has a meaning without a network:
    ``anchor=False`` or ``straighten=False`` (which draw the network's walls only) raise
    :class:`~map2map.core.errors.InputError`; ``device`` is ignored.
    """

    name = "none"
    source = "none"

    def correct_many(self, maps: list[OccupancyMap], **options) -> list[OccupancyMap]:
        from .autocorrect import autocorrect_many

        if options.get("anchor", True) is False or options.get("straighten", True) is False:
            raise InputError("model", "'none' is the anchored, straightened post-processing "
                                      "alone: anchor=False and straighten=False "
                                      "(--no-anchor, --no-straighten) need a network")
        options.pop("device", None)
        return [r.map for r in autocorrect_many(maps, NullNetwork(), **options)]


class ThesisCorrector:
    """The thesis's Model_BA: Model_32 (eqs. 3.1-3.7) and its post-processing.

    Parameters
    ----------
    weights : "pretrained", run folder or weights file
        Loaded at once (:func:`~map2map.learn.ba.model.load_model`: one clear error for a
        missing or wrong file).
    device : str
        Torch device.
    name : str, optional
        What tables and messages call it (default ``"thesis"`` for the shipped weights,
        else the path as given).
    """

    def __init__(self, weights: str | os.PathLike = "pretrained", device: str = "cpu",
                 name: str | None = None):
        from .model import load_model

        self.net = load_model(weights, device)
        self.device = device
        self.name = name or ("thesis" if str(weights) == "pretrained" else os.fspath(weights))
        self.source = self.net.source

    def correct_many(self, maps: list[OccupancyMap], **options) -> list[OccupancyMap]:
        from .autocorrect import autocorrect_many

        options.pop("device", None)
        return [r.map for r in autocorrect_many(maps, self.net, device=self.device,
                                                **options)]
