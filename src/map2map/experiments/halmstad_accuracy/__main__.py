"""Accuracy of the alignment on the Halmstad maps, scored by annotated keypoints, and its warnings.

Usage::

    python3 -m map2map.experiments.halmstad_accuracy [--data ../shared/data]
        [--pairs E5_01,HIH_02] [--json OUT.json] [--no-wrong] [--one-way]
        [--resolutions both|none|given] [--as-cli]

For each sensor map and its layout, in both directions (36 pairs), the source's
associated keypoints are mapped through the similarity and through the nonrigid
chain (affine + optimised piecewise-affine warp), and the mean distance to their
annotated counterparts is reported in target pixels. The floor is the residual of
the least-squares similarity fitted to the annotations themselves (robustly: E5_08
holds a wrong association).

Each pair runs the whole evaluation (``evaluate_maps``, what ``map2map evaluate``
runs) and lists the warnings it carries, by check (:mod:`map2map.evaluate.confidence`),
with the figure behind each check. An alignment is *good* when its similarity lands
the keypoints within 1.5 x the floor and 30 px, *bad* otherwise; the summary counts
the warnings on good and bad pairs. Wrong-map pairs (a sensor map against the other
building's layout, skipped with ``--no-wrong``) are bad by construction: every one
of them must warn. ``--json`` writes every figure, warning and transform (for a
before/after comparison of a change: the transforms must not move unless meant to).

Every keypoint pair runs twice (``--resolutions both``, the default): without
resolutions (the scale searched blind, 0.5-2) and with them (the search keeps within
10 % of their scale). The data gives no resolution; "with resolutions" means the
layout at the placeholder 0.05 m/px and every sensor map of a building at 0.05 x
that building's median annotated keypoint scale
(:func:`map2map.maps.halmstad.annotated_scale`: E5 0.823, HIH 1.160), one figure
per building as a user who knows the robot's map resolution would give. The summary
counts the pairs within 1.5 x the floor (and 30 px), sensor map -> layout (the 18 of
issue #34) and all, each way. ``--as-cli`` reads the pictures as ``map2map
evaluate`` reads them (:func:`map2map.maps.formats.load_map`, ROS thresholds: the
anti-aliased layout's walls come out thicker than the data README's threshold at
128 makes them) instead of :func:`map2map.maps.halmstad.load_halmstad`.

Measured 2026-11-23 (2.3 min for the 40 pairs on a loaded, shared 2-core machine):
35 good pairs, 1 bad (E5_layout -> E5_01, 1.96 x the floor), 4 wrong maps. Before
the recalibration of :mod:`map2map.evaluate.confidence` every good pair carried a
warning (alignment warnings on 30/35: poor fit on 30, ambiguity 5, weak hypothesis
2; "most wall points match no plan wall" on 32); after, 7/35 (ambiguity 5: E5_01,
E5_04, E5_12 both ways, which a known metric scale clears on E5_01/E5_04; weak
hypothesis 2: HIH_04), every good pair carrying notes instead, and all 5 bad or
wrong-map pairs still warn (ambiguity 5, poor fit 3, free space 2, no shared walls
2). Transforms and error figures identical before and after on all 40 pairs.
Since 2026-11-27 one "doubtful alignment" warning (``p_correct``, calibrated by
``map2map.experiments.alignment_confidence``) replaces ambiguity, poor fit and free space:
good pairs warned 3/35, bad or wrong-map pairs 5/5 (README.md).
Measured 2026-11-27 (issue #34 item 1, 6.4 min for 76 pairs): sensor map -> layout within
1.5 x the floor 18/18 without resolutions and 18/18 with them (scale at most 1.7 % from
theirs); layout -> sensor map 17/18 both ways (E5_layout -> E5_01, 1.96 x).
"""

from __future__ import annotations

import argparse
import json
import sys
import time
from pathlib import Path

import numpy as np

