"""map2map: move robot maps between CAD floor plans and SLAM occupancy maps.

The public API re-exports the library functions behind every command line tool.
The map functions load at once; the heavier stages (numba kernels, matplotlib) load
on first use, so ``import map2map`` stays quick.

Examples
--------
>>> import map2map
>>> plan = map2map.generate_floorplan(3, kind="apartment")
>>> plan.resolution
0.05
>>> callable(map2map.simulate) and callable(map2map.deform)
True
"""

import importlib

from ._version import __version__
from .core.errors import InputError
from .maps import (
    FREE,
    OCCUPIED,
    UNKNOWN,
    OccupancyMap,
    crop_to_content,
    generate_floorplan,
    harmonise,
    load_map,
    preprocess,
    save_map,
    save_map_figure,
    square_resize,
    ternarize,
    thicken,
)
from .robotlog.mappers import register_mapper as _register_mapper

#: Stage entry points loaded on first use: name -> module.
_LAZY = {
    "run_demo": "map2map.demo",
    "deform": "map2map.parametric.pipeline",
    "run_deform": "map2map.jobs.deform",
    "simulate": "map2map.sim.runner",
    "save_run": "map2map.jobs.simulate",
    "run_slam": "map2map.slam.offline",
    "evaluate_maps": "map2map.evaluate.pipeline",
    "run_align": "map2map.jobs.evaluate",
    "run_evaluate": "map2map.jobs.evaluate",
    "autocorrect": "map2map.learn.ba.autocorrect",
    "train_ba": "map2map.learn.ba.train",
}

__all__ = [
    "__version__",
    "InputError",
    "FREE",
    "OCCUPIED",
    "UNKNOWN",
    "OccupancyMap",
    "ternarize",
    "load_map",
    "save_map",
    "save_map_figure",
    "generate_floorplan",
    "square_resize",
    "harmonise",
    "thicken",
    "crop_to_content",
    "preprocess",
    *_LAZY,
]


# The mapping backends by name (robotlog.mappers holds only the registry; sim and slam,
# above it, must not import each other, so the root wires them). Each factory imports its
# backend (numba kernels) on first use.
def _oracle(**kw):
    """The simulator's oracle mapper (:class:`map2map.sim.mapping.OracleMapper`)."""
    from .sim.mapping import OracleMapper

    return OracleMapper(**kw)


def _rbpf(**kw):
    """The GMapping-style particle filter (:func:`map2map.slam.rbpf.make_rbpf`)."""
    from .slam.rbpf import make_rbpf

    return make_rbpf(**kw)


def _graph(**kw):
    """Karto-style graph SLAM (:func:`map2map.slam.graph.make_graph`)."""
    from .slam.graph import make_graph

    return make_graph(**kw)


_register_mapper("oracle", _oracle)
_register_mapper("rbpf", _rbpf)
_register_mapper("graph", _graph)


def __getattr__(name: str):
    """Load a stage's entry point on first use (PEP 562)."""
    if name in _LAZY:
        return getattr(importlib.import_module(_LAZY[name]), name)
    raise AttributeError(f"module 'map2map' has no attribute {name!r}")


def __dir__() -> list[str]:
    return sorted(set(globals()) | set(_LAZY))
