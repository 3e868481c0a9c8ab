"""Realism per plan (issue #33): ranks among simulated runs, a classifier two-sample test
and the diversity of K hypotheses; ``python -m map2map.experiments.realism.per_plan``."""
