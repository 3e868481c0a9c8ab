"""Training loop of Model_AB, CAD plan -> SLAM map, grown progressively (``map2map train
ab``), thesis sec. 3.1 and 5.1 (Figs. 5.1, 5.3, Tables 5.1-5.2).

The objective is eq. 3.2 with the roles of the maps swapped against Model_BA: the input
``x`` is the plan (``a`` of the packed pairs), the target ``y`` the SLAM map (``b``).
``D_d`` (eq. 3.3, with false targets: other plans' SLAM maps), ``D_r`` (eq. 3.4), feature
matching (3.5), input consistency (3.6) and L1 (3.7) are the functions of
:mod:`~map2map.learn.losses`; the networks are those of :mod:`~map2map.learn.progressive`
(generator and both discriminators grown coarse to fine, each new block faded in).

The machinery is Model_BA's (:mod:`~map2map.learn.train`): data resident on the device
(:class:`~map2map.learn.data.ResidentPairs`, one per stage, built when the stage starts),
Adam 2e-4 / (0.55, 0.99) with the learning rate a pure function of the epoch
(:func:`~map2map.learn.config.lr_factor` over all the epochs), safetensors checkpoints
written atomically after every epoch and on Ctrl-C, exact ``--resume`` (the dropout's
random state is saved too) (the stage and the
fade-in alpha are functions of (epoch, batch), so nothing else has to be stored), DDP under
``torchrun`` (``find_unused_parameters``: the blocks of the stages not reached have no
gradient), bf16 autocast + channels_last on CUDA.

A run folder holds ``config.json``, ``model.safetensors`` (generator + header: the
resolution reached and its alpha), ``last.safetensors``, ``log.csv`` (one row per epoch
with its resolution, batch size and alpha), ``losses.png`` (Fig. 5.1, resolution switches
marked) and ``samples/epoch_NNNN.png`` (plan | generated | simulated SLAM map).

Examples
--------
>>> import tempfile, pathlib, numpy as np
>>> rng = np.random.default_rng(0)
>>> a = rng.choice(np.array([0, 127, 255], np.uint8), size=(4, 32, 32))
>>> pairs = PackedPairs(a, a[:, :, ::-1], np.arange(4).astype(str), np.array(["train"] * 4))
>>> cfg = ABConfig(schedule=((16, 1), (32, 1)), batch=2, g_channels=8, g_max_channels=16,
...                d_channels=8, d_layers=1, d_scales=2, fade_batches=4)
>>> run = pathlib.Path(tempfile.mkdtemp()) / "run"
>>> result = train_ab(pairs, run, cfg, progress=False, figures=False)
>>> [(r["resolution"], r["alpha"]) for r in result.history]
[(16, 1.0), (32, 0.25)]
"""

from __future__ import annotations

import json
import math
import os
import signal
import threading
import time
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
from .config import lr_factor
from .data import ResidentPairs, load_pairs
from .figures import save_sample_grid
from .losses import discriminator_loss_3_2, generator_loss_3_2
from .networks import count_parameters, from_unit
from .progressive import ABConfig, build_ab_networks, fade_alpha, fade_steps, stage_of
from .train import (
    CHECKPOINT_FILE,
    MODEL_FILE,
    TrainResult,
    _Dist,
    _set_grad,
    _split,
    _write_csv,
    false_targets,
)

__all__ = ["train_ab", "gan_step", "save_prog_loss_curves", "FORMAT_AB", "schedule_table"]

FORMAT_AB = "map2map-model-ab"


class _DistAB(_Dist):
    def wrap(self, net):
        if self.world == 1:
            return net
        from torch.nn.parallel import DistributedDataParallel as DDP

        ids = [self.device.index] if self.device.type == "cuda" else None
        return DDP(net, device_ids=ids, find_unused_parameters=True)


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


