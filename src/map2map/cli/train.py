"""``map2map train ba``: train Model_BA, the learned SLAM -> CAD auto-correct."""

from __future__ import annotations

import argparse
import sys


def register(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser(
        "train",
        help="train a learned model (ba: SLAM -> CAD auto-correct)",
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
    b.add_argument("--no-false-targets", action="store_true",
                   help="no false-target augmentation for D_d")
    b.add_argument("--no-amp", action="store_true", help="fp32 on CUDA (no bf16 autocast)")
    b.add_argument("--compile", action="store_true", help="torch.compile the generator")
    b.add_argument("--quiet", action="store_true", help="no progress bar")
    b.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    from ..core.errors import InputError

    try:
        from ..learn.config import TrainConfig
        from ..learn.train import train_ba
    except ImportError as exc:
        raise InputError("train", f"needs PyTorch: pip install 'map2map[learn]' ({exc})") from None
    for name in ("epochs", "batch"):
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
    )
    res = train_ba(args.data, args.out, cfg, resume=args.resume,
                   epochs=args.epochs if args.resume else None, progress=not args.quiet)
    import os

    if int(os.environ.get("RANK", "0")) != 0:  # torchrun: one report, from rank 0
        return 0
    last = res.history[-1] if res.history else {}
    print(f"trained {res.epochs_done} epochs at {res.images_per_s:.0f} img/s; "
          f"loss G {last.get('loss_G', float('nan')):.4f} D {last.get('loss_D', float('nan')):.4f}"
          f"; run in {res.run}", file=sys.stderr)
    return 0
