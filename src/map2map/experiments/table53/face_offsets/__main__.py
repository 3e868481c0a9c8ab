"""Per observed wall face of Model_BA's anchored walls: how far is the plan's face, the
network's, and the face a post-processing rule would draw? (docs/autocorrect.md, "Moving
drifted walls".)

For every held-out pair whose map is not deskewed, the anchored step's faces
(:func:`map2map.learn.ba.postprocess.anchored_walls` before any move: straight segments of
the input, faces at the map's angle) are compared with the plan after the SLAM map's own
rigid alignment (:func:`map2map.evaluate.pipeline.evaluate_maps`): per face, the median
offset across the wall to the nearest plan face pixel facing the same way (within 1.5 px
along, 5 px across). Printed, length-weighted mean absolute offsets (px):

* ``input``: the face where the map has it;
* ``network``: moved to where the upsampled network output crosses the wall level,
  less each map's median per side (the network draws thicker walls);
* ``collinear``: moved to its group's length-weighted mean line
  (:func:`~map2map.learn.ba.postprocess.collinear_faces`, 3 px, one map at a time);
* ``two-sided``: faces of walls seen from both sides, grown to 4 / 5 / 6 px
  (:func:`~map2map.learn.ba.postprocess.thicken_two_sided`).

    python3 -m map2map.experiments.table53.face_offsets --data /work/datasets/gen6300 --split val
"""

from __future__ import annotations

import argparse
import math
import sys
import warnings

import numpy as np

from map2map.core.geometry import apply
from map2map.core.grid import OCCUPIED, OccupancyMap
from map2map.evaluate.pipeline import EvaluateParams, evaluate_maps
from map2map.experiments.table53.measure import heldout_pairs_from_dataset
from map2map.learn.ba import anchor, faces, pieces
from map2map.learn.ba import autocorrect as ac
from map2map.learn.ba import postprocess as pp
from map2map.learn.ba.squares import prepare
from map2map.maps.segments import straight_segments


def _faces(guide: np.ndarray, data_px: float):
    """The anchored step's faces before any move: (horiz, (K, 2) faces, lo, hi, slope)."""
    guide = pieces.drop_free_specks(guide, anchor.ANCHOR.speck * data_px ** 2)
    s = straight_segments(guide == OCCUPIED, anchor.ANCHOR.cell * data_px)
    horiz, f, lo, hi, _, slope = anchor._observed_faces(guide, s, anchor.ANCHOR.band * data_px, 0.3,
                                                    True)
    return horiz, f, lo, hi, slope


def _net_offset(grey: np.ndarray, horiz: bool, js, across, side: int) -> float:
    """Median offset (px) of the network's wall boundary on ``side`` from the face."""
    n = grey.shape[0]
    sign = -1 if side == 0 else 1
    offs = np.arange(-4, 5)
    out = []
    for j, a in zip(js, across, strict=True):
        r = int(round(a)) + offs
        okr = (r >= 0) & (r < n)
        prof = np.full(len(offs), np.nan)
        prof[okr] = grey[r[okr], j] if horiz else grey[j, r[okr]]
        wall = np.flatnonzero(prof < pp.WALL_BELOW)
        if not len(wall):
            continue
        e = wall.max() if sign > 0 else wall.min()
        e2 = e + sign
        if not (0 <= e2 < len(prof)) or np.isnan(prof[e2]):
            continue
        v0, v1 = prof[e], prof[e2]
        t = (pp.WALL_BELOW - v0) / (v1 - v0) if v1 != v0 else 0.0
        out.append(int(round(a)) - a + offs[e] + sign * t - sign * 0.5)
    return float(np.median(out)) if len(out) >= 0.3 * len(js) else float("nan")


