"""Checks every job makes before any work (parameter names, not command-line flags)."""

from __future__ import annotations

import os
from pathlib import Path

from ..core.errors import InputError

__all__ = ["check_seed", "check_positive", "final_paths"]


def check_seed(seed: int, name: str = "seed") -> int:
    """Refuse a seed numpy cannot take (negative, or 128 bits and more) with one line.

    Examples
    --------
    >>> check_seed(3)
    3
    >>> check_seed(-1)
    Traceback (most recent call last):
    ...
    map2map.core.errors.InputError: seed: seed must be a non-negative integer, got -1
    """
    if not 0 <= int(seed) < 2**128:
        raise InputError(name, f"seed must be a non-negative integer, got {seed}")
    return int(seed)


def check_positive(value: float | None, name: str) -> None:
    """Refuse a given (not ``None``) value that is not a positive number.

    >>> check_positive(0.05, "resolution"); check_positive(None, "resolution")
    """
    if value is not None and not value > 0:
        raise InputError(name, f"must be > 0, got {value:g}")


def final_paths(written: dict[str, Path], tmp: Path, final: str | os.PathLike) -> dict[str, Path]:
    """The paths of files written under temporary folder ``tmp`` once it is ``final``.

    >>> final_paths({"a": Path("/t/.x.tmp-1/a.txt")}, Path("/t/.x.tmp-1"), "/t/x")
    {'a': PosixPath('/t/x/a.txt')}
    """
    return {k: Path(final) / Path(p).relative_to(tmp) for k, p in written.items()}
