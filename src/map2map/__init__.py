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


def __getattr__(name: str):
    """Load a stage's entry point on first use (PEP 562)."""
    if name in _LAZY:
        return getattr(importlib.import_module(_LAZY[name]), name)
    raise AttributeError(f"module 'map2map' has no attribute {name!r}")


def __dir__() -> list[str]:
    return sorted(set(globals()) | set(_LAZY))
