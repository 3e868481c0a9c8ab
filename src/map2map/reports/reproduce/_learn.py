"""Shared by the two learning sections: is the ``learn`` extra (torch) installed?

torch itself is imported only by :mod:`map2map.learn` (tests/test_architecture.py).

Examples
--------
>>> need_torch() is None or True      # raises Skipped without torch
True
"""

from __future__ import annotations

from importlib.util import find_spec

from ._base import Skipped


def need_torch() -> None:
    """Raise :class:`Skipped` when torch (``pip install -e '.[learn]'``) is missing."""
    if find_spec("torch") is None:
        raise Skipped("needs the learn extra (torch): pip install -e '.[learn]'")
