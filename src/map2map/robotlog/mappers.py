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
    """Add or replace a backend (a ``"module:attr"`` string or a callable)."""
    MAPPERS[name] = factory


def available_mappers() -> list[str]:
    return sorted(MAPPERS)


def make_mapper(name: str, *, resolution: float = 0.05, seed: int = 0, **options) -> Mapper:
    """Instantiate the backend registered as ``name``."""
    if name not in MAPPERS:
        choices = ", ".join(available_mappers())
        raise InputError("mapper", f"unknown mapper '{name}' (choose from {choices})")
    factory = MAPPERS[name]
    if isinstance(factory, str):
        module, _, attr = factory.partition(":")
        factory = getattr(importlib.import_module(module), attr)
    return factory(resolution=resolution, seed=seed, **options)
