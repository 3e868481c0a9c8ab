"""Shared by the two learning sections: is the ``learn`` extra (torch) installed?"""

from __future__ import annotations

from ._base import Skipped


def need_torch() -> None:
    """Raise :class:`Skipped` when torch (``pip install -e '.[learn]'``) is missing."""
    try:
        import torch  # noqa: F401
    except ImportError:
        raise Skipped("needs the learn extra (torch): pip install -e '.[learn]'") from None
    import torch as _t

    _t.set_num_threads(1)
