"""table53 error sources: the script is ``__main__`` (``python3 -m
map2map.experiments.table53.error_sources --help``)."""
