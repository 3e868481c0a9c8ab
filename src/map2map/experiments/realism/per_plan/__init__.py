"""Realism per plan (issue #33): ranks among simulated runs, a classifier two-sample test
and the diversity of K hypotheses; ``python -m map2map.experiments.realism.per_plan``.
``results.json`` beside this file is its last full run (``--json``), which ``map2map
reproduce`` quotes."""

from pathlib import Path

#: The last full run's ``--json`` report (with ``date`` and ``command`` added).
RESULTS = Path(__file__).with_name("results.json")
