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
a pure function of the epoch (:func:`~map2map.learn.config.lr_factor`). On CUDA: bf16
autocast with the output head and the losses in fp32, channels_last, data resident on the
GPU; ``torchrun --nproc_per_node K -m map2map train ba ...`` runs DDP (NCCL on GPUs,
gloo on CPU): every process draws the same permutation and takes its share of each batch.

A run folder holds ``config.json`` (configuration, dataset identity, network sizes),
``model.safetensors`` (the generator, with that configuration in its header: all
``map2map autocorrect --model RUN`` needs), ``last.safetensors`` (everything needed to
resume exactly: weights, optimiser moments, random-generator state, epoch and position
in it, loss history), ``log.csv`` (every logged value, one row per epoch),
``losses.png`` (thesis Fig. 5.2) and ``samples/epoch_NNNN.png`` (input | output | target).
Checkpoints are written atomically after every epoch and on Ctrl-C.

Examples
--------
>>> import tempfile, pathlib, numpy as np
>>> rng = np.random.default_rng(0)
>>> a = rng.choice(np.array([0, 127, 255], np.uint8), size=(4, 32, 32))
>>> pairs = PackedPairs(a, a[:, :, ::-1], np.arange(4).astype(str), np.array(["train"] * 4))
>>> cfg = TrainConfig(size=16, epochs=1, batch=2, g_channels=8, d_channels=8, d_layers=2)
>>> run = pathlib.Path(tempfile.mkdtemp()) / "run"
>>> result = train_ba(pairs, run, cfg, progress=False, figures=False)
>>> result.epochs_done, sorted(p.name for p in run.iterdir())
(1, ['config.json', 'last.safetensors', 'log.csv', 'model.safetensors', 'samples'])
"""

from __future__ import annotations

import csv
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

from ..core._io import atomic_path, ensure_output_dir
from ..core.errors import InputError
from ..datasets.packed import PackedPairs
from .checkpoint import (
    load_checkpoint,
    load_module,
    load_optimizer,
    module_tensors,
    optimizer_tensors,
    save_checkpoint,
)
from .config import TrainConfig, lr_factor
from .data import ResidentPairs, load_pairs
from .figures import save_loss_curves, save_sample_grid
from .losses import discriminator_loss_3_2, generator_loss_3_2
from .networks import MultiScaleDiscriminator, UNetGenerator, count_parameters, from_unit
from .postprocess import wall_thickness_px

__all__ = ["TrainResult", "build_networks", "train_ba", "resolve_device", "MODEL_FILE",
           "CHECKPOINT_FILE"]

MODEL_FILE = "model.safetensors"
CHECKPOINT_FILE = "last.safetensors"
FORMAT = "map2map-model-ba"


@dataclass
class TrainResult:
    """What a call of :func:`train_ba` did."""

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
        raise InputError("--device", "CUDA requested but not available")
    return dev


def build_networks(cfg: TrainConfig) -> tuple[UNetGenerator, MultiScaleDiscriminator,
                                              MultiScaleDiscriminator]:
    """``G``, ``D_d`` (2 channels: input and output) and ``D_r`` (1 channel) of ``cfg``,
    initialised from ``cfg.seed``."""
    torch.manual_seed(cfg.seed)
    g = UNetGenerator(cfg.size, cfg.g_channels, cfg.g_max_channels, cfg.bottleneck)
    dd = MultiScaleDiscriminator(2, cfg.d_channels, cfg.d_layers, cfg.d_scales)
    dr = MultiScaleDiscriminator(1, cfg.d_channels, cfg.d_layers, cfg.d_scales)
    return g, dd, dr


def _split(scales: list[list[torch.Tensor]], n: int) -> list[list[list[torch.Tensor]]]:
    """Cut every feature map of a batched discriminator output into ``n`` equal parts."""
    parts = [[[f.chunk(n)[i] for f in feats] for feats in scales] for i in range(n)]
    return parts


def false_targets(y: torch.Tensor, shift: int) -> torch.Tensor:
    """Targets of other inputs: ``y`` rolled by ``shift`` (1 <= shift < B) along the batch.

    Examples
    --------
    >>> false_targets(torch.arange(4.0), 1).tolist()
    [3.0, 0.0, 1.0, 2.0]
    """
    return torch.roll(y, shifts=int(shift), dims=0)


def _set_grad(nets, flag: bool) -> None:
    for n in nets:
        for p in n.parameters():
            p.requires_grad_(flag)


def _write_csv(history: list[dict], path: Path) -> None:
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


def model_header(cfg: TrainConfig, meta: dict, extra: dict) -> dict:
    """The JSON stored with the generator: what inference needs and where it came from."""
    return {"format": FORMAT, "generator": dict(size=cfg.size, channels=cfg.g_channels,
                                                max_channels=cfg.g_max_channels,
                                                bottleneck=cfg.bottleneck),
            "train": cfg.to_dict(), "dataset": meta, **extra}


class _Dist:
    """torchrun's environment (WORLD_SIZE, RANK, LOCAL_RANK) or a single process."""

    def __init__(self, cfg: TrainConfig):
        self.world = int(os.environ.get("WORLD_SIZE", "1"))
        self.rank = int(os.environ.get("RANK", "0"))
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
        return DDP(net, device_ids=ids)

    def close(self) -> None:
        if self.world > 1:
            import torch.distributed as dist

            if dist.is_initialized():
                dist.barrier()
                dist.destroy_process_group()

    def mean(self, values: dict[str, float]) -> dict[str, float]:
        if self.world == 1:
            return values
        import torch.distributed as dist

        keys = sorted(values)
        t = torch.tensor([values[k] for k in keys], dtype=torch.float64, device=self.device)
        dist.all_reduce(t)
        return {k: float(v) / self.world for k, v in zip(keys, t.tolist(), strict=True)}


