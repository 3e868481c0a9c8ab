"""The network of ``map2map autocorrect --model none``: a stand-in for Model_BA's generator
that draws no wall (:class:`NullNetwork`), so that the pipeline of
:mod:`~map2map.learn.ba.autocorrect` runs as the classical cleaning alone
(:class:`~map2map.learn.ba.correctors.NullCorrector`). No torch, no weights."""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from ...core.grid import FREE

__all__ = ["NullNetwork", "PLAN_WALL_PX"]

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
