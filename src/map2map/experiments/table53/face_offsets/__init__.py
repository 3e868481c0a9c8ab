"""table53 face offsets: the script is ``__main__`` (``python3 -m
map2map.experiments.table53.face_offsets --help``)."""