def train_ba(data: str | os.PathLike | PackedPairs, out: str | os.PathLike,
             config: TrainConfig | None = None, *, resume: bool = False,
             epochs: int | None = None, progress: bool = True, figures: bool = True
             ) -> TrainResult:
    """Train Model_BA (input: SLAM map ``b``, target: plan ``a``) on the ``train`` split.

    Parameters
    ----------
    data : path or PackedPairs
        A dataset folder (``packed.npz`` inside), a packed ``.npz``, or pairs in memory.
    out : path
        Run folder (created).
    config : TrainConfig
        Settings (defaults: see :class:`TrainConfig`); ignored when resuming, except
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
    out = Path(out)
    pairs = load_pairs(data)
    ck_path = out / CHECKPOINT_FILE
    tensors, state = {}, {}
    if resume:
        tensors, state = load_checkpoint(ck_path)
        if state.get("format") != FORMAT:
            raise InputError(ck_path, "not a Model_BA training checkpoint")
        cfg = TrainConfig.from_dict(state["config"])
        if state["dataset"].get("digest") != pairs.meta.get("digest", pairs.digest()):
            raise InputError(data if not isinstance(data, PackedPairs) else None,
                             "this is not the dataset the run was trained on (digest differs)")
    else:
        cfg = config or TrainConfig()
        if ck_path.exists():
            raise InputError(out, "the run folder already holds a checkpoint; "
                                  "use --resume to continue it or another --out")
    if epochs is not None:
        cfg.epochs = int(epochs)
    dist = _Dist(cfg)
    dev = dist.device
    cuda = dev.type == "cuda"
    amp = cuda and cfg.amp
    if dist.main:
        ensure_output_dir(out)
        (out / "samples").mkdir(exist_ok=True)

    train = pairs.select("train")
    if len(train) == 0:
        raise InputError(data if not isinstance(data, PackedPairs) else None,
                         "the dataset has no 'train' pairs")
    smallest = cfg.size // 2 ** (cfg.d_scales - 1)
    if smallest < 2**cfg.d_layers:
        raise InputError("--size", f"at {cfg.size} px the coarsest discriminator scale is "
                                   f"{smallest} px, too small for {cfg.d_layers} stride-2 "
                                   "layers (use a larger size or fewer --d-layers)")
    if pairs.a.shape[-1] < cfg.size:
        raise InputError(None, f"dataset maps are {pairs.a.shape[-1]} px; cannot train at "
                               f"{cfg.size}")
    val = pairs.select("val")
    show = val if len(val) else train
    res = ResidentPairs(train.b, train.a, cfg.size, dev, channels_last=amp,
                        input_reduce=cfg.input_reduce)
    shown = ResidentPairs(show.b[:cfg.samples], show.a[:cfg.samples], cfg.size, dev,
                          channels_last=amp, input_reduce=cfg.input_reduce)
    meta = dict(pairs.meta)
    meta.setdefault("digest", pairs.digest())

    g, dd, dr = build_networks(cfg)
    nets = [g, dd, dr]
    for n in nets:
        n.to(dev)
        if amp:
            n.to(memory_format=torch.channels_last)
    opt_g = torch.optim.Adam(g.parameters(), lr=cfg.lr, betas=(cfg.beta1, cfg.beta2))
    opt_d = torch.optim.Adam(list(dd.parameters()) + list(dr.parameters()), lr=cfg.lr,
                             betas=(cfg.beta1, cfg.beta2))
    gen = torch.Generator().manual_seed(cfg.seed)
    history: list[dict] = []
    epoch, start_batch, sums = 0, 0, {}
    if resume:
        for n, name in ((g, "G"), (dd, "D_d"), (dr, "D_r")):
            load_module(n, tensors, name, ck_path)
        load_optimizer(opt_g, tensors, "opt_G", state["opt_G"])
        load_optimizer(opt_d, tensors, "opt_D", state["opt_D"])
        gen.set_state(tensors["rng.shuffle"])
        epoch, start_batch = state["epoch"], state["batch"]
        sums = state["sums"]
        history = state["history"]
    extra = {"target_wall_px": wall_thickness_px(train.a), "data_size": int(pairs.a.shape[-1]),
             "parameters": {"G": count_parameters(g), "D_d": count_parameters(dd),
                            "D_r": count_parameters(dr)}}
    header = model_header(cfg, meta, extra)
    if dist.main:
        with atomic_path(out / "config.json") as tmp:
            tmp.write_text(json.dumps(header, indent=2, sort_keys=True))

    g_run = torch.compile(g) if cfg.compile else g
    g_run, dd_run, dr_run = dist.wrap(g_run), dist.wrap(dd), dist.wrap(dr)
    B = cfg.batch_size
    n = len(res)
    per_rank = max(1, B // dist.world)
    n_batches = n // B if dist.world > 1 else math.ceil(n / B)
    if n_batches == 0:
        raise InputError(None, f"{n} training pairs are fewer than one batch of {B}")
    autocast = torch.autocast("cuda", dtype=torch.bfloat16, enabled=amp) if cuda else \
        torch.autocast("cpu", enabled=False)

    def checkpoint(ep: int, batch: int, rng_state: torch.Tensor, run_sums: dict) -> None:
        if not dist.main:
            return
        t = {**module_tensors(g, "G"), **module_tensors(dd, "D_d"), **module_tensors(dr, "D_r")}
        tg, groups_g = optimizer_tensors(opt_g, "opt_G")
        td, groups_d = optimizer_tensors(opt_d, "opt_D")
        t.update(tg)
        t.update(td)
        t["rng.shuffle"] = rng_state
        st = {"format": FORMAT, "config": cfg.to_dict(), "dataset": meta, "epoch": ep,
              "batch": batch, "sums": run_sums, "history": history, "opt_G": groups_g,
              "opt_D": groups_d}
        save_checkpoint(ck_path, t, st)
        g_header = {"map2map": json.dumps({**header, "epochs_trained": ep}, sort_keys=True)}
        with atomic_path(out / MODEL_FILE) as tmp:
            from safetensors.torch import save_file

            save_file({k: v.detach().cpu().contiguous() for k, v in g.state_dict().items()},
                      str(tmp), metadata=g_header)

    def sample_grid(ep: int) -> None:
        if not dist.main or len(shown) == 0:
            return
        with torch.no_grad(), autocast:
            idx = torch.arange(len(shown))
            x, y = shown.batch(idx)
            o = g(x)
        save_sample_grid(from_unit(x[:, 0]), from_unit(o[:, 0]), from_unit(y[:, 0]),
                         out / "samples" / f"epoch_{ep:04d}.png")

    total = cfg.epochs * n_batches
    bar = None
    if progress and dist.main:
        from tqdm.auto import tqdm

        bar = tqdm(total=total, initial=min(total, epoch * n_batches + start_batch),
                   desc="train ba", unit="batch", dynamic_ncols=True)
    images, t_start = 0, time.perf_counter()
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
    b = start_batch
    try:
        while epoch < cfg.epochs:
            rng_state = gen.get_state()
            perm = torch.randperm(n, generator=gen)
            shifts = torch.randint(1, max(2, B), (n_batches,), generator=gen)
            f = lr_factor(epoch, cfg)
            for o in (opt_g, opt_d):
                for grp in o.param_groups:
                    grp["lr"] = cfg.lr * f
            t_epoch = time.perf_counter()
            b = start_batch
            while b < n_batches:
                idx = perm[b * B:(b + 1) * B]
                if dist.world > 1:
                    idx = idx[dist.rank * per_rank:(dist.rank + 1) * per_rank]
                x, y = res.batch(idx)
                k = len(idx)
                use_false = cfg.false_targets and k > 1
                with autocast:
                    fake = g_run(x)
                    real_pair = torch.cat([x, y], 1)
                    fake_pair = torch.cat([x, fake.detach()], 1)
                    groups = [real_pair, fake_pair]
                    if use_false:
                        groups.append(torch.cat([x, false_targets(y, int(shifts[b]) % k or 1)],
                                                1))
                    dd_out = _split(dd_run(torch.cat(groups)), len(groups))
                    dr_out = _split(dr_run(torch.cat([y, fake.detach()])), 2)
                loss_d, d_terms = discriminator_loss_3_2(
                    dd_out[0], dd_out[1], dd_out[2] if use_false else None, dr_out[0], dr_out[1])
                opt_d.zero_grad(set_to_none=True)
                loss_d.backward()
                opt_d.step()
                if dist.world == 1:
                    _set_grad((dd, dr), False)
                with autocast:
                    dd_out = _split(dd_run(torch.cat([real_pair, torch.cat([x, fake], 1)])), 2)
                    dr_out = _split(dr_run(torch.cat([y, fake])), 2)
                loss_g, g_terms = generator_loss_3_2(
                    dd_out[0], dd_out[1], dr_out[0], dr_out[1], fake, y,
                    lambda_l1=cfg.lambda_l1, lambda_fm=cfg.lambda_fm, lambda_ic=cfg.lambda_ic)
                opt_g.zero_grad(set_to_none=True)
                loss_g.backward()
                opt_g.step()
                if dist.world == 1:
                    _set_grad((dd, dr), True)
                vals = {"loss_G": loss_g, "loss_D": loss_d, **g_terms, **d_terms}
                for key, v in vals.items():
                    sums[key] = sums.get(key, 0.0) + float(v.detach()) * k
                sums["_n"] = sums.get("_n", 0.0) + k
                images += k * dist.world
                b += 1
                if bar is not None:
                    el = time.perf_counter() - t_start
                    bar.set_postfix_str(f"epoch {epoch + 1}/{cfg.epochs} "
                                        f"{images / max(el, 1e-9):.0f} img/s "
                                        f"G {float(loss_g):.3f} D {float(loss_d):.3f}")
                    bar.update(1)
                if stop["flag"]:
                    raise KeyboardInterrupt
            row = {"epoch": epoch + 1, "lr": cfg.lr * f}
            means = dist.mean({k: v / sums["_n"] for k, v in sums.items() if k != "_n"})
            row.update(means)
            row["img_per_s"] = images / max(time.perf_counter() - t_start, 1e-9)
            row["epoch_s"] = time.perf_counter() - t_epoch
            history.append(row)
            epoch += 1
            start_batch, sums = 0, {}
            rng_state = gen.get_state()
            checkpoint(epoch, 0, rng_state, {})
            if dist.main:
                _write_csv(history, out / "log.csv")
                every = max(1, cfg.epochs // 50)
                if figures and (epoch % every == 0 or epoch == cfg.epochs):
                    save_loss_curves(history, out / "losses.png")
                if figures:
                    sample_grid(epoch)
    except KeyboardInterrupt:
        interrupted = True
        if stop["flag"] and epoch < cfg.epochs:
            # --resume continues the epoch in progress at its first batch not done
            stop["flag"] = False
            checkpoint(epoch, b, rng_state, sums)
        if dist.main and history:
            _write_csv(history, out / "log.csv")
            if figures:
                save_loss_curves(history, out / "losses.png")
        raise
    finally:
        if old_handler is not None:
            signal.signal(signal.SIGINT, old_handler)
        if bar is not None:
            bar.close()
    dist.close()
    el = time.perf_counter() - t_start
    return TrainResult(out, epoch, history, images / el if el > 0 else float("nan"),
                       interrupted)
