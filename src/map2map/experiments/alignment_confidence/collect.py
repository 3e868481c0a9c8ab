"""The labelled alignments behind ``p_correct``: the synthetic sweep and the Halmstad pairs.

Every case is one :func:`~map2map.evaluate.align.align_maps` run whose quality dict
(:mod:`map2map.evaluate.confidence`) is stored with a label (the alignment is right or
wrong, from a known truth) and a group (the plan or building it was made from, so that
held-out folds never share a plan with their training set). Cached as JSON (a list of
rows) so that refitting is cheap.

Data sets:

* ``sweep``: synthetic plans (:mod:`map2map.experiments.align_sweep`: HouseExpo renders,
  generated, irregular) against rotated and scaled copies of themselves, with the
  metric scale known (prior) and searched blind (no prior), against a partial copy
  (a 55% window), and against a copy of a *different* plan (wrong by construction).
  Right when the similarity's scale is within 3%, its rotation within 1.5 deg and the
  source's wall points land within 3 px (mean) of where the truth puts them;
* ``halmstad``: every sensor map <-> its layout, both ways (36); right when the
  similarity lands the annotated keypoints within 1.5 x the floor and 30 px
  (:mod:`map2map.experiments.halmstad_accuracy`);
* ``wrong_building``: every sensor map <-> the other building's layout, both ways
  (36): wrong by construction.

Examples
--------
>>> room = _symmetric_room(20, 30)  # one rectangular room: turned 180 deg, the same
>>> room.shape, bool((room[::-1, ::-1] == room).all())
((40, 50), True)
"""

from __future__ import annotations

import math
import time
from concurrent.futures import ProcessPoolExecutor
from pathlib import Path
from types import SimpleNamespace
from typing import Any

import numpy as np

from map2map.core.geometry import apply, decompose_similarity
from map2map.core.grid import FREE, OCCUPIED, UNKNOWN
from map2map.evaluate.align import AlignParams, align_maps
from map2map.evaluate.features import surface_points
from map2map.experiments.align_sweep.__main__ import plans, transformed_copy
from map2map.maps.halmstad import halmstad_pairs, keypoint_residuals, load_halmstad
from map2map.maps.irregular import irregular_plan
from map2map.maps.synthetic import cluttered, draw_walls, office_walls

SAME_ROT = (23.0, 90.0, -37.0)
SAME_SCALE = (0.8, 1.3)
BLIND = ((23.0, 0.8), (-37.0, 1.3))


def _scalars(d: dict) -> dict:
    return {k: v for k, v in d.items() if isinstance(v, (int, float, bool, str, type(None)))}


def _row(al, **extra) -> dict[str, Any]:
    h = al.hypotheses
    return {
        **extra,
        "quality": _scalars(h.get("quality", {})),
        "search": _scalars(h),
        "warnings": list(al.warnings),
        "notes": list(al.notes),
    }


def sweep_case(args) -> dict[str, Any]:
    """One synthetic case: (kind, name, group, plan, other, scale, angle, prior, crop)."""
    kind, name, group, plan, other, scale, angle, prior, crop = args
    copy, T = transformed_copy(plan if other is None else other, scale, angle)
    off = np.zeros(2)
    if crop:  # a partial map: the left 55% of the copy
        c1 = int(0.55 * copy.shape[1])
        copy = copy[:, :c1].copy()
    truth = np.linalg.inv(T)  # copy pixels -> plan pixels
    p = AlignParams(rigid_scale=1.0 / scale, metric_scale=(1.0 / scale) if prior else None)
    t0 = time.perf_counter()
    try:
        al = align_maps(copy, plan, params=p)
    except Exception as exc:  # noqa: BLE001 - a failed alignment is a wrong one, reported
        return {"dataset": "sweep", "name": name, "error": repr(exc)}
    dt = time.perf_counter() - t0
    s, a, _, _ = decompose_similarity(al.similarity @ np.linalg.inv(truth))
    pts = surface_points(copy) + off
    disp = float(np.hypot(*(apply(al.similarity, pts) - apply(truth, pts)).T).mean())
    right = other is None and abs(s - 1) <= 0.03 and abs(math.degrees(a)) <= 1.5 and disp <= 3
    case = ("different" if other is not None else "partial" if crop else "same") + (
        "" if prior else ", no prior"
    )
    return _row(al, dataset="sweep", kind=kind, name=f"{name} {case} rot {angle:g} s {scale:g}",
                case=case, group=group, right=bool(right), displacement_px=disp,
                seconds=dt)  # fmt: skip


def sweep_cases(data: Path, n_plans: int) -> list[tuple]:
    ps = plans(SimpleNamespace(data=str(data), plans=n_plans))
    out = []
    for i, (kind, name, plan) in enumerate(ps):
        other = ps[(i + 1) % len(ps)][2]
        for a in SAME_ROT:
            for s in SAME_SCALE:
                out.append((kind, name, name, plan, None, s, a, True, False))
        for a, s in BLIND:
            out.append((kind, name, name, plan, None, s, a, False, False))
        out.append((kind, name, name, plan, None, 1.05, 23.0, True, True))
        out.append((kind, name, name, plan, None, 1.05, -37.0, False, True))
        # a different plan's copy: grouped with the target plan (its features come from it)
        out.append((kind, name, name, plan, other, 1.05, 23.0, True, False))
        out.append((kind, name, name, plan, other, 0.8, -37.0, False, False))
    return out


def _symmetric_room(h: int, w: int) -> np.ndarray:
    plan = np.full((h + 20, w + 20), UNKNOWN, np.uint8)
    plan[10 : h + 10, 10 : w + 10] = OCCUPIED
    plan[16 : h + 4, 16 : w + 4] = FREE
    return plan


