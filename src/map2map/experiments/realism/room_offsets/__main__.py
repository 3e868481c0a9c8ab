"""Per-room rigid offsets of SLAM maps against their plans (issue #15: what the simulated
maps' wall error looks like, so that a drift model is fitted to it).

For each plan of ``--split`` (a ``map2map dataset build`` folder): the plan's rooms
(:func:`map2map.learn.ab.room_drift.segment_rooms` of ``A.png``), every occupied pixel of a
map given to the room its pixel belongs to, and per room with at least ``--min-pts``
such pixels the rigid transform (rotation about the room's centroid, then a shift) that
brings them closest to the plan's walls: brute force over rotations (``--max-deg``) and
shifts (``--max-px``), coarse then fine, minimising the mean distance to the nearest plan
wall truncated at ``--cap`` px (so unrelated pixels, rays through windows, do not pull).

Maps: ``sim1`` (the dataset's ``B.png``), and with ``--model``: Model_AB without drift
(the null: what the fit finds where there is no drift), with the parametric drift
(``parametric``) and with the room-wise drift (``rooms``, :class:`RoomDriftParams` from
``--rooms`` JSON). Prints per map kind: the per-room rotation and shift quantiles, the
per-map wall error before and after the per-room fit, and the share of rooms off by
more than 1 deg / 2 px; ``--npz`` keeps every room's row.

    python3 -m map2map.experiments.realism.room_offsets --data DS --split val [--plans N] \
        [--model pretrained]
        [--rooms '{"rot_deg": 1}' ...] [--npz out.npz]
"""

from __future__ import annotations

import argparse
import json
import sys
import time
import warnings

import numpy as np
from scipy import ndimage

from map2map.learn.ab.room_drift import segment_rooms


def fit_room(pts: np.ndarray, dist: np.ndarray, centre, max_deg=8.0, max_px=14.0, cap=3.0):
    """(theta_deg, tx, ty, cost_before, cost_after) of the rigid fit of ``pts`` ((n, 2)
    x, y) to the walls whose distance map is ``dist``: a 1 deg x 2 px grid over the whole
    range, then 0.5 deg x 1 px and 0.25 deg x 0.25 px around the best."""
    cx, cy = centre
    x0, y0 = pts[:, 0] - cx, pts[:, 1] - cy

    def costs(thetas, shifts):
        out = np.empty((len(thetas), len(shifts)))
        for i, th in enumerate(np.radians(thetas)):
            c, s = np.cos(th), np.sin(th)
            xr, yr = c * x0 - s * y0 + cx, s * x0 + c * y0 + cy
            X = xr[None] + shifts[:, 0, None]
            Y = yr[None] + shifts[:, 1, None]
            v = ndimage.map_coordinates(dist, [Y.ravel(), X.ravel()], order=1, mode="nearest")
            out[i] = np.minimum(v.reshape(X.shape), cap).mean(1)
        return out

    def grid(step, half):
        g = np.arange(-half, half + 1e-9, step)
        return np.stack(np.meshgrid(g, g), -1).reshape(-1, 2)

    base = costs(np.array([0.0]), np.zeros((1, 2)))[0, 0]
    best = (0.0, np.zeros(2))
    for dth, hth, dsh, hsh in ((1.0, max_deg, 2.0, max_px), (0.5, 1.0, 1.0, 2.0),
                               (0.25, 0.5, 0.25, 0.5)):
        th = best[0] + np.arange(-hth, hth + 1e-9, dth)
        sh = best[1] + grid(dsh, hsh)
        c = costs(th, sh)
        i, j = np.unravel_index(int(np.argmin(c)), c.shape)
        best = (float(th[i]), sh[j])
        cost = float(c[i, j])
    return best[0], float(best[1][0]), float(best[1][1]), float(base), cost


def map_rooms(m: np.ndarray, plan: np.ndarray, rooms: np.ndarray, min_pts=30, **kw):
    """Per room of ``rooms`` holding >= ``min_pts`` occupied pixels of ``m``: a row
    (room, n, theta, tx, ty, cost0, cost1, dist_before_mean, dist_after_mean)."""
    walls = plan == 0
    dist = ndimage.distance_transform_edt(~walls)
    occ = m == 0
    rows = []
    free = plan == 255
    for r in range(1, int(rooms.max()) + 1):
        sel = occ & (rooms == r)
        n = int(sel.sum())
        if n < min_pts:
            continue
        yy, xx = np.nonzero(sel)
        pts = np.stack([xx, yy], 1).astype(float)
        cy, cx = ndimage.center_of_mass(free & (rooms == r))
        th, tx, ty, c0, c1 = fit_room(pts, dist, (cx, cy), **kw)
        a = np.radians(th)
        xr = np.cos(a) * (xx - cx) - np.sin(a) * (yy - cy) + cx + tx
        yr = np.sin(a) * (xx - cx) + np.cos(a) * (yy - cy) + cy + ty
        after = ndimage.map_coordinates(dist, [yr, xr], order=1, mode="nearest")
        rows.append((r, n, th, tx, ty, c0, c1, float(dist[sel].mean()), float(after.mean())))
    return rows