from map2map.evaluate.pipeline import evaluate_maps
from map2map.experiments._data import shared_data
from map2map.maps.formats import load_map
from map2map.maps.halmstad import (
    HALMSTAD_RESOLUTION,
    annotated_scale,
    halmstad_pairs,
    keypoint_residuals,
    load_halmstad,
    map_path,
)

#: warning text -> the check that raised it (confidence.py, align.py)
CHECKS = (
    ("doubtful alignment", "doubtful"),  # p_correct (since 2026-11-27, issue #34 item 2)
    ("ambiguous alignment", "ambiguity"),  # the warnings it replaced, for old --json files
    ("poor fit", "fitness"),
    ("free space disagrees", "free_space"),
    ("scale mismatch", "scale"),
    ("low-confidence alignment", "weak_hypothesis"),
    ("no alignment hypothesis passed", "no_hypothesis"),
    ("fit far better at scale", "prior_scale"),
    ("aligned maps disagree", "iou_free"),
    ("match no plan wall", "unmatched"),
)

#: wrong-map pairs: a sensor map against the other building's layout
WRONG = (
    ("E5_01", "HIH_layout"),
    ("E5_09", "HIH_layout"),
    ("HIH_01", "E5_layout"),
    ("HIH_03", "E5_layout"),
)


def check_of(text: str) -> str:
    for key, name in CHECKS:
        if key in text:
            return name
    return "other"


def figures(report: dict) -> dict:
    """The figures behind the checks, from an evaluation report."""
    q = report["alignment"]["hypotheses"]["quality"]
    iou_known = report["iou"][report["chosen_chain"]].get("free_known")
    return {
        "p_correct": report.get("p_correct"),
        "fitness": q.get("fitness"),
        "free_agreement": q.get("free_agreement"),
        "runner_up_ratio": q.get("runner_up_ratio"),
        "search_score": max(
            report["alignment"]["hypotheses"].get("score_source_to_target", 0.0),
            report["alignment"]["hypotheses"].get("score_target_to_source", 0.0),
        ),
        "iou_free_known": iou_known,
        "unmatched_share": report["chosen_errors"].get("unmatched_share"),
    }


def short(fig: dict) -> str:
    def f(v):
        return "  -  " if v is None else f"{v:5.2f}"

    return " ".join(
        f(fig[k]) for k in ("fitness", "free_agreement", "runner_up_ratio", "iou_free_known",
                            "unmatched_share")
    )


def load(data: Path, name: str, as_cli: bool):
    """A Halmstad map, read by :func:`load_halmstad` or as ``map2map evaluate`` reads it."""
    if as_cli:
        return load_map(map_path(data, name), resolution=HALMSTAD_RESOLUTION)
    return load_halmstad(data, name)


def run_pair(data: Path, src_name: str, tgt_name: str, keypoints: bool,
             rigid_scale: float | None = None, as_cli: bool = False) -> dict:
    """One pair through ``evaluate_maps``; ``rigid_scale`` is the metric scale its
    resolutions give (target pixels per source pixel), None: no resolutions."""
    src = load(data, src_name, as_cli)
    tgt = load(data, tgt_name, as_cli)
    t0 = time.perf_counter()
    ev = evaluate_maps(src, tgt, names=(src_name, tgt_name), rigid_scale=rigid_scale)
    dt = time.perf_counter() - t0
    res = ev.registration
    row = {"pair": f"{src_name}->{tgt_name}", "time_s": dt, "wrong_map": not keypoints,
           "resolutions": rigid_scale is not None, "metric_scale": rigid_scale,
           "to_layout": tgt_name.endswith("layout"),
           "scale": ev.report["alignment"]["scale"]}  # fmt: skip
    if keypoints:
        floor, sim, nonrigid = keypoint_residuals(
            data, src_name, tgt_name, src, tgt, res.map_points
        )
        row.update(floor=floor, similarity=sim, nonrigid=nonrigid, ratio=sim / floor,
                   good=bool(sim <= 1.5 * floor and sim <= 30))
    else:
        row.update(floor=None, similarity=None, nonrigid=None, ratio=None, good=False)
    row["warnings"] = [{"check": check_of(w), "text": w} for w in ev.report["warnings"]]
    row["alignment_warnings"] = list(res.alignment.warnings)
    row["notes"] = list(ev.report.get("notes", []))
    row["figures"] = figures(ev.report)
    row["transforms"] = {
        k: np.asarray(getattr(res.alignment, k)).tolist() for k in ("similarity", "affine", "rigid")
    }
    row["errors"] = ev.report["errors"]
    return row


