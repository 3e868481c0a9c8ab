"""Table 5.3 on REAL maps: does auto-correct bring the Halmstad sensor maps closer to their
floor plans? (issue #14; library: :mod:`map2map.experiments.table53_real.measure`.)

Usage::

    OMP_NUM_THREADS=1 python3 -m map2map.experiments.table53_real --out OUT [--data ../shared/data]
        [--maps E5_01,HIH_01] [--model pretrained] [--no-anchor] [--seed 0]
        [--figures docs/] [--ac thickness=input --ac large=tile ...]

For each of the 18 sensor maps (E5: 14 office maps, HIH: 4 apartment maps) and its
layout: the appendix metric of the map and of its auto-corrected version against the
layout, whether the metric's alignment landed the annotated keypoints, the wall guards
against the layout placed by the ground-truth similarity, and the summary (improved /
worse among the maps whose alignments are good, sign test). Writes ``OUT/table53_real.csv``,
``OUT/table53_real.txt``, the box plot ``OUT/learn_real_table53_box.png`` and the overlays
``OUT/learn_real_table53_overlays.png`` (``--figures DIR`` writes the two PNGs there instead).

Run time: 5 min for the 18 maps (293-331 s over two runs; auto-correct 14-15 s, the rest
the metric run four times per map), 1.1 GB peak memory, one process, OMP_NUM_THREADS=1,
on the shared 2-core machine under load (2026-11-25). Results: docs/autocorrect.md, "Table 5.3
on real maps".
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

from map2map.experiments._data import shared_data
from map2map.experiments.table53.measure import ac_options
from map2map.experiments.table53_real.measure import run_table53_real

SHARED = shared_data()


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--out", default="table53_real_out")
    ap.add_argument("--data", default=str(SHARED))
    ap.add_argument("--maps", default="", help="comma-separated sensor maps (default: all)")
    ap.add_argument("--model", default="pretrained",
                    help="pretrained (the thesis's Model_BA, the default here), or a name of "
                         "map2map autocorrect's registry as that command runs it: none (its "
                         "default, drawn like a plan), thesis")
    ap.add_argument("--no-anchor", action="store_true", help="auto-correct with anchor=False")
    ap.add_argument("--no-draw", action="store_true",
                    help="with --model none or thesis: not through the plan drawer "
                         "(map2map autocorrect --no-draw)")
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--figures", default=None, help="folder of the two PNGs (default: OUT)")
    ap.add_argument("--overlay-maps", default="",
                    help="maps of the overlay figure (default: HIH_01, the best and the "
                         "worst counted E5 map)")
    ap.add_argument("--ac", action="append", default=[], metavar="KEY=VALUE",
                    help="an option of autocorrect (repeatable), e.g. thickness=resolution, "
                         "open_frontiers=true")
    ap.add_argument("--draw-option", action="append", default=[], metavar="KEY=VALUE",
                    help="with --model none or thesis, drawn: a tolerance of the plan "
                         "drawer (repeatable; map2map autocorrect --draw-option)")
    args = ap.parse_args(argv)
    root = Path(args.data) / "halmstad"
    if not root.is_dir():
        print(f"no Halmstad data at {root}; nothing to do")
        return 0
    names = [n for n in args.maps.split(",") if n] or None
    model = args.model
    if model in ("none", "thesis"):
        from map2map.jobs.autocorrect import corrector, parse_draw_options

        model = corrector(model, draw=False if args.no_draw else None,
                          draw_options=parse_draw_options(args.draw_option))
    t = run_table53_real(root, names, model, seed=args.seed, anchor=not args.no_anchor,
                         autocorrect_kw=ac_options(args.ac))
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    text = t.format()
    print(text)
    (out / "table53_real.txt").write_text(text + "\n")
    t.to_csv(out / "table53_real.csv")
    figs = Path(args.figures) if args.figures else out
    figs.mkdir(parents=True, exist_ok=True)
    t.figure(figs / "learn_real_table53_box.png")
    picks = [n for n in args.overlay_maps.split(",") if n]
    if not picks:
        e5 = [r for r in t.rows if r["counted"] and r["map"].startswith("E5")]
        e5.sort(key=lambda r: r["diff"])
        picks = [r["map"] for r in t.rows if r["map"].startswith("HIH")][:1]
        picks += [r["map"] for r in (e5[-1:] + e5[:1]) if r["map"] not in picks]
    t.overlay_figure(picks, figs / "learn_real_table53_overlays.png")
    print(f"written: {out / 'table53_real.csv'}, figures in {figs} ({', '.join(picks)})")
    return 0


if __name__ == "__main__":
    sys.exit(main())
