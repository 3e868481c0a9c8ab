"""The plan drawer on SLAM maps' own walls: is the output drawn like a plan? (issue #32)

Usage::

    python3 -m benchmarks.bench_drawing [--data DS] [--n 200] [--demo DEMO_OUT]
    python3 -m benchmarks.bench_drawing --data DS --model none   # what autocorrect outputs

Runs :func:`map2map.maps.vectorize.draw_plan` directly on the input SLAM maps' wall
pixels (the classical path, no network) and measures the output with
:func:`map2map.evaluate.drawing.drawing_report` against its input and its plan:

* on the finished pairs of a dataset (``DS/pairs/NNNNNN/``, 256 px ``A.png`` plan and
  ``B.png`` SLAM map; every split, every cleaner decision; a build still running is read
  as it stands). The 256 px maps' resolution is the pair's full-size resolution times the
  ratio of the known extents of ``A.yaml`` and ``A.png``;
* on the demo's SLAM map (``map2map demo``'s ``simulate/slam_map.yaml`` against its
  ``plan.yaml``, 0.05 m/px): ``--demo`` names a demo output folder; without it the demo's
  plan (generated apartment, seed 0) is simulated here for the demo's five minutes. When
  the folder holds ``autocorrect/cad.yaml`` (Model_BA's output, as the demo wrote it), it
  is measured too, for comparison;
* on the HouseExpo plans of the shared data (``--houseexpo``, default
  ``../shared/data/houseexpo/json``; skipped when absent), each simulated here for five
  minutes (rbpf, seed 0), at the plan's 0.05 m/px.

With ``--model NAME`` (a ``map2map autocorrect --model`` name: ``none``, the default,
is the classical cleaning drawn like a plan; ``thesis``) each map is the whole corrector's
output, its segments the ones its DXF holds, and the time is the corrector's per map.

Prints, per set, the medians of the four measurements, the share of maps meeting each
target and all four, the unknown pockets (unknown enclosed between a wall and free
space: reported, no target) and the drawer's milliseconds per map (one OpenCV thread;
the speed target itself is ``bench_autocorrect``'s).
"""

from __future__ import annotations

import argparse
import math
import os
import statistics
import sys
import tempfile
import time
from pathlib import Path

import cv2
import numpy as np

from map2map.evaluate.drawing import drawing_report
from map2map.maps.vectorize import draw_plan


def _resolution_256(folder: Path, a256: np.ndarray) -> float:
    """Metres per pixel of a pair's 256 px pictures (see the module doc)."""
    from map2map.maps.formats import load_map

    full = load_map(folder / "A.yaml")

    def extent(m: np.ndarray) -> int:
        k = np.argwhere(m != 127)
        return int((k.max(axis=0) - k.min(axis=0) + 1).max()) if len(k) else 0

    e256 = extent(a256)
    return full.resolution * extent(full.data) / e256 if e256 else full.resolution


def _dataset(ds: Path, n: int | None) -> list[tuple[str, np.ndarray, np.ndarray, float]]:
    from map2map.datasets.pairfolder import pair_dir
    from map2map.experiments.table53.measure import heldout_pairs_from_dataset

    pairs = heldout_pairs_from_dataset(ds, ("train", "val", "test"), n, keep=())
    idx = pairs.meta["heldout"]["indices"][: len(pairs.a)]
    return [(f"{i:06d}", a, b, _resolution_256(pair_dir(ds, i), a))
            for i, a, b in zip(idx, pairs.a, pairs.b, strict=True)]


def _demo(folder: Path | None) -> tuple[list, list]:
    """The demo's (plan, SLAM map) and, when written, Model_BA's output."""
    from map2map.maps.formats import load_map

    if folder is None:
        from map2map.jobs.simulate import SimulateSpec, simulate
        from map2map.maps.floorplan import generate_floorplan

        plan = generate_floorplan(0, kind="apartment")
        with tempfile.TemporaryDirectory() as tmp:
            t0 = time.perf_counter()
            run = simulate(SimulateSpec(plan, Path(tmp) / "simulate", seed=0, duration=300.0,
                                        figures=False, progress=False))
            print(f"demo map simulated in {time.perf_counter() - t0:.0f} s", flush=True)
            slam = run.result.slam_map_plan
        return [("demo", plan.data, slam.data, plan.resolution)], []
    plan = load_map(folder / "plan.yaml")
    slam = load_map(folder / "simulate" / "slam_map.yaml")
    extra = []
    cad = folder / "autocorrect" / "cad.yaml"
    if cad.is_file():
        extra = [("demo autocorrect (Model_BA)", plan.data, slam.data, plan.resolution,
                  load_map(cad).data)]
    return [("demo", plan.data, slam.data, plan.resolution)], extra