def good_counts(rows: list[dict]) -> str:
    """Pairs within 1.5 x the floor (and 30 px), without and with resolutions."""
    out = []
    for label, sel in (("sensor map -> layout", lambda r: r["to_layout"]),
                       ("layout -> sensor map", lambda r: not r["to_layout"])):  # fmt: skip
        parts = []
        for given in (False, True):
            rs = [r for r in rows if not r["wrong_map"] and sel(r) and r["resolutions"] == given]
            if not rs:
                continue
            txt = f"{sum(r['good'] for r in rs)}/{len(rs)} {'with' if given else 'without'}"
            if given:
                off = max(abs(r["scale"] / r["metric_scale"] - 1) for r in rs)
                txt += f" (scale at most {off:.1%} from theirs)"
            bad = [f"{r['pair']} {r['ratio']:.2f}x" for r in rs if not r["good"]]
            parts.append(txt + (f" [bad: {', '.join(bad)}]" if bad else ""))
        if parts:
            out.append(f"{label} within 1.5 x floor: " + "; ".join(parts) + " resolutions")
    return "\n".join(out)


def summary(rows: list[dict]) -> str:
    out = [good_counts(rows)] if any(not r["wrong_map"] for r in rows) else []
    given = [r for r in rows if r["resolutions"]]
    if given:
        out.append(f"without resolutions ({len(rows) - len(given)} pairs):")
    out.append(_summary([r for r in rows if not r["resolutions"]]))
    if given:
        out.append(f"with resolutions ({len(given)} pairs):")
        out.append(_summary(given))
    return "\n".join(out)


