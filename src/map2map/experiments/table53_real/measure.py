"""Thesis Table 5.3 on REAL maps: does auto-correct bring a real SLAM map closer to its
real floor plan? (issue #14; the Halmstad sensor maps and their layouts.)

:mod:`map2map.experiments.table53.measure` measures Model_BA on simulated pairs. Here the pairs are
real: a sensor map ``B`` built by a real robot and the layout ``A`` (the floor plan) of
the same building, in another frame and at another scale, with annotated keypoint
correspondences (:mod:`map2map.maps.halmstad`). Per map:

* ``error_real`` = the appendix-paper metric
  (:func:`map2map.evaluate.pipeline.evaluate_maps`: the chosen chain's mean local error,
  Algorithm 1, in layout pixels) of ``B`` against ``A``; ``error_gen`` = the same, with
  the same settings, of ``autocorrect(B)`` against ``A``; ``diff = error_real -
  error_gen`` (positive: improved), as ``Error(sim) - Error(gen)`` of Table 5.3.
  Algorithm 1 measures each wall point from its place under the *rigid* alignment,
  whose scale is ``rigid_scale`` (1 when both maps share a resolution, as in the
  simulated table). Here they do not (sensor-to-layout scale 0.82 on E5, 1.16 on HIH),
  so the metric is run twice: with the scale known (``rigid_scale`` = the ground-truth
  scale, what ``--source-resolution/--target-resolution`` give ``map2map evaluate``;
  the analogue of the simulated table, keys without prefix) and at scale 1
  (:func:`~map2map.experiments.table53.measure.run_table53`'s settings, keys ``s1_``), where the
  error is mostly the scale mismatch, growing with the distance from where the rigid
  placement pins the map.
* **whether the metric's own alignment succeeded**, for ``B`` and for
  ``autocorrect(B)``: the keypoints of ``B`` mapped through the metric's similarity
  land within :data:`KP_GOOD_RATIO` x the floor (the residual of the least-squares
  similarity fitted to the keypoints themselves) and :data:`KP_GOOD_PX` layout pixels
  of their annotated counterparts (the rule of ``benchmarks/halmstad_accuracy.py``). A
  map whose either alignment failed is *flagged*: its diff is listed, not counted.
* **guards** (:func:`map2map.evaluate.wallmetrics.wall_metrics`: wall recall, boundary
  F1 at 2 px, Chamfer, per-class IoU) against the layout, placed by the GROUND-TRUTH
  similarity (fitted robustly to the keypoints: one association of E5_08 is wrong).
  The comparison frame is the **sensor map's** (prefix ``real_`` / ``gen_``): the layout
  is warped into it by the inverse of the ground truth, so the two maps under test are
  compared as they are, never resampled, against one and the same warped layout (a
  layout pixel of E5 is about 1.2 sensor pixels: warping the sensor maps into the
  layout, scale 0.82, would drop pixels of their one-pixel walls while the output's
  thicker walls survive, a bias in the output's favour; the layout's loss, on HIH,
  is the same for both maps). The layout's frame is given
  too (prefix ``lf_real_`` / ``lf_gen_``: both maps warped into it by nearest
  neighbour), as a check that the conclusion does not hang on the frame. A sensor map
  covers only part of the building (the E5 maps a third to a half of the floor), so the
  guards are also given against the part of the layout the robot observed (prefix
  ``ob_``: the layout within :data:`OBSERVED_MARGIN_PX` of the sensor map's known cells).

The summary counts improved / worse maps among those counted, the one-sided sign test
(:func:`scipy.stats.binomtest`, ties left out) and the medians, as
:func:`~map2map.experiments.table53.measure.run_table53` does.
``map2map.experiments.table53_real`` is the
command line.

Resolution: the data give none; maps are read at 0.05 m/px
(:data:`map2map.maps.halmstad.HALMSTAD_RESOLUTION`). The metric's annealing schedule is
in metres (``EvaluateParams.sigma_f``), so that assumption sets its pixel scale, the
same for ``B`` and ``autocorrect(B)``. Auto-correct itself does not read the
resolution: it squares the map's known content and resizes it to the dataset's 256 px
whatever the metres per pixel (:mod:`map2map.learn.ba.autocorrect`); the shrink factor
(``shrink``: content side / 256) is recorded per map.

Examples
--------
A generated pair: a plan, and a "sensor map" that is the plan turned by 90 degrees and
drawn at 1.25x its scale; the "auto-correct" is the identity, so nothing changes.

>>> import numpy as np
>>> from map2map.core.grid import OccupancyMap
>>> plan = np.full((120, 120), 127, np.uint8)
>>> plan[20:100, 20:100] = 0; plan[24:96, 24:96] = 255; plan[24:96, 58:62] = 0
>>> plan[50:70, 58:62] = 255
>>> T = np.array([[0.0, -0.8, 130.0], [0.8, 0.0, 10.0], [0.0, 0.0, 1.0]])  # sensor -> plan
>>> from map2map.evaluate.nonrigid import warp_image
>>> sensor = warp_image(plan, np.linalg.inv(T), (150, 150))
>>> ks = np.array([[20.0, 20], [100, 20], [20, 100], [100, 100], [60, 60]])
>>> kt = ks @ T[:2, :2].T + T[:2, 2]
>>> row = real_pair_row("toy", OccupancyMap(sensor, 0.05), OccupancyMap(sensor, 0.05),
...                     OccupancyMap(plan, 0.05), ks, kt)
>>> row["diff"], round(row["gt_scale"], 2), row["counted"], row["real_wall_recall"]
(0.0, 0.8, True, 1.0)
"""

