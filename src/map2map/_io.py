"""Moved to :mod:`map2map.core._io`; this name stays importable for existing code."""

from .core._io import *  # noqa: F403
from .core._io import __all__  # noqa: F401
