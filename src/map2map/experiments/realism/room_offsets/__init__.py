"""room offsets: the script is ``__main__`` (``python3 -m
map2map.experiments.realism.room_offsets --help``)."""
