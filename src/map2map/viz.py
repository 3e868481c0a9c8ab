"""Moved to :mod:`map2map.core.viz`; this name stays importable for existing code.

>>> import map2map.core.viz, map2map.viz
>>> map2map.viz.draw_map is map2map.core.viz.draw_map
True
"""

from .core.viz import *  # noqa: F403
from .core.viz import __all__  # noqa: F401