def gan_step(g_run, dd_run, dr_run, opt_g, opt_d, x: torch.Tensor, y: torch.Tensor,
             alpha: torch.Tensor | None, cfg, shift: int, autocast, freeze=(),
             g_input: torch.Tensor | None = None) -> dict:
    """One step of eq. 3.2: the discriminators (max side, false targets rolled by
    ``shift``), then the generator (min side). ``alpha`` (None or a 0-d tensor) is passed
    to every network. ``x`` is the input at the stage's resolution (what ``D_d`` sees);
    the generator reads ``g_input`` when given (decoder growth: the full-size input),
    else ``x``. Returns the logged values as tensors."""
    k = len(x)
    use_false = cfg.false_targets and k > 1
    with autocast:
        fake = g_run(x if g_input is None else g_input, alpha)
        real_pair = torch.cat([x, y], 1)
        groups = [real_pair, torch.cat([x, fake.detach()], 1)]
        if use_false:
            groups.append(torch.cat([x, false_targets(y, shift % k or 1)], 1))
        dd_out = _split(dd_run(torch.cat(groups), alpha), len(groups))
        dr_out = _split(dr_run(torch.cat([y, fake.detach()]), alpha), 2)
    loss_d, d_terms = discriminator_loss_3_2(
        dd_out[0], dd_out[1], dd_out[2] if use_false else None, dr_out[0], dr_out[1])
    opt_d.zero_grad(set_to_none=True)
    loss_d.backward()
    opt_d.step()
    _set_grad(freeze, False)
    with autocast:
        dd_out = _split(dd_run(torch.cat([real_pair, torch.cat([x, fake], 1)]), alpha), 2)
        dr_out = _split(dr_run(torch.cat([y, fake]), alpha), 2)
    loss_g, g_terms = generator_loss_3_2(
        dd_out[0], dd_out[1], dr_out[0], dr_out[1], fake, y,
        lambda_l1=cfg.lambda_l1, lambda_fm=cfg.lambda_fm, lambda_ic=cfg.lambda_ic)
    opt_g.zero_grad(set_to_none=True)
    loss_g.backward()
    opt_g.step()
    _set_grad(freeze, True)
    return {"loss_G": loss_g, "loss_D": loss_d, **g_terms, **d_terms}


def save_prog_loss_curves(history: list[dict], path: str | os.PathLike,
                          title: str = "Model_AB") -> None:
    """G and D losses per epoch as thesis Fig. 5.1, a dashed line and the new resolution
    at every stage switch, the terms of eq. 3.2 in a second panel.

    Examples
    --------
    >>> import tempfile, pathlib
    >>> rows = [{"epoch": e, "loss_G": 3.0 - e / 9, "loss_D": 1.2, "resolution": r}
    ...         for e, r in ((1, 32), (2, 32), (3, 64))]
    >>> p = pathlib.Path(tempfile.mkdtemp()) / "l.png"; save_prog_loss_curves(rows, p)
    >>> p.stat().st_size > 1000
    True
    """
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from .figures import TERMS

    ep = [r["epoch"] for r in history]
    fig, axes = plt.subplots(1, 2, figsize=(11, 4))
    axes[0].plot(ep, [r["loss_G"] for r in history], label="G")
    axes[0].plot(ep, [r["loss_D"] for r in history], label="D")
    axes[0].set(xlabel="epoch", ylabel="loss", title=f"{title}: G and D losses (Fig. 5.1)")
    terms = [t for t in TERMS if history and t in history[0]]
    for t in terms:
        axes[1].plot(ep, [max(r[t], 1e-6) for r in history], label=t)
    axes[1].set(xlabel="epoch", yscale="log", title="terms of eq. 3.2 (l1 unweighted)")
    for prev, row in zip(history, history[1:], strict=False):
        if row.get("resolution") != prev.get("resolution"):
            for ax in axes:
                ax.axvline(row["epoch"] - 0.5, color="0.5", ls="--", lw=0.8)
            axes[0].annotate(f"{row['resolution']} px", (row["epoch"] - 0.5, 1.0),
                             xycoords=("data", "axes fraction"), fontsize=7, ha="left",
                             va="top", rotation=90)
    axes[0].legend()
    if terms:
        axes[1].legend(fontsize=7)
    fig.tight_layout()
    with atomic_path(path) as tmp:
        fig.savefig(tmp, dpi=90, format="png")
    plt.close(fig)


