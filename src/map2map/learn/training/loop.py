"""The training loop Model_BA and Model_AB share (thesis sec. 4.2 and 5.1).

Both models are the same GAN of eq. 3.2 -- a generator ``G`` and two multi-scale
discriminators, ``D_d`` (pairs, eq. 3.3) and ``D_r`` (maps, eq. 3.4) -- trained the same
way; only what the networks see differs. This module holds everything that does not:

* :func:`gan_step` -- one step of eq. 3.2 (discriminators on the max side with the false
  targets of :func:`false_targets`, then the generator on the min side);
* :func:`open_run` -- a new run or ``--resume`` of one (format, dataset digest, config);
* :class:`GANRun` -- device and DDP set-up (:class:`Dist`), Adam for ``G`` and for both
  discriminators with the learning rate a pure function of the epoch
  (:func:`~map2map.learn.training.config.lr_factor`), the epoch/batch loop over data resident on
  the device, Ctrl-C handling, atomic checkpoints after every epoch and on Ctrl-C with
  everything ``--resume`` needs to continue bit for bit (weights, optimiser moments,
  random-generator states, epoch and position in it, loss history), ``log.csv``,
  ``losses.png``, ``samples/epoch_NNNN.png`` and the tqdm bar.

A trainer subclasses :class:`GANRun` and states only what is its own: the data and batch
size of an epoch (:meth:`GANRun.epoch_plan`), the step (:meth:`GANRun.step`), the
generator's output for the sample grid, the extra fields of the model header. Model_BA
(:mod:`~map2map.learn.ba.train`): one resolution, one batch size. Model_AB
(:mod:`~map2map.learn.ab.train`): a resolution and batch size per stage, the fade-in
alpha, the stage switches marked in the loss curves.

Examples
--------
>>> batches_per_epoch(10, 4, world=1), batches_per_epoch(10, 4, world=2)
(3, 2)
>>> false_targets(torch.arange(4.0), 1).tolist()
[3.0, 0.0, 1.0, 2.0]
"""

from __future__ import annotations

import csv
import gc
import io
import json
import math
import os
import signal
import threading
import time
from dataclasses import dataclass, field
from pathlib import Path

import torch

from ...core._io import atomic_path, ensure_output_dir
from ...core.errors import InputError
from ...datasets.packed import PackedPairs
from ..nets.networks import count_parameters, from_unit
from .checkpoint import (
    load_checkpoint,
    load_module,
    load_optimizer,
    module_tensors,
    optimizer_tensors,
    save_checkpoint,
)
from .config import TrainConfig, lr_factor
from .data import ResidentPairs, load_pairs, warn_about_data
from .figures import save_loss_curves, save_sample_grid
from .step import false_targets, gan_step, set_lr

__all__ = ["MODEL_FILE", "CHECKPOINT_FILE", "TrainResult", "resolve_device", "false_targets",
           "gan_step", "write_log_csv", "batches_per_epoch", "Dist", "RunStart", "open_run",
           "EpochPlan", "GANRun", "place_networks", "step_autocast", "set_lr"]

MODEL_FILE = "model.safetensors"
CHECKPOINT_FILE = "last.safetensors"


@dataclass
class TrainResult:
    """What a call of :func:`~map2map.learn.ba.train.train_ba` or
    :func:`~map2map.learn.ab.train.train_ab` did."""

    run: Path
    epochs_done: int
    history: list[dict] = field(default_factory=list)
    images_per_s: float = float("nan")
    interrupted: bool = False


def resolve_device(name: str = "auto") -> torch.device:
    """``"auto"`` -> CUDA when present, else CPU; any other name as given.

    Examples
    --------
    >>> resolve_device("cpu").type
    'cpu'
    """
    if name == "auto":
        return torch.device("cuda" if torch.cuda.is_available() else "cpu")
    dev = torch.device(name)
    if dev.type == "cuda" and not torch.cuda.is_available():
        raise InputError("device", "CUDA requested but not available")
    return dev


def place_networks(nets, dev: torch.device, amp: bool, cfg: TrainConfig
                   ) -> tuple[torch.optim.Adam, torch.optim.Adam]:
    """Move ``(G, D_d, D_r)`` to ``dev`` (channels_last under ``amp`` unless
    ``cfg.channels_last`` is False) and return Adam for
    ``G`` and Adam for both discriminators (thesis 4.2: lr, betas of ``cfg``)."""
    g, dd, dr = nets
    for net in nets:
        net.to(dev)
        if amp and cfg.channels_last:
            net.to(memory_format=torch.channels_last)
    opt_g = torch.optim.Adam(g.parameters(), lr=cfg.lr, betas=(cfg.beta1, cfg.beta2))
    opt_d = torch.optim.Adam(list(dd.parameters()) + list(dr.parameters()), lr=cfg.lr,
                             betas=(cfg.beta1, cfg.beta2))
    return opt_g, opt_d


