"""drift tune: the script is ``__main__`` (``python3 -m
map2map.experiments.realism.drift_tune --help``)."""