from __future__ import annotations

import csv
import os
import time
import warnings
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from ...core.grid import FREE, OCCUPIED, UNKNOWN, OccupancyMap
from ..table53.measure import GUARDS

__all__ = ["RealTable53", "run_table53_real", "real_pair_row", "summarise_real",
           "KP_GOOD_RATIO", "KP_GOOD_PX", "KP_FLOOR_MIN_PX",
           "OBSERVED_MARGIN_PX"]

#: An alignment is good when its similarity lands the keypoints within this multiple of
#: the floor (the keypoints' own least-squares similarity) ...
KP_GOOD_RATIO = 1.5
#: ... and within this many layout pixels (``benchmarks/halmstad_accuracy.py``).
KP_GOOD_PX = 30.0
#: Guards ``ob_``: the layout's walls more than this many sensor pixels (0.5 m at the
#: assumed 0.05 m/px, about the keypoint floor) from any known cell of the sensor map
#: were never observed and are left out.
OBSERVED_MARGIN_PX = 10
#: The floor is taken as at least this many pixels: exact keypoints (a generated pair)
#: have a zero floor; the Halmstad floors are 4.4 to 13 px, so this never acts there.
KP_FLOOR_MIN_PX = 2.0


def _metric(src: OccupancyMap, plan: OccupancyMap, seed: int, scale: float | None = None):
    """(error px, evaluation or None): the metric of
    :func:`map2map.experiments.table53.measure._error`
    (``scale=None``: both maps at one resolution), or with the metric scale ratio known
    (``rigid_scale=scale``), the evaluation kept for the alignment check."""
    from ...evaluate.pipeline import EvaluateParams, evaluate_maps

    try:
        ev = evaluate_maps(OccupancyMap(src.data, 0.05), OccupancyMap(plan.data, 0.05),
                           params=EvaluateParams(seed=seed), rigid_scale=scale)
        return float(ev.report["chosen_errors"]["mean_px"]), ev
    except Exception:  # noqa: BLE001 - a failed alignment is a result (nan), not a crash
        return float("nan"), None


