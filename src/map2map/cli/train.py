"""``map2map train ba`` / ``train ab``: train Model_BA (SLAM -> CAD) or Model_AB (CAD ->
SLAM). Parsing only: :func:`map2map.jobs.train.train` does the work; every default is the
model's config dataclass's (:class:`~map2map.learn.ba.config.BAConfig`,
:class:`~map2map.learn.ab.config.ABConfig`), read here, not written again."""

from __future__ import annotations

import argparse
import sys

from ..learn.ab.config import GROWTHS, ABConfig
from ..learn.ba.config import BAConfig

#: settings both models take from their own options of the same name
_COMMON = ("epochs", "batch", "device", "seed", "lambda_l1", "g_channels", "g_max_channels",
           "d_channels", "d_layers", "save_every")


def register(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser(
        "train",
        help="train a learned model (ba: SLAM -> CAD auto-correct; ab: CAD -> SLAM)",
        description="Train a learned map model on a packed dataset (thesis 3.1, 4.2). "
        "Multi-GPU: torchrun --nproc_per_node K -m map2map train ba ...",
    )
    tsub = p.add_subparsers(dest="model", metavar="MODEL")
    tsub.required = True
    register_ba(tsub)
    register_ab(tsub)
    register_pose_error(tsub)


def register_pose_error(tsub) -> None:
    """``map2map train pose-error``: the learned SLAM pose error of ``synthesize``'s scans."""
    b = tsub.add_parser(
        "pose-error",
        help="the learned pose error of 'synthesize --pose-error learned' (a particle "
        "filter's error, learned from simulated runs)",
        description="Explore RUNS generated plans (as 'dataset build --plans generated "
        "--seed SEED' draws them) with the simulator's robot on its rbpf particle filter's "
        "map, and fit the learned pose-error model to the filter's errors "
        "(map2map.learn.ab.pose_error). Writes OUT (.safetensors, the settings in its "
        "header), its .json, OUT-losses.png and OUT-samples.png (recorded errors beside "
        "drawn ones).",
    )
    b.add_argument("--out", required=True, help="the model file (.safetensors)")
    b.add_argument("--runs", type=int, default=400, help="plans explored (default 400)")
    b.add_argument("--seed", type=int, default=20270101,
                   help="the generated plans' seed (default 20270101, the shipped model's)")
    b.add_argument("--epochs", type=int, default=30, help="training epochs (default 30)")
    b.add_argument("--duration", type=float, default=420.0,
                   help="simulated seconds of each exploration (default 420, the datasets')")
    b.add_argument("--workers", type=int, help="exploring processes (default one per core)")
    b.add_argument("--quiet", action="store_true", help="no progress bars")
    b.set_defaults(func=run_pose_error)


def run_pose_error(args: argparse.Namespace) -> int:
    from ..jobs.train import train_pose_error_job

    cfg = train_pose_error_job(args.out, runs=args.runs, seed=args.seed, epochs=args.epochs,
                               duration=args.duration, workers=args.workers,
                               command="map2map " + " ".join(sys.argv[1:]),
                               progress=not args.quiet)
    print(f"pose error: {cfg['runs']} runs ({cfg['train_steps'] + cfg['val_steps']} steps), "
          f"held-out log-likelihood {cfg['val_loglik']:.3f} per step; wrote {args.out}",
          file=sys.stderr)
    return 0


def _data_options(b: argparse.ArgumentParser, epochs_help: str) -> None:
    b.add_argument("--data", required=True, nargs="+", metavar="DS",
                   help="dataset folder (packed.npz inside) or .npz; several: their pairs "
                   "merged, each keeping its splits")
    b.add_argument("--out", required=True, help="run folder")
    b.add_argument("--epochs", type=int, help=epochs_help)
    b.add_argument("--resume", action="store_true", help="continue the run in --out exactly")


def _width_options(b: argparse.ArgumentParser, cfg, g_help: str, d_layers_help: str) -> None:
    b.add_argument("--device", default=cfg.device,
                   help=f"auto (CUDA when present), cpu, cuda, ... (default {cfg.device})")
    b.add_argument("--seed", type=int, default=cfg.seed,
                   help=f"random seed (default {cfg.seed})")
    b.add_argument("--lambda-l1", type=float, default=cfg.lambda_l1,
                   help=f"weight of eq. 3.7 ({cfg.lambda_l1:g})")
    b.add_argument("--g-channels", type=int, default=cfg.g_channels,
                   help=f"{g_help} ({cfg.g_channels})")
    b.add_argument("--g-max-channels", type=int, default=cfg.g_max_channels,
                   help=f"generator cap ({cfg.g_max_channels})")
    b.add_argument("--d-channels", type=int, default=cfg.d_channels,
                   help=f"discriminator width ({cfg.d_channels})")
    b.add_argument("--d-layers", type=int, default=cfg.d_layers,
                   help=f"{d_layers_help} ({cfg.d_layers})")


def _step_options(b: argparse.ArgumentParser, cfg) -> None:
    """The options ``train ba`` and ``train ab`` share after their own: the step, the
    checkpoints, the progress bar."""
    b.add_argument("--no-false-targets", action="store_true",
                   help="no false-target augmentation for D_d")
    b.add_argument("--no-amp", action="store_true", help="fp32 on CUDA (no bf16 autocast)")
    b.add_argument("--nchw", action="store_true", help="CUDA: keep networks and data NCHW "
                   "under bf16 (default channels-last; benchmarks.bench_ab --nchw says which "
                   "is faster)")
    b.add_argument("--compile", action="store_true", help="torch.compile the generator")
    b.add_argument("--cuda-graph", action="store_true",
                   help="run each training step as one CUDA graph replay (single process; "
                   "falls back to eager steps if capture fails; on CPU: eager, same result)")
    b.add_argument("--save-every", type=int, default=cfg.save_every, metavar="N",
                   help=f"checkpoint, sample grid and logs every N epochs (default "
                   f"{cfg.save_every}; also after the last and on Ctrl-C)")
    b.add_argument("--quiet", action="store_true", help="no progress bar")


def register_ba(tsub) -> None:
    """``map2map train ba``: Model_BA (SLAM -> CAD)."""
    cfg = BAConfig()
    b = tsub.add_parser(
        "ba",
        help=f"Model_BA: SLAM map -> CAD plan ({cfg.size} px by default; --size 32 = "
        "Model_32)",
        description="Train Model_BA (eq. 3.2) on the train split of DATA; write config.json, "
        "model.safetensors, last.safetensors (resumable), log.csv, losses.png and "
        "samples/epoch_NNNN.png under --out. Ctrl-C saves a checkpoint; --resume continues.",
    )
    _data_options(b, f"number of epochs (default {cfg.epochs}; with --resume: extend the run "
                  "to this many)")
    b.add_argument("--size", type=int, default=cfg.size,
                   help=f"training resolution (default {cfg.size}, measured better than the "
                   "thesis's Model_32: --size 32; the dataset's size for the full-resolution "
                   "variant)")
    b.add_argument("--batch", type=int, help="batch size (default: Table 5.1 x batch_rate "
                   f"{cfg.batch_rate:g})")
    _width_options(b, cfg, "generator width", "stride-2 layers per patch discriminator")
    b.add_argument("--input-reduce", choices=("area", "classes"), default=cfg.input_reduce,
                   help="how the SLAM map is reduced to --size: area average or per class, "
                   f"walls kept (default {cfg.input_reduce})")
    _step_options(b, cfg)
    b.set_defaults(func=run)


def register_ab(tsub) -> None:
    """``map2map train ab``: Model_AB (CAD -> SLAM), grown progressively (Model_prog)."""
    cfg = ABConfig()
    b = tsub.add_parser(
        "ab",
        help="Model_AB: CAD plan -> SLAM map, grown coarse to fine (Model_prog)",
        description="Train Model_AB (eq. 3.2, plan -> SLAM map) on the train split of DATA, "
        "generator and both discriminators grown coarse to fine with a fade-in of each new "
        "resolution (thesis 3.1; Table 5.2's schedule, Table 5.1's batches x batch_rate 1). "
        "Writes what 'train ba' writes; losses.png marks the resolution switches (Fig. 5.1).",
    )
    _data_options(b, "total epochs (default: the schedule's sum; beyond it the last "
                  "resolution continues; with --resume: extend)")
    schedule = ",".join(f"{r}:{e}" for r, e in cfg.schedule)
    b.add_argument("--schedule", default=schedule,
                   help=f"RES:EPOCHS per stage, coarse to fine (default Table 5.2: {schedule})")
    b.add_argument("--batch", type=int, help="one batch size for every stage (default: "
                   "Table 5.1 x --batch-rate)")
    b.add_argument("--batch-rate", type=float, default=cfg.batch_rate,
                   help=f"Table 5.1 multiplier ({cfg.batch_rate:g})")
    b.add_argument("--fade-share", type=float, default=cfg.fade_share,
                   help=f"fade-in length as a share of each new stage's batches "
                   f"({cfg.fade_share:g})")
    b.add_argument("--fade-batches", type=int, help="fade-in length in batches (overrides "
                   "--fade-share)")
    b.add_argument("--dropout", type=float, default=cfg.dropout,
                   help=f"decoder dropout, the hypotheses' noise source ({cfg.dropout:g})")
    b.add_argument("--growth", choices=GROWTHS, default=cfg.growth,
                   help="full: generator and discriminators at each stage's resolution "
                   "(the thesis's reading); decoder: the generator always reads the last "
                   f"stage's size and its decoder exits early (anime2clothing's); default "
                   f"{cfg.growth}")
    _width_options(b, cfg, "generator width at the finest resolution",
                   "stride-2 layers of the first stage's patch discriminators")
    _step_options(b, cfg)
    b.set_defaults(func=run_ab)


def _settings(args: argparse.Namespace, own: tuple[str, ...]) -> dict:
    return {**{k: getattr(args, k) for k in (*_COMMON, *own)},
            "false_targets": not args.no_false_targets, "amp": not args.no_amp,
            "channels_last": not args.nchw, "compile": args.compile,
            "cuda_graph": args.cuda_graph}


def _train(args: argparse.Namespace, model: str, own: tuple[str, ...]) -> int:
    from ..jobs.train import TrainSpec, train

    data = args.data if len(args.data) > 1 else args.data[0]
    run = train(TrainSpec(model, data, args.out, _settings(args, own),
                          resume=args.resume, progress=not args.quiet))
    if run.main:
        print(run.summary(), file=sys.stderr)
    return 0


def run(args: argparse.Namespace) -> int:
    return _train(args, "ba", ("size", "input_reduce"))


def run_ab(args: argparse.Namespace) -> int:
    return _train(args, "ab", ("schedule", "batch_rate", "fade_share", "fade_batches",
                               "dropout", "growth"))
