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
from dataclasses import dataclass, fields, replace
from pathlib import Path

from ..core.errors import InputError
from ..core.grid import OccupancyMap
from .raster import IMAGE_SUFFIXES

__all__ = [
    "MapReadOptions",
    "check_plausible",
    "load_map",
    "save_map",
    "map_kind",
    "READ_SUFFIXES",
    "WRITE_SUFFIXES",
]

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


@dataclass(frozen=True)
class MapReadOptions:
    """How to read a map file: every option :func:`load_map` takes, ``None`` = the default.

    One value of this class travels from the command line (``cli/_mapargs.py``) to
    every command that reads a map, so that they all read maps the same way -- a
    real map whose walls are grey (value 170) needs ``occupied_thresh`` below 0.33
    (or ``negate``) in ``align`` and ``evaluate`` as much as in ``convert``.

    Attributes
    ----------
    resolution : float, optional
        Metres per pixel (pictures, HouseExpo JSON, DXF).
    occupied_thresh, free_thresh : float, optional
        map_server thresholds (ROS yaml, pictures).
    negate : bool, optional
        White is occupied (ROS yaml, pictures).
    mode : str, optional
        ROS yaml mode override.
    layers : tuple of str, optional
        DXF layers to draw.
    wall_thickness : float, optional
        DXF wall thickness, metres.
    units : str, optional
        DXF drawing units.

    Examples
    --------
    >>> o = MapReadOptions(occupied_thresh=0.3, layers=("WALLS",))
    >>> o.given()
    ['occupied_thresh', 'layers']
    >>> o.applicable("image")
    MapReadOptions(resolution=None, occupied_thresh=0.3, free_thresh=None, negate=None, \
mode=None, layers=None, wall_thickness=None, units=None)
    """

    resolution: float | None = None
    occupied_thresh: float | None = None
    free_thresh: float | None = None
    negate: bool | None = None
    mode: str | None = None
    layers: tuple[str, ...] | None = None
    wall_thickness: float | None = None
    units: str | None = None

    def given(self) -> list[str]:
        """Names of the options set (not ``None``).

        Returns
        -------
        list of str
        """
        return [f.name for f in fields(self) if getattr(self, f.name) is not None]

    def to_args(self) -> list[str]:
        """The command-line flags that give these options (to repeat a run).

        Returns
        -------
        list of str

        Examples
        --------
        >>> MapReadOptions(negate=True, occupied_thresh=0.3, layers=("A", "B")).to_args()
        ['--occupied-thresh', '0.3', '--negate', '--layers', 'A,B']
        """
        out: list[str] = []
        for name in self.given():
            v = getattr(self, name)
            flag = "--" + name.replace("_", "-")
            if name == "units":
                flag = "--dxf-units"
            if isinstance(v, bool):
                out += [flag] if v else []
            elif isinstance(v, tuple):
                out += [flag, ",".join(v)]
            else:
                out += [flag, repr(v) if isinstance(v, float) else str(v)]
        return out

    def applicable(self, kind: str) -> MapReadOptions:
        """A copy without the options that do not apply to a ``kind`` file (see
        :func:`map_kind`), for commands reading several maps of different formats.

        Parameters
        ----------
        kind : str
            A :func:`map_kind` result.

        Returns
        -------
        MapReadOptions
        """
        drop = {n: None for n in self.given() if kind not in _OPTION_KINDS[n]}
        return replace(self, **drop)


def map_kind(path: str | os.PathLike) -> str:
    """``"ros"``, ``"image"``, ``"houseexpo"`` or ``"dxf"`` from the file's suffix.

    Parameters
    ----------
    path : path-like
        A map file name.

    Returns
    -------
    str

    Raises
    ------
    InputError
        Unknown suffix.

    Examples
    --------
    >>> map_kind("plan.YAML"), map_kind("floor.dxf")
    ('ros', 'dxf')
    """
    p = Path(path)
    kind = _KINDS.get(p.suffix.lower())
    if kind is None:
        known = " ".join(sorted(set(READ_SUFFIXES)))
        raise InputError(p, f"unknown map format {p.suffix or '(no suffix)'!r} (known: {known})")
    return kind


