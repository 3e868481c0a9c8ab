"""Model_BA as a file (thesis 3.1, SLAM -> CAD): its networks built from a
:class:`~map2map.learn.ba.config.BAConfig`, the header its weights carry, loading a run
or a weights file (:func:`load_model`), the shipped weights (:func:`pretrained_path`) and
their export (:func:`export_model`). Weights are safetensors with a JSON header
(``format`` :data:`FORMAT`), never pickle."""

from __future__ import annotations

import os
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
import torch

from ..nets.networks import MultiScaleDiscriminator, UNetGenerator, from_unit
from ..training.data import reduce_input
from .config import BAConfig

__all__ = ["FORMAT", "PRETRAINED", "BAModel", "build_networks", "model_header", "load_model",
           "pretrained_path", "export_model", "CPU_CHUNK"]


FORMAT = "map2map-model-ba"


def build_networks(cfg: BAConfig) -> tuple[UNetGenerator, MultiScaleDiscriminator,
                                              MultiScaleDiscriminator]:
    """``G``, ``D_d`` (2 channels: input and output) and ``D_r`` (1 channel) of ``cfg``,
    initialised from ``cfg.seed``."""
    torch.manual_seed(cfg.seed)
    g = UNetGenerator(cfg.size, cfg.g_channels, cfg.g_max_channels, cfg.bottleneck)
    dd = MultiScaleDiscriminator(2, cfg.d_channels, cfg.d_layers, cfg.d_scales)
    dr = MultiScaleDiscriminator(1, cfg.d_channels, cfg.d_layers, cfg.d_scales)
    return g, dd, dr


def model_header(cfg: BAConfig, meta: dict, extra: dict) -> dict:
    """The JSON stored with the generator: what inference needs and where it came from."""
    return {"format": FORMAT, "generator": dict(size=cfg.size, channels=cfg.g_channels,
                                                max_channels=cfg.g_max_channels,
                                                bottleneck=cfg.bottleneck),
            "train": cfg.to_dict(), "dataset": meta, **extra}


PRETRAINED = "model_ba.safetensors"


CPU_CHUNK = 16  # maps per forward pass on the CPU (BAModel.predict)


def pretrained_path() -> Path:
    """The weights shipped in the package (``map2map/learn/ba/weights/model_ba.safetensors``)."""
    from ..training.checkpoint import shipped_weights

    return shipped_weights(__package__, PRETRAINED)


@dataclass
class BAModel:
    """A loaded Model_BA generator and what inference needs to know about its training."""

    generator: UNetGenerator
    size: int
    data_size: int
    target_wall_px: float
    header: dict
    source: str
    device: torch.device = field(default_factory=lambda: torch.device("cpu"))

    def predict(self, inputs: np.ndarray, batch: int = 256) -> np.ndarray:
        """(N, data_size, data_size) uint8 maps -> (N, size, size) float32 grey outputs.

        On the CPU the network runs on chunks of at most :data:`CPU_CHUNK` maps whatever
        ``batch`` says: a small chunk's activations stay in the cache (measured about 1.5x
        faster than one batch of 256 on 2 cores); the outputs do not depend on it."""
        how = self.header.get("train", {}).get("input_reduce", "area")
        small = reduce_input(inputs, self.size, how)
        if self.device.type == "cpu":
            batch = min(batch, CPU_CHUNK)
        out = []
        with torch.inference_mode():
            for i in range(0, len(small), batch):
                x = torch.from_numpy(small[i:i + batch])[:, None].to(self.device)
                y = self.generator(x.float() / 127.5 - 1.0)
                out.append(from_unit(y[:, 0]))
        return np.concatenate(out) if out else np.zeros((0, self.size, self.size), np.float32)


def load_model(model: str | os.PathLike | BAModel | None = "pretrained",
               device: str | torch.device = "cpu") -> BAModel:
    """Load Model_BA from ``"pretrained"`` (the shipped weights), a training run folder
    (its ``model.safetensors``) or a ``.safetensors`` file written by the trainer."""
    if isinstance(model, BAModel):
        return model
    from ..training.checkpoint import load_generator, read_model_file

    path, header, tensors = read_model_file(
        model, pretrained_path(), FORMAT, "Model_BA",
        no_pretrained="no pretrained weights in this installation",
        missing="no Model_BA weights here (expected a training run "
                "folder holding model.safetensors, or that file)",
        wrong="not a Model_BA weights file (no map2map-model-ba header)",
    )  # fmt: skip
    g = UNetGenerator(**header["generator"])
    dev = load_generator(g, tensors, path, device)
    return BAModel(g, int(header["generator"]["size"]), int(header.get("data_size", 256)),
                   float(header.get("target_wall_px", 2.0)), header, str(path), dev)


def export_model(run: str | os.PathLike, dest: str | os.PathLike, *, note: str = "") -> Path:
    """Copy a run's generator to ``dest`` in float16 with its header (and ``note``), plus a
    readable ``.json`` beside it: how the shipped ``model_ba.safetensors`` is made
    (:func:`~map2map.learn.training.checkpoint.export_generator` with :func:`load_model`).

    Examples
    --------
    >>> import tempfile, pathlib
    >>> d = pathlib.Path(tempfile.mkdtemp())
    >>> p = export_model(pretrained_path(), d / "m.safetensors", note="copy")
    >>> load_model(p).header["note"]
    'copy'
    """
    from ..training.checkpoint import export_generator

    return export_generator(run, dest, lambda p: load_model(p).header, note=note)
