"""autocorrect real: the script is ``__main__`` (``python3 -m
map2map.experiments.table53_real.autocorrect_real --help``)."""
