"""Training loop of Model_AB, CAD plan -> SLAM map, grown progressively (``map2map train
ab``), thesis sec. 3.1 and 5.1 (Figs. 5.1, 5.3, Tables 5.1-5.2).

The objective is eq. 3.2 with the roles of the maps swapped against Model_BA: the input
``x`` is the plan (``a`` of the packed pairs), the target ``y`` the SLAM map (``b``).
``D_d`` (eq. 3.3, with false targets: other plans' SLAM maps), ``D_r`` (eq. 3.4), feature
matching (3.5), input consistency (3.6) and L1 (3.7) are the functions of
:mod:`~map2map.learn.nets.losses`; the networks are those of :mod:`~map2map.learn.nets.progressive`
(generator and both discriminators grown coarse to fine, each new block faded in).

The training loop is the one Model_BA uses (:mod:`~map2map.learn.training.loop`; this module
states only the stages, the fade-in and the stage switches): data resident on the device
(:class:`~map2map.learn.training.data.ResidentPairs`, one per stage, built when the stage starts),
Adam 2e-4 / (0.55, 0.99) with the learning rate a pure function of the epoch
(:func:`~map2map.learn.training.config.lr_factor` over all the epochs), safetensors checkpoints
written atomically after every epoch and on Ctrl-C, exact ``--resume`` (the dropout's
random state is saved too; the stage and the fade-in alpha are functions of (epoch,
batch), so nothing else has to be stored), DDP under
``torchrun`` (``find_unused_parameters``: the blocks of the stages not reached have no
gradient), bf16 autocast + channels_last on CUDA.

A run folder holds ``config.json``, ``model.safetensors`` (generator + header: the
resolution reached and its alpha), ``last.safetensors``, ``log.csv`` (one row per epoch
with its resolution, batch size and alpha), ``losses.png`` (Fig. 5.1, resolution switches
marked) and ``samples/epoch_NNNN.png`` (plan | generated | simulated SLAM map).

Examples
--------
>>> import tempfile, pathlib, numpy as np
>>> plans = np.random.default_rng(0).choice(np.array([0, 127, 255], np.uint8), (4, 32, 32))
>>> pairs = PackedPairs(plans, plans.transpose(0, 2, 1).copy(), np.array(list("abcd")),
...                     np.full(4, "train"))
>>> cfg = ABConfig(schedule=((16, 1), (32, 1)), batch=2, g_channels=8, g_max_channels=16,
...                d_channels=8, d_layers=1, d_scales=2, fade_batches=4)
>>> run = pathlib.Path(tempfile.mkdtemp()) / "run"
>>> result = train_ab(pairs, run, cfg, progress=False, figures=False)
>>> [(r["resolution"], r["alpha"]) for r in result.history]
[(16, 1.0), (32, 0.25)]
"""

from __future__ import annotations

import math
import os

import torch

from ...core.errors import InputError
from ...datasets.packed import PackedPairs
from ..nets.progressive import fade_alpha
from ..training.data import ResidentPairs
from ..training.figures import save_loss_curves
from ..training.loop import EpochPlan, GANRun, RunStart, TrainResult, batches_per_epoch, open_run
from ..training.step import gan_step
from .config import ABConfig, fade_steps, stage_of
from .model import FORMAT_AB, build_ab_networks, model_header_ab

__all__ = ["train_ab", "save_prog_loss_curves", "schedule_table"]



def schedule_table(cfg: ABConfig, n_train: int) -> list[dict]:
    """Per stage: resolution, epochs (first, last), batch size, batches per epoch and the
    fade-in length in batches (the numbers ``map2map train ab`` prints).

    Examples
    --------
    >>> [(s["resolution"], s["batch"], s["batches_per_epoch"], s["fade_batches"])
    ...  for s in schedule_table(ABConfig(), 4224)]
    [(32, 64, 66, 0), (64, 32, 132, 1980), (128, 16, 264, 7920), (256, 4, 1056, 52800)]
    """
    rows, start = [], 0
    for i, (r, e) in enumerate(cfg.schedule):
        if i == len(cfg.schedule) - 1:
            e = max(e, cfg.epochs - start)
        B = cfg.stage_batch(r)
        nb = max(1, math.ceil(n_train / B))
        rows.append({"resolution": r, "first_epoch": start + 1, "last_epoch": start + e,
                     "batch": B, "batches_per_epoch": nb, "fade_batches": fade_steps(i, nb, cfg)})
        start += e
    return rows


