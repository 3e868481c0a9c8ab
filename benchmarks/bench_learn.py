"""Speed of Model_BA: training images/s and inference maps/s (CPU here; GPU when present).

* training: one epoch of ``train_ba`` on 256 box-plan pairs (the full eq. 3.2 loss):
  Model_32 with the default and the shipped (16-channel) widths, Model_64 shipped widths;
  images/s over the epoch (checkpoint and figures excluded);
* inference at 256 px, batched: the generator alone, and ``autocorrect_many`` end to end
  (resize, network, post-processing to 256 px), after a warm-up on the same batch.
  Target: >= 50 maps/s on CPU. Besides wall-clock rates it prints maps per CPU-second
  (process time), which a machine shared with other jobs disturbs much less.

    python3 -m benchmarks.bench_learn [--maps 200] [--device cpu|cuda] [--threads T]
        [--data DS] [--inference-only] [--repeat R]

``--data`` takes the simulated SLAM maps (``B``) of a ``map2map dataset build`` folder
instead of generated boxes (the maps ``autocorrect`` is for).

``--steps-at SIZE:BATCH,...`` measures instead the training step alone (the full eq. 3.2
step of :func:`map2map.learn.training.step.gan_step`, default widths, bf16 + channels_last on
CUDA) on random ternary maps resident on the device, for each resolution and batch,
over ``--seconds`` after warm-up; ``--compile`` also times a ``torch.compile``d generator.
``--graph`` also times the same step as one CUDA graph replay
(:class:`map2map.learn.training.static_step.StaticStep`: 3 eager warm-up steps, capture, replays;
it falls back to eager steps if capture fails and the line says which ran); on CPU it
runs eagerly; ``--check-graph`` first runs 8 steps both ways from the same weights and
prints how far losses and weights differ and whether a learning rate set to 0 in place
stops the graphed weights. ``--count-ops`` counts instead the top-level operator calls of
one step (``torch.profiler``; today's ``gan_step`` and the static step). Issue #14's target:
Model_32 >= 10,000 img/s on one H100.

    python3 -m benchmarks.bench_learn --steps-at 32:32,32:256,64:16 --device cuda --graph
    python3 -m benchmarks.bench_learn --steps-at 32:32 --device cpu --count-ops
"""

from __future__ import annotations

import argparse
import sys
import tempfile
import time
import warnings
from pathlib import Path

import numpy as np
import torch

from map2map.core.grid import FREE, OCCUPIED, UNKNOWN, OccupancyMap
from map2map.datasets.packed import PackedPairs
from map2map.learn.ba.autocorrect import autocorrect_many
from map2map.learn.ba.model import load_model
from map2map.learn.ba.train import train_ba
from map2map.learn.training.config import TrainConfig


