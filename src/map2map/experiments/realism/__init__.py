"""Realism of Model_AB's synthesized SLAM maps against simulated runs of the same plans
(:mod:`~map2map.experiments.realism.measure`); the scripts are
``python -m map2map.experiments.realism`` (the table, the third run's floor, the perfect
generator's null draws), ``.drift_tune`` and ``.room_offsets`` (fitting the drift);
README.md has the current result."""