def save_prog_loss_curves(history: list[dict], path: str | os.PathLike,
                          title: str = "Model_AB") -> None:
    """G and D losses per epoch as thesis Fig. 5.1, a dashed line and the new resolution
    at every stage switch, the terms of eq. 3.2 in a second panel
    (:func:`~map2map.learn.training.figures.save_loss_curves` with Fig. 5.1's title).

    Examples
    --------
    >>> import tempfile, pathlib
    >>> rows = [{"epoch": e, "loss_G": 3.0 - e / 9, "loss_D": 1.2, "resolution": r}
    ...         for e, r in ((1, 32), (2, 32), (3, 64))]
    >>> p = pathlib.Path(tempfile.mkdtemp()) / "l.png"; save_prog_loss_curves(rows, p)
    >>> p.stat().st_size > 1000
    True
    """
    save_loss_curves(history, path, title, figure="5.1")


def train_ab(data: str | os.PathLike | PackedPairs, out: str | os.PathLike,
             config: ABConfig | None = None, *, resume: bool = False,
             epochs: int | None = None, progress: bool = True,
             figures: bool = True) -> TrainResult:
    """Train Model_AB (input: CAD plan ``a``, target: SLAM map ``b``) progressively, the
    networks grown stage by stage with a fade-in (:mod:`~map2map.learn.nets.progressive`).

    Parameters
    ----------
    data, out : path or PackedPairs, path
        The pairs (:func:`~map2map.learn.training.loop.open_run`: their plans are the
        inputs, their SLAM maps the targets) and the run folder, created (or, with
        ``resume``, continued).
    config : ABConfig
        Settings (default: Table 5.2's schedule, Table 5.1's batches with batch_rate 1);
        ignored when resuming, except ``epochs``.
    resume : bool
        Continue the run in ``out`` exactly (same stage, batch and alpha).
    epochs : int, optional
        Total epochs (with ``resume``: extend the run; extra epochs stay at the last
        resolution).
    progress, figures : bool
        tqdm bar; ``losses.png`` and per-epoch sample grids.

    Returns
    -------
    TrainResult
        ``history`` rows carry ``resolution``, ``batch``, ``alpha`` (at the epoch's end)
        and ``fade_batches`` besides the losses.
    """
    start = open_run(data, out, config, config_type=ABConfig, fmt=FORMAT_AB, model="Model_AB",
                     resume=resume, epochs=epochs, find_unused=True)
    cfg, pairs, train, src = start.cfg, start.pairs, start.train, start.source
    if pairs.a.shape[-1] < cfg.size:
        raise InputError(src, f"dataset maps are {pairs.a.shape[-1]} px; the schedule "
                              f"ends at {cfg.size}")
    try:
        nets = build_ab_networks(cfg)
    except ValueError as exc:
        raise InputError("schedule", str(exc)) from None
    for r, _ in cfg.schedule:
        if batches_per_epoch(len(train), cfg.stage_batch(r), start.dist.world) == 0:
            raise InputError(src, f"{len(train)} training pairs are fewer than one batch of "
                                  f"{cfg.stage_batch(r)} at {r} px")
    fields = GANRun.header_fields(train.b, pairs.a.shape[-1], nets)
    header = model_header_ab(cfg, start.meta, {**fields, "direction": "CAD -> SLAM",
                                               "schedule_table": schedule_table(cfg, len(train))})
    return _ABRun(start, nets, header, progress=progress, figures=figures).run()


