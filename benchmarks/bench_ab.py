"""Speed of Model_prog (Model_AB) training per stage, and Table 5.2's schedule projected.

For each stage resolution: the full eq. 3.2 step (:func:`map2map.learn.ab.train.gan_step`:
two 3-scale progressive discriminators with false targets, feature matching, input
consistency, L1) at Table 5.1's batch (batch_rate 1) on data resident on the device,
during the fade-in (alpha a tensor), after warm-up steps; images/s. Then the time the
whole Table 5.2 schedule would take on ``--pairs`` pairs (4,224: the issue's dataset).
Issue #15's target: >= 700 img/s at 256 px on one H100 (bf16 + channels_last there).

    python3 -m benchmarks.bench_ab [--quick] [--device cpu|cuda] [--steps 10]
        [--growth full|decoder] [--threads N] [--graph | --compile] [--nchw] [--profile]
        [--only 256]

On a machine without CUDA it measures the CPU and says that the GPU target is
unmeasured (a CPU figure is no evidence for or against it).

``--quick``: stages 32 and 64 only, 2 timed steps, narrow networks (G 8-32 channels,
D 8): a CPU smoke run of the script, not a figure to compare with the target.
"""

from __future__ import annotations

import argparse
import sys
import time

import torch

from map2map.learn.ab.config import ABConfig
from map2map.learn.ab.model import build_ab_networks
from map2map.learn.training.loop import place_networks, step_autocast
from map2map.learn.training.static_step import StaticStep, graph_autocast
from map2map.learn.training.step import gan_step