def model_header_ab(cfg: ABConfig, meta: dict, extra: dict) -> dict:
    """The JSON stored with the generator: what :func:`~map2map.learn.synthesize.synthesize`
    needs and where it came from."""
    return {"format": FORMAT_AB,
            "generator": dict(size=cfg.size, channels=cfg.g_channels,
                              max_channels=cfg.g_max_channels, bottleneck=cfg.bottleneck,
                              min_size=cfg.min_size, dropout=cfg.dropout, growth=cfg.growth),
            "train": cfg.to_dict(), "dataset": meta, **extra}


def train_ab(data: str | os.PathLike | PackedPairs, out: str | os.PathLike,
             config: ABConfig | None = None, *, resume: bool = False,
             epochs: int | None = None, progress: bool = True, figures: bool = True
             ) -> TrainResult:
    """Train Model_AB (input: CAD plan ``a``, target: SLAM map ``b``) progressively.

    Parameters
    ----------
    data : path or PackedPairs
        A dataset folder (``packed.npz`` inside), a packed ``.npz``, or pairs in memory.
    out : path
        Run folder (created).
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
    out = Path(out)
    pairs = load_pairs(data)
    src = data if not isinstance(data, PackedPairs) else None
    ck_path = out / CHECKPOINT_FILE
    tensors, state = {}, {}
    if resume:
        tensors, state = load_checkpoint(ck_path)
        if state.get("format") != FORMAT_AB:
            raise InputError(ck_path, "not a Model_AB training checkpoint")
        cfg = ABConfig.from_dict(state["config"])
        if state["dataset"].get("digest") != pairs.meta.get("digest", pairs.digest()):
            raise InputError(src, "this is not the dataset the run was trained on "
                                  "(digest differs)")
    else:
        cfg = config or ABConfig()
        if ck_path.exists():
            raise InputError(out, "the run folder already holds a checkpoint; "
                                  "use --resume to continue it or another --out")
    if epochs is not None:
        cfg.epochs = int(epochs)
    dist = _DistAB(cfg)
    dev = dist.device
    cuda = dev.type == "cuda"
    amp = cuda and cfg.amp
    train = pairs.select("train")
    if len(train) == 0:
        raise InputError(src, "the dataset has no 'train' pairs")
    if pairs.a.shape[-1] < cfg.size:
        raise InputError(src, f"dataset maps are {pairs.a.shape[-1]} px; the schedule "
                              f"ends at {cfg.size}")
    try:
        g, dd, dr = build_ab_networks(cfg)
    except ValueError as exc:
        raise InputError("--schedule", str(exc)) from None
    if dist.main:
        ensure_output_dir(out)
        (out / "samples").mkdir(exist_ok=True)
    val = pairs.select("val")
    show = val if len(val) else train
    meta = dict(pairs.meta)
    meta.setdefault("digest", pairs.digest())
    for n in (g, dd, dr):
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
        torch.set_rng_state(tensors["rng.torch"])
        if cuda and "rng.cuda" in tensors:
            torch.cuda.set_rng_state(tensors["rng.cuda"], dev)
        epoch, start_batch = state["epoch"], state["batch"]
        sums, history = state["sums"], state["history"]
    from .postprocess import wall_thickness_px

    table = schedule_table(cfg, len(train))
    extra = {"target_wall_px": wall_thickness_px(train.b), "data_size": int(pairs.a.shape[-1]),
             "direction": "CAD -> SLAM", "schedule_table": table,
             "parameters": {"G": count_parameters(g), "D_d": count_parameters(dd),
                            "D_r": count_parameters(dr)}}
    header = model_header_ab(cfg, meta, extra)
    if dist.main:
        with atomic_path(out / "config.json") as tmp:
            tmp.write_text(json.dumps(header, indent=2, sort_keys=True))

    g_run = torch.compile(g) if cfg.compile else g
    g_run, dd_run, dr_run = dist.wrap(g_run), dist.wrap(dd), dist.wrap(dr)
    autocast = torch.autocast("cuda", dtype=torch.bfloat16, enabled=amp) if cuda else \
        torch.autocast("cpu", enabled=False)
    alpha_t = torch.zeros((), device=dev)  # updated in place: one tensor for the whole run
    n = len(train)
    resident: dict[int, tuple[ResidentPairs, ResidentPairs]] = {}
    decoder = cfg.growth == "decoder"
    full_inputs: dict[str, ResidentPairs] = {}

    def stage_data(r: int):
        if r not in resident:
            resident.clear()  # one stage's data on the device at a time
            resident[r] = (
                ResidentPairs(train.a, train.b, r, dev, channels_last=amp,
                              input_reduce=cfg.input_reduce),
                ResidentPairs(show.a[:cfg.samples], show.b[:cfg.samples], r, dev,
                              channels_last=amp, input_reduce=cfg.input_reduce))
            g.out_size = r
        if decoder and not full_inputs:  # the generator's input: always cfg.size
            for name, part in (("train", train.a), ("show", show.a[:cfg.samples])):
                full_inputs[name] = ResidentPairs(part, part[:, :1, :1], cfg.size, dev,
                                                  channels_last=amp, input_reduce=cfg.input_reduce,
                                                  target_size=1)
        return resident[r]

    def g_input(name: str, idx: torch.Tensor) -> torch.Tensor | None:
        return full_inputs[name].batch(idx)[0] if decoder else None

    def n_batches_at(r: int) -> int:
        B = cfg.stage_batch(r)
        return n // B if dist.world > 1 else math.ceil(n / B)

    for r, _ in cfg.schedule:
        if n_batches_at(r) == 0:
            raise InputError(src, f"{n} training pairs are fewer than one batch of "
                                  f"{cfg.stage_batch(r)} at {r} px")

    def alpha_at(ep: int, b: int) -> tuple[float, int]:
        stage, r, first = stage_of(ep, cfg.schedule)
        nb = n_batches_at(r)
        steps = fade_steps(stage, nb, cfg)
        return fade_alpha((ep - first) * nb + b, steps), steps

    def checkpoint(ep: int, batch: int, rng_state: torch.Tensor, run_sums: dict) -> None:
        if not dist.main:
            return
        t = {**module_tensors(g, "G"), **module_tensors(dd, "D_d"), **module_tensors(dr, "D_r")}
        tg, groups_g = optimizer_tensors(opt_g, "opt_G")
        td, groups_d = optimizer_tensors(opt_d, "opt_D")
        t.update(tg)
        t.update(td)
        t["rng.shuffle"] = rng_state
        t["rng.torch"] = torch.get_rng_state()  # the dropout masks draw from it
        if cuda:
            t["rng.cuda"] = torch.cuda.get_rng_state(dev)
        st = {"format": FORMAT_AB, "config": cfg.to_dict(), "dataset": meta, "epoch": ep,
              "batch": batch, "sums": run_sums, "history": history, "opt_G": groups_g,
              "opt_D": groups_d}
        save_checkpoint(ck_path, t, st)
        # the generator as trained so far: the stage of the last batch done, its alpha
        last_ep, last_b = (ep, batch - 1) if batch > 0 else (ep - 1, None)
        if last_ep < 0:
            return
        r_done = stage_of(last_ep, cfg.schedule)[1]
        a_done = alpha_at(last_ep, last_b if last_b is not None else n_batches_at(r_done) - 1
                          )[0]
        g_header = {"map2map": json.dumps({**header, "epochs_trained": ep,
                                           "resolution": r_done, "alpha": a_done},
                                          sort_keys=True)}
        with atomic_path(out / MODEL_FILE) as tmp:
            from safetensors.torch import save_file

            save_file({k: v.detach().cpu().contiguous() for k, v in g.state_dict().items()},
                      str(tmp), metadata=g_header)

    def sample_grid(ep: int, shown: ResidentPairs, alpha) -> None:
        if not dist.main or len(shown) == 0:
            return
        g.eval()
        with torch.no_grad(), autocast:
            idx = torch.arange(len(shown))
            x, y = shown.batch(idx)
            gi = g_input("show", idx)
            o = g(x if gi is None else gi, alpha)
        g.train()
        save_sample_grid(from_unit(x[:, 0]), from_unit(o[:, 0]), from_unit(y[:, 0]),
                         out / "samples" / f"epoch_{ep:04d}.png")

    total = sum(n_batches_at(stage_of(e, cfg.schedule)[1]) for e in range(cfg.epochs))
    done = sum(n_batches_at(stage_of(e, cfg.schedule)[1]) for e in range(epoch)) + start_batch
    bar = None
    if progress and dist.main:
        from tqdm.auto import tqdm

        bar = tqdm(total=total, initial=min(total, done), desc="train ab", unit="batch",
                   dynamic_ncols=True)
    images, t_start = 0, time.perf_counter()
    interrupted = False
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
    freeze = (dd, dr) if dist.world == 1 else ()
    try:
        while epoch < cfg.epochs:
            stage, r, first = stage_of(epoch, cfg.schedule)
            res, shown = stage_data(r)
            B, nb = cfg.stage_batch(r), n_batches_at(r)
            per_rank = max(1, B // dist.world)
            rng_state = gen.get_state()
            perm = torch.randperm(n, generator=gen)
            shifts = torch.randint(1, max(2, B), (nb,), generator=gen)
            f = lr_factor(epoch, cfg)
            for o in (opt_g, opt_d):
                for grp in o.param_groups:
                    grp["lr"] = cfg.lr * f
            t_epoch = time.perf_counter()
            b = start_batch
            a = 1.0
            while b < nb:
                a, steps = alpha_at(epoch, b)
                if a < 1.0:
                    alpha_t.fill_(a)
                alpha = alpha_t if a < 1.0 else None
                idx = perm[b * B:(b + 1) * B]
                if dist.world > 1:
                    idx = idx[dist.rank * per_rank:(dist.rank + 1) * per_rank]
                x, y = res.batch(idx)
                vals = gan_step(g_run, dd_run, dr_run, opt_g, opt_d, x, y, alpha, cfg,
                                int(shifts[b]), autocast, freeze, g_input("train", idx))
                k = len(idx)
                for key, v in vals.items():
                    sums[key] = sums.get(key, 0.0) + float(v.detach()) * k
                sums["_n"] = sums.get("_n", 0.0) + k
                images += k * dist.world
                b += 1
                if bar is not None:
                    el = time.perf_counter() - t_start
                    bar.set_postfix_str(f"epoch {epoch + 1}/{cfg.epochs} {r}px a={a:.2f} "
                                        f"{images / max(el, 1e-9):.0f} img/s "
                                        f"G {float(vals['loss_G'].detach()):.3f} "
                                        f"D {float(vals['loss_D'].detach()):.3f}")
                    bar.update(1)
                if stop["flag"]:
                    raise KeyboardInterrupt
            a_end, steps = alpha_at(epoch, nb - 1)
            row = {"epoch": epoch + 1, "lr": cfg.lr * f, "resolution": r, "batch": B,
                   "alpha": a_end, "fade_batches": steps}
            row.update(dist.mean({k: v / sums["_n"] for k, v in sums.items() if k != "_n"}))
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
                    save_prog_loss_curves(history, out / "losses.png")
                if figures:
                    if a_end < 1.0:
                        alpha_t.fill_(a_end)
                    sample_grid(epoch, shown, alpha_t if a_end < 1.0 else None)
    except KeyboardInterrupt:
        interrupted = True
        if stop["flag"] and epoch < cfg.epochs:
            stop["flag"] = False
            checkpoint(epoch, b, rng_state, sums)
        if dist.main and history:
            _write_csv(history, out / "log.csv")
            if figures:
                save_prog_loss_curves(history, out / "losses.png")
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