def summarise(name, per_map):
    rows = np.array([r for m in per_map for r in m], float)
    if not len(rows):
        print(f"{name}: no rooms")
        return
    th, sh = np.abs(rows[:, 2]), np.hypot(rows[:, 3], rows[:, 4])
    n = rows[:, 1]
    before = np.array([np.average([r[7] for r in m], weights=[r[1] for r in m])
                       for m in per_map if m])
    after = np.array([np.average([r[8] for r in m], weights=[r[1] for r in m])
                      for m in per_map if m])
    q = (50, 75, 90, 95, 99)
    print(f"{name:<28} rooms {len(rows):>4}  |rot| deg q{q}: "
          + " ".join(f"{v:.2f}" for v in np.percentile(th, q))
          + "  |shift| px: " + " ".join(f"{v:.2f}" for v in np.percentile(sh, q)))
    print(f"{'':<28} >1 deg {np.mean(th > 1):.2f}  >2 deg {np.mean(th > 2):.2f}  "
          f">2 px {np.mean(sh > 2):.2f}  >4 px {np.mean(sh > 4):.2f}; per-map wall dist "
          f"(room pixels) before {before.mean():.2f} (q90 {np.percentile(before, 90):.2f}, "
          f"max {before.max():.2f}) after per-room fit {after.mean():.2f} "
          f"(q90 {np.percentile(after, 90):.2f}); weighted |rot| "
          f"{np.average(th, weights=n):.2f} deg")


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--data", required=True)
    ap.add_argument("--split", default="val")
    ap.add_argument("--plans", type=int)
    ap.add_argument("--model", default=None, help="also Model_AB's maps (e.g. pretrained)")
    ap.add_argument("--rooms", nargs="*", default=[], help="RoomDriftParams JSON objects")
    ap.add_argument("--min-pts", type=int, default=30)
    ap.add_argument("--cap", type=float, default=3.0)
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--npz", help="write every room row here")
    args = ap.parse_args(argv)

    from map2map.datasets.pairfolder import pair_dir, read_pair
    from map2map.experiments.realism.measure import pair_square_resolution, split_indices

    t0 = time.perf_counter()
    idx = split_indices(args.data, args.split)[:args.plans]
    a, b = (np.stack(m) for m in zip(*(read_pair(pair_dir(args.data, i)) for i in idx),
                                     strict=True))
    kinds = {"sim1": b}
    if args.model:
        from map2map.learn.ab.room_drift import RoomDriftParams
        from map2map.learn.ab.synthesize import synthesize_squares

        res = np.array([pair_square_resolution(args.data, i, a.shape[-1]) for i in idx])
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            kinds["Model_AB no drift"] = synthesize_squares(args.model, a, seed=args.seed,
                                                            drift="none")
            kinds["Model_AB parametric"] = synthesize_squares(args.model, a, seed=args.seed,
                                                              drift="parametric",
                                                              resolution=res)
            for v in args.rooms:
                kinds[f"rooms {v}"] = synthesize_squares(
                    args.model, a, seed=args.seed, drift=RoomDriftParams(**json.loads(v)),
                    resolution=res)
    print(f"{len(idx)} '{args.split}' plans of {args.data}")
    rooms = [segment_rooms(p) for p in a]
    out = {}
    for name, maps in kinds.items():
        per_map = [map_rooms(m, p, r, args.min_pts, cap=args.cap)
                   for m, p, r in zip(maps, a, rooms, strict=True)]
        summarise(name, per_map)
        out[name] = np.array([(k,) + r for k, m in enumerate(per_map) for r in m], float)
    if args.npz:
        np.savez_compressed(args.npz, indices=np.array(idx), **{k.replace(" ", "_"): v
                                                              for k, v in out.items()})
    print(f"{time.perf_counter() - t0:.0f} s")
    return 0


if __name__ == "__main__":
    sys.exit(main())
