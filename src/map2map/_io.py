"""Moved to :mod:`map2map.core._io`; this name stays importable for existing code.

>>> import map2map.core._io, map2map._io
>>> map2map._io.atomic_path is map2map.core._io.atomic_path
True
"""

from .core._io import *  # noqa: F403
from .core._io import __all__  # noqa: F401