def real_pair_row(name: str, sensor: OccupancyMap, corrected: OccupancyMap,
                  layout: OccupancyMap, ks: np.ndarray, kt: np.ndarray, *,
                  seed: int = 0) -> dict:
    """One row of the real Table 5.3: a sensor map, its auto-corrected version and the
    layout, with associated keypoints (module docstring).

    Parameters
    ----------
    name : str
        Row label.
    sensor, corrected : OccupancyMap
        The real SLAM map ``B`` and ``autocorrect(B)`` (same frame and shape).
    layout : OccupancyMap
        The floor plan ``A``.
    ks, kt : (N, 2) float arrays
        Associated keypoints: ``ks[i]`` in the sensor map's pixels (x, y; y down)
        corresponds to ``kt[i]`` in the layout's; N >= 3.
    seed : int
        Seed of the metric's point subsampling, the same for both maps.

    Returns
    -------
    dict
        ``error_real``, ``error_gen``, ``diff``; ``kp_floor`` (px), ``kp_real`` /
        ``kp_gen`` (residual of the metric's similarity, layout px), ``align_ok_real`` /
        ``align_ok_gen``, ``counted`` (the metric with the ground-truth scale as
        ``rigid_scale``, which also narrows the alignment's scale search to 10 % of it;
        the same keys prefixed ``s1_`` at scale 1, as ``run_table53``); ``gt_scale`` /
        ``gt_rotation_deg`` / ``gt_inliers``; the guards ``real_<g>`` / ``gen_<g>`` in
        the sensor's frame, ``lf_real_<g>`` / ``lf_gen_<g>`` in the layout's, and
        ``ob_real_<g>`` / ``ob_gen_<g>`` against the observed part of the layout (plus
        wall precision); wall thickness ``layout_wall_px`` / ``real_wall_px`` /
        ``gen_wall_px`` (sensor px); and
        ``chain_real`` / ``chain_gen`` (the metric's chosen chain) and ``seconds``.
    """
    from scipy import ndimage

    from ...core.geometry import apply, decompose_similarity
    from ...evaluate.nonrigid import warp_image
    from ...evaluate.wallmetrics import wall_metrics
    from ...maps.halmstad import robust_similarity
    from ...maps.preprocess import wall_thickness_px

    t0 = time.perf_counter()
    ks, kt = np.asarray(ks, float), np.asarray(kt, float)
    gt, inl = robust_similarity(ks, kt)
    floor = float(np.hypot(*(apply(gt, ks[inl]) - kt[inl]).T).mean())
    scale, angle, _, _ = decompose_similarity(gt)
    row: dict = {"map": name, "gt_scale": float(scale),
                 "gt_rotation_deg": float(np.degrees(angle)),
                 "gt_inliers": f"{int(inl.sum())}/{len(inl)}", "kp_floor": floor}
    for pre, sc in (("", float(scale)), ("s1_", None)):
        for tag, m in (("real", sensor), ("gen", corrected)):
            err, ev = _metric(m, layout, seed, sc)
            row[f"{pre}error_{tag}"] = err
            if ev is None:
                row[f"{pre}kp_{tag}"], row[f"{pre}align_ok_{tag}"] = float("nan"), False
                row[f"{pre}chain_{tag}"] = ""
                continue
            sim, _ = ev.registration.map_points(ks[inl])
            kp = float(np.hypot(*(sim - kt[inl]).T).mean())
            row[f"{pre}kp_{tag}"] = kp
            row[f"{pre}align_ok_{tag}"] = bool(
                kp <= KP_GOOD_RATIO * max(floor, KP_FLOOR_MIN_PX) and kp <= KP_GOOD_PX)
            row[f"{pre}chain_{tag}"] = ev.report["chosen_chain"]
        row[f"{pre}diff"] = row[f"{pre}error_real"] - row[f"{pre}error_gen"]
        row[f"{pre}counted"] = bool(np.isfinite(row[f"{pre}diff"])
                                    and row[f"{pre}align_ok_real"] and row[f"{pre}align_ok_gen"])
    # guards: the layout in the sensor's frame (the maps under test untouched) ...
    plan_s = warp_image(layout.data, np.linalg.inv(gt), sensor.shape)
    for tag, m in (("real", sensor), ("gen", corrected)):
        for k, v in wall_metrics(m.data, plan_s).items():
            row[f"{tag}_{k}"] = v
    # ... restricted to what the robot observed (the layout's walls within
    # OBSERVED_MARGIN_PX of the sensor map's known cells; the rest is unknown for both) ...
    seen = ndimage.binary_dilation(sensor.data != UNKNOWN, iterations=OBSERVED_MARGIN_PX)
    plan_seen = np.where(seen, plan_s, UNKNOWN).astype(np.uint8)
    for tag, m in (("real", sensor), ("gen", corrected)):
        for k, v in wall_metrics(m.data, plan_seen).items():
            row[f"ob_{tag}_{k}"] = v
    # ... and, as a check, both maps in the layout's frame
    for tag, m in (("real", sensor), ("gen", corrected)):
        for k, v in wall_metrics(warp_image(m.data, gt, layout.shape), layout.data).items():
            row[f"lf_{tag}_{k}"] = v
    row["layout_wall_px"] = wall_thickness_px(plan_s[None])
    row["real_wall_px"] = wall_thickness_px(sensor.data[None])
    row["gen_wall_px"] = wall_thickness_px(corrected.data[None])
    row["seconds"] = time.perf_counter() - t0
    return row