class _ABRun(GANRun):
    """Model_AB's part of the loop: a resolution and batch size per stage (its data put
    on the device when the stage starts), the fade-in alpha a function of (epoch, batch),
    stage switches marked in the loss curves."""

    fmt = FORMAT_AB
    desc = "train ab"
    torch_rng = True  # the dropout masks draw from torch's global generator
    title, figure = "Model_AB", "5.1"

    def __init__(self, start: RunStart, nets, header: dict, **kw):
        super().__init__(start, nets, header, **kw)
        val = start.pairs.select("val")
        self.show = val if len(val) else start.train
        self.alpha_t = torch.zeros((), device=self.dev)  # updated in place for the whole run
        self.decoder = self.cfg.growth == "decoder"
        self.resident: dict[int, tuple[ResidentPairs, ResidentPairs]] = {}
        self.full_inputs: dict[str, ResidentPairs] = {}

    def _stage_data(self, r: int) -> tuple[ResidentPairs, ResidentPairs]:
        cfg, dev, train, show = self.cfg, self.dev, self.start.train, self.show
        cl = self.amp and cfg.channels_last
        if r not in self.resident:
            self.resident.clear()  # one stage's data on the device at a time
            self.resident[r] = (
                ResidentPairs(train.a, train.b, r, dev, channels_last=cl,
                              input_reduce=cfg.input_reduce),
                ResidentPairs(show.a[:cfg.samples], show.b[:cfg.samples], r, dev,
                              channels_last=cl, input_reduce=cfg.input_reduce))
            self.g.out_size = r
        if self.decoder and not self.full_inputs:  # the generator's input: always cfg.size
            for name, part in (("train", train.a), ("show", show.a[:cfg.samples])):
                self.full_inputs[name] = ResidentPairs(
                    part, part[:, :1, :1], cfg.size, dev, channels_last=cl,
                    input_reduce=cfg.input_reduce, target_size=1)
        return self.resident[r]

    def _g_input(self, name: str, idx: torch.Tensor) -> torch.Tensor | None:
        return self.full_inputs[name].batch(idx)[0] if self.decoder else None

    def _n_batches_at(self, r: int) -> int:
        return batches_per_epoch(self.n, self.cfg.stage_batch(r), self.dist.world)

    def alpha_at(self, ep: int, b: int) -> tuple[float, int]:
        """(fade-in alpha, fade length in batches) at batch ``b`` of 0-based ``ep``."""
        stage, r, first = stage_of(ep, self.cfg.schedule)
        nb = self._n_batches_at(r)
        steps = fade_steps(stage, nb, self.cfg)
        return fade_alpha((ep - first) * nb + b, steps), steps

    def _alpha(self, a: float) -> torch.Tensor | None:
        """The one alpha tensor set to ``a``, or None when the fade is over."""
        if a < 1.0:
            self.alpha_t.fill_(a)
            return self.alpha_t
        return None

    def batches_in(self, epoch: int) -> int:
        return self._n_batches_at(stage_of(epoch, self.cfg.schedule)[1])

    def epoch_plan(self, epoch: int) -> EpochPlan:
        r = stage_of(epoch, self.cfg.schedule)[1]
        res, shown = self._stage_data(r)
        B, nb = self.cfg.stage_batch(r), self._n_batches_at(r)
        a_end, steps = self.alpha_at(epoch, nb - 1)
        return EpochPlan(res, shown, B, nb, {"resolution": r, "batch": B, "alpha": a_end,
                                             "fade_batches": steps})

    def step(self, epoch, b, idx, x, y, shift) -> dict:
        alpha = self._alpha(self.alpha_at(epoch, b)[0])
        gi = self._g_input("train", idx)
        if self.static is not None:  # cfg.cuda_graph
            return self.static(x, y, shift, alpha, gi)
        return gan_step(self.g_run, self.dd_run, self.dr_run, self.opt_g, self.opt_d, x, y,
                        alpha, self.cfg, shift, self.autocast, self.freeze, gi)

    def postfix(self, epoch: int, b: int) -> str:
        return f"{stage_of(epoch, self.cfg.schedule)[1]}px a={self.alpha_at(epoch, b)[0]:.2f} "

    def generate(self, plan: EpochPlan, idx, x) -> torch.Tensor:
        alpha = self._alpha(plan.log["alpha"])
        gi = self._g_input("show", idx)
        self.g.eval()
        try:
            return self.g(x if gi is None else gi, alpha)
        finally:
            self.g.train()

    def model_state(self, ep: int, batch: int) -> dict | None:
        # the generator as trained so far: the stage of the last batch done, its alpha
        last_ep, last_b = (ep, batch - 1) if batch > 0 else (ep - 1, None)
        if last_ep < 0:
            return None
        r_done = stage_of(last_ep, self.cfg.schedule)[1]
        a_done = self.alpha_at(last_ep, last_b if last_b is not None
                               else self._n_batches_at(r_done) - 1)[0]
        return {"resolution": r_done, "alpha": a_done}
