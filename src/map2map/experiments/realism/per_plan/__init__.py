"""Realism per plan (issue #33): ranks among simulated runs, a classifier two-sample test
and the diversity of K hypotheses; ``python -m map2map.experiments.realism.per_plan``.
``results.json`` beside this file is its last full run (``--json``) of the shipped
Model_AB, ``results_scans.json`` that of ``synthesize --model scans``; ``map2map
reproduce`` quotes both."""

import argparse
from pathlib import Path

#: The last full run's ``--json`` report (with ``date`` and ``command`` added).
RESULTS = Path(__file__).with_name("results.json")
#: The same for ``synthesize --model scans``.
RESULTS_SCANS = Path(__file__).with_name("results_scans.json")
#: ``per_plan``'s classifier: trained to convergence (early stopping after this many
#: checks without a lower held-out loss, at most this many steps a fold). At a fixed
#: 600 steps (the default until 2026-11-27) it was far from converged and understated
#: every gap (docs/synthesize.md, "How long the classifier must train").
CONVERGED_PATIENCE, CONVERGED_STEPS = 5, 12000


def add_classifier_options(ap: argparse.ArgumentParser, steps: int, steps_help: str,
                           patience: int = 0) -> None:
    """``--classifier-steps`` (default ``steps``), ``--classifier-patience`` (default
    ``patience``) and ``--classifier-seeds``, as ``per_plan`` and ``per_plan.variants``
    take them; check them with :func:`check_classifier_options` after parsing."""
    ap.add_argument("--classifier-steps", type=int, default=steps, help=steps_help)
    ap.add_argument("--classifier-patience", type=int, default=patience, metavar="N",
                    help="train the classifier to convergence: stop each fold after N checks "
                    "(every 200 steps) without a lower loss on a quarter of its training "
                    "plans held out, --classifier-steps then the most (0: exactly "
                    f"--classifier-steps; default {patience})")
    ap.add_argument("--classifier-seeds", type=int, default=3,
                    help="classifier runs (seeds --seed, --seed + 1, ...); the AUC is their "
                    "mean, with their standard deviation (default 3: one seed's AUC moves "
                    "by a few hundredths)")


def check_classifier_options(ap: argparse.ArgumentParser, args: argparse.Namespace) -> None:
    if args.classifier_seeds < 1:
        ap.error("--classifier-seeds must be >= 1")
    if args.classifier_patience < 0:
        ap.error("--classifier-patience must be >= 0")


def classifier_auc(args: argparse.Namespace, plans, a, b):
    """:func:`~map2map.learn.two_sample.repeated_auc` of ``b`` against ``a`` with the
    options of :func:`add_classifier_options` (seeds ``--seed``, ``--seed + 1``, ...)."""
    from map2map.learn.two_sample import repeated_auc

    seeds = [args.seed + k for k in range(args.classifier_seeds)]
    return repeated_auc(plans, a, b, seeds, steps=args.classifier_steps,
                        patience=args.classifier_patience)


def plan_hypotheses(item) -> tuple[int, list]:
    """``synthesize``'s hypotheses of pair ``i``'s plan, cut to the pair's square (one of
    ``per_plan``'s tasks, run in a worker process for ``--model scans``).

    ``item = (ds, i, model, seed, size, samples, start, runs)``: the plan (``A.yaml``, its
    own resolution) is synthesized with ``samples`` hypotheses and seed ``seed + i`` once
    per keyword set in ``runs`` (e.g. ``[{}]``, or the network's dropout alone as well);
    with ``model="scans"``, ``start == "pair"`` starts each at the pair's start pose
    (``meta.json``), ``"own"`` where its seed draws one (a network's exploration for its
    coverage always draws its own). Returns ``(i, [(samples, size, size) uint8 per run])``.
    """
    import warnings

    import numpy as np

    from map2map.datasets.pair import crop_box, preprocess_pair, read_pair_meta
    from map2map.datasets.pairfolder import PLAN_YAML, SLAM_YAML, pair_dir
    from map2map.learn.ab.synthesize import synthesize
    from map2map.maps.formats import load_map

    ds, i, model, seed, size, samples, start, runs = item
    folder = pair_dir(ds, i)
    a, b = load_map(folder / PLAN_YAML), load_map(folder / SLAM_YAML)
    box = crop_box(a, b)
    pair = start == "pair" and isinstance(model, str)   # a network's coverage: its own
    at = {"start": tuple(read_pair_meta(folder)["start_pose"])} if pair else {}
    got = []
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        for kw in runs:
            res = synthesize(a, model, samples=samples, seed=seed + i, **at, **kw)
            got.append(np.stack([preprocess_pair(a, h, size, 0, box)[1] for h in res.maps]))
    return i, got