def load_map(
    path: str | os.PathLike,
    options: MapReadOptions | None = None,
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
    options : MapReadOptions, optional
        All the options below in one value (the command line's reading options);
        a keyword given as well overrides its field.
    resolution : float, optional
        Metres per pixel for pictures (default: stored in the file, else 0.05),
        HouseExpo plans and DXF drawings (default 0.05). A ROS map has its own.
    occupied_thresh, free_thresh, negate : optional
        map_server thresholds for ROS maps (overriding the yaml) and pictures.
    mode : {"trinary", "scale", "raw"}, optional
        Overrides a ROS yaml's mode.
    layers, wall_thickness, units : optional
        DXF options (see :func:`map2map.maps.dxf.load_dxf`).

    Returns
    -------
    OccupancyMap
        The map in the internal convention (occupied 0, free 255, unknown 127, ROS
        origin); ``meta`` says where it came from and what was assumed.

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
    if options is not None:
        given = {k: getattr(options, k) if v is None else v for k, v in given.items()}
    resolution, occupied_thresh, free_thresh, negate = (
        given["resolution"],
        given["occupied_thresh"],
        given["free_thresh"],
        given["negate"],
    )
    mode, layers, wall_thickness, units = (
        given["mode"],
        given["layers"],
        given["wall_thickness"],
        given["units"],
    )
    for name, value in given.items():
        if value is not None and kind not in _OPTION_KINDS[name]:
            flag = "--" + name.replace("_", "-")
            raise InputError(p, f"{flag} does not apply to a {_NAMES[kind]}")
    if kind == "ros":
        from .ros import load_ros_map

        m = load_ros_map(
            p, mode=mode, negate=negate, occupied_thresh=occupied_thresh, free_thresh=free_thresh
        )
    elif kind == "image":
        from .image import load_image_map

        m = load_image_map(
            p,
            resolution=resolution,
            occupied_thresh=occupied_thresh,
            free_thresh=free_thresh,
            negate=negate,
        )
    elif kind == "houseexpo":
        from .houseexpo import load_houseexpo

        m = load_houseexpo(p, resolution=resolution)
    else:
        from .dxf import DEFAULT_WALL_THICKNESS, load_dxf

        m = load_dxf(
            p,
            resolution=resolution,
            wall_thickness=DEFAULT_WALL_THICKNESS if wall_thickness is None else wall_thickness,
            layers=layers,
            units=units,
        )
    check_plausible(m, p)
    return m


#: A map less than this many metres on a side, or more than MAX_EXTENT_M across,
#: is flagged as implausible.
MIN_EXTENT_M = 1.0
MAX_EXTENT_M = 2000.0


def check_plausible(m: OccupancyMap, source=None) -> list[str]:
    """Flag a degenerate map: refuse an empty one, warn on an implausible one.

    Empty (nothing known: every pixel unknown) is an :class:`InputError`. A map
    with no free space, less than :data:`MIN_EXTENT_M` metres on a side, or more
    than :data:`MAX_EXTENT_M` metres across, gets a
    :class:`~map2map.core.errors.MapWarning` (one line, returned too): a DXF drawn in
    metres read as millimetres, a wrong ``--resolution``, or a picture read with
    the wrong thresholds all look like this.

    Parameters
    ----------
    m : OccupancyMap
        A map just read.
    source : path-like, optional
        Its file, named in the warning or error.

    Returns
    -------
    list of str
        The warnings issued (empty for a plausible map).

    Raises
    ------
    InputError
        Every pixel is unknown.

    Examples
    --------
    >>> import numpy as np, warnings
    >>> from map2map.core.grid import OccupancyMap
    >>> with warnings.catch_warnings():
    ...     warnings.simplefilter("ignore")
    ...     check_plausible(OccupancyMap(np.zeros((20, 20), np.uint8), 0.05), "d.dxf")
    ['map is 20 x 20 px (1 x 1 m) with no free space: implausible for a floor plan \
(wrong `units` or `resolution`, or thresholds?)']
    """
    import warnings

    from ..core.errors import MapWarning
    from ..core.grid import FREE, UNKNOWN

    data = m.data
    if data.size == 0 or not (data != UNKNOWN).any():
        raise InputError(source, "the map is empty: no wall and no free pixel was read")
    h, w = data.shape
    wm, hm = w * m.resolution, h * m.resolution
    problems = []
    if not (data == FREE).any():
        problems.append("with no free space")
    if min(wm, hm) < MIN_EXTENT_M:
        problems.append(f"under {MIN_EXTENT_M:g} m on a side")
    if max(wm, hm) > MAX_EXTENT_M:
        problems.append(f"over {MAX_EXTENT_M:g} m across")
    if not problems:
        return []
    msg = (
        f"map is {w} x {h} px ({wm:.3g} x {hm:.3g} m) {', '.join(problems)}: implausible "
        "for a floor plan (wrong `units` or `resolution`, or thresholds?)"
    )
    warnings.warn(f"{source}: {msg}" if source is not None else msg, MapWarning, stacklevel=3)
    return [msg]


def check_output_path(path: str | os.PathLike, suffixes: Iterable[str] = WRITE_SUFFIXES) -> Path:
    """Check, without writing anything, that ``path`` can be written as a map.

    The suffix must be one of ``suffixes`` and the nearest existing folder above
    ``path`` must be a writable directory. Raises :class:`InputError` otherwise.

    Parameters
    ----------
    path : path-like
        The map file to write.
    suffixes : iterable of str
        Accepted suffixes, lower case with the dot.

    Returns
    -------
    pathlib.Path
        ``path`` as a Path.

    Raises
    ------
    InputError
        Unknown suffix, ``path`` is a directory, or no writable folder above it.

    Examples
    --------
    >>> check_output_path("out/map.yaml").name
    'map.yaml'
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

    Parameters
    ----------
    m : OccupancyMap
        The map.
    path : path-like
        Output file; the suffix selects the format.

    Raises
    ------
    InputError
        Unknown suffix or unwritable folder (checked before anything is written).

    Examples
    --------
    >>> import tempfile, pathlib
    >>> import numpy as np
    >>> m = OccupancyMap(np.full((10, 20), 255, np.uint8), 0.05)
    >>> path = pathlib.Path(tempfile.mkdtemp()) / "m.yaml"
    >>> save_map(m, path)
    >>> load_map(path) == m
    True
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
