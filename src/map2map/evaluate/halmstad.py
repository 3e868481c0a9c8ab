"""Moved to :mod:`map2map.maps.halmstad`; the old path stays importable.

>>> import map2map.evaluate.halmstad as old, map2map.maps.halmstad as new
>>> old.__all__ == new.__all__
True
"""

from ..maps.halmstad import *  # noqa: F403
from ..maps.halmstad import __all__  # noqa: F401
