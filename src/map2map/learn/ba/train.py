"""Training loop of Model_BA (``map2map train ba``), thesis sec. 4.2 and 5.1.

One step (a batch of SLAM maps ``x`` and their plans ``y``, in [-1, 1]):

1. ``G(x)``;
2. discriminators (eq. 3.2, max side): ``D_d`` sees the associated pairs ``(x, y)`` as
   real and both the generated pairs ``(x, G(x))`` and the false pairs ``(x, y')`` as not
   associated, ``y'`` being the batch's targets rolled by a random shift in ``1..B-1`` (a
   derangement: every input gets another input's target, untransformed -- the same maps
   the real pairs use, so ``D_d`` can only tell them apart by association); ``D_r`` sees
   ``y`` as real and ``G(x)`` as fake. Each discriminator runs once on the concatenated
   batch;
3. generator (min side): eqs. 3.3 + 3.4 (non-saturating) + 3.5 + 3.6 + lambda 3.7.

Adam (2e-4, betas 0.55/0.99) for ``G`` and for both discriminators; the learning rate is
a pure function of the epoch (:func:`~map2map.learn.training.config.lr_factor`). On CUDA: bf16
autocast with the output head and the losses in fp32, channels_last, data resident on the
GPU; ``torchrun --nproc_per_node K -m map2map train ba ...`` runs DDP (NCCL on GPUs,
gloo on CPU): every process draws the same permutation and takes its share of each batch.

A run folder holds ``config.json`` (configuration, dataset identity, network sizes),
``model.safetensors`` (the generator, with that configuration in its header: all
``map2map autocorrect --model RUN`` needs), ``last.safetensors`` (everything needed to
resume exactly: weights, optimiser moments, random-generator state, epoch and position
in it, loss history), ``log.csv`` (every logged value, one row per epoch),
``losses.png`` (thesis Fig. 5.2) and ``samples/epoch_NNNN.png`` (input | output | target).
Checkpoints are written atomically after every epoch and on Ctrl-C. The machinery (device,
DDP, resident data, checkpoints and exact resume, logs, figures, progress) is the one
Model_AB uses too (:mod:`~map2map.learn.training.loop`); this module states only Model_BA's part.

Examples
--------
>>> import tempfile, pathlib, numpy as np
>>> rng = np.random.default_rng(0)
>>> a = rng.choice(np.array([0, 127, 255], np.uint8), size=(4, 32, 32))
>>> pairs = PackedPairs(a, a[:, :, ::-1], np.arange(4).astype(str), np.array(["train"] * 4))
>>> cfg = BAConfig(size=16, epochs=1, batch=2, g_channels=8, d_channels=8, d_layers=2)
>>> run = pathlib.Path(tempfile.mkdtemp()) / "run"
>>> result = train_ba(pairs, run, cfg, progress=False, figures=False)
>>> result.epochs_done, sorted(p.name for p in run.iterdir())
(1, ['config.json', 'last.safetensors', 'log.csv', 'model.safetensors', 'samples'])
"""

from __future__ import annotations

import os

from ...core.errors import InputError
from ...datasets.packed import PackedPairs
from ..training.data import ResidentPairs
from ..training.loop import EpochPlan, GANRun, RunStart, TrainResult, batches_per_epoch, open_run
from ..training.step import gan_step
from .config import BAConfig
from .model import FORMAT, build_networks, model_header

__all__ = ["train_ba"]


class _BARun(GANRun):
    """Model_BA's part of the loop: one resolution, one batch size, no fade-in."""

    fmt = FORMAT
    desc = "train ba"

    def __init__(self, start: RunStart, nets, header: dict, data: ResidentPairs,
                 shown: ResidentPairs, **kw):
        super().__init__(start, nets, header, **kw)
        B = self.cfg.batch_size
        self.plan = EpochPlan(data, shown, B, batches_per_epoch(self.n, B, self.dist.world))

    def epoch_plan(self, epoch: int) -> EpochPlan:
        return self.plan

    def batches_in(self, epoch: int) -> int:
        return self.plan.batches

    def step(self, epoch, b, idx, x, y, shift) -> dict:
        if self.static is not None:  # cfg.cuda_graph
            return self.static(x, y, shift)
        return gan_step(self.g_run, self.dd_run, self.dr_run, self.opt_g, self.opt_d, x, y,
                        None, self.cfg, shift, self.autocast, self.freeze)


def train_ba(data: str | os.PathLike | PackedPairs, out: str | os.PathLike,
             config: BAConfig | None = None, *, resume: bool = False,
             epochs: int | None = None, progress: bool = True, figures: bool = True
             ) -> TrainResult:
    """Train Model_BA (input: SLAM map ``b``, target: plan ``a``) on the ``train`` split.

    Parameters
    ----------
    data : path or PackedPairs
        A dataset folder (``packed.npz`` inside), a packed ``.npz``, or pairs in memory.
    out : path
        Run folder (created).
    config : BAConfig
        Settings (defaults: see :class:`BAConfig`); ignored when resuming, except
        ``epochs`` (which may extend a run).
    resume : bool
        Continue the run in ``out`` exactly where its last checkpoint stopped.
    progress : bool
        tqdm bar (epoch, images/s, losses, ETA).
    figures : bool
        Write ``losses.png`` and the per-epoch sample grids.

    Returns
    -------
    TrainResult
    """
    start = open_run(data, out, config, config_type=BAConfig, fmt=FORMAT,
                     model="Model_BA", resume=resume, epochs=epochs)
    cfg, pairs, train, dist = start.cfg, start.pairs, start.train, start.dist
    smallest = cfg.size // 2 ** (cfg.d_scales - 1)
    if smallest < 2**cfg.d_layers:
        raise InputError("size", f"at {cfg.size} px the coarsest discriminator scale is "
                                   f"{smallest} px, too small for {cfg.d_layers} stride-2 "
                                   "layers (use a larger `size` or fewer `d_layers`)")
    if pairs.a.shape[-1] < cfg.size:
        raise InputError(None, f"dataset maps are {pairs.a.shape[-1]} px; cannot train at "
                               f"{cfg.size}")
    B = cfg.batch_size
    if batches_per_epoch(len(train), B, dist.world) == 0:
        raise InputError(None, f"{len(train)} training pairs are fewer than one batch of {B}")
    val = pairs.select("val")
    show = val if len(val) else train
    dev, amp = dist.device, dist.device.type == "cuda" and cfg.amp
    cl = amp and cfg.channels_last
    res = ResidentPairs(train.b, train.a, cfg.size, dev, channels_last=cl,
                        input_reduce=cfg.input_reduce)
    shown = ResidentPairs(show.b[:cfg.samples], show.a[:cfg.samples], cfg.size, dev,
                          channels_last=cl, input_reduce=cfg.input_reduce)
    nets = build_networks(cfg)
    header = model_header(cfg, start.meta,
                          GANRun.header_fields(train.a, pairs.a.shape[-1], nets))
    return _BARun(start, nets, header, res, shown, progress=progress, figures=figures).run()