def hard_case(args) -> dict[str, Any]:
    """The hard synthetic cases of tests/test_trust.py and tests/test_confidence.py, varied:
    (name, group, source, target, truth source->target or None, metric_scale)."""
    name, group, src, tgt, truth, m = args
    t0 = time.perf_counter()
    al = align_maps(src, tgt, params=AlignParams(metric_scale=m))
    dt = time.perf_counter() - t0
    right, disp = False, float("nan")
    if truth is not None:
        s, a, _, _ = decompose_similarity(al.similarity @ np.linalg.inv(truth))
        pts = surface_points(src)
        disp = float(np.hypot(*(apply(al.similarity, pts) - apply(truth, pts)).T).mean())
        right = abs(s - 1) <= 0.03 and abs(math.degrees(a)) <= 1.5 and disp <= 3
    return _row(al, dataset="sweep", kind="hard", name=name, case=name.split(" ")[0],
                group=group, right=bool(right), displacement_px=disp, seconds=dt)  # fmt: skip


def hard_cases() -> list[tuple]:
    out = []
    for i, (h, w) in enumerate(((100, 140), (90, 90), (120, 200))):
        plan = _symmetric_room(h, w)
        for ang in (37.0, 90.0):
            copy, T = transformed_copy(plan, 1.0, ang)
            for m in (1.0, None):
                out.append((f"symmetric room {h}x{w} rot {ang:g} prior {m}", f"sym{i}", copy,
                            plan, np.linalg.inv(T), m))  # fmt: skip
    office = draw_walls((240, 300), office_walls(300, 240))
    for k in (1, 2, 3, 4):
        out.append((f"unrelated irr{k} on office", "office", irregular_plan(k), office, None,
                    None))  # fmt: skip
    for cols in (45, 90, 150):
        part = np.full_like(office, UNKNOWN)
        part[:, :cols] = office[:, :cols]
        out.append((f"partial office {cols} cols", "office", part, office, np.eye(3), None))
    for seed in (0, 1):
        out.append((f"cluttered office seed {seed}", "office", cluttered(office, seed), office,
                    np.eye(3), None))  # fmt: skip
    small, T = transformed_copy(office, 0.75, 0.0)
    out.append(("wrong resolution office 0.75 told 1", "office", small, office,
                 np.linalg.inv(T), 1.0))  # fmt: skip
    out.append(("right resolution office 0.75", "office", small, office, np.linalg.inv(T),
                1 / 0.75))  # fmt: skip
    for k in (5, 6):
        plan = irregular_plan(k)
        copy, T = transformed_copy(plan, 1.3, -37.0)
        out.append((f"wrong resolution irr{k} 1.3 told 1", f"irr{k}", copy, plan,
                    np.linalg.inv(T), 1.0))  # fmt: skip
    for k in (6, 7):
        out.append((f"different irr{k} irr{k + 2}", f"irr{k}", irregular_plan(k),
                    irregular_plan(k + 2), None, None))  # fmt: skip
    return out


def halmstad_case(args) -> dict[str, Any]:
    root, src_name, tgt_name, keypoints = args
    src, tgt = load_halmstad(root, src_name), load_halmstad(root, tgt_name)
    t0 = time.perf_counter()
    al = align_maps(src.data, tgt.data, params=AlignParams(), names=(src_name, tgt_name))
    dt = time.perf_counter() - t0
    env = {src_name.split("_")[0], tgt_name.split("_")[0]}
    row = {"name": f"{src_name}->{tgt_name}", "seconds": dt}
    if keypoints:
        def mapper(pts):
            q = apply(al.similarity, pts)
            return q, q

        floor, sim, _ = keypoint_residuals(root, src_name, tgt_name, src, tgt, mapper)
        row.update(dataset="halmstad", group=env.pop(), floor=floor, similarity=sim,
                   right=bool(sim <= 1.5 * floor and sim <= 30))  # fmt: skip
    else:
        row.update(dataset="wrong_building", group="cross", right=False)
    return _row(al, **row)


def halmstad_cases(data: Path) -> list[tuple]:
    root = data / "halmstad"
    if not root.is_dir():
        print(f"no Halmstad data at {root}: halmstad and wrong_building skipped")
        return []
    out = [(root, s, t, True) for s, t in halmstad_pairs(root)]
    other = {"E5": "HIH", "HIH": "E5"}
    for s, _ in halmstad_pairs(root, both_ways=False):
        wrong = f"{other[s.split('_')[0]]}_layout"
        out += [(root, s, wrong, False), (root, wrong, s, False)]
    return out


def _run(job):
    fn, args = job
    return fn(args)


def collect(data: Path, n_plans: int = 3, jobs: int = 2, log=print) -> list[dict[str, Any]]:
    """Run every case (``jobs`` processes); returns the rows (see the module docstring)."""
    work = [(sweep_case, c) for c in sweep_cases(data, n_plans)]
    work += [(hard_case, c) for c in hard_cases()]
    work += [(halmstad_case, c) for c in halmstad_cases(data)]
    log(f"{len(work)} alignments on {jobs} processes")
    rows = []
    t0 = time.perf_counter()
    with ProcessPoolExecutor(jobs) as pool:
        for r in pool.map(_run, work):
            rows.append(r)
            if "error" in r:
                log(f"  {r['name']}: ERROR {r['error']}")
                continue
            q = r["quality"]
            log(f"  {r['dataset']:<14s} {r['name']:<42s} {'right' if r['right'] else 'WRONG'} "
                f"fit {q['fitness']:.2f} free {q['free_agreement']:.3f} "
                f"r-up {q.get('runner_up_ratio', 0):.2f} {r['seconds']:.1f} s")  # fmt: skip
    log(f"collected {len(rows)} rows in {time.perf_counter() - t0:.0f} s")
    return rows
