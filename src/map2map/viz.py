"""Moved to :mod:`map2map.core.viz`; this name stays importable for existing code."""

from .core.viz import *  # noqa: F403
from .core.viz import __all__  # noqa: F401
