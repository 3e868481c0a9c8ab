"""Registry of mapping backends selectable by name (``map2map simulate --mapper NAME``).

Each entry maps a name to ``"module:attribute"``, a factory called as
``factory(resolution=..., seed=..., **options)`` that returns an object
implementing :class:`map2map.robotlog.base.Mapper`. Modules are imported only when
the mapper is used. A backend adds itself with one line in :data:`MAPPERS` (or at
run time with :func:`register_mapper`).

Examples
--------
>>> m = make_mapper("oracle", resolution=0.05, seed=0)
>>> m.name
'oracle'
>>> "oracle" in available_mappers()
True
"""

from __future__ import annotations

import importlib
from collections.abc import Callable

from ..core.errors import InputError
from .base import Mapper

__all__ = ["MAPPERS", "make_mapper", "register_mapper", "available_mappers"]

#: name -> "module:factory": the oracle, the GMapping-style particle filter, graph SLAM.
MAPPERS: dict[str, str | Callable[..., Mapper]] = {
    "oracle": "map2map.sim.mapping:OracleMapper",
    "rbpf": "map2map.slam.rbpf:make_rbpf",
    "graph": "map2map.slam.graph:make_graph",
}


def register_mapper(name: str, factory: str | Callable[..., Mapper]) -> None:
    """Add or replace a backend (a ``"module:attr"`` string or a callable).

    Parameters
    ----------
    name : str
        Name given to :func:`make_mapper` (and ``--mapper``).
    factory : str or callable
        ``"module:attr"`` imported on first use, or a callable taking
        ``resolution=``, ``seed=`` and the backend's options and returning a Mapper.

    Examples
    --------
    >>> register_mapper("oracle2", "map2map.sim.mapping:OracleMapper")
    >>> "oracle2" in available_mappers()
    True
    >>> del MAPPERS["oracle2"]
    """
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
    factory = MAPPERS[name]
    if isinstance(factory, str):
        module, _, attr = factory.partition(":")
        factory = getattr(importlib.import_module(module), attr)
    return factory(resolution=resolution, seed=seed, **options)