def _median(v) -> float:
    v = np.asarray(v, float)
    return float(np.nanmedian(v)) if np.isfinite(v).any() else float("nan")


def _counts(rows: list[dict], pre: str) -> dict:
    """Improved / worse among the counted maps of one metric setting (``pre``)."""
    from scipy.stats import binomtest

    diff = np.array([r[f"{pre}diff"] for r in rows], float)
    counted = np.array([bool(r[f"{pre}counted"]) for r in rows], bool)
    d = diff[counted]
    improved, worse = int((d > 0).sum()), int((d < 0).sum())
    p = binomtest(improved, improved + worse, 0.5, alternative="greater").pvalue \
        if improved + worse else float("nan")
    fin = np.isfinite(diff)
    return {
        "n": len(rows), "counted": int(counted.sum()),
        "flagged": int((fin & ~counted).sum()), "failed": int((~fin).sum()),
        "improved": improved, "worse": worse, "ties": int((d == 0).sum()),
        "share_improved": improved / len(d) if len(d) else float("nan"),
        "sign_test_p": float(p),
        "flagged_improved": int((diff[fin & ~counted] > 0).sum()),
        "improved_all": int((diff[fin] > 0).sum()), "finite": int(fin.sum()),
        "median_diff": _median(d),
        "median_error_real": _median([r[f"{pre}error_real"] for r in rows]),
        "median_error_gen": _median([r[f"{pre}error_gen"] for r in rows]),
        "improved_but_lost_recall": sum(
            1 for r, c in zip(rows, counted, strict=True)
            if c and r[f"{pre}diff"] > 0 and r["gen_wall_recall"] < r["real_wall_recall"]),
    }


def summarise_real(rows: list[dict]) -> dict:
    """Summary of :func:`real_pair_row` rows: counts over the *counted* maps (both
    alignments good), the one-sided sign test, medians; the same counts for the metric
    at scale 1 under ``s1_`` keys when the rows carry them.

    Examples
    --------
    >>> rows = [{"diff": d, "counted": c, "error_real": 1.0, "error_gen": 1.0 - d,
    ...          "real_wall_recall": 0.5, "gen_wall_recall": 0.6}
    ...         for d, c in ((0.5, True), (0.2, True), (-0.1, True), (0.3, False))]
    >>> s = summarise_real(rows)
    >>> s["counted"], s["improved"], s["worse"], s["flagged_improved"], round(s["sign_test_p"], 3)
    (3, 2, 1, 1, 0.5)
    """
    s = _counts(rows, "")
    if rows and "s1_diff" in rows[0]:
        s.update({f"s1_{k}": v for k, v in _counts(rows, "s1_").items()})
    for pre in ("", "ob_", "lf_"):
        for k in (*GUARDS, "wall_precision"):
            for tag in ("real", "gen"):
                key = f"{pre}{tag}_{k}"
                if rows and key in rows[0]:
                    s[f"median_{key}"] = _median([r[key] for r in rows])
    for k in ("layout_wall_px", "real_wall_px", "gen_wall_px"):
        if rows and k in rows[0]:
            s[f"median_{k}"] = _median([r[k] for r in rows])
    return s


