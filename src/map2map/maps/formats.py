"""One entry point for every map format: :func:`load_map` and :func:`save_map`.

========================  ====================================  =========================
suffix                    format                                module
========================  ====================================  =========================
``.yaml``, ``.yml``       ROS map_server / Nav2 (yaml + image)  :mod:`map2map.maps.ros`
``.png`` ``.pgm`` ...     plain picture                         :mod:`map2map.maps.image`
``.json``                 HouseExpo floor plan                  :mod:`map2map.maps.houseexpo`
``.dxf``                  CAD floor plan                        :mod:`map2map.maps.dxf`
========================  ====================================  =========================

:func:`save_map` writes ROS maps (``.yaml``: the yaml plus a ``.pgm`` of the same
stem beside it), pictures (``.png``, ``.pgm``) and CAD drawings of the walls
(``.dxf``). Options that do not apply to
the input's format are refused rather than silently ignored.

Examples
--------
>>> import numpy as np, tempfile, pathlib
>>> from map2map.core.grid import OccupancyMap
>>> folder = pathlib.Path(tempfile.mkdtemp())
>>> m = OccupancyMap(np.array([[0, 127], [255, 255]], np.uint8), 0.05)
>>> save_map(m, folder / "map.yaml")
>>> sorted(p.name for p in folder.iterdir())
['map.pgm', 'map.yaml']
>>> load_map(folder / "map.yaml") == m
True
"""

from __future__ import annotations

import os
from collections.abc import Iterable
from pathlib import Path

from ..core.errors import InputError
from ..core.grid import OccupancyMap
from .raster import IMAGE_SUFFIXES

__all__ = ["load_map", "save_map", "map_kind", "READ_SUFFIXES", "WRITE_SUFFIXES"]

_KINDS = {".yaml": "ros", ".yml": "ros", ".json": "houseexpo", ".dxf": "dxf"}
_KINDS.update({s: "image" for s in IMAGE_SUFFIXES})
#: Suffixes :func:`load_map` reads.
READ_SUFFIXES = tuple(_KINDS)
#: Suffixes :func:`save_map` writes.
WRITE_SUFFIXES = (".yaml", ".yml", ".png", ".pgm", ".dxf")

_OPTION_KINDS = {
    "resolution": ("image", "houseexpo", "dxf"),
    "occupied_thresh": ("ros", "image"),
    "free_thresh": ("ros", "image"),
    "negate": ("ros", "image"),
    "mode": ("ros",),
    "layers": ("dxf",),
    "wall_thickness": ("dxf",),
    "units": ("dxf",),
}
_NAMES = {"ros": "ROS map yaml", "image": "picture", "houseexpo": "HouseExpo JSON", "dxf": "DXF"}


def map_kind(path: str | os.PathLike) -> str:
    """``"ros"``, ``"image"``, ``"houseexpo"`` or ``"dxf"`` from the file's suffix."""
    p = Path(path)
    kind = _KINDS.get(p.suffix.lower())
    if kind is None:
        known = " ".join(sorted(set(READ_SUFFIXES)))
        raise InputError(p, f"unknown map format {p.suffix or '(no suffix)'!r} (known: {known})")
    return kind


