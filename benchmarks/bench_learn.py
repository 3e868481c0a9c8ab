"""Speed of Model_BA: training images/s and inference maps/s (CPU here; GPU when present).

* training: one epoch of ``train_ba`` on 256 box-plan pairs (the full eq. 3.2 loss):
  Model_32 with the default and the shipped (16-channel) widths, Model_64 shipped widths;
  images/s over the epoch (checkpoint and figures excluded);
* inference at 256 px, batched: the generator alone, and ``autocorrect_many`` end to end
  (resize, network, post-processing to 256 px), after a warm-up on the same batch.
  Target: >= 50 maps/s on CPU. Besides wall-clock rates it prints maps per CPU-second
  (process time), which a machine shared with other jobs disturbs much less.

    python3 benchmarks/bench_learn.py [--maps 200] [--device cpu|cuda] [--threads T]
        [--data DS] [--inference-only] [--repeat R]

``--data`` takes the simulated SLAM maps (``B``) of a ``map2map dataset build`` folder
instead of generated boxes (the maps ``autocorrect`` is for).
"""

from __future__ import annotations

import argparse
import sys
import tempfile
import time
import warnings
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "src"))

import torch  # noqa: E402

from map2map.core.grid import FREE, OCCUPIED, UNKNOWN, OccupancyMap  # noqa: E402
from map2map.datasets.packed import PackedPairs  # noqa: E402
from map2map.learn.autocorrect import autocorrect_many, load_model  # noqa: E402
from map2map.learn.config import TrainConfig  # noqa: E402
from map2map.learn.train import train_ba  # noqa: E402


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
    args = ap.parse_args(argv)
    if args.threads:
        torch.set_num_threads(args.threads)
    print(f"device {args.device}, {torch.get_num_threads()} threads (CPU figures are from "
          "whatever else the machine runs)")
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
