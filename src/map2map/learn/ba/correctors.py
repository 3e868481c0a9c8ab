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

from ...core.grid import OccupancyMap
from .null import PLAN_WALL_PX, NullNetwork

__all__ = ["NullNetwork", "NullCorrector", "ThesisCorrector", "PLAN_WALL_PX"]

class NullCorrector:
    """``none``: the post-processing with :class:`NullNetwork` inside (module docstring).

    Only the anchored, straightened pipeline has a meaning without a network:
    ``anchor=False`` or ``straighten=False`` (which draw the network's walls only) raise
    :class:`~map2map.core.errors.InputError` (in
    :func:`~map2map.learn.ba.autocorrect.autocorrect_many`); ``device`` is ignored.
    """

    name = "none"
    source = "none"

    def correct_many(self, maps: list[OccupancyMap], **options) -> list[OccupancyMap]:
        from .autocorrect import autocorrect_many

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