def _maps(n: int, size: int = 256, seed: int = 0) -> np.ndarray:
    """Boxes of rooms: walls, free inside, unknown outside (fast to make in bulk)."""
    rng = np.random.default_rng(seed)
    out = np.full((n, size, size), UNKNOWN, np.uint8)
    for i in range(n):
        r0, c0 = rng.integers(10, 60, 2)
        r1, c1 = size - rng.integers(10, 60, 2)
        out[i, r0:r1, c0:c1] = FREE
        out[i, [r0, r1 - 1], c0:c1] = OCCUPIED
        out[i, r0:r1, [c0, c1 - 1]] = OCCUPIED
        for c in rng.integers(c0 + 20, c1 - 20, 2):
            out[i, r0:r1, c] = OCCUPIED
    return out


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--maps", type=int, default=200)
    ap.add_argument("--device", default="cuda" if torch.cuda.is_available() else "cpu")
    ap.add_argument("--threads", type=int, help="torch CPU threads (default: torch's)")
    ap.add_argument("--data", help="a 'map2map dataset build' folder: its SLAM maps")
    ap.add_argument("--inference-only", action="store_true", help="skip the training rates")
    ap.add_argument("--repeat", type=int, default=1, help="timed inference rounds")
    ap.add_argument("--steps-at", help="SIZE:BATCH,... : time training steps only")
    ap.add_argument("--seconds", type=float, default=3.0, help="timed seconds per --steps-at")
    ap.add_argument("--compile", action="store_true", help="--steps-at: also compiled G")
    ap.add_argument("--graph", action="store_true", help="--steps-at: also the step as one "
                    "CUDA graph replay (StaticStep; on CPU it runs eagerly)")
    ap.add_argument("--count-ops", action="store_true", help="--steps-at: count the "
                    "top-level operator calls of one step (torch.profiler) instead of timing")
    ap.add_argument("--check-graph", action="store_true", help="--steps-at: compare 8 "
                    "graphed steps with 8 eager ones (losses, weights, lr set to 0) first")
    ap.add_argument("--profile", action="store_true", help="--steps-at: then print the "
                    "eager step's top kernels (torch.profiler, 5 steps)")
    args = ap.parse_args(argv)
    if args.threads:
        torch.set_num_threads(args.threads)
    print(f"device {args.device}, {torch.get_num_threads()} threads (CPU figures are from "
          "whatever else the machine runs)")
    if args.steps_at:
        for item in args.steps_at.split(","):
            size, batch = (int(v) for v in item.split(":"))
            if args.count_ops:
                _count(size, batch, args.device)
                continue
            if args.check_graph:
                _check_graph(size, batch, args.device)
            kinds = [(False, False)] + [(True, False)] * args.compile + [(False, True)] * args.graph
            for comp, graph in kinds:
                ips, n, mode = _step_rate(size, batch, args.device, args.seconds, comp, graph)
                label = ", compiled G" if comp else f", CUDA graph ({mode})" if graph else ""
                print(f"training step, Model_{size} default widths, batch {batch}{label}: "
                      f"{ips:.0f} img/s ({n} steps, {1e3 * batch / ips:.2f} ms a step)",
                      flush=True)
            if args.profile:
                from benchmarks._profile import print_top

                fn, _ = _step_fn(size, batch, args.device, False, False)
                for i in range(3):
                    fn(i)
                print_top(fn, 5, torch.device(args.device),
                          title=f"Model_{size} default widths, batch {batch}, eager")
        return 0
    if not args.inference_only:
        _training(args)
    _inference(args)
    return 0


def _dataset_maps(ds: str, n: int) -> np.ndarray:
    import cv2

    files = sorted(Path(ds).glob("pairs/*/B.png"))
    if not files:
        raise SystemExit(f"{ds}: no pairs/*/B.png here (not a dataset build folder)")
    maps = [cv2.imread(str(f), cv2.IMREAD_GRAYSCALE) for f in files[:n]]
    return np.stack([maps[i % len(maps)] for i in range(n)])


def _training(args) -> None:
    a = _maps(256)
    pairs = PackedPairs(a, np.roll(a, 2, axis=2), np.arange(256).astype(str),
                        np.array(["train"] * 256))
    small = dict(g_channels=16, g_max_channels=64, d_channels=16)
    for name, extra in (("Model_32, default widths (32 ch)", dict(size=32)),
                        ("Model_32, shipped widths (16 ch)", dict(size=32, **small)),
                        ("Model_64, shipped widths (16 ch)", dict(size=64, **small))):
        cfg = TrainConfig(epochs=1, samples=0, device=args.device, **extra)
        with tempfile.TemporaryDirectory() as d:
            res = train_ba(pairs, Path(d) / "run", cfg, progress=False, figures=False)
        print(f"training {name}, batch {cfg.batch_size}: "
              f"{res.history[-1]['img_per_s']:.0f} img/s")


