"""Training configuration of Model_BA (thesis sec. 4.2, 5.1) and Table 5.1's batch mapping.

Defaults follow the thesis where it says something: Adam with learning rate 2e-4 and
betas (0.55, 0.99), the learning rate constant for the first 70 % of the epochs and then
decaying linearly (to zero after the last epoch), batch size ``batch_rate *
batch_mapping[resolution]`` with Table 5.1's mapping and ``batch_rate = 0.5`` for
Model_BA, no augmentation (sec. 4.2 removed it for Model_BA). Where it is silent
(lambda, channel widths) the choice is ours and stated here. The thesis trained Model_BA
at 32 x 32 (Model_32, ``size=32``); the default here is 64, which measured better.

Examples
--------
>>> batch_size(32, 0.5)            # Table 5.1: 64 at 32 px, times Model_BA's batch_rate
32
>>> TrainConfig().batch_size       # at the default 64 px: 32 x 0.5
16
>>> cfg = TrainConfig(epochs=10)
>>> [round(lr_factor(e, cfg), 3) for e in range(10)]
[1.0, 1.0, 1.0, 1.0, 1.0, 1.0, 1.0, 0.75, 0.5, 0.25]
>>> TrainConfig.from_dict(cfg.to_dict()) == cfg
True
"""

from __future__ import annotations

from dataclasses import asdict, dataclass, fields

__all__ = ["BATCH_MAPPING", "batch_size", "TrainConfig", "lr_factor"]

#: Table 5.1: batch size per current resolution (before ``batch_rate``).
BATCH_MAPPING = {4: 128, 8: 64, 16: 128, 32: 64, 64: 32, 128: 16, 256: 4}


def batch_size(resolution: int, batch_rate: float) -> int:
    """``batch_rate * batch_mapping[resolution]`` (Table 5.1), at least 1."""
    if resolution not in BATCH_MAPPING:
        raise ValueError(f"Table 5.1 has no batch size for resolution {resolution}")
    return max(1, int(round(BATCH_MAPPING[resolution] * batch_rate)))


@dataclass
class TrainConfig:
    """Every setting of a Model_BA training run (saved with the run as ``config.json``).

    Parameters
    ----------
    size : int
        Training resolution, up to the dataset's. 32 is the thesis's Model_BA (Model_32);
        the default is 64, which beat Model_32 on the same held-out maps and the same
        training time (``docs/autocorrect.md``).
    epochs : int
        Number of epochs.
    batch : int or None
        Batch size; None: Table 5.1's mapping times ``batch_rate``.
    batch_rate : float
        0.5 for Model_BA (thesis 5.1).
    lr, beta1, beta2 : float
        Adam (thesis 4.2).
    decay_start : float
        Share of the epochs after which the learning rate decays linearly.
    lambda_l1, lambda_fm, lambda_ic : float
        Weights of eqs. 3.7, 3.5, 3.6 in eq. 3.2 (the thesis gives no lambda; 100 is
        pix2pix's, FM and IC are unweighted in eq. 3.2).
    false_targets : bool
        False-target augmentation for ``D_d`` (sec. 3.1).
    g_channels, g_max_channels, bottleneck : int
        Generator width at ``size``, channel cap, resolution of its deepest level.
    d_channels, d_layers, d_scales : int
        Discriminator width, stride-2 layers per patch discriminator, number of scales.
    seed : int
        Seeds the weights' initialisation, the shuffling and the false-target draws.
    device : str
        ``"auto"`` (CUDA when present), ``"cpu"``, ``"cuda"``, ``"cuda:1"``...
    amp : bool
        bf16 autocast + channels_last on CUDA (ignored on CPU).
    channels_last : bool
        Under ``amp``, networks and data in channels-last layout (the default); False
        keeps them NCHW (``python -m benchmarks.bench_ab --nchw`` measures which is
        faster: GroupNorm returns NCHW, so cuDNN may transpose around each convolution
        after it). No effect on CPU or without ``amp``.
    compile : bool
        ``torch.compile`` the generator (not the spectral-normalised discriminators).
    cuda_graph : bool
        Run each training step as one CUDA graph replay
        (:class:`~map2map.learn.training.static_step.StaticStep`): one graph per (resolution,
        batch size), captured after 3 eager warm-up steps; a capture failure falls back
        to eager steps with a warning. Single process only (under DDP, or with
        ``compile``, the steps run eagerly); on CPU the same static step runs eagerly
        (bit-identical to the default). Off by default until measured on a GPU.
    samples : int
        Validation pairs shown in each epoch's sample grid.
    save_every : int
        Checkpoint, sample grid and logs every this many epochs (and after the last, and
        on Ctrl-C). 1 (default): every epoch; a GPU run whose epochs take a fraction of a
        second would otherwise spend more time writing checkpoints than training.
    input_reduce : {"area", "classes"}
        How the input (SLAM map) is brought to ``size``: ``"area"`` averages grey values
        (a one-pixel wall becomes a faint line), ``"classes"`` reduces per class as the
        targets are (walls kept dark; :func:`map2map.learn.training.data.downsample_target`).
    """

    size: int = 64
    epochs: int = 200
    batch: int | None = None
    batch_rate: float = 0.5
    lr: float = 2e-4
    beta1: float = 0.55
    beta2: float = 0.99
    decay_start: float = 0.7
    lambda_l1: float = 100.0
    lambda_fm: float = 1.0
    lambda_ic: float = 1.0
    false_targets: bool = True
    g_channels: int = 32
    g_max_channels: int = 128
    bottleneck: int = 4
    d_channels: int = 32
    d_layers: int = 3
    d_scales: int = 3
    seed: int = 0
    device: str = "auto"
    amp: bool = True
    channels_last: bool = True
    compile: bool = False
    cuda_graph: bool = False
    samples: int = 6
    save_every: int = 1
    input_reduce: str = "area"

    @property
    def batch_size(self) -> int:
        return self.batch if self.batch else batch_size(self.size, self.batch_rate)

    def to_dict(self) -> dict:
        return asdict(self)

    @classmethod
    def from_dict(cls, d: dict) -> TrainConfig:
        names = {f.name for f in fields(cls)}
        return cls(**{k: v for k, v in d.items() if k in names})


def lr_factor(epoch: int, cfg: TrainConfig) -> float:
    """Learning-rate multiplier of 0-based ``epoch``: 1 until ``decay_start * epochs``, then
    linear towards 0 (thesis 4.2). A pure function of the epoch, so resuming needs no
    scheduler state beyond the epoch number."""
    start = int(round(cfg.decay_start * cfg.epochs))
    if epoch < start:
        return 1.0
    return 1.0 - (epoch - start + 1) / (cfg.epochs - start + 1)
