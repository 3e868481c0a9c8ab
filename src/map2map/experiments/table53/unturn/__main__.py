"""Undo each wall's turn, then measure Table 5.3 (issue #32; module doc of the package).

For the held-out pairs of a dataset (coverage at least ``--min-coverage``): the turns of
the SLAM maps' straight wall pieces against each map's dominant direction (percentiles
of their size), and with ``--oracle N`` the same for the first N plans mapped at the true
poses (``simulate --mapper oracle`` with the pair's own simulation seed and duration: the
measurement's own noise); then Table 5.3 (:func:`~map2map.experiments.table53.measure.
run_table53`) with four rows: ``none`` (the default of ``map2map autocorrect``),
``unturn`` (the SLAM map warped by :func:`~map2map.experiments.table53.unturn.
unturn_field`, nothing else) and ``unturn+none`` (warped, then ``none``), newest last::

    python -m map2map.experiments.table53.unturn --data DS --n 100 --oracle 8
"""

from __future__ import annotations

import argparse
import sys
import warnings

import numpy as np

from map2map.core.grid import OccupancyMap
from map2map.experiments.table53.unturn import piece_turns, unturn_field


def unturned(m: np.ndarray) -> np.ndarray:
    """SLAM map ``m`` (uint8) warped by its :func:`unturn_field`."""
    from map2map.learn.ba.field import warp
    from map2map.maps.vectorize import dominant_angle, wall_points

    walls = m == 0
    return warp(m, unturn_field(walls, dominant_angle(wall_points(walls))))


class Unturn:
    """Table 5.3 stand-in: the map warped, not cleaned."""

    name, source = "unturn", "unturn_field, no cleaning"

    def correct(self, maps):
        return [unturned(m) for m in maps]


class UnturnNone:
    """The map warped, then ``map2map autocorrect --model none``."""

    name, source = "unturn+none", "unturn_field, then autocorrect --model none"

    def __init__(self):
        from map2map.jobs.autocorrect import corrector

        self.none = corrector("none")

    def correct(self, maps):
        outs = self.none.correct_many([OccupancyMap(unturned(m), 0.05) for m in maps])
        return [o.data for o in outs]


def _turns(maps) -> np.ndarray:
    from map2map.maps.vectorize import dominant_angle, wall_points

    out = []
    for m in maps:
        walls = m == 0
        t, w = piece_turns(walls, dominant_angle(wall_points(walls)))
        out.append(np.abs(t[w > 0]))
    return np.concatenate(out) if out else np.zeros(0)


def _oracle_maps(ds: str, n: int) -> tuple[list, list]:
    """(rbpf, oracle) 256 px maps of the first ``n`` pairs of dataset ``ds``."""
    from map2map.datasets.pair import crop_box, preprocess_pair, read_pair_meta
    from map2map.datasets.pairfolder import PLAN_YAML, SLAM_YAML, pair_dir
    from map2map.maps.formats import load_map
    from map2map.sim.runner import simulate

    rbpf, oracle = [], []
    for i in range(n):
        folder = pair_dir(ds, i)
        meta = read_pair_meta(folder)
        a, b = load_map(folder / PLAN_YAML), load_map(folder / SLAM_YAML)
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            r = simulate(a, seed=meta["sim_seed"], duration=meta["simulated_seconds"],
                         mapper="oracle", progress=False)
        box = crop_box(a, b)
        rbpf.append(preprocess_pair(a, b, 256, 0, box)[1])
        oracle.append(preprocess_pair(a, r.slam_map_plan, 256, 0, box)[1])
    return rbpf, oracle


def main(argv=None) -> int:
    from map2map.datasets.packed import PackedPairs
    from map2map.experiments.table53.__main__ import _covered
    from map2map.experiments.table53.measure import heldout_pairs_from_dataset, run_table53

    ap = argparse.ArgumentParser(prog="python -m map2map.experiments.table53.unturn",
                                 description=__doc__.split("\n\n")[0])
    ap.add_argument("--data", required=True, help="a 'map2map dataset build' folder")
    ap.add_argument("--split", nargs="+", default=["train", "val", "test"])
    ap.add_argument("--n", type=int, default=100, help="at most this many pairs (default 100)")
    ap.add_argument("--min-coverage", type=float, default=0.8)
    ap.add_argument("--oracle", type=int, default=0, metavar="N",
                    help="also the turns of the first N plans mapped at the true poses")
    a = ap.parse_args(argv)
    pairs = _covered(heldout_pairs_from_dataset(a.data, tuple(a.split), None, keep=()),
                     a.data, a.min_coverage)
    k = min(a.n, len(pairs.a))
    pairs = PackedPairs(pairs.a[:k], pairs.b[:k], pairs.plan_id[:k], pairs.split[:k],
                        pairs.meta)
    q = (50, 75, 90)
    print(f"turn of straight wall pieces (deg), percentiles {q}:")
    print(f"  rbpf maps ({k} pairs)        {np.percentile(_turns(pairs.b), q).round(2)}")
    if a.oracle > 0:
        rbpf, oracle = _oracle_maps(a.data, a.oracle)
        print(f"  first {a.oracle} plans, rbpf       {np.percentile(_turns(rbpf), q).round(2)}")
        print(f"  same, at the true poses   {np.percentile(_turns(oracle), q).round(2)}")
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        t = run_table53(pairs, ["none", Unturn(), UnturnNone()], progress=False)
    print(f"\nTable 5.3 on {k} maps: input {t.summary['median_error_sim']:.3f} / "
          f"{t.summary['median_error_sim_all']:.3f} px (matched / every point)")
    for r in t.models:
        s = r.summary
        print(f"  {r.name:12s} improved {s['improved']}/{s['n']}, median Error "
              f"{s['median_error_gen']:.3f} / {s['median_error_gen_all']:.3f} px, "
              f"wall recall {s['median_gen_wall_recall']:.2f}")
    ts = t.tests
    for who in ("none", "unturn"):
        v = ts["vs"][who]
        print(f"  unturn+none against {who}: matched better {v['matched']['better']}, worse "
              f"{v['matched']['worse']} (p {v['matched']['p']:.2g}); every point better "
              f"{v['all']['better']}, worse {v['all']['worse']}")
    v = ts["vs_input"]
    print(f"  unturn+none against the input: better {v['better']}, worse {v['worse']}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
