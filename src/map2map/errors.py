"""Moved to :mod:`map2map.core.errors`; this name stays importable for existing code."""

from .core.errors import EXIT_BAD_INPUT, InputError

__all__ = ["EXIT_BAD_INPUT", "InputError"]
