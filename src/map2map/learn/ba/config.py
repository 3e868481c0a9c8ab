"""Model_BA's settings (thesis 3.1, 4.2; Table 5.1 at ``batch_rate`` 0.5): the shared
:class:`~map2map.learn.training.config.TrainConfig`, whose defaults are Model_BA's, as
the model's own type (what ``map2map train ba`` and ``config.json`` use).

Examples
--------
>>> cfg = BAConfig(size=32)                      # the thesis's Model_32
>>> cfg.batch_size, BAConfig.from_dict(cfg.to_dict()) == cfg
(32, True)
"""

from __future__ import annotations

from dataclasses import dataclass

from ..training.config import TrainConfig

__all__ = ["BAConfig"]


@dataclass
class BAConfig(TrainConfig):
    """Every setting of a Model_BA training run (:class:`TrainConfig`'s fields and
    defaults: size 64, batch_rate 0.5, lambda_l1 100, ...)."""