def load_map(
    path: str | os.PathLike,
    *,
    resolution: float | None = None,
    occupied_thresh: float | None = None,
    free_thresh: float | None = None,
    negate: bool | None = None,
    mode: str | None = None,
    layers: Iterable[str] | None = None,
    wall_thickness: float | None = None,
    units: str | None = None,
) -> OccupancyMap:
    """Load any supported map file as an :class:`~map2map.core.grid.OccupancyMap`.

    Parameters
    ----------
    path : path-like
        The file; its suffix selects the format (table in the module docstring).
    resolution : float, optional
        Metres per pixel for pictures (default: stored in the file, else 0.05),
        HouseExpo plans and DXF drawings (default 0.05). A ROS map has its own.
    occupied_thresh, free_thresh, negate : optional
        map_server thresholds for ROS maps (overriding the yaml) and pictures.
    mode : {"trinary", "scale", "raw"}, optional
        Overrides a ROS yaml's mode.
    layers, wall_thickness, units : optional
        DXF options (see :func:`map2map.maps.dxf.load_dxf`).

    Raises
    ------
    InputError
        Missing or unreadable file, unknown suffix, options that do not apply to
        the format, or any problem the format's loader reports.
    """
    p = Path(path)
    kind = map_kind(p)
    if not p.exists():
        raise InputError(p, "file not found")
    given = {
        "resolution": resolution,
        "occupied_thresh": occupied_thresh,
        "free_thresh": free_thresh,
        "negate": negate,
        "mode": mode,
        "layers": layers,
        "wall_thickness": wall_thickness,
        "units": units,
    }
    for name, value in given.items():
        if value is not None and kind not in _OPTION_KINDS[name]:
            flag = "--" + name.replace("_", "-")
            raise InputError(p, f"{flag} does not apply to a {_NAMES[kind]}")
    if kind == "ros":
        from .ros import load_ros_map

        return load_ros_map(
            p, mode=mode, negate=negate, occupied_thresh=occupied_thresh, free_thresh=free_thresh
        )
    if kind == "image":
        from .image import load_image_map

        return load_image_map(
            p,
            resolution=resolution,
            occupied_thresh=occupied_thresh,
            free_thresh=free_thresh,
            negate=negate,
        )
    if kind == "houseexpo":
        from .houseexpo import DEFAULT_RESOLUTION, load_houseexpo

        return load_houseexpo(
            p, resolution=DEFAULT_RESOLUTION if resolution is None else resolution
        )
    from .dxf import DEFAULT_WALL_THICKNESS, load_dxf

    return load_dxf(
        p,
        resolution=resolution,
        wall_thickness=DEFAULT_WALL_THICKNESS if wall_thickness is None else wall_thickness,
        layers=layers,
        units=units,
    )


def check_output_path(path: str | os.PathLike, suffixes: Iterable[str] = WRITE_SUFFIXES) -> Path:
    """Check, without writing anything, that ``path`` can be written as a map.

    The suffix must be one of ``suffixes`` and the nearest existing folder above
    ``path`` must be a writable directory. Raises :class:`InputError` otherwise.
    """
    p = Path(path)
    suffixes = tuple(suffixes)
    if p.suffix.lower() not in suffixes:
        raise InputError(
            p, f"cannot write {p.suffix or 'a file without suffix'!r}; use {', '.join(suffixes)}"
        )
    if p.is_dir():
        raise InputError(p, "is a directory; give a file name")
    folder = p.parent if str(p.parent) else Path(".")
    probe = folder
    while not probe.exists():
        if probe.parent == probe:
            break
        probe = probe.parent
    if not probe.is_dir():
        raise InputError(folder, f"output directory cannot be created ({probe} is not a directory)")
    if not os.access(probe, os.W_OK | os.X_OK):
        raise InputError(probe, "output directory is not writable")
    return p


def save_map(m: OccupancyMap, path: str | os.PathLike) -> None:
    """Write a map: ``.yaml``/``.yml`` as a ROS map (plus ``.pgm``), ``.png``/``.pgm`` as a
    picture, ``.dxf`` as a CAD drawing of the walls (:func:`map2map.maps.dxf.save_dxf`).

    Every file is written atomically; on error nothing is left half-written.
    """
    p = check_output_path(path)
    if p.suffix.lower() in (".yaml", ".yml"):
        from .ros import save_ros_map

        save_ros_map(m, p)
        return
    if p.suffix.lower() == ".dxf":
        from .dxf import save_dxf

        save_dxf(m, p)
        return
    from .image import save_image_map

    save_image_map(m, p)
