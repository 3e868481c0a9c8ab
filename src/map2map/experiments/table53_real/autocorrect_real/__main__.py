"""Model_BA on real SLAM maps nobody simulated: before/after figures and what happened.

Maps (from ``../shared/data``; skipped when absent): the Halmstad sensor maps E5_01 and
HIH_01 (real robots, 1585 x 1585, no metric resolution: 0.05 m/px assumed) and the
BreezySLAM corridor ``exp2.dat`` mapped by ``map2map slam --backend graph --max-range 5``.
For each: the auto-corrected map, the before/after figure, the DXF of its walls, and one
line: size, wall support (share of output wall pixels near an input wall), warnings, and
wall recall of the output against the input's walls (2 px; how much of what the robot
saw survives).

    python3 -m map2map.experiments.table53_real.autocorrect_real --out real_out [--model RUN]
"""

from __future__ import annotations

import argparse
import sys
import time
import warnings
from pathlib import Path

from map2map.evaluate.wallmetrics import wall_metrics
from map2map.experiments._data import shared_data
from map2map.learn.ba.autocorrect import autocorrect_many
from map2map.learn.ba.model import load_model
from map2map.learn.training.figures import save_before_after
from map2map.maps.formats import load_map, save_map

SHARED = shared_data()


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--out", default="real_out")
    ap.add_argument("--model", default="pretrained")
    args = ap.parse_args(argv)
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    if not SHARED.is_dir():
        print(f"shared data not found at {SHARED}; nothing to do")
        return 0
    maps = {}
    for env in ("E5", "HIH"):
        p = SHARED / "halmstad" / "maps" / env / "pseudo_occupancy" / f"{env}_01.png"
        if p.is_file():
            maps[f"halmstad_{env}_01"] = load_map(p, resolution=0.05)
    exp2 = SHARED / "breezyslam" / "exp2.dat"
    if exp2.is_file():
        from map2map.jobs.slam import SlamSpec, slam

        slam_out = out / "exp2_slam"
        if not (slam_out / "map.yaml").is_file():
            slam(SlamSpec(exp2, slam_out, backend="graph", max_range=5.0))
        maps["breezyslam_exp2"] = load_map(slam_out / "map.yaml")
    model = load_model(args.model)
    t0 = time.perf_counter()
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        results = autocorrect_many(list(maps.values()), model)
    dt = time.perf_counter() - t0
    for (name, m), r in zip(maps.items(), results, strict=True):
        save_map(r.map, out / f"{name}_corrected.png")
        r.save_dxf(out / f"{name}_walls.dxf")
        save_before_after(m, r.map, out / f"{name}_before_after.png",
                          r.map.meta["autocorrect"]["segments_px"], title=name)
        wm = wall_metrics(r.map.data, m.data)
        sup = r.map.meta["autocorrect"]["support"]
        print(f"{name}: {m.shape[1]}x{m.shape[0]} px, {len(r.segments)} wall segments, "
              f"support {sup if sup is None else round(sup, 3)}, recall of input walls "
              f"{wm['wall_recall']:.3f}, precision {wm['wall_precision']:.3f}; "
              f"warnings: {r.warnings or 'none'}")
    print(f"{len(maps)} maps in {dt:.1f} s (model {model.source}); figures in {out}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