def step_autocast(dev: torch.device, amp: bool):
    """The autocast context of a training step: bf16 on CUDA under ``amp``, else off."""
    if dev.type == "cuda":
        return torch.autocast("cuda", dtype=torch.bfloat16, enabled=amp)
    return torch.autocast("cpu", enabled=False)


def _sums_dict(dev_sums: dict, keys: list | None, acc: torch.Tensor | None) -> dict:
    """The running sums by name: the resumed ones, or the step's vector once it ran."""
    return dev_sums if keys is None else dict(zip(keys, acc.unbind(), strict=True))


def _host_sums(dev_sums: dict, n: float) -> dict:
    """An epoch's running loss sums, kept on the device, as host floats (one
    synchronisation); ``_n`` counts the pairs summed."""
    keys = sorted(dev_sums)
    vals = torch.stack([dev_sums[k] for k in keys]).tolist() if keys else []
    out = dict(zip(keys, vals, strict=True))
    out["_n"] = n
    return out


def write_log_csv(history: list[dict], path: Path) -> None:
    """``log.csv``: one row per epoch, the losses first, the other columns sorted."""
    if not history:
        return
    first = ["epoch", "lr", "loss_G", "loss_D", "gan_domain_3_3", "gan_real_fake_3_4",
             "fm_3_5", "ic_3_6", "l1_3_7", "d_domain_3_3", "d_real_fake_3_4"]
    keys = [k for k in first if k in history[0]] + sorted(set(history[0]) - set(first))
    buf = io.StringIO()
    w = csv.DictWriter(buf, fieldnames=keys)
    w.writeheader()
    for r in history:
        w.writerow({k: (f"{v:.6g}" if isinstance(v, float) else v) for k, v in r.items()})
    with atomic_path(path) as tmp:
        tmp.write_text(buf.getvalue())


def batches_per_epoch(n: int, batch: int, world: int) -> int:
    """Batches of ``batch`` pairs in an epoch of ``n``: the last one may be short on one
    process; under DDP every batch is whole (each process takes ``batch // world``)."""
    return n // batch if world > 1 else math.ceil(n / batch)


class Dist:
    """torchrun's environment (WORLD_SIZE, RANK, LOCAL_RANK) or a single process.

    ``find_unused``: DDP's ``find_unused_parameters`` (Model_AB: the blocks of the
    stages not reached have no gradient).
    """

    def __init__(self, cfg: TrainConfig, find_unused: bool = False):
        self.world = int(os.environ.get("WORLD_SIZE", "1"))
        self.rank = int(os.environ.get("RANK", "0"))
        self.find_unused = find_unused
        local = int(os.environ.get("LOCAL_RANK", "0"))
        if self.world > 1:
            import torch.distributed as dist

            use_cuda = torch.cuda.is_available() and cfg.device in ("auto", "cuda")
            self.device = torch.device(f"cuda:{local}" if use_cuda else "cpu")
            if use_cuda:
                torch.cuda.set_device(self.device)
            if not dist.is_initialized():
                dist.init_process_group("nccl" if use_cuda else "gloo")
        else:
            self.device = resolve_device(cfg.device)

    @property
    def main(self) -> bool:
        return self.rank == 0

    def wrap(self, net):
        if self.world == 1:
            return net
        from torch.nn.parallel import DistributedDataParallel as DDP

        ids = [self.device.index] if self.device.type == "cuda" else None
        if self.find_unused:
            return DDP(net, device_ids=ids, find_unused_parameters=True)
        return DDP(net, device_ids=ids)

    def close(self) -> None:
        if self.world > 1:
            import torch.distributed as dist

            if dist.is_initialized():
                dist.barrier()
                gc.collect()  # the DDP wrappers the caller dropped, in cycles or not
                dist.destroy_process_group()

    def mean(self, values: dict[str, float]) -> dict[str, float]:
        if self.world == 1:
            return values
        import torch.distributed as dist

        keys = sorted(values)
        t = torch.tensor([values[k] for k in keys], dtype=torch.float64, device=self.device)
        dist.all_reduce(t)
        return {k: float(v) / self.world for k, v in zip(keys, t.tolist(), strict=True)}


