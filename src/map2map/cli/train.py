"""``map2map train ba``: train Model_BA, the learned SLAM -> CAD auto-correct."""

from __future__ import annotations

import argparse
import sys


def register(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser(
        "train",
        help="train a learned model (ba: SLAM -> CAD auto-correct; ab: CAD -> SLAM)",
        description="Train a learned map model on a packed dataset (thesis 3.1, 4.2). "
        "Multi-GPU: torchrun --nproc_per_node K -m map2map train ba ...",
    )
    tsub = p.add_subparsers(dest="model", metavar="MODEL")
    tsub.required = True
    b = tsub.add_parser(
        "ba",
        help="Model_BA: SLAM map -> CAD plan (64 px by default; --size 32 = Model_32)",
        description="Train Model_BA (eq. 3.2) on the train split of DATA; write config.json, "
        "model.safetensors, last.safetensors (resumable), log.csv, losses.png and "
        "samples/epoch_NNNN.png under --out. Ctrl-C saves a checkpoint; --resume continues.",
    )
    b.add_argument("--data", required=True, help="dataset folder (packed.npz inside) or .npz")
    b.add_argument("--out", required=True, help="run folder")
    b.add_argument("--epochs", type=int, help="number of epochs (default 200; with --resume: "
                   "extend the run to this many)")
    b.add_argument("--resume", action="store_true", help="continue the run in --out exactly")
    b.add_argument("--size", type=int, default=64, help="training resolution (default 64, "
                   "measured better than the thesis's Model_32: --size 32; the dataset's size "
                   "for the full-resolution variant)")
    b.add_argument("--batch", type=int, help="batch size (default: Table 5.1 x batch_rate 0.5)")
    b.add_argument("--device", default="auto", help="auto (CUDA when present), cpu, cuda, ...")
    b.add_argument("--seed", type=int, default=0, help="random seed (default 0)")
    b.add_argument("--lambda-l1", type=float, default=100.0, help="weight of eq. 3.7 (100)")
    b.add_argument("--g-channels", type=int, default=32, help="generator width (32)")
    b.add_argument("--g-max-channels", type=int, default=128, help="generator cap (128)")
    b.add_argument("--d-channels", type=int, default=32, help="discriminator width (32)")
    b.add_argument("--d-layers", type=int, default=3,
                   help="stride-2 layers per patch discriminator (3)")
    b.add_argument("--input-reduce", choices=("area", "classes"), default="area",
                   help="how the SLAM map is reduced to --size: area average (default) or "
                   "per class, walls kept")
    _step_options(b)
    b.set_defaults(func=run)
    register_ab(tsub)


def _step_options(b: argparse.ArgumentParser) -> None:
    """The options ``train ba`` and ``train ab`` share after their own: the step, the
    checkpoints, the progress bar."""
    b.add_argument("--no-false-targets", action="store_true",
                   help="no false-target augmentation for D_d")
    b.add_argument("--no-amp", action="store_true", help="fp32 on CUDA (no bf16 autocast)")
    b.add_argument("--compile", action="store_true", help="torch.compile the generator")
    b.add_argument("--cuda-graph", action="store_true",
                   help="run each training step as one CUDA graph replay (single process; "
                   "falls back to eager steps if capture fails; on CPU: eager, same result)")
    b.add_argument("--save-every", type=int, default=1, metavar="N",
                   help="checkpoint, sample grid and logs every N epochs (default 1; also "
                   "after the last and on Ctrl-C)")
    b.add_argument("--quiet", action="store_true", help="no progress bar")


def register_ab(tsub) -> None:
    """``map2map train ab``: Model_AB (CAD -> SLAM), grown progressively (Model_prog)."""
    b = tsub.add_parser(
        "ab",
        help="Model_AB: CAD plan -> SLAM map, grown coarse to fine (Model_prog)",
        description="Train Model_AB (eq. 3.2, plan -> SLAM map) on the train split of DATA, "
        "generator and both discriminators grown coarse to fine with a fade-in of each new "
        "resolution (thesis 3.1; Table 5.2's schedule, Table 5.1's batches x batch_rate 1). "
        "Writes what 'train ba' writes; losses.png marks the resolution switches (Fig. 5.1).",
    )
    b.add_argument("--data", required=True, help="dataset folder (packed.npz inside) or .npz")
    b.add_argument("--out", required=True, help="run folder")
    b.add_argument("--schedule", default="32:15,64:30,128:60,256:100",
                   help="RES:EPOCHS per stage, coarse to fine (default Table 5.2)")
    b.add_argument("--epochs", type=int, help="total epochs (default: the schedule's sum; "
                   "beyond it the last resolution continues; with --resume: extend)")
    b.add_argument("--resume", action="store_true", help="continue the run in --out exactly")
    b.add_argument("--batch", type=int, help="one batch size for every stage (default: "
                   "Table 5.1 x --batch-rate)")
    b.add_argument("--batch-rate", type=float, default=1.0, help="Table 5.1 multiplier (1)")
    b.add_argument("--fade-share", type=float, default=0.5,
                   help="fade-in length as a share of each new stage's batches (0.5)")
    b.add_argument("--fade-batches", type=int, help="fade-in length in batches (overrides "
                   "--fade-share)")
    b.add_argument("--dropout", type=float, default=0.5,
                   help="decoder dropout, the hypotheses' noise source (0.5)")
    b.add_argument("--growth", choices=("full", "decoder"), default="full",
                   help="full: generator and discriminators at each stage's resolution "
                   "(the thesis's reading, default); decoder: the generator always reads "
                   "the last stage's size and its decoder exits early (anime2clothing's)")
    b.add_argument("--device", default="auto", help="auto (CUDA when present), cpu, cuda, ...")
    b.add_argument("--seed", type=int, default=0, help="random seed (default 0)")
    b.add_argument("--lambda-l1", type=float, default=100.0, help="weight of eq. 3.7 (100)")
    b.add_argument("--g-channels", type=int, default=32, help="generator width at the "
                   "finest resolution (32)")
    b.add_argument("--g-max-channels", type=int, default=256, help="generator cap (256)")
    b.add_argument("--d-channels", type=int, default=32, help="discriminator width (32)")
    b.add_argument("--d-layers", type=int, default=3,
                   help="stride-2 layers of the first stage's patch discriminators (3)")
    _step_options(b)
    b.set_defaults(func=run_ab)


def run_ab(args: argparse.Namespace) -> int:
    from ..core.errors import InputError

    try:
        from ..learn.ab.config import ABConfig, parse_schedule
        from ..learn.ab.train import train_ab
    except ImportError as exc:
        raise InputError("train", f"needs PyTorch: pip install 'map2map[learn]' ({exc})") from None
    for name in ("epochs", "batch", "fade_batches", "save_every"):
        v = getattr(args, name)
        if v is not None and v < (0 if name == "fade_batches" else 1):
            raise InputError(f"--{name.replace('_', '-')}", f"must be positive, got {v}")
    try:
        cfg = ABConfig(
            schedule=parse_schedule(args.schedule), epochs=args.epochs or 0, batch=args.batch,
            batch_rate=args.batch_rate, fade_share=args.fade_share,
            fade_batches=args.fade_batches, dropout=args.dropout, device=args.device,
            seed=args.seed, lambda_l1=args.lambda_l1, g_channels=args.g_channels,
            g_max_channels=args.g_max_channels, d_channels=args.d_channels,
            d_layers=args.d_layers, false_targets=not args.no_false_targets,
            amp=not args.no_amp, compile=args.compile, cuda_graph=args.cuda_graph,
            growth=args.growth,
            save_every=args.save_every)
    except ValueError as exc:
        raise InputError("--schedule", str(exc)) from None
    res = train_ab(args.data, args.out, cfg, resume=args.resume,
                   epochs=args.epochs if args.resume else None, progress=not args.quiet)
    import os

    if int(os.environ.get("RANK", "0")) != 0:
        return 0
    last = res.history[-1] if res.history else {}
    steps = f" ({last['step']} steps)" if "step" in last else ""
    print(f"trained {res.epochs_done} epochs (now {last.get('resolution', '?')} px, alpha "
          f"{last.get('alpha', float('nan')):.2f}) at {res.images_per_s:.0f} img/s{steps}; "
          f"loss G {last.get('loss_G', float('nan')):.4f} D {last.get('loss_D', float('nan')):.4f}"
          f"; run in {res.run}", file=sys.stderr)
    return 0


def run(args: argparse.Namespace) -> int:
    from ..core.errors import InputError

    try:
        from ..learn.ba.train import train_ba
        from ..learn.training.config import TrainConfig
    except ImportError as exc:
        raise InputError("train", f"needs PyTorch: pip install 'map2map[learn]' ({exc})") from None
    for name in ("epochs", "batch", "save_every"):
        v = getattr(args, name)
        if v is not None and v < 1:
            raise InputError(f"--{name}", f"must be >= 1, got {v}")
    if args.size < 4 or args.size & (args.size - 1):
        raise InputError("--size", f"must be a power of two >= 4, got {args.size}")
    cfg = TrainConfig(
        size=args.size, epochs=args.epochs or 200, batch=args.batch, device=args.device,
        seed=args.seed, lambda_l1=args.lambda_l1, g_channels=args.g_channels,
        g_max_channels=args.g_max_channels, d_channels=args.d_channels, d_layers=args.d_layers,
        input_reduce=args.input_reduce,
        false_targets=not args.no_false_targets, amp=not args.no_amp, compile=args.compile,
        cuda_graph=args.cuda_graph, save_every=args.save_every,
    )
    res = train_ba(args.data, args.out, cfg, resume=args.resume,
                   epochs=args.epochs if args.resume else None, progress=not args.quiet)
    import os

    if int(os.environ.get("RANK", "0")) != 0:  # torchrun: one report, from rank 0
        return 0
    last = res.history[-1] if res.history else {}
    steps = f" ({last['step']} steps)" if "step" in last else ""
    print(f"trained {res.epochs_done} epochs at {res.images_per_s:.0f} img/s{steps}; "
          f"loss G {last.get('loss_G', float('nan')):.4f} D {last.get('loss_D', float('nan')):.4f}"
          f"; run in {res.run}", file=sys.stderr)
    return 0
