"""Registry of mapping backends selectable by name (``map2map simulate --mapper NAME``).

Each entry maps a name to a factory called as ``factory(resolution=..., seed=...,
**options)`` that returns an object implementing :class:`map2map.robotlog.base.Mapper`.
This module holds only the registry: it imports no backend. The backends live above it
(the oracle in :mod:`map2map.sim`, the particle filter and graph SLAM in
:mod:`map2map.slam`), so they are registered from above, by the package root
(``map2map/__init__.py``, which Python runs before any of its modules), with factories
that import their backend only when the mapper is made. Other backends add themselves
with :func:`register_mapper`.

Examples
--------
>>> m = make_mapper("oracle", resolution=0.05, seed=0)
>>> m.name
'oracle'
>>> "oracle" in available_mappers()
True
"""

from __future__ import annotations

from collections.abc import Callable

from ..core.errors import InputError
from .base import Mapper

__all__ = ["MAPPERS", "make_mapper", "register_mapper", "available_mappers"]

#: name -> factory; the package root registers the oracle, the GMapping-style particle
#: filter and graph SLAM (``oracle``, ``rbpf``, ``graph``).
MAPPERS: dict[str, Callable[..., Mapper]] = {}


def register_mapper(name: str, factory: Callable[..., Mapper]) -> None:
    """Add or replace a backend.

    Parameters
    ----------
    name : str
        Name given to :func:`make_mapper` (and ``--mapper``).
    factory : callable
        Called with ``resolution=``, ``seed=`` and the backend's options; returns a Mapper.

    Raises
    ------
    TypeError
        ``factory`` is not callable (a backend is no longer named by a string).

    Examples
    --------
    >>> register_mapper("oracle2", MAPPERS["oracle"])
    >>> "oracle2" in available_mappers()
    True
    >>> del MAPPERS["oracle2"]
    """
    if not callable(factory):
        raise TypeError(f"mapper factory for {name!r} must be callable, got {factory!r}")
    MAPPERS[name] = factory


def available_mappers() -> list[str]:
    """Names of the registered backends, sorted.

    Returns
    -------
    list of str

    Examples
    --------
    >>> available_mappers()[:3]
    ['graph', 'oracle', 'rbpf']
    """
    return sorted(MAPPERS)


def make_mapper(name: str, *, resolution: float = 0.05, seed: int = 0, **options) -> Mapper:
    """Instantiate the backend registered as ``name``.

    Parameters
    ----------
    name : str
        A registered name (:func:`available_mappers`).
    resolution : float
        Metres per cell of the map the backend builds.
    seed : int
        Seed of the backend's random steps.
    **options
        Passed to the backend's factory.

    Returns
    -------
    Mapper

    Raises
    ------
    InputError
        Unknown name.

    Examples
    --------
    >>> make_mapper("oracle", resolution=0.1).name
    'oracle'
    """
    if name not in MAPPERS:
        choices = ", ".join(available_mappers())
        raise InputError("mapper", f"unknown mapper '{name}' (choose from {choices})")
    return MAPPERS[name](resolution=resolution, seed=seed, **options)
