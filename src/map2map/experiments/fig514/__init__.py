"""Thesis Fig. 5.14: a simulated SLAM map, the parametric model's and Model_AB's of the
same plans, with the appendix-metric error and wall recall of each
(:mod:`~map2map.experiments.fig514.measure`); the script is
``python -m map2map.experiments.fig514``; README.md has the current result."""