@dataclass
class RunStart:
    """A run about to train: its data, settings, process group and, on ``--resume``,
    the checkpoint's tensors and state (empty for a new run)."""

    out: Path
    pairs: PackedPairs
    source: object  # the dataset path for error messages, None for pairs in memory
    cfg: TrainConfig
    dist: Dist
    train: PackedPairs  # the 'train' split
    meta: dict  # the dataset's identity (its digest included), stored with the model
    tensors: dict = field(default_factory=dict)
    state: dict = field(default_factory=dict)

    @property
    def resume(self) -> bool:
        return bool(self.state)


def open_run(data, out, config: TrainConfig | None, *, config_type: type, fmt: str,
             model: str, resume: bool, epochs: int | None, find_unused: bool = False
             ) -> RunStart:
    """Start or resume a run in ``out`` on ``data``.

    A new run refuses a folder that already holds a checkpoint; ``resume`` reads the
    checkpoint, checks its format (``fmt``, ``model`` names it in the error) and that
    ``data`` is the dataset it was trained on, and takes its configuration (of
    ``config_type``); ``epochs`` overrides the configuration's in both cases. The
    process group (:class:`Dist`) is set up here; nothing is written.
    """
    out = Path(out)
    pairs = load_pairs(data)
    src = None if isinstance(data, PackedPairs) else (
        ", ".join(map(os.fspath, data)) if isinstance(data, (list, tuple)) else data)
    ck_path = out / CHECKPOINT_FILE
    tensors, state = {}, {}
    if resume:
        tensors, state = load_checkpoint(ck_path)
        if state.get("format") != fmt:
            raise InputError(ck_path, f"not a {model} training checkpoint")
        cfg = config_type.from_dict(state["config"])
        if state["dataset"].get("digest") != pairs.meta.get("digest", pairs.digest()):
            raise InputError(src, "this is not the dataset the run was trained on "
                                  "(digest differs)")
    else:
        cfg = config or config_type()
        if ck_path.exists():
            raise InputError(out, "the run folder already holds a checkpoint; "
                                  "use `resume` to continue it or another `out`")
    if epochs is not None:
        cfg.epochs = int(epochs)
    dist = Dist(cfg, find_unused=find_unused)
    train = pairs.select("train")
    if len(train) == 0:
        raise InputError(src, "the dataset has no 'train' pairs")
    if dist.main:
        warn_about_data(src, len(train), len(pairs.select("val")))
    meta = dict(pairs.meta)
    meta.setdefault("digest", pairs.digest())
    return RunStart(out, pairs, src, cfg, dist, train, meta, tensors, state)


@dataclass
class EpochPlan:
    """What one epoch trains on: the training pairs and the sample-grid pairs at its
    resolution, its batch size and number of batches, and the columns it adds to its
    row of the log (Model_AB: resolution, batch, alpha, fade length)."""

    data: ResidentPairs
    shown: ResidentPairs
    batch: int
    batches: int
    log: dict = field(default_factory=dict)


