"""Table 5.3 on real maps: Model_BA on the Halmstad sensor maps against their floor
plans (:mod:`~map2map.experiments.table53_real.measure`); the scripts are
``python -m map2map.experiments.table53_real`` and ``.autocorrect_real`` (auto-correct
the real maps and draw them); README.md has the current result."""
