"""Thesis Table 5.3 / Fig. 5.12: does Model_BA bring simulated SLAM maps closer to their
plans? The library is :mod:`~map2map.experiments.table53.measure`; the scripts are
``python -m map2map.experiments.table53`` (the table), ``.error_sources`` (where the
error comes from) and ``.face_offsets`` (wall-face offsets); README.md has the current
result."""