def face_offsets(pairs, net) -> list[dict]:
    """One row per observed face: map, which side, length, the plan's and the network's
    offsets across the wall (px, map rows/columns), and the face's line."""
    import cv2
    from scipy import ndimage

    rows = []
    for i in range(len(pairs)):
        m = OccupancyMap(pairs.b[i], 0.05)
        prep = prepare(m, net.data_size, True, ac.MIN_SKEW_ANCHORED_DEG)
        angle, model_sq = prep.angle, prep.model
        row0, col0 = prep.square.row0, prep.square.col0
        if angle:
            continue
        n = model_sq.shape[0]
        out = net.predict(ac.square_resize(model_sq, net.data_size)[None])[0]
        grey = cv2.resize(out.astype(np.float32), (n, n), interpolation=cv2.INTER_LINEAR)
        horiz, f, lo, hi, slope = _faces(model_sq, n / net.data_size)
        ev = evaluate_maps(m, OccupancyMap(pairs.a[i], 0.05), params=EvaluateParams(seed=0))
        T = ev.registration.alignment.rigid
        th = math.atan2(T[1, 0], T[0, 0])
        back = np.array([[math.cos(th), math.sin(th)], [-math.sin(th), math.cos(th)]])
        near = [ndimage.distance_transform_edt(~mk, return_indices=True)[1]
                for mk in faces.surface_masks(pairs.a[i])]
        H, W = pairs.a[i].shape
        for k in range(len(horiz)):
            for sd in (0, 1):
                if f[k, sd] < 0:
                    continue
                which = sd if horiz[k] else 2 + sd
                js = np.arange(max(0, lo[k]), min(n, hi[k] + 1))
                mid = (lo[k] + hi[k]) / 2
                across = f[k, sd] + slope[k] * (js - mid)
                X = np.stack([js + col0 + 0.5, across + row0 + 0.5] if horiz[k]
                             else [across + col0 + 0.5, js + row0 + 0.5], 1)
                P = apply(T, X)
                pc = np.clip(np.round(P[:, 0] - 0.5).astype(int), 0, W - 1)
                pr = np.clip(np.round(P[:, 1] - 0.5).astype(int), 0, H - 1)
                qr, qc = near[which][0][pr, pc], near[which][1][pr, pc]
                d = np.stack([qc + 0.5 - P[:, 0], qr + 0.5 - P[:, 1]], 1) @ back.T
                acr, alo = (d[:, 1], d[:, 0]) if horiz[k] else (d[:, 0], d[:, 1])
                ok = (np.abs(alo) <= 1.5) & (np.abs(acr) <= 5)
                if ok.sum() < max(3, 0.3 * len(js)):
                    continue
                rows.append(dict(map=i, k=k, horiz=bool(horiz[k]), side=sd, which=which,
                                 length=len(js), face=int(f[k, sd]), lo=int(lo[k]),
                                 hi=int(hi[k]), slope=float(slope[k]),
                                 plan=float(np.median(acr[ok])),
                                 net=_net_offset(grey, bool(horiz[k]), js, across, sd)))
    return rows


def summary(rows: list[dict]) -> str:
    """The length-weighted mean absolute offsets of the module docstring, as text."""
    col = {k: np.array([r[k] for r in rows]) for k in rows[0]}
    L, dp, mp, wh = col["length"].astype(float), col["plan"], col["map"], col["which"]

    def w(x, m):
        return float(np.average(np.abs(x[m]), weights=L[m])) if m.any() else float("nan")

    every = np.ones(len(rows), bool)
    has = np.isfinite(col["net"])
    dn = col["net"].copy()
    for m in np.unique(mp):
        for k in range(4):
            s = (mp == m) & (wh == k) & has
            dn[s] -= np.median(dn[s]) if s.any() else 0.0
    lines = [f"{len(rows)} faces on {len(np.unique(mp))} maps: input {w(dp, every):.3f} px",
             f"  where the network has a wall ({has.sum()}): input {w(dp, has):.3f}, network "
             f"{w(dp - dn, has):.3f} (correlation {np.corrcoef(dp[has], dn[has])[0, 1]:.2f})"]
    horiz, side = col["horiz"], col["side"]
    shift = np.zeros(len(rows), np.int64)
    for m in np.unique(mp):  # one map's faces at a time
        s = mp == m
        shift[s] = faces.collinear_faces(horiz[s], side[s], col["face"][s], col["lo"][s],
                                      col["hi"][s], col["slope"][s], 3.0) - col["face"][s]
    lines.append(f"  collinear (3 px, mean line): {w(dp, every):.3f} -> "
                 f"{w(dp - shift, every):.3f} ({(shift != 0).sum()} faces moved)")
    pairs = {}
    for j, r in enumerate(rows):
        pairs.setdefault((r["map"], r["k"]), {})[r["side"]] = j
    two = np.array([(v[0], v[1]) for v in pairs.values() if len(v) == 2]).reshape(-1, 2)
    if len(two):
        i0, i1 = two[:, 0], two[:, 1]
        f0, f1 = col["face"][i0], col["face"][i1]

        def both(e0, e1):  # mean of the two sides' length-weighted means
            return (np.average(np.abs(e0), weights=L[i0])
                    + np.average(np.abs(e1), weights=L[i1])) / 2

        out = []
        for width in (4, 5, 6):
            g0, g1 = faces.thicken_two_sided(f0, f1, width)
            out.append(f"{width} px {both(dp[i0] - (g0 - f0), dp[i1] - (g1 - f1)):.3f}")
        lines.append(f"  two-sided walls ({len(two)}): {both(dp[i0], dp[i1]):.3f} -> "
                     + ", ".join(out))
    return "\n".join(lines)


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--data", required=True, help="dataset folder or packed .npz")
    ap.add_argument("--split", nargs="+", default=["val"])
    ap.add_argument("--n", type=int, default=None)
    args = ap.parse_args(argv)
    warnings.simplefilter("ignore")
    pairs = heldout_pairs_from_dataset(args.data, tuple(args.split), n=args.n)
    rows = face_offsets(pairs, ac.load_model("pretrained"))
    print(summary(rows) if rows else "no faces")
    return 0


if __name__ == "__main__":
    sys.exit(main())
