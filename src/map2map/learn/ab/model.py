"""Model_AB as a file (thesis 3.1, CAD -> SLAM): its networks built from an
:class:`~map2map.learn.ab.config.ABConfig`, the header its weights carry, loading a run or
a weights file (:func:`load_ab_model`), the shipped weights (:func:`pretrained_ab_path`)
and their export (:func:`export_ab_model`). Weights are safetensors with a JSON header
(``format`` :data:`FORMAT_AB`), never pickle."""

from __future__ import annotations

import os
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
import torch

from ...core.errors import InputError
from ..nets.networks import from_unit
from ..nets.progressive import ProgMultiScaleDiscriminator, StochasticUNet
from ..training.data import reduce_input
from .config import ABConfig
from .render import DEFAULT_WALL_PX

__all__ = ["FORMAT_AB", "PRETRAINED", "ABModel", "build_ab_networks", "model_header_ab",
           "load_ab_model", "pretrained_ab_path", "export_ab_model"]

FORMAT_AB = "map2map-model-ab"



def build_ab_networks(cfg: ABConfig) -> tuple[StochasticUNet, ProgMultiScaleDiscriminator,
                                              ProgMultiScaleDiscriminator]:
    """``G`` (plan -> SLAM map), ``D_d`` (2 channels) and ``D_r`` of ``cfg``, seeded.

    Examples
    --------
    >>> cfg = ABConfig(schedule=((16, 1), (32, 1)), g_channels=8, d_channels=8, d_layers=1,
    ...                d_scales=2)
    >>> g, dd, dr = build_ab_networks(cfg)
    >>> [tuple(g(torch.zeros(1, 1, r, r)).shape[-2:]) for r in (16, 32)]
    [(16, 16), (32, 32)]
    """
    if cfg.min_size // 2 ** (cfg.d_scales - 1) < 2**cfg.d_layers:
        raise ValueError(f"at the first stage ({cfg.min_size} px) the coarsest discriminator "
                         f"scale is {cfg.min_size // 2 ** (cfg.d_scales - 1)} px, too small "
                         f"for {cfg.d_layers} stride-2 layers")
    torch.manual_seed(cfg.seed)
    g = StochasticUNet(cfg.size, cfg.g_channels, cfg.g_max_channels, cfg.bottleneck,
                       min_size=cfg.min_size, dropout=cfg.dropout, growth=cfg.growth)
    dd = ProgMultiScaleDiscriminator(2, cfg.d_channels, cfg.d_layers, cfg.d_scales, cfg.size,
                                     cfg.min_size)
    dr = ProgMultiScaleDiscriminator(1, cfg.d_channels, cfg.d_layers, cfg.d_scales, cfg.size,
                                     cfg.min_size)
    return g, dd, dr


PRETRAINED = "model_ab.safetensors"


def pretrained_ab_path() -> Path:
    """The shipped weights (``map2map/learn/ab/weights/model_ab.safetensors``)."""
    from ..training.checkpoint import shipped_weights

    return shipped_weights(__package__, PRETRAINED)


@dataclass
class ABModel:
    """A loaded Model_AB generator: the resolution it reached and its fade-in alpha."""

    generator: StochasticUNet
    resolution: int
    alpha: float
    data_size: int
    header: dict
    source: str
    device: torch.device = field(default_factory=lambda: torch.device("cpu"))

    @property
    def wall_px(self) -> float:
        """The training targets' wall thickness (px of a ``data_size`` square; header
        ``target_wall_px``, :data:`~map2map.learn.ab.render.DEFAULT_WALL_PX` if absent)."""
        return float(self.header.get("target_wall_px", DEFAULT_WALL_PX))

    @torch.no_grad()
    def sample(self, inputs: np.ndarray, samples: int, seed: int = 0) -> np.ndarray:
        """(data_size, data_size) uint8 plan -> (samples, r, r) float32 grey SLAM maps."""
        return self.sample_many(inputs[None], samples, seed)[0]

    @torch.no_grad()
    def sample_many(self, inputs: np.ndarray, samples: int = 1, seed: int = 0) -> np.ndarray:
        """(N, data_size, data_size) uint8 plans -> (N, samples, r, r) float32 grey maps,
        one batch (dropout masks drawn from ``seed``; ``samples == 1``: dropout off)."""
        how = self.header.get("train", {}).get("input_reduce", "area")
        g = self.generator
        decoder = getattr(g, "growth", "full") == "decoder"
        size = g.size if decoder else self.resolution
        g.out_size = self.resolution
        n = len(inputs)
        x = torch.from_numpy(reduce_input(np.asarray(inputs, np.uint8), size, how))[:, None]
        x = (x.float() / 127.5 - 1.0).to(self.device)
        x = x[:, None].expand(-1, samples, -1, -1, -1).reshape(n * samples, 1, size, size)
        alpha = torch.tensor(self.alpha, device=self.device) if self.alpha < 1.0 else None
        g.stochastic = samples > 1
        with torch.random.fork_rng(devices=[self.device] if self.device.type == "cuda" else []):
            torch.manual_seed(seed)
            y = g(x.contiguous(), alpha)
        g.stochastic = False
        out = from_unit(y[:, 0])
        return out.reshape(n, samples, *out.shape[-2:])


def load_ab_model(model: str | os.PathLike | ABModel | None = "pretrained",
                  device: str | torch.device = "cpu") -> ABModel:
    """Model_AB from ``"pretrained"``, a ``map2map train ab`` run folder or its
    ``model.safetensors``."""
    if isinstance(model, ABModel):
        return model
    from ..training.checkpoint import load_generator, read_model_file

    path, header, tensors = read_model_file(
        model, pretrained_ab_path(), FORMAT_AB, "Model_AB",
        no_pretrained="no pretrained Model_AB weights in this installation",
        missing="no Model_AB weights here (expected a 'map2map train ab' "
                "run folder holding model.safetensors, or that file)",
        wrong="not a Model_AB weights file (no map2map-model-ab header; "
              "Model_BA weights go to 'map2map autocorrect')",
    )  # fmt: skip
    if "resolution" not in header:
        raise InputError(path, "the run has not finished an epoch yet (no resolution)")
    g = StochasticUNet(**{k: v for k, v in header["generator"].items() if k != "dropout"},
                       dropout=header["generator"].get("dropout", 0.5))
    dev = load_generator(g, tensors, path, device)
    return ABModel(g, int(header["resolution"]), float(header.get("alpha", 1.0)),
                   int(header.get("data_size", 256)), header, str(path), dev)


def export_ab_model(run: str | os.PathLike, dest: str | os.PathLike, *, note: str = ""
                    ) -> Path:
    """A run's generator in float16 with its header (and ``note``) plus a readable
    ``.json`` beside it: how the shipped ``model_ab.safetensors`` is made."""
    from ..training.checkpoint import export_generator

    return export_generator(run, dest, lambda p: load_ab_model(p).header, note=note)


def model_header_ab(cfg: ABConfig, meta: dict, extra: dict) -> dict:
    """The JSON stored with the generator: what :func:`~map2map.learn.ab.synthesize.synthesize`
    needs and where it came from."""
    return {"format": FORMAT_AB,
            "generator": dict(size=cfg.size, channels=cfg.g_channels,
                              max_channels=cfg.g_max_channels, bottleneck=cfg.bottleneck,
                              min_size=cfg.min_size, dropout=cfg.dropout, growth=cfg.growth),
            "train": cfg.to_dict(), "dataset": meta, **extra}
