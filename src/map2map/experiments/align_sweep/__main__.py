"""Known-similarity sweep of ``evaluate``: recovered, flagged and silently wrong alignments.

Usage::

    python3 -m map2map.experiments.align_sweep [--quick] [--data ../shared/data] [--plans N]
        [--jobs J]

Every plan is evaluated against copies of itself rotated (0, 23, 90, -37 deg) and
scaled (pixel scale 0.8-1.3); the copy's resolution is set so that the metric scale
is exactly 1 (``res_copy = res_plan / s``), as a SLAM map of the same building would
be. Plans are of three kinds:

* ``houseexpo``: real HouseExpo renders (``../shared/data/houseexpo/renders``, 1 cm/px)
  downsampled to 5 cm/px, the rest of the bounding box solid occupied (skipped when
  the data are absent);
* ``generated``: :func:`map2map.maps.generate_floorplan` apartments and offices;
* ``irregular``: HouseExpo-style plans generated here (a union of rectangles, some
  diagonal walls, slit interior walls; the rest of the bounding box occupied).

A case is *recovered* when the similarity's scale is within 3% of the truth, its
rotation within 1.5 deg and the chosen chain's mean error below 1.5 px; *flagged*
when it is not recovered but the result carries a warning; *silently wrong* when it
is neither (the outcome that must not happen). ``false alarms`` counts recovered
cases that carry a warning anyway. Target: 0 silently wrong, >= 96% recovered.
"""

from __future__ import annotations

import argparse
import math
import os
import sys
import time
from concurrent.futures import ProcessPoolExecutor
from pathlib import Path

import cv2
import numpy as np

from map2map.core.geometry import decompose_similarity, similarity_matrix
from map2map.core.grid import FREE, OCCUPIED, UNKNOWN, OccupancyMap
from map2map.evaluate.pipeline import EvaluateParams, evaluate_maps
from map2map.experiments._data import shared_data
from map2map.maps.irregular import irregular_plan

ROTATIONS = (0.0, 23.0, 90.0, -37.0)
SCALES = (0.8, 1.05, 1.3)
RES = 0.05  # metres per pixel of every plan


