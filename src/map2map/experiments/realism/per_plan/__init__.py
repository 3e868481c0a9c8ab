"""Realism per plan (issue #33): ranks among simulated runs, a classifier two-sample test
and the diversity of K hypotheses; ``python -m map2map.experiments.realism.per_plan``.
``results.json`` beside this file is its last full run (``--json``) of the shipped
Model_AB, ``results_scans.json`` that of ``synthesize --model scans``; ``map2map
reproduce`` quotes both."""

from pathlib import Path

#: The last full run's ``--json`` report (with ``date`` and ``command`` added).
RESULTS = Path(__file__).with_name("results.json")
#: The same for ``synthesize --model scans``.
RESULTS_SCANS = Path(__file__).with_name("results_scans.json")