def _summary(rows: list[dict]) -> str:
    kp = [r for r in rows if not r["wrong_map"]]
    good = [r for r in rows if r["good"]]
    bad = [r for r in rows if not r["good"]]
    out = []
    if kp:
        a = np.array([(r["floor"], r["similarity"], r["nonrigid"], r["time_s"]) for r in kp])
        out.append(
            f"{len(a)} keypoint pairs: median floor {np.median(a[:, 0]):.1f} px, similarity "
            f"{np.median(a[:, 1]):.1f} px, nonrigid {np.median(a[:, 2]):.1f} px; within 30 px: "
            f"{(a[:, 1] <= 30).sum()}/{len(a)}; similarity <= 1.5 x floor: "
            f"{(a[:, 1] <= 1.5 * a[:, 0]).sum()}/{len(a)}; median time {np.median(a[:, 3]):.1f} s, "
            f"worst {a[:, 3].max():.1f} s"
        )

    def warned(rs, alignment_only=False):
        key = "alignment_warnings" if alignment_only else "warnings"
        return sum(1 for r in rs if r[key])

    out.append(
        f"good alignments with a warning: {warned(good)}/{len(good)} (alignment warnings "
        f"{warned(good, True)}/{len(good)}); bad or wrong-map with a warning: "
        f"{warned(bad)}/{len(bad)} (alignment warnings {warned(bad, True)}/{len(bad)})"
    )
    out.append(
        f"good alignments with a note (a fact, not a doubt): "
        f"{sum(1 for r in good if r.get('notes'))}/{len(good)}"
    )
    names = sorted({w["check"] for r in rows for w in r["warnings"]})
    for n in names:
        g = sum(1 for r in good if any(w["check"] == n for w in r["warnings"]))
        b = sum(1 for r in bad if any(w["check"] == n for w in r["warnings"]))
        out.append(f"  {n:<16s} fires on {g:2d}/{len(good)} good, {b:2d}/{len(bad)} bad")
    for k in ("p_correct", "fitness", "free_agreement", "runner_up_ratio", "search_score",
              "iou_free_known", "unmatched_share"):
        def rng(rs, k=k):
            v = [r["figures"][k] for r in rs if r["figures"].get(k) is not None]
            return f"{min(v):.2f}-{max(v):.2f}" if v else "-"

        out.append(f"  {k:<24s} good {rng(good):>11s}   bad/wrong {rng(bad):>11s}")
    return "\n".join(out)


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(
        prog="python3 -m map2map.experiments.halmstad_accuracy",
        description=__doc__.splitlines()[0],
    )
    ap.add_argument("--data", default=str(shared_data()),
                    help="real-data folder (default: $MAP2MAP_SHARED_DATA or ../shared/data)")
    ap.add_argument("--pairs", default="", help="comma-separated sensor map names (default: all)")
    ap.add_argument("--one-way", action="store_true", help="only sensor -> layout")
    ap.add_argument("--no-wrong", action="store_true", help="skip the wrong-map pairs")
    ap.add_argument("--json", default=None, help="write every row (figures, transforms) here")
    ap.add_argument("--resolutions", choices=("both", "none", "given"), default="both",
                    help="run the keypoint pairs without resolutions, with them (the layout "
                         "at 0.05 m/px, the sensor maps at 0.05 x their building's annotated "
                         "scale), or both (default)")
    ap.add_argument("--as-cli", action="store_true",
                    help="read the pictures as `map2map evaluate` does (ROS thresholds)")
    args = ap.parse_args(argv)
    data = Path(args.data) / "halmstad"
    if not data.is_dir():
        print(f"no Halmstad data at {data} (--data, or $MAP2MAP_SHARED_DATA)")
        return 0
    wanted = {w for w in args.pairs.split(",") if w}
    scale = {env: annotated_scale(data, env) for env in ("E5", "HIH")}
    modes = {"both": (False, True), "none": (False,), "given": (True,)}[args.resolutions]
    jobs = []
    for given in modes:
        for src_name, tgt_name in halmstad_pairs(data, both_ways=not args.one_way):
            sensor = src_name if "layout" not in src_name else tgt_name
            m = scale[sensor.split("_")[0]]
            m = (m if src_name == sensor else 1.0 / m) if given else None
            if not wanted or sensor in wanted:
                jobs.append((src_name, tgt_name, True, m))
    if not args.no_wrong:
        jobs += [(s, t, False, None) for s, t in WRONG if not wanted or s in wanted]
    rows = []
    print(f"{'pair':<22s} {'res':>5s} {'floor':>6s} {'simil':>6s} {'ratio':>6s} {'nonrig':>6s} "
          f"{'scale':>6s} {'time':>5s}   fit  free  r-up  iouF unmat  warnings")
    for src_name, tgt_name, kp, m in jobs:
        r = run_pair(data, src_name, tgt_name, kp, m, args.as_cli)
        rows.append(r)
        nums = (
            f"{r['floor']:6.1f} {r['similarity']:6.1f} {r['ratio']:6.2f} {r['nonrigid']:6.1f}"
            if kp else f"{'wrong map':>27s}"
        )
        res = "  -  " if m is None else f"{m:5.3f}"
        checks = ",".join(w["check"] for w in r["warnings"]) or "-"
        print(f"{r['pair']:<22s} {res} {nums} {r['scale']:6.3f} {r['time_s']:5.1f} "
              f"{short(r['figures'])}  {checks}", flush=True)
    if not rows:
        return 0
    print()
    print(summary(rows))
    if args.json:
        Path(args.json).write_text(json.dumps(rows, indent=1))
    return 0


if __name__ == "__main__":
    sys.exit(main())