def houseexpo_plan(path: Path, factor: int = 5) -> np.ndarray:
    """A 1 cm/px HouseExpo render at ``factor`` cm/px: 0 occupied, 255 free, 127 unknown.

    A cell is occupied when at least a third of it is wall (thin walls survive), free
    when most of it is free, unknown otherwise (the canvas outside the bounding box).
    """
    img = cv2.imread(str(path), cv2.IMREAD_GRAYSCALE)
    h, w = (img.shape[0] // factor) * factor, (img.shape[1] // factor) * factor
    img = img[:h, :w]
    blocks = lambda m: m.reshape(h // factor, factor, w // factor, factor).mean(axis=(1, 3))  # noqa: E731
    occ = blocks(img < 64)
    free = blocks(img > 192)
    out = np.full(occ.shape, UNKNOWN, np.uint8)
    out[free > 0.5] = FREE
    out[occ >= 1 / 3] = OCCUPIED
    return out


def generated_plan(seed: int) -> np.ndarray:
    from map2map.maps import generate_floorplan

    kind = "apartment" if seed % 2 == 0 else "office"
    size = None if kind == "apartment" else (22.0, 14.0)
    return generate_floorplan(seed, kind=kind, size=size, resolution=RES).data


def transformed_copy(
    data: np.ndarray, scale: float, angle_deg: float
) -> tuple[np.ndarray, np.ndarray]:
    """The map rotated and scaled onto a canvas that holds it; returns (copy, T plan->copy).

    Occupancy and knowledge are resampled bilinearly and re-quantised (occupied where a
    cell is at least 40% wall), so that walls one or two pixels thick stay unbroken.
    ``T`` maps continuous plan pixels (x, y) to continuous copy pixels.
    """
    h, w = data.shape
    a = math.radians(angle_deg)
    corners = np.array([[0, 0], [w, 0], [0, h], [w, h]], float)
    T = similarity_matrix(scale, a, 0.0, 0.0)
    q = corners @ T[:2, :2].T
    lo, hi = q.min(0) - 8, q.max(0) + 8
    T[:2, 2] = -lo
    W, H = (int(math.ceil(v)) for v in hi - lo)
    C = np.array([[1, 0, 0.5], [0, 1, 0.5], [0, 0, 1.0]])
    M = (np.linalg.inv(C) @ T @ C)[:2]
    occ = cv2.warpAffine((data == OCCUPIED).astype(np.float32), M, (W, H), flags=cv2.INTER_LINEAR)
    free = cv2.warpAffine((data == FREE).astype(np.float32), M, (W, H), flags=cv2.INTER_LINEAR)
    out = np.full((H, W), UNKNOWN, np.uint8)
    out[free >= 0.5] = FREE
    out[occ >= 0.4] = OCCUPIED
    return out, T


def run_case(args) -> dict:
    kind, name, data, scale, angle, prior = args
    copy, _ = transformed_copy(data, scale, angle)
    src = OccupancyMap(copy, RES / scale)
    tgt = OccupancyMap(data, RES)
    t0 = time.perf_counter()
    try:
        if prior:  # both resolutions known: the metric scale is the alignment's prior
            ev = evaluate_maps(src, tgt, resolution=RES, rigid_scale=1.0 / scale)
        else:  # the hypotheses alone, over the whole scale range 0.5-2
            p = EvaluateParams()
            p.align.rigid_scale = 1.0 / scale
            ev = evaluate_maps(src, tgt, resolution=RES, params=p)
    except Exception as exc:  # noqa: BLE001 - a crash is reported, not hidden
        return {"kind": kind, "name": name, "scale": scale, "angle": angle, "error": repr(exc)}
    dt = time.perf_counter() - t0
    s, a, _, _ = decompose_similarity(ev.registration.alignment.similarity)
    ds = abs(s * scale - 1.0)
    da = abs((math.degrees(a) + angle + 180.0) % 360.0 - 180.0)
    mean = ev.report["chosen_errors"]["mean_px"]
    ok = ds <= 0.03 and da <= 1.5 and mean < 1.5
    return {
        "kind": kind,
        "name": name,
        "scale": scale,
        "angle": angle,
        "ds": ds,
        "da": da,
        "mean_px": mean,
        "chain": ev.chosen,
        "fitness": ev.report["alignment"]["fitness"],
        "quality": ev.report["alignment"]["hypotheses"]["quality"],
        "recovered": bool(ok),
        "warnings": list(ev.report["warnings"]),
        "seconds": dt,
    }


def plans(args) -> list[tuple[str, str, np.ndarray]]:
    out = []
    renders = Path(args.data) / "houseexpo" / "renders"
    if renders.is_dir():
        for p in sorted(renders.glob("*.png"))[: args.plans]:
            out.append(("houseexpo", p.stem[:8], houseexpo_plan(p)))
    else:
        print(f"no HouseExpo renders at {renders}: houseexpo plans skipped")
    for i in range(args.plans):
        out.append(("generated", f"gen{i}", generated_plan(i)))
        out.append(("irregular", f"irr{i}", irregular_plan(i)))
    return out


def _q(q: dict) -> str:
    return (
        f"fit {q['fitness']:.2f} free {q['free_agreement']:.2f} "
        f"runner-up {q.get('runner_up_ratio', 0):.2f}"
    )


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(
        prog="python3 -m map2map.experiments.align_sweep",
        description=__doc__.splitlines()[0],
    )
    ap.add_argument("--data", default=str(shared_data()),
                    help="real-data folder (default: $MAP2MAP_SHARED_DATA or ../shared/data)")
    ap.add_argument("--plans", type=int, default=4, help="plans of each kind (default 4)")
    ap.add_argument("--quick", action="store_true", help="1 plan of each kind, 2 x 2 cases")
    ap.add_argument("--jobs", type=int, default=2, help="processes (default 2)")
    ap.add_argument(
        "--no-prior",
        action="store_true",
        help="do not tell the alignment the metric scale (search scales 0.5-2 blind)",
    )
    ap.add_argument("--verbose", action="store_true", help="print the confidence figures")
    ap.add_argument("--only", default="", help="run only cases whose plan name contains this")
    args = ap.parse_args(argv)
    rotations, scales = ROTATIONS, SCALES
    if args.quick:
        args.plans = 1
        rotations, scales = (23.0, -37.0), (0.8, 1.3)
    cases = [
        (kind, name, data, s, a, not args.no_prior)
        for kind, name, data in plans(args)
        if args.only in name
        for a in rotations
        for s in scales
    ]
    t0 = time.perf_counter()
    rows = []
    print(f"{len(cases)} cases on {args.jobs} processes")
    print(f"{'plan':<20s} {'rot':>6s} {'scale':>5s} {'dscale':>7s} {'drot':>6s} {'mean':>6s} "
          f"{'fit':>5s} {'time':>5s}  outcome")  # fmt: skip
    with ProcessPoolExecutor(args.jobs) as pool:
        for r in pool.map(run_case, cases):
            rows.append(r)
            label = f"{r['kind'][:3]}/{r['name']}"
            if "error" in r:
                print(f"{label:<20s} {r['angle']:6.1f} {r['scale']:5.2f}  ERROR {r['error']}")
                continue
            outcome = "recovered" if r["recovered"] else "FLAGGED" if r["warnings"] else "SILENT"
            if r["recovered"] and r["warnings"]:
                outcome += " (false alarm)"
            print(
                f"{label:<20s} {r['angle']:6.1f} {r['scale']:5.2f} {r['ds']:7.4f} {r['da']:6.2f} "
                f"{r['mean_px']:6.2f} {r['fitness']:5.2f} {r['seconds']:5.1f}  {outcome}"
                + (f" q={_q(r['quality'])}" if args.verbose else "")
                + (f"  [{'; '.join(w[:70] for w in r['warnings'])}]" if r["warnings"] else ""),
                flush=True,
            )
    wall = time.perf_counter() - t0
    done = [r for r in rows if "error" not in r]
    n = len(rows)
    rec = sum(r["recovered"] for r in done)
    flagged = sum((not r["recovered"]) and bool(r["warnings"]) for r in done)
    silent = sum((not r["recovered"]) and not r["warnings"] for r in done)
    false_alarm = sum(r["recovered"] and bool(r["warnings"]) for r in done)
    errors = n - len(done)
    print(f"\n{'kind':<10s} {'cases':>5s} {'recovered':>9s} {'flagged':>7s} {'silent':>6s} "
          f"{'false alarms':>12s}")  # fmt: skip
    for kind in sorted({r["kind"] for r in rows}) + ["all"]:
        sel = [r for r in done if kind in ("all", r["kind"])]
        print(
            f"{kind:<10s} {len(sel):5d} {sum(r['recovered'] for r in sel):9d} "
            f"{sum((not r['recovered']) and bool(r['warnings']) for r in sel):7d} "
            f"{sum((not r['recovered']) and not r['warnings'] for r in sel):6d} "
            f"{sum(r['recovered'] and bool(r['warnings']) for r in sel):12d}"
        )
    print(
        f"\n{n} cases: recovered {rec} ({100 * rec / max(n, 1):.1f}%), flagged {flagged}, "
        f"silently wrong {silent}, false alarms {false_alarm}, errors {errors}; "
        f"median {np.median([r['seconds'] for r in done]):.1f} s/case, wall {wall:.0f} s "
        f"({os.cpu_count()} cores, shared)"
    )
    return 0 if silent == 0 and errors == 0 else 1


if __name__ == "__main__":
    sys.exit(main())
