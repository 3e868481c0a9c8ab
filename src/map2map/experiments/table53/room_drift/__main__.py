"""Drift room by room: Table 5.3's metric with each room moved by the translation fitted
knowing the plan, and by the one the map's own consistency gives (module doc of the
package)::

    python -m map2map.experiments.table53.room_drift --data DS --split val --n 12 --all

Prints per map the matched error (px) of the input, the input moved room by room
(fitted, solved) and ``map2map autocorrect --model none`` on each, then the medians, the
sign counts of ``none`` after either against ``none``, and how the solved translations
correlate with the fitted ones (per axis, each map's translations centred on their
pixel-weighted mean: the metric's rigid alignment ignores a common shift).
"""

from __future__ import annotations

import argparse
import sys
import warnings

import numpy as np

from map2map.core.grid import OccupancyMap
from map2map.experiments.table53.field_ceiling.__main__ import plan_in_slam_frame
from map2map.experiments.table53.measure import _errors, heldout_pairs_from_dataset
from map2map.experiments.table53.room_drift import fit_rooms, room_field, rooms, solve_rooms


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(prog="python -m map2map.experiments.table53.room_drift",
                                 description=__doc__.split("\n\n")[0])
    ap.add_argument("--data", required=True, help="dataset folder or packed .npz")
    ap.add_argument("--split", nargs="+", default=["val"])
    ap.add_argument("--n", type=int, default=12)
    ap.add_argument("--all", action="store_true", help="every finished pair, not only 'complete'")
    a = ap.parse_args(argv)
    from map2map.jobs.autocorrect import corrector
    from map2map.learn.ba.field import warp

    pairs = heldout_pairs_from_dataset(a.data, tuple(a.split), a.n,
                                       keep=() if a.all else ("complete",))
    none = corrector("none")
    rows, fitted, solved = [], [], []
    print("map: input / fitted / solved ; none / none after fitted / none after solved (px)")
    for i, pid in enumerate(pairs.plan_id):
        plan, slam = pairs.a[i], pairs.b[i]
        lab, near = rooms(slam)
        T = fit_rooms(slam, plan_in_slam_frame(plan, slam), near)
        S = solve_rooms(slam, lab)
        wf = warp(slam, room_field(near, T))
        ws = warp(slam, room_field(near, S))
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            outs = none.correct_many([OccupancyMap(x, 0.05) for x in (slam, wf, ws)])
        r = [_errors(x, plan, 0)[0] for x in (slam, wf, ws, *(o.data for o in outs))]
        rows.append(r)
        R = int(lab.max())
        cnt = np.bincount(near.ravel(), minlength=R + 1)[1:].astype(float)
        To = np.array([T.get(k, (0.0, 0.0)) for k in range(1, R + 1)])
        Se = S[1:R + 1]
        if cnt.sum() > 0 and R > 1:
            fitted.append(To - np.average(To, axis=0, weights=cnt))
            solved.append(Se - np.average(Se, axis=0, weights=cnt))
        print(f"{pid} ({R} rooms): {r[0]:.3f} / {r[1]:.3f} / {r[2]:.3f} ; "
              f"{r[3]:.3f} / {r[4]:.3f} / {r[5]:.3f}", flush=True)
    r = np.array(rows)
    med = np.nanmedian(r, axis=0)
    print(f"\n{len(rows)} maps, median matched error px:")
    print(f"  input {med[0]:.3f}, moved by the fitted translations {med[1]:.3f}, by the "
          f"solved ones {med[2]:.3f}")
    print(f"  none  {med[3]:.3f}, after the fitted {med[4]:.3f}, after the solved {med[5]:.3f}")
    for k, name in ((4, "fitted"), (5, "solved")):
        d = r[:, k] - r[:, 3]
        print(f"  none after the {name} against none: lower on {(d < 0).sum()}, higher on "
              f"{(d > 0).sum()} (by > 0.05 px: {(d < -0.05).sum()} / {(d > 0.05).sum()})")
    if fitted:
        F, S = np.concatenate(fitted), np.concatenate(solved)
        c = [np.corrcoef(F[:, ax], S[:, ax])[0, 1] for ax in (0, 1)]
        print(f"  solved against fitted translations ({len(F)} rooms): correlation x "
              f"{c[0]:.2f}, y {c[1]:.2f}; mean |fitted| {np.abs(F).mean():.2f} px")
    return 0


if __name__ == "__main__":
    sys.exit(main())
