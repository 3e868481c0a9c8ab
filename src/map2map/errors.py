"""Moved to :mod:`map2map.core.errors`; this name stays importable for existing code.

>>> import map2map.core.errors, map2map.errors
>>> map2map.errors.InputError is map2map.core.errors.InputError
True
"""

from .core.errors import EXIT_BAD_INPUT, InputError, MapWarning, warnings_unless_error

__all__ = ["EXIT_BAD_INPUT", "InputError", "MapWarning", "warnings_unless_error"]