def _houseexpo(folder: Path) -> list:
    """HouseExpo plans (``json/*.json``) simulated here for five minutes (rbpf), each SLAM
    map in its plan's frame."""
    from map2map.jobs.simulate import SimulateSpec, simulate

    out = []
    for f in sorted(folder.glob("*.json")):
        if f.stem.endswith("_trajectory"):
            continue
        with tempfile.TemporaryDirectory() as tmp:
            r = simulate(SimulateSpec(f, Path(tmp) / "sim", seed=0, duration=300.0,
                                      figures=False, progress=False)).result
        out.append((f.stem[:8], r.plan.data, r.slam_map_plan.data, r.plan.resolution))
    return out


def _drawn(b: np.ndarray, res: float, thickness: float | None, model):
    """(map, segments px, angle) of the drawer on ``b``'s walls, or of ``model``."""
    if model is None:
        d = draw_plan(b == 0, b, res, thickness)
        return d.map, d.segments, d.angle
    import warnings

    from map2map.core.grid import OccupancyMap

    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        (out,) = model.correct_many([OccupancyMap(b, res)])
    ac = out.meta["autocorrect"]
    return out.data, np.asarray(ac["segments_px"], float).reshape(-1, 4), \
        ac.get("drawn", {}).get("angle", float("nan"))


def _measure(items, label: str, verbose: bool, thickness: float | None = None,
             model=None) -> None:
    rows, ms, cpu = [], [], []
    for name, a, b, res in items:
        _drawn(b, res, thickness, model)                            # warm (first call)
        t0, c0 = time.perf_counter(), time.process_time()
        dmap, segs, angle = _drawn(b, res, thickness, model)
        ms.append(1e3 * (time.perf_counter() - t0))
        cpu.append(1e3 * (time.process_time() - c0))
        r = drawing_report(dmap, b, a, res, segs)
        rows.append(r)
        if verbose:
            print(f"  {name}: {res:.4f} m/px, angle {angle:+.1f}, comp {r['components']}/"
                  f"{r['components_input']}, thick {r['thickness_px']:.1f}/"
                  f"{r['thickness_plan_px']:.1f}, seg {r['segments']}/{r['plan_walls']}, "
                  f"broken {r['broken']}/{r['runs']}, pockets {r['pockets']}, "
                  f"{ms[-1]:.1f} ms")
    _summary(label, rows, ms, cpu)