class GANRun:
    """One training run of ``G``, ``D_d`` and ``D_r`` (see the module's docstring).

    Subclasses set :attr:`fmt`, :attr:`desc`, :attr:`torch_rng`, :attr:`title` and
    :attr:`figure` and implement
    :meth:`epoch_plan`, :meth:`batches_in` and :meth:`step`; :meth:`generate`,
    :meth:`model_state` and :meth:`postfix` have defaults.

    Parameters
    ----------
    start : RunStart
        From :func:`open_run`.
    nets : (G, D_d, D_r)
        Freshly built (on resume the checkpoint's weights are loaded into them).
    header : dict
        The JSON stored with the generator (``config.json``, ``model.safetensors``).
    progress, figures : bool
        tqdm bar; ``losses.png`` and the per-epoch sample grids.
    """

    #: ``format`` of the checkpoint and of the model header
    fmt = ""
    #: the progress bar's label
    desc = "train"
    #: also checkpoint torch's global random state (dropout draws from it)
    torch_rng = False
    #: the model's name and thesis figure in the title of ``losses.png``
    title, figure = "Model_BA", "5.2"

    def __init__(self, start: RunStart, nets, header: dict, *, progress: bool = True,
                 figures: bool = True):
        self.start, self.cfg, self.dist = start, start.cfg, start.dist
        self.out, self.header = start.out, header
        self.progress, self.figures = progress, figures
        self.dev = self.dist.device
        self.cuda = self.dev.type == "cuda"
        self.amp = self.cuda and self.cfg.amp
        if self.cuda:  # fixed shapes per stage: let cuDNN pick the fastest convolutions
            torch.backends.cudnn.benchmark = True
        self.g, self.dd, self.dr = nets
        self.n = len(start.train)
        cfg = self.cfg
        self.opt_g, self.opt_d = place_networks(nets, self.dev, self.amp, cfg)
        self.gen = torch.Generator().manual_seed(cfg.seed)
        self.history: list[dict] = []
        self.epoch, self.start_batch, self.sums = 0, 0, {}
        self.static = None  # the StaticStep under cfg.cuda_graph, made by run()
        if start.resume:
            self._load(start.tensors, start.state)
        self.autocast = step_autocast(self.dev, self.amp)

    # ----------------------------------------------------------------- what differs
    def epoch_plan(self, epoch: int) -> EpochPlan:
        """The data, batch size and log columns of 0-based ``epoch``."""
        raise NotImplementedError

    def batches_in(self, epoch: int) -> int:
        """Number of batches of 0-based ``epoch`` (cheap: the progress bar's total)."""
        raise NotImplementedError

    def step(self, epoch: int, b: int, idx: torch.Tensor, x: torch.Tensor,
             y: torch.Tensor, shift: int) -> dict:
        """Train on batch ``b`` of ``epoch`` (pairs ``idx``, tensors ``x``, ``y``);
        returns the logged values as tensors (:func:`gan_step`'s, or :attr:`static`'s
        -- the :class:`~map2map.learn.training.static_step.StaticStep` -- when it is not None)."""
        raise NotImplementedError

    def generate(self, plan: EpochPlan, idx: torch.Tensor, x: torch.Tensor) -> torch.Tensor:
        """The generator's output for the sample grid (under no_grad and autocast) at
        the end of the epoch of ``plan``."""
        return self.g(x)

    def model_state(self, epoch: int, batch: int) -> dict | None:
        """Fields added to the model header when the checkpoint at (``epoch``,
        ``batch``) is written; None: do not write the model file."""
        return {}

    def postfix(self, epoch: int, b: int) -> str:
        """Text of the progress bar after the epoch counter for batch ``b`` (done)."""
        return ""

    def _static_step(self):
        """The static step under ``cfg.cuda_graph`` (None otherwise, or when it cannot
        apply: DDP or a compiled generator, with a warning)."""
        cfg = self.cfg
        if not cfg.cuda_graph:
            return None
        if self.dist.world > 1 or cfg.compile:
            import warnings

            warnings.warn("`cuda_graph` is single-process and not combined with `compile`: "
                          "training eagerly", RuntimeWarning, stacklevel=2)
            return None
        from .static_step import StaticStep, graph_autocast

        if self.cuda:
            self.autocast = graph_autocast(self.dev, self.amp)
        return StaticStep((self.g_run, self.dd_run, self.dr_run), (self.opt_g, self.opt_d),
                          cfg, self.autocast, self.freeze, graph=self.cuda)

    # ----------------------------------------------------------------- what is shared
    def _load(self, tensors: dict, state: dict) -> None:
        ck_path = self.out / CHECKPOINT_FILE
        for net, name in ((self.g, "G"), (self.dd, "D_d"), (self.dr, "D_r")):
            load_module(net, tensors, name, ck_path)
        load_optimizer(self.opt_g, tensors, "opt_G", state["opt_G"])
        load_optimizer(self.opt_d, tensors, "opt_D", state["opt_D"])
        self.gen.set_state(tensors["rng.shuffle"])
        if self.torch_rng:
            torch.set_rng_state(tensors["rng.torch"])
            if self.cuda and "rng.cuda" in tensors:
                torch.cuda.set_rng_state(tensors["rng.cuda"], self.dev)
        self.epoch, self.start_batch = state["epoch"], state["batch"]
        self.sums, self.history = state["sums"], state["history"]

    @staticmethod
    def header_fields(targets, data_size: int, nets) -> dict:
        """The model-header fields both models carry: the training targets' wall
        thickness, the dataset's map size and the networks' parameter counts."""
        from ...maps.preprocess import wall_thickness_px

        g, dd, dr = nets
        return {"target_wall_px": wall_thickness_px(targets), "data_size": int(data_size),
                "parameters": {"G": count_parameters(g), "D_d": count_parameters(dd),
                               "D_r": count_parameters(dr)}}

    def checkpoint(self, ep: int, batch: int, rng_state: torch.Tensor, run_sums: dict
                   ) -> None:
        """``last.safetensors`` (all ``--resume`` needs) and ``model.safetensors``."""
        if not self.dist.main:
            return
        g, dd, dr = self.g, self.dd, self.dr
        t = {**module_tensors(g, "G"), **module_tensors(dd, "D_d"), **module_tensors(dr, "D_r")}
        tg, groups_g = optimizer_tensors(self.opt_g, "opt_G")
        td, groups_d = optimizer_tensors(self.opt_d, "opt_D")
        t.update(tg)
        t.update(td)
        t["rng.shuffle"] = rng_state
        if self.torch_rng:
            t["rng.torch"] = torch.get_rng_state()  # the dropout masks draw from it
            if self.cuda:
                t["rng.cuda"] = torch.cuda.get_rng_state(self.dev)
        st = {"format": self.fmt, "config": self.cfg.to_dict(), "dataset": self.start.meta,
              "epoch": ep, "batch": batch, "sums": run_sums, "history": self.history,
              "opt_G": groups_g, "opt_D": groups_d}
        save_checkpoint(self.out / CHECKPOINT_FILE, t, st)
        extra = self.model_state(ep, batch)
        if extra is None:
            return
        save_checkpoint(self.out / MODEL_FILE, g.state_dict(),
                        {**self.header, "epochs_trained": ep, **extra})

    def sample_grid(self, ep: int, plan: EpochPlan) -> None:
        """``samples/epoch_NNNN.png``: input | output | target of the shown pairs."""
        shown = plan.shown
        if not self.dist.main or len(shown) == 0:
            return
        with torch.no_grad(), self.autocast:
            idx = torch.arange(len(shown))
            x, y = shown.batch(idx)
            o = self.generate(plan, idx, x)
        save_sample_grid(from_unit(x[:, 0]), from_unit(o[:, 0]), from_unit(y[:, 0]),
                         self.out / "samples" / f"epoch_{ep:04d}.png")

    def _write_logs(self, curves: bool) -> None:
        write_log_csv(self.history, self.out / "log.csv")
        if curves:
            save_loss_curves(self.history, self.out / "losses.png", self.title, self.figure)

    def run(self) -> TrainResult:
        """Write ``config.json`` and train from where the run stands to ``cfg.epochs``."""
        cfg, dist, out = self.cfg, self.dist, self.out
        if dist.main:
            ensure_output_dir(out)
            (out / "samples").mkdir(exist_ok=True)
            with atomic_path(out / "config.json") as tmp:
                tmp.write_text(json.dumps(self.header, indent=2, sort_keys=True))
        g_run = torch.compile(self.g) if cfg.compile else self.g
        self.g_run, self.dd_run, self.dr_run = dist.wrap(g_run), dist.wrap(self.dd), \
            dist.wrap(self.dr)
        self.freeze = (self.dd, self.dr) if dist.world == 1 else ()
        self.static = self._static_step()
        epoch, sums, history, gen = self.epoch, self.sums, self.history, self.gen
        bar = None
        if self.progress and dist.main:
            from tqdm.auto import tqdm

            total = sum(self.batches_in(e) for e in range(cfg.epochs))
            done = sum(self.batches_in(e) for e in range(epoch)) + self.start_batch
            bar = tqdm(total=total, initial=min(total, done), desc=self.desc, unit="batch",
                       dynamic_ncols=True)
        images, t_start, t_shown = 0, time.perf_counter(), -1.0
        interrupted = False
        # Ctrl-C stops at the end of the batch in progress, so the checkpoint is consistent
        # (a second Ctrl-C stops at once, without a checkpoint)
        stop = {"flag": False}

        def on_sigint(signum, frame):
            if stop["flag"]:
                raise KeyboardInterrupt
            stop["flag"] = True

        old_handler = None
        if threading.current_thread() is threading.main_thread():
            old_handler = signal.signal(signal.SIGINT, on_sigint)
        rng_state = gen.get_state()
        b = start_batch = self.start_batch
        try:
            while epoch < cfg.epochs:
                plan = self.epoch_plan(epoch)
                B, nb = plan.batch, plan.batches
                per_rank = max(1, B // dist.world)
                rng_state = gen.get_state()
                perm = torch.randperm(self.n, generator=gen).to(self.dev)
                shifts = torch.randint(1, max(2, B), (nb,), generator=gen).tolist()
                # a resumed epoch's sums continue on the device (same additions, same order)
                dev_sums = {k: torch.tensor(v, dtype=torch.float64, device=self.dev)
                            for k, v in sums.items() if k != "_n"}
                zero = torch.zeros((), dtype=torch.float64, device=self.dev)
                keys, acc = None, None  # the logged values' names, their sums in one vector
                n_sum = sums.get("_n", 0.0)
                f = lr_factor(epoch, cfg)
                for o in (self.opt_g, self.opt_d):
                    set_lr(o, cfg.lr * f)  # in place when a captured graph reads it
                t_epoch, images_epoch = time.perf_counter(), images
                b = start_batch
                while b < nb:
                    idx = perm[b * B:(b + 1) * B]
                    if dist.world > 1:
                        idx = idx[dist.rank * per_rank:(dist.rank + 1) * per_rank]
                    x, y = plan.data.batch(idx)
                    vals = self.step(epoch, b, idx, x, y, shifts[b])
                    k = len(idx)
                    # summed on the device in float64 (as float(v) * k on the host would,
                    # bit for bit): no host-device synchronisation per batch, and all the
                    # values in one vector (4 operator calls a step, not 4 per value)
                    if keys is None:  # (0 + term: the same bits as term)
                        keys = sorted(vals)
                        acc = torch.stack([dev_sums.get(key, zero) for key in keys])
                    acc = acc + torch.stack([vals[key].detach() for key in keys]).double() * k
                    n_sum += k
                    images += k * dist.world
                    b += 1
                    if bar is not None:
                        el = time.perf_counter() - t_start
                        if el - t_shown >= 0.5 or b == nb:  # losses read twice a second
                            t_shown = el
                            bar.set_postfix_str(f"epoch {epoch + 1}/{cfg.epochs} "
                                                f"{self.postfix(epoch, b - 1)}"
                                                f"{images / max(el, 1e-9):.0f} img/s "
                                                f"G {float(vals['loss_G'].detach()):.3f} "
                                                f"D {float(vals['loss_D'].detach()):.3f}")
                        bar.update(1)
                    if stop["flag"]:
                        sums = _host_sums(_sums_dict(dev_sums, keys, acc), n_sum)
                        raise KeyboardInterrupt
                sums = _host_sums(_sums_dict(dev_sums, keys, acc), n_sum)
                row = {"epoch": epoch + 1, "lr": cfg.lr * f, **plan.log}
                row.update(dist.mean({k: v / sums["_n"] for k, v in sums.items() if k != "_n"}))
                t_now = time.perf_counter()
                # this epoch's rate (the run's average, start-up included, is the result's
                # images_per_s)
                row["img_per_s"] = (images - images_epoch) / max(t_now - t_epoch, 1e-9)
                if self.static is not None:  # which step ran: graph, eager, or a fallback
                    row["step"] = self.static.mode
                row["epoch_s"] = t_now - t_epoch
                history.append(row)
                epoch += 1
                start_batch, sums = 0, {}
                rng_state = gen.get_state()
                if epoch % max(1, cfg.save_every) and epoch < cfg.epochs:
                    continue  # --save-every: not a saving epoch
                self.checkpoint(epoch, 0, rng_state, {})
                if dist.main:
                    every = max(1, cfg.epochs // 50, cfg.save_every)
                    self._write_logs(self.figures and (epoch % every == 0
                                                       or epoch == cfg.epochs))
                    if self.figures:
                        self.sample_grid(epoch, plan)
        except KeyboardInterrupt:
            interrupted = True
            if stop["flag"] and epoch < cfg.epochs:
                # --resume continues the epoch in progress at its first batch not done
                stop["flag"] = False
                self.checkpoint(epoch, b, rng_state, sums)
            if dist.main and history:
                self._write_logs(self.figures)
            raise
        finally:
            if old_handler is not None:
                signal.signal(signal.SIGINT, old_handler)
            if bar is not None:
                bar.close()
        # DDP's wrappers hold the process group: dropped here, the group is freed by
        # dist.close() while the interpreter is alive; freed at exit instead, a gloo
        # worker can die taking the GIL in a barrier's destructor (SIGABRT)
        self.g_run = self.dd_run = self.dr_run = self.static = None
        dist.close()
        el = time.perf_counter() - t_start
        return TrainResult(out, epoch, history, images / el if el > 0 else float("nan"),
                           interrupted)