@dataclass
class RealTable53:
    """Table 5.3 on real maps (module docstring).

    Attributes
    ----------
    rows : list of dict
        :func:`real_pair_row` per map, plus the auto-correct's ``shrink``,
        ``deskew_deg``, ``support`` and ``warnings`` (how many).
    summary : dict
        :func:`summarise_real`, plus ``seconds`` (whole run) and ``autocorrect_s``.
    inputs, outputs, layouts : dict of name -> OccupancyMap
        Sensor maps, auto-corrected maps, layouts (by environment).
    gt : dict of name -> (3, 3) array
        Ground-truth similarity sensor -> layout.
    model : str
        Which model.
    """

    rows: list[dict]
    summary: dict
    inputs: dict = field(repr=False, default_factory=dict)
    outputs: dict = field(repr=False, default_factory=dict)
    layouts: dict = field(repr=False, default_factory=dict)
    gt: dict = field(repr=False, default_factory=dict)
    model: str = ""

    def format(self) -> str:
        """The table and its summary as text."""
        s = self.summary
        nan = float("nan")
        lines = [f"Table 5.3 on {len(self.rows)} real Halmstad maps; model {self.model}",
                 "metric with the scale known (rigid_scale = ground-truth scale) | at scale 1 "
                 "(run_table53's settings); ok: the metric's alignment on the keypoints "
                 "(real, gen); guards in the sensor's frame",
                 f"{'map':<7} {'shrink':>6} {'Err(real)':>9} {'Err(gen)':>9} {'diff':>8} "
                 f"{'ok':>3} | {'diff@1':>8} {'ok':>3} | {'kp floor/real/gen px':>20} "
                 f"{'recall r/g':>11} {'F1 r/g':>11} {'Chamfer r/g':>13} {'wall px L/r/g':>15}"]

        def ok(r, pre):
            return "".join("y" if r.get(f"{pre}align_ok_{t}") else "n" for t in ("real", "gen"))

        for r in self.rows:
            lines.append(
                f"{r['map']:<7} {r.get('shrink', nan):>6.2f} {r['error_real']:>9.3f} "
                f"{r['error_gen']:>9.3f} {r['diff']:>+8.3f} {ok(r, ''):>3} | "
                f"{r.get('s1_diff', nan):>+8.3f} {ok(r, 's1_'):>3} | {r['kp_floor']:>5.1f}/"
                f"{r['kp_real']:>5.1f}/{r['kp_gen']:<5.1f}   "
                f"{r['real_wall_recall']:>5.2f}/{r['gen_wall_recall']:<5.2f} "
                f"{r['real_boundary_f1']:>5.2f}/{r['gen_boundary_f1']:<5.2f} "
                f"{r['real_chamfer_px']:>6.1f}/{r['gen_chamfer_px']:<6.1f} "
                f"{r.get('layout_wall_px', nan):>4.1f}/{r.get('real_wall_px', nan):>4.1f}/"
                f"{r.get('gen_wall_px', nan):<4.1f}")
        for pre, what in (("", "metric scale known"), ("s1_", "metric at scale 1")):
            if f"{pre}n" not in s:
                continue
            g = {k: s[f"{pre}{k}"] for k in ("n", "counted", "flagged", "failed", "improved",
                                              "worse", "ties", "share_improved", "sign_test_p",
                                              "improved_all", "finite", "flagged_improved",
                                              "improved_but_lost_recall", "median_error_real",
                                              "median_error_gen", "median_diff")}
            lines += [
                f"[{what}] maps {g['n']}: counted {g['counted']} (both alignments good), "
                f"flagged {g['flagged']} (an alignment off the keypoints), metric failed "
                f"{g['failed']}",
                f"[{what}] improved (Error(real) - Error(gen) > 0): {g['improved']}/"
                f"{g['counted']} = {g['share_improved']:.1%}, worse {g['worse']}, ties "
                f"{g['ties']}; one-sided sign test p = {g['sign_test_p']:.3g}; flags ignored: "
                f"{g['improved_all']}/{g['finite']} ({g['flagged_improved']} flagged)",
                f"[{what}] median Error(real) {g['median_error_real']:.3f} px, Error(gen) "
                f"{g['median_error_gen']:.3f} px, median diff (counted) {g['median_diff']:+.3f}"
                f" px; improved but lost wall recall: {g['improved_but_lost_recall']}",
            ]
        for pre, frame in (("", "sensor frame"), ("ob_", "observed part"),
                           ("lf_", "layout frame")):
            for k in (*GUARDS, "wall_precision"):
                a, b = s.get(f"median_{pre}real_{k}"), s.get(f"median_{pre}gen_{k}")
                if a is not None:
                    lines.append(f"median {k:<14} ({frame:<13}) real {a:8.3f}  "
                                 f"auto-corrected {b:8.3f}")
        if "median_gen_wall_px" in s:
            lines.append(f"median wall thickness (sensor px): layout "
                         f"{s['median_layout_wall_px']:.1f}, real map "
                         f"{s['median_real_wall_px']:.1f}, auto-corrected "
                         f"{s['median_gen_wall_px']:.1f}")
        if s.get("seconds"):
            lines.append(f"run time {s['seconds']:.0f} s (auto-correct {s['autocorrect_s']:.0f}"
                         " s), one process")
        return "\n".join(lines)

    def to_csv(self, path: str | os.PathLike) -> Path:
        """Write :attr:`rows` as CSV (atomically)."""
        from ...core._io import atomic_path

        path = Path(path)
        with atomic_path(path) as tmp, open(tmp, "w", newline="") as fh:
            w = csv.DictWriter(fh, fieldnames=list(self.rows[0]) if self.rows else ["map"])
            w.writeheader()
            w.writerows(self.rows)
        return path

    def figure(self, path: str | os.PathLike | None = None):
        """Fig. 5.12 on real maps: box plots of the counted diffs (layout px), the metric
        with the scale known and at scale 1, every map a dot (E5 circles, HIH squares;
        flagged maps hollow red). Returns the figure."""
        from ...core.viz import plt

        env = np.array([str(r["map"]).split("_")[0] for r in self.rows])
        pres = [p for p in ("", "s1_") if self.rows and f"{p}diff" in self.rows[0]]
        fig, ax = plt.subplots(figsize=(5, 5))
        rng = np.random.default_rng(0)  # seeded jitter of the dots
        labels = []
        for pos, pre in enumerate(pres, start=1):
            d = np.array([r[f"{pre}diff"] for r in self.rows], float)
            c = np.array([bool(r[f"{pre}counted"]) for r in self.rows])
            if c.any():
                ax.boxplot(d[c], positions=[pos], widths=0.5, showfliers=False)
            x = pos + rng.uniform(-0.12, 0.12, len(d))
            for e, mk in (("E5", "o"), ("HIH", "s")):
                sel = (env == e) & c & np.isfinite(d)
                ax.scatter(x[sel], d[sel], marker=mk, s=18, color="k", zorder=3,
                           label=e if pos == 1 else None)
                sel = (env == e) & ~c & np.isfinite(d)
                if sel.any():
                    ax.scatter(x[sel], d[sel], marker=mk, s=30, facecolors="none",
                               edgecolors="red", zorder=3,
                               label=f"{e} flagged" if pos == 1 else None)
            k = self.summary.get(f"{pre}improved"), self.summary.get(f"{pre}counted")
            labels.append(("scale known" if pre == "" else "scale 1") + f"\n{k[0]}/{k[1]} "
                          "improved")
        ax.axhline(0, color="grey", lw=0.8)
        ax.set_xticks(range(1, len(pres) + 1), labels)
        ax.set(ylabel="Error(real) - Error(gen) [layout px]", xlim=(0.5, len(pres) + 0.5),
               title="Fig. 5.12 on the 18 real Halmstad maps")
        ax.legend(fontsize=7, loc="best")
        fig.tight_layout()
        if path is not None:
            from ...core.viz import save_figure

            save_figure(fig, path, dpi=100)
        return fig

    def overlay_figure(self, names: list[str], path: str | os.PathLike | None = None,
                       px: int = 420):
        """Per map: layout | real map | auto-corrected, the maps warped into the layout by
        the ground truth and drawn over it (map walls red, map free space light blue),
        cropped to the layout's content and reduced to about ``px`` pixels (walls kept:
        any wall pixel in a reduced cell draws it)."""
        import cv2

        from ...core.viz import plt
        from ...evaluate.nonrigid import warp_image

        names = [n for n in names if n in self.inputs]
        fig, axes = plt.subplots(max(1, len(names)), 3, figsize=(10.5, 3.6 * max(1, len(names))),
                                 squeeze=False)
        by = {r["map"]: r for r in self.rows}
        for i, n in enumerate(names):
            lay = self.layouts[n.split("_")[0]].data
            box = OccupancyMap(lay, 1.0).content_bbox()
            r0, r1, c0, c1 = box if box is not None else (0, lay.shape[0], 0, lay.shape[1])
            f = max(1.0, max(r1 - r0, c1 - c0) / px)
            size = (max(1, round((c1 - c0) / f)), max(1, round((r1 - r0) / f)))

            def small(mask, size=size, r0=r0, r1=r1, c0=c0, c1=c1):
                return cv2.resize(mask[r0:r1, c0:c1].astype(np.float32), size,
                                  interpolation=cv2.INTER_AREA) > 0

            base = np.full((size[1], size[0], 3), 0.93)
            base[small(lay == FREE)] = 1.0
            lay_wall = small(lay == OCCUPIED)
            for j, (title, m) in enumerate((("layout", None), ("real map", self.inputs[n]),
                                            ("auto-corrected", self.outputs[n]))):
                img = base.copy()
                img[lay_wall] = (0.35, 0.35, 0.35)
                if m is not None:
                    w = warp_image(m.data, self.gt[n], lay.shape)
                    img[small(w == FREE) & ~lay_wall] = (0.80, 0.90, 1.0)
                    img[small(w == OCCUPIED)] = (0.85, 0.1, 0.1)
                ax = axes[i, j]
                ax.imshow(img, interpolation="nearest")
                ax.set_xticks([])
                ax.set_yticks([])
                if j == 0:
                    r = by.get(n, {})
                    ax.set_ylabel(f"{n}: diff {r.get('diff', float('nan')):+.2f} px", fontsize=8)
                if j == 1 and n in by:
                    title += (f"\nErr {by[n]['error_real']:.2f} px, recall "
                              f"{by[n]['real_wall_recall']:.2f}")
                if j == 2 and n in by:
                    title += (f"\nErr {by[n]['error_gen']:.2f} px, recall "
                              f"{by[n]['gen_wall_recall']:.2f}")
                ax.set_title(title, fontsize=8)
        fig.suptitle("walls of the map (red) over the layout (grey), ground-truth placement",
                     fontsize=9)
        fig.tight_layout()
        if path is not None:
            from ...core.viz import save_figure

            save_figure(fig, path, dpi=90)
        return fig