def _step_setup(size: int, batch: int, device: str, compiled: bool = False):
    """Networks, optimisers, autocast and a random ternary batch resident on ``device``
    (module doc), as the trainer sets them up."""
    from map2map.learn.ba.model import build_networks
    from map2map.learn.training.loop import place_networks, step_autocast

    cfg = TrainConfig(size=size, batch=batch, device=device)
    dev = torch.device(device)
    torch.backends.cudnn.benchmark = dev.type == "cuda"  # as the trainer does
    amp = dev.type == "cuda" and cfg.amp
    g, dd, dr = build_networks(cfg)
    opts = place_networks((g, dd, dr), dev, amp, cfg)
    gen = torch.Generator().manual_seed(0)
    x, y = ((torch.randint(0, 3, (batch, 1, size, size), generator=gen).float() - 1).to(dev)
            for _ in range(2))
    if amp:
        x, y = (t.contiguous(memory_format=torch.channels_last) for t in (x, y))
    g_run = torch.compile(g) if compiled else g
    return cfg, dev, amp, (g_run, dd, dr), opts, x, y, step_autocast(dev, amp)


def _step_fn(size: int, batch: int, device: str, compiled: bool, graph: bool):
    """``(step(i), mode)``: one eq. 3.2 training step; ``graph``: the
    :class:`~map2map.learn.training.static_step.StaticStep` with ``graph=True`` (eager on CPU)."""
    from map2map.learn.training.static_step import StaticStep, graph_autocast
    from map2map.learn.training.step import gan_step

    cfg, dev, amp, nets, opts, x, y, autocast = _step_setup(size, batch, device, compiled)
    freeze = nets[1:]
    if not graph:
        return (lambda i: gan_step(*nets, *opts, x, y, None, cfg, 1 + i % max(1, batch - 1),
                                   autocast, freeze)), None
    step = StaticStep(nets, opts, cfg, graph_autocast(dev, amp), freeze, graph=True)
    return (lambda i: step(x, y, 1 + i % max(1, batch - 1))), step


def _step_rate(size: int, batch: int, device: str, seconds: float, compiled: bool,
               graph: bool = False) -> tuple[float, int, str]:
    """Images/s of the eq. 3.2 training step at ``size`` and ``batch`` (module doc), the
    steps timed, and which step ran (``graph``: the static step's mode)."""
    dev = torch.device(device)
    fn, static = _step_fn(size, batch, device, compiled, graph)

    def sync():
        if dev.type == "cuda":
            torch.cuda.synchronize()

    for i in range(3 if not (compiled or graph) else 6):  # graph: 3 warm-up, capture, 2 replays
        fn(i)
    sync()
    n, t0 = 0, time.perf_counter()
    while True:
        for _ in range(5):
            fn(n)
            n += 1
        sync()
        el = time.perf_counter() - t0
        if el >= seconds:
            return n * batch / el, n, (static.mode if static is not None else "eager")


def _count(size: int, batch: int, device: str) -> None:
    """Top-level operator calls of one step (``--count-ops``): today's ``gan_step`` and the
    static step run eagerly (what a capture records), by name."""
    from map2map.learn.training.static_step import StaticStep, count_ops

    plain, _ = _step_fn(size, batch, device, False, False)
    cfg, dev, amp, nets, opts, x, y, autocast = _step_setup(size, batch, device)
    static = StaticStep(nets, opts, cfg, autocast, nets[1:], graph=False)
    for what, fn in (("gan_step", plain),
                     ("static step (eager)", lambda i: static(x, y, 1 + i % max(1, batch - 1)))):
        for i in range(2):
            fn(i)
        c = count_ops(fn, 2)
        print(f"operator calls per step, Model_{size} default widths, batch {batch}, {what}: "
              f"{c.top} top-level ({c.total} with nested)", flush=True)
        print("  most called: " + ", ".join(f"{k.removeprefix('aten::')} {v}"
                                            for k, v in c.most_common(12)), flush=True)


