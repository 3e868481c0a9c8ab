"""Accuracy of the alignment on the Halmstad maps, scored by annotated keypoints.

Usage::

    python3 benchmarks/halmstad_accuracy.py [--data ../shared/data] [--pairs E5_01,HIH_02]

For each sensor map and its layout, in both directions (36 pairs), the source's
associated keypoints are mapped through the similarity and through the nonrigid
chain (affine + optimised piecewise-affine warp), and the mean distance to their
annotated counterparts is reported in target pixels. The floor is the residual of
the least-squares similarity fitted to the annotations themselves (robustly: E5_08
holds a wrong association). Prints one line per pair and a summary.
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "src"))

from map2map.evaluate.pipeline import register  # noqa: E402
from map2map.maps.halmstad import halmstad_pairs, keypoint_residuals, load_halmstad  # noqa: E402


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--data", default=str(ROOT.parent / "shared" / "data"))
    ap.add_argument("--pairs", default="", help="comma-separated sensor map names (default: all)")
    ap.add_argument("--one-way", action="store_true", help="only sensor -> layout")
    args = ap.parse_args(argv)
    data = Path(args.data) / "halmstad"
    if not data.is_dir():
        print(f"no Halmstad data at {data}")
        return 0
    wanted = {w for w in args.pairs.split(",") if w}
    rows = []
    print(f"{'pair':<22s} {'floor':>6s} {'simil':>6s} {'ratio':>6s} {'nonrig':>6s} {'time':>5s}")
    for src_name, tgt_name in halmstad_pairs(data, both_ways=not args.one_way):
        sensor = src_name if "layout" not in src_name else tgt_name
        if wanted and sensor not in wanted:
            continue
        src = load_halmstad(data, src_name)
        tgt = load_halmstad(data, tgt_name)
        t0 = time.perf_counter()
        res = register(src, tgt)
        dt = time.perf_counter() - t0
        floor, sim, nonrigid = keypoint_residuals(
            data, src_name, tgt_name, src, tgt, res.map_points
        )
        warned = len(res.alignment.warnings)
        rows.append((floor, sim, nonrigid, dt, warned))
        print(
            f"{src_name + '->' + tgt_name:<22s} {floor:6.1f} {sim:6.1f} {sim / floor:6.2f} "
            f"{nonrigid:6.1f} {dt:5.1f} {warned:4d}",
            flush=True,
        )
    if not rows:
        return 0
    a = np.array(rows)
    print(
        f"\n{len(a)} pairs: median floor {np.median(a[:, 0]):.1f} px, similarity "
        f"{np.median(a[:, 1]):.1f} px, nonrigid {np.median(a[:, 2]):.1f} px; "
        f"within 30 px: {(a[:, 1] <= 30).sum()}/{len(a)}; similarity <= 1.5 x floor: "
        f"{(a[:, 1] <= 1.5 * a[:, 0]).sum()}/{len(a)}; median time {np.median(a[:, 3]):.1f} s, "
        f"worst {a[:, 3].max():.1f} s; with a warning: {(a[:, 4] > 0).sum()}/{len(a)}"
    )
    return 0


if __name__ == "__main__":
    sys.exit(main())