def run_table53_real(root: str | os.PathLike, names: list[str] | None = None,
                     model="pretrained", *, seed: int = 0, anchor: bool = True,
                     straighten: bool = True, workers: int | None = 1,
                     progress: bool = True, autocorrect_kw: dict | None = None) -> RealTable53:
    """Table 5.3 of ``model`` on the Halmstad sensor maps (module docstring).

    Parameters
    ----------
    root : path-like
        The Halmstad data folder (``shared/data/halmstad``).
    names : list of str, optional
        Sensor maps (``E5_01``, ``HIH_03``, ...); default all 18.
    model : "pretrained", run folder, weights file, BAModel, or a corrector
        (:func:`map2map.jobs.autocorrect.corrector`: ``correct_many``, as ``map2map
        autocorrect --model NAME`` runs it; or the older ``correct`` form)
        As :func:`~map2map.experiments.table53.measure.run_table53`: the Model_BA to measure, or an
        object with ``correct(list of uint8 maps) -> list of maps`` and ``source``.
    seed : int
        Seed of the metric's point subsampling.
    anchor, straighten : bool
        Passed to :func:`~map2map.learn.ba.autocorrect.autocorrect_many` (defaults: the
        shipped behaviour).
    workers : int or None
        Threads of the auto-correct's per-map work (1: single-threaded; the output does
        not depend on it).
    progress : bool
        tqdm progress bar over the maps.
    autocorrect_kw : dict, optional
        More keyword arguments of ``autocorrect_many`` (``thickness``,
        ``open_frontiers``, ...).

    Returns
    -------
    RealTable53
    """
    from tqdm import tqdm

    from ...maps.halmstad import (
        halmstad_pairs,
        load_association,
        load_halmstad,
        load_keypoints,
        robust_similarity,
    )
    from ...maps.preprocess import content_square

    t_all = time.perf_counter()
    root = Path(root)
    pairs = [(s, t) for s, t in halmstad_pairs(root, both_ways=False)
             if names is None or s in names]
    inputs = {s: load_halmstad(root, s) for s, _ in pairs}
    layouts = {t.split("_")[0]: load_halmstad(root, t) for t in {t for _, t in pairs}}
    maps = [inputs[s] for s, _ in pairs]
    t0 = time.perf_counter()
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        if hasattr(model, "correct_many"):       # a corrector of the autocorrect registry
            outs = model.correct_many(maps, **(autocorrect_kw or {}))
            extra = [{"deskew_deg": o.meta.get("autocorrect", {}).get("deskew_deg")}
                     for o in outs]
            name = model.name
            data_size = 256
        elif hasattr(model, "correct"):
            gen = model.correct([m.data for m in maps])
            outs = [m.copy(data=np.asarray(g, np.uint8)) for m, g in zip(maps, gen, strict=True)]
            extra = [{} for _ in maps]
            name = model.source
            data_size = 256
        else:
            from ...learn.ba.autocorrect import autocorrect_many
            from ...learn.ba.model import load_model

            net = load_model(model)
            name = net.source + ("" if anchor else " (anchor off)")
            data_size = net.data_size
            res = autocorrect_many(maps, net, straighten=straighten, anchor=anchor,
                                   workers=workers, **(autocorrect_kw or {}))
            outs = [r.map for r in res]
            extra = [{"deskew_deg": r.map.meta["autocorrect"].get("deskew_deg"),
                      "support": r.map.meta["autocorrect"].get("support"),
                      "warnings": len(r.warnings)} for r in res]
    t_ac = time.perf_counter() - t0
    rows, gts = [], {}
    for (s, t), out, ex in tqdm(list(zip(pairs, outs, extra, strict=True)),
                                desc="Table 5.3 (real)", disable=not progress):
        src, lay = inputs[s], layouts[t.split("_")[0]]
        assoc = load_association(root, s, t)
        ks = load_keypoints(root, s, src.height)[assoc[:, 0]]
        kt = load_keypoints(root, t, lay.height)[assoc[:, 1]]
        row = real_pair_row(s, src, out, lay, ks, kt, seed=seed)
        sq = content_square(src, data_size)
        row = {"map": s, "shrink": sq.side / data_size if sq is not None else float("nan"),
               **ex, **{k: v for k, v in row.items() if k != "map"}}
        rows.append(row)
        gts[s] = robust_similarity(ks, kt)[0]
    summary = summarise_real(rows)
    summary.update(seed=seed, seconds=time.perf_counter() - t_all, autocorrect_s=t_ac)
    return RealTable53(rows, summary, inputs, dict(zip((s for s, _ in pairs), outs,
                                                       strict=True)), layouts, gts, name)