def _check_graph(size: int, batch: int, device: str, steps: int = 8) -> None:
    """``--check-graph``: the same ``steps`` steps (distinct random batches, same initial
    weights) as eager static steps and as CUDA graph replays; prints the largest loss and
    weight differences, and whether a learning rate set to 0 (in place) for the last two
    steps stops the weights of the graphed run (the per-epoch decay reaches the graph).
    A second eager run gives the baseline: on CUDA two eager runs differ too (cuDNN's
    algorithm choice, atomics), and the graph's differences mean something only beside
    those."""
    from map2map.learn.training.static_step import StaticStep, graph_autocast
    from map2map.learn.training.step import set_lr

    gen = torch.Generator().manual_seed(1)
    data = [tuple(torch.randint(0, 3, (batch, 1, size, size), generator=gen).float() - 1
                  for _ in range(2)) for _ in range(steps)]
    runs = {}
    for graph in (False, "again", True):
        cfg, dev, amp, nets, opts, _, _, _ = _step_setup(size, batch, device)
        step = StaticStep(nets, opts, cfg, graph_autocast(dev, amp), nets[1:],
                          graph=graph is True)
        losses, frozen = [], None
        for i, (x, y) in enumerate(data):
            if i == steps - 2:
                for o in opts:
                    set_lr(o, 0.0)
                frozen = [p.detach().clone() for p in nets[0].parameters()]
            if amp:
                x, y = (t.contiguous(memory_format=torch.channels_last) for t in (x, y))
            out = step(x.to(dev), y.to(dev), 1 + 3 * i)
            losses.append([float(out["loss_G"].detach()), float(out["loss_D"].detach())])
        params = [p.detach().float() for n in nets for p in n.parameters()]
        still = all(torch.equal(a, b) for a, b in zip(frozen, nets[0].parameters(),
                                                      strict=True))
        runs[graph] = (losses, params, still, step.mode)
    def diffs(r0, r1):
        (l0, p0), (l1, p1) = r0[:2], r1[:2]
        dl = max(abs(a - b) / max(abs(a), 1e-6) for u, v in zip(l0, l1, strict=True)
                 for a, b in zip(u, v, strict=True))
        dw = max(float((a - b).abs().max() / a.abs().max().clamp_min(1e-12))
                 for a, b in zip(p0, p1, strict=True))
        return dl, dw

    (l0, _, s0, _), (l1, _, s1, mode) = runs[False], runs[True]
    dl, dw = diffs(runs[False], runs[True])
    bl, bw = diffs(runs[False], runs["again"])
    print(f"graph check, Model_{size} default widths, batch {batch}, {steps} steps: "
          f"mode {mode}; max relative loss difference {dl:.2e}, max relative weight "
          f"difference {dw:.2e} (eager against eager: {bl:.2e}, {bw:.2e}); lr 0 stops the "
          f"weights: eager {s0}, graph {s1}; losses G/D eager {l0[-1][0]:.4f}/"
          f"{l0[-1][1]:.4f} graph {l1[-1][0]:.4f}/{l1[-1][1]:.4f}", flush=True)


def _timed(fn) -> tuple[float, float]:
    w, c = time.perf_counter(), time.process_time()
    fn()
    return time.perf_counter() - w, time.process_time() - c


def _inference(args) -> None:
    model = load_model("pretrained", args.device)
    maps = _dataset_maps(args.data, args.maps) if args.data else _maps(args.maps, seed=1)
    what = f"SLAM maps of {args.data}" if args.data else "generated boxes"
    model.predict(maps)
    ms = [OccupancyMap(m, 0.05) for m in maps]
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        autocorrect_many(ms[:16], model, device=args.device)
        for r in range(args.repeat):
            t_net, c_net = _timed(lambda: model.predict(maps))
            t_all, c_all = _timed(lambda: autocorrect_many(ms, model, device=args.device))
            n = args.maps
            print(f"inference at 256 px, {n} {what} (round {r + 1}): generator "
                  f"{n / t_net:.0f} maps/s ({n / c_net:.0f} per CPU-second); end to end "
                  f"(resize + network + post-processing) {n / t_all:.1f} maps/s "
                  f"({n / c_all:.1f} per CPU-second; target >= 50 maps/s on CPU)")


if __name__ == "__main__":
    sys.exit(main())