def stage_speed(cfg: ABConfig, r: int, dev: torch.device, steps: int, warm: int = 2,
                graph: bool = False, profile: bool = False,
                compiled: bool = False, nchw: bool = False) -> tuple[float, str]:
    """Images/s of ``steps`` training steps at stage ``r`` (fading in), and which step ran
    (``graph``: the :class:`~map2map.learn.training.static_step.StaticStep` replayed as a CUDA
    graph,
    eager elsewhere); ``profile``: then print where the device time goes; ``compiled``:
    G through ``torch.compile`` (as ``train ab --compile``; not with ``graph``); ``nchw``:
    networks and data kept in NCHW under bf16 (the trainer uses channels-last; GroupNorm
    returns NCHW, so cuDNN transposes around every convolution after it)."""
    g, dd, dr = build_ab_networks(cfg)
    amp = dev.type == "cuda" and cfg.amp
    opt_g, opt_d = place_networks((g, dd, dr), dev, amp, cfg)
    if nchw:
        for net in (g, dd, dr):
            net.to(memory_format=torch.contiguous_format)
    B = cfg.stage_batch(r)
    gen = torch.Generator().manual_seed(0)
    x = (torch.randint(0, 3, (B, 1, r, r), generator=gen).float() - 1).to(dev)
    y = (torch.randint(0, 3, (B, 1, r, r), generator=gen).float() - 1).to(dev)
    s = cfg.size
    gi = None
    if cfg.growth == "decoder":  # the generator reads the full-size input, exits at r
        gi = (torch.randint(0, 3, (B, 1, s, s), generator=gen).float() - 1).to(dev)
        g.out_size = r
    if amp and not nchw:
        x, y = (t.contiguous(memory_format=torch.channels_last) for t in (x, y))
        if gi is not None:
            gi = gi.contiguous(memory_format=torch.channels_last)
    alpha = torch.tensor(0.5, device=dev) if r > cfg.min_size else None
    if compiled:
        g = torch.compile(g)
        warm = max(warm, 3)
    static = None
    if graph and not compiled:
        static = StaticStep((g, dd, dr), (opt_g, opt_d), cfg, graph_autocast(dev, amp),
                            (dd, dr), graph=True)
        warm = max(warm, static.warmup + 3)  # warm-up steps, the capture, two replays
    autocast = step_autocast(dev, amp)

    def one(i=0):
        if static is not None:
            static(x, y, 1, alpha, gi)
        else:
            gan_step(g, dd, dr, opt_g, opt_d, x, y, alpha, cfg, 1, autocast, (dd, dr), gi)

    def run(n):
        for _ in range(n):
            one()

    run(warm)
    if dev.type == "cuda":
        torch.cuda.synchronize()
    t0 = time.perf_counter()
    run(steps)
    if dev.type == "cuda":
        torch.cuda.synchronize()
    ips = steps * B / (time.perf_counter() - t0)
    if profile:
        from benchmarks._profile import print_top

        print_top(one, min(steps, 5), dev, title=f"Model_prog stage {r}, batch {B}")
    return ips, (static.mode if static is not None else
                 "eager, compiled G" if compiled else "eager")


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--device", default="cuda" if torch.cuda.is_available() else "cpu")
    ap.add_argument("--steps", type=int, default=10)
    ap.add_argument("--pairs", type=int, default=4224)
    ap.add_argument("--quick", action="store_true")
    ap.add_argument("--growth", choices=("full", "decoder"), default="full")
    ap.add_argument("--threads", type=int, help="torch CPU threads (default: torch's)")
    ap.add_argument("--batch", type=int, help="one batch size for every stage (default: "
                    "Table 5.1's)")
    ap.add_argument("--batch-rate", type=float, default=1.0, help="Table 5.1 multiplier (1)")
    ap.add_argument("--only", type=int, help="time this stage resolution alone")
    ap.add_argument("--g-channels", type=int, help="generator width (default ABConfig's)")
    ap.add_argument("--g-max-channels", type=int, help="generator cap (default ABConfig's)")
    ap.add_argument("--graph", action="store_true", help="the step as one CUDA graph "
                    "replay (StaticStep; on a CPU it runs eagerly)")
    ap.add_argument("--compile", action="store_true", help="G through torch.compile "
                    "(eager step; overrides --graph)")
    ap.add_argument("--nchw", action="store_true", help="keep networks and data NCHW "
                    "under bf16 (the trainer uses channels-last)")
    ap.add_argument("--profile", action="store_true", help="after each stage's timing, "
                    "print its top kernels (torch.profiler)")
    args = ap.parse_args(argv)
    if args.threads:
        torch.set_num_threads(args.threads)
    dev = torch.device(args.device)
    torch.backends.cudnn.benchmark = dev.type == "cuda"  # as the trainer does
    widths = {k: v for k, v in (("g_channels", args.g_channels),
                                ("g_max_channels", args.g_max_channels)) if v}
    cfg = ABConfig(device=args.device, growth=args.growth, batch=args.batch,
                   batch_rate=args.batch_rate, **widths)
    if args.quick:
        cfg = ABConfig(device=args.device, g_channels=8, g_max_channels=32, d_channels=8,
                       growth=args.growth)
    stages = cfg.schedule[:2] if args.quick else cfg.schedule
    if args.only:
        stages = [st for st in cfg.schedule if st[0] == args.only]
    steps = 2 if args.quick else args.steps
    print(f"device {dev}, {torch.get_num_threads()} threads, growth {cfg.growth}; "
          f"G {cfg.g_channels}-"
          f"{cfg.g_max_channels} ch, D {cfg.d_channels} ch x {cfg.d_scales} scales; "
          "CPU figures depend on whatever else the machine runs")
    total_s = 0.0
    print(f"{'stage':>6} {'batch':>6} {'epochs':>7} {'img/s':>9} {'stage time':>11}  step")
    for r, epochs in stages:
        ips, mode = stage_speed(cfg, r, dev, steps, graph=args.graph, profile=args.profile,
                                compiled=args.compile, nchw=args.nchw)
        t = epochs * args.pairs / ips
        total_s += t
        print(f"{r:>6} {cfg.stage_batch(r):>6} {epochs:>7} {ips:>9.1f} {t / 60:>9.1f} min"
              f"  {mode}", flush=True)
    what = "stages shown" if args.quick else "Table 5.2"
    print(f"{what} on {args.pairs} pairs: {total_s / 60:.1f} min (issue target: the whole "
          "schedule <= 20 min on one H100, >= 700 img/s at 256)")
    if dev.type != "cuda":
        print("GPU target UNMEASURED: no CUDA device here; the figures above are CPU "
              f"({torch.get_num_threads()} threads) and say nothing about the H100 target")
    return 0


if __name__ == "__main__":
    sys.exit(main())
