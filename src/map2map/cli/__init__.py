"""The ``map2map`` command line: thin argument parsing over the library."""
