"""Speed of ``map2map evaluate`` (alignment, both chains, metric, ICP, figures).

Usage::

    python3 -m benchmarks.bench_evaluate [--data ../shared/data] [--pairs 6] [--no-large]

Runs the full evaluation, figures included, exactly as the command does, on
Halmstad sensor-map / layout pairs (1585 x 1585) and on one pair upscaled to
3228 x 3228 (the size of the appendix paper's maps, which took it 8.7-16.9 hours).
Prints wall and CPU seconds per pair and the median / worst. Targets: 1585 px
<= 5 s median and <= 15 s worst; 3228 px <= 20 s. On a shared machine the wall
time includes waiting for the CPU: the CPU time is the figure to compare.
Without the shared data it falls back to generated plans of the same sizes.
"""

from __future__ import annotations

import argparse
import statistics
import sys
import tempfile
import time
from pathlib import Path

import cv2
import numpy as np

from map2map.jobs.evaluate import run_evaluate

ROOT = Path(__file__).resolve().parents[1]


def _timed(src: Path, tgt: Path, out: Path) -> tuple[float, float, dict]:
    w0, c0 = time.perf_counter(), time.process_time()
    ev = run_evaluate(src, tgt, out, resolution=0.05)
    return time.perf_counter() - w0, time.process_time() - c0, ev.report


def _upscale(path: Path, size: int, out: Path) -> Path:
    img = cv2.imread(str(path), cv2.IMREAD_UNCHANGED)
    big = cv2.resize(img, (size, size), interpolation=cv2.INTER_NEAREST)
    cv2.imwrite(str(out), big)
    return out


def _generated(tmp: Path, size: int) -> tuple[Path, Path]:
    from map2map.maps.synthetic import deform, draw_walls, gaussian_field, office_walls

    plan = draw_walls((size, size), office_walls(size, size, margin=size // 8, thickness=5))
    field = gaussian_field(plan.shape, (0.7 * size, 0.6 * size), (size / 150, 0.0), size / 5)
    slam, _ = deform(plan, field)
    slam = np.ascontiguousarray(np.rot90(slam))
    a, b = tmp / f"slam_{size}.png", tmp / f"plan_{size}.png"
    cv2.imwrite(str(a), slam)
    cv2.imwrite(str(b), plan)
    return a, b


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--data", default=str(ROOT.parent / "shared" / "data"))
    ap.add_argument("--pairs", type=int, default=18, help="how many Halmstad pairs (max 18)")
    ap.add_argument("--no-large", action="store_true", help="skip the 3228 x 3228 pair")
    args = ap.parse_args(argv)
    tmp = Path(tempfile.mkdtemp(prefix="bench_evaluate_"))
    halmstad = Path(args.data) / "halmstad" / "maps"
    pairs = []
    if halmstad.is_dir():
        for env in ("E5", "HIH"):
            layout = halmstad / env / "layout" / f"{env}_layout.png"
            for p in sorted((halmstad / env / "pseudo_occupancy").glob("*.png")):
                pairs.append((p, layout))
        step = max(1, len(pairs) // max(1, args.pairs))
        pairs = pairs[::step][: args.pairs]
    else:
        print("no shared data: generated 1585 x 1585 pair")
        pairs = [_generated(tmp, 1585)]
    _timed(*pairs[0], tmp / "warmup")  # imports, caches
    walls, cpus = [], []
    print(f"{'pair':<28s} {'wall s':>7s} {'cpu s':>7s}  breakdown (s)")
    for i, (src, tgt) in enumerate(pairs):
        w, c, rep = _timed(src, tgt, tmp / f"pair{i}")
        walls.append(w)
        cpus.append(c)
        t = rep["timings_s"]
        parts = ", ".join(f"{k} {v:.2f}" for k, v in t.items() if k != "total")
        print(f"{src.stem + ' -> ' + tgt.stem:<28s} {w:7.2f} {c:7.2f}  {parts}", flush=True)
    print(
        f"\n1585 px, {len(walls)} pairs: median {statistics.median(walls):.2f} s wall "
        f"({statistics.median(cpus):.2f} s CPU), worst {max(walls):.2f} s wall "
        f"({max(cpus):.2f} s CPU); targets 5 s median, 15 s worst"
    )
    if not args.no_large:
        src, tgt = pairs[0]
        if halmstad.is_dir():
            big_src = _upscale(src, 3228, tmp / "big_src.png")
            big_tgt = _upscale(tgt, 3228, tmp / "big_tgt.png")
        else:
            big_src, big_tgt = _generated(tmp, 3228)
        w, c, _ = _timed(big_src, big_tgt, tmp / "big")
        print(f"3228 px pair ({src.stem} upscaled): {w:.2f} s wall ({c:.2f} s CPU); target 20 s")
    return 0


if __name__ == "__main__":
    sys.exit(main())