def _summary(label: str, rows: list[dict], ms: list[float], cpu: list[float] = ()) -> None:
    if not rows:
        print(f"{label}: no maps")
        return
    med = lambda k: statistics.median(r[k] for r in rows)            # noqa: E731
    share = lambda k: 100.0 * sum(bool(r[k]) for r in rows) / len(rows)  # noqa: E731
    print(f"{label}: {len(rows)} maps")
    print(f"  wall components  output {med('components'):.0f} vs input "
          f"{med('components_input'):.0f} (medians); output <= input: "
          f"{share('ok_components'):.0f} %")
    miss = [r["thickness_px"] - r["thickness_plan_px"] for r in rows]
    miss = [m for m in miss if math.isfinite(m)]
    print(f"  wall thickness   output {med('thickness_px'):.1f} px vs plan "
          f"{med('thickness_plan_px'):.1f} px; within 1 px: {share('ok_thickness'):.0f} %"
          + (f"; mean miss {statistics.mean(abs(m) for m in miss):.2f} px (output - plan "
             f"{statistics.mean(miss):+.2f})" if miss else ""))
    print(f"  segments         output {med('segments'):.0f} vs plan walls "
          f"{med('plan_walls'):.0f} (ratio {med('segments_ratio'):.2f}); <= 1.5x: "
          f"{share('ok_segments'):.0f} %")
    print(f"  broken runs      {med('broken'):.0f} of {med('runs'):.0f} runs >= 1 m; "
          f"none broken: {share('ok_broken'):.0f} %  (total {sum(r['broken'] for r in rows)}"
          f" of {sum(r['runs'] for r in rows)}, of which {sum(r['opened'] for r in rows)}"
          f" opened: no output wall within 9 px; shortened at an end: "
          f"{sum(r['shortened'] for r in rows)})")
    print(f"  all four targets {share('targets_met'):.0f} %")
    print(f"  none opened      {share('ok_opened'):.0f} %; all four with 'none opened' for "
          f"'none broken': {share('targets_met_opened'):.0f} %")
    print(f"  unknown pockets  {sum(r['pockets'] for r in rows)} (unknown enclosed between "
          f"a wall and free space; no target); maps with none: "
          f"{100.0 * sum(r['pockets'] == 0 for r in rows) / len(rows):.0f} %")
    if ms:
        print(f"  drawer time      median {statistics.median(ms):.1f} ms/map wall, "
              f"{statistics.median(cpu):.1f} ms CPU (mean {statistics.mean(ms):.1f} / "
              f"{statistics.mean(cpu):.1f}, max {max(ms):.1f} / {max(cpu):.1f}); "
              f"one thread, {os.cpu_count()} cores, load {os.getloadavg()[0]:.1f}")


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--data", type=Path, default=None,
                    help="dataset folder (pairs/NNNNNN/) built by `map2map dataset build`")
    ap.add_argument("--model", default=None, metavar="NAME",
                    help="measure `map2map autocorrect --model NAME`'s output (e.g. none, "
                         "the default, or thesis) instead of the drawer on the input's walls")
    ap.add_argument("--n", type=int, default=None, help="at most this many pairs")
    ap.add_argument("--demo", type=Path, default=None,
                    help="a `map2map demo --out` folder (default: simulate the demo's map)")
    ap.add_argument("--no-demo", action="store_true")
    ap.add_argument("--houseexpo", type=Path,
                    default=Path(__file__).resolve().parents[2] / "shared/data/houseexpo/json",
                    help="HouseExpo JSON plans to simulate and draw (skipped when absent)")
    ap.add_argument("--verbose", "-v", action="store_true", help="one line per map")
    ap.add_argument("--thickness", type=float, default=None,
                    help="wall thickness in pixels (default: the drawer's, 0.30 m)")
    ap.add_argument("--draw-option", action="append", metavar="KEY=VALUE",
                    help="with --model: a DrawOptions field, as `map2map autocorrect "
                         "--draw-option` (repeatable), e.g. sliver=0")
    args = ap.parse_args(argv)
    cv2.setNumThreads(1)
    model = None
    if args.model:
        from map2map.jobs.autocorrect import corrector, parse_draw_options

        model = corrector(args.model, draw_options=parse_draw_options(args.draw_option))
    elif args.draw_option:
        ap.error("--draw-option needs --model")
    what = f"autocorrect --model {args.model}" if model else "drawer"
    if args.data is not None and (args.data / "manifest.sqlite").is_file():
        _measure(_dataset(args.data, args.n), f"dataset {args.data} (256 px, {what})",
                 args.verbose, args.thickness, model)
    else:
        print(f"no dataset ({args.data}): skipped")
    if not args.no_demo:
        demo, extra = _demo(args.demo)
        _measure(demo, f"demo SLAM map ({what})", True, args.thickness, model)
        for name, a, b, res, out in extra:
            r = drawing_report(out, b, a, res)
            _summary(name, [r], [])
    if args.houseexpo.is_dir():
        _measure(_houseexpo(args.houseexpo), f"HouseExpo plans simulated ({args.houseexpo}, "
                 f"{what})", True, args.thickness, model)
    else:
        print(f"no HouseExpo plans at {args.houseexpo}: skipped")
    return 0


if __name__ == "__main__":
    sys.exit(main())
