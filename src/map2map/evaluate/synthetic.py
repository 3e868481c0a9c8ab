"""Moved to :mod:`map2map.maps.synthetic`; the old path stays importable.

>>> import map2map.evaluate.synthetic as old, map2map.maps.synthetic as new
>>> old.__all__ == new.__all__
True
"""

from ..maps.synthetic import *  # noqa: F403
from ..maps.synthetic import __all__  # noqa: F401
