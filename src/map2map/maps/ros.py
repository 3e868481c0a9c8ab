"""ROS map_server / Nav2 maps: a ``.yaml`` beside a ``.pgm``/``.png`` picture.

Reading follows ``nav2_map_server`` (``map_io.cpp``: ``loadMapYaml`` and
``loadMapFromFile``) cell for cell; ``flavor="ros1"`` follows ROS 1 ``map_server``
(``image_loader.cpp``) instead. Writing produces what ``map_saver`` writes.

The yaml keys
-------------
``image``
    The picture; a relative path is relative to the yaml's folder.
``resolution``
    Metres per pixel (> 0).
``origin``
    ``[x, y, yaw]``: the world pose of the lower-left corner of the lower-left
    pixel. This is exactly :class:`~map2map.core.grid.OccupancyMap`'s origin.
``negate``, ``occupied_thresh``, ``free_thresh``, ``mode``
    How pixel values become occupancy (below). ``mode`` is ``trinary`` (default),
    ``scale`` or ``raw``. map_server requires the thresholds and ``negate``; we
    default them to map_saver's values (0.65, 0.196, 0) when absent.

map_server's semantics (Nav2)
-----------------------------
For each pixel, ``shade`` in [0, 1] is the mean of its R, G, B channels divided by
the maximum value (grey images: the grey value); in trinary mode an alpha channel is
averaged in as a fourth channel (255 = opaque). ``p = 1 - shade``, or ``p = shade``
when ``negate`` is set. Then, in map_server's OccupancyGrid values:

* trinary: ``p > occupied_thresh`` -> 100, ``p < free_thresh`` -> 0, else -1;
* scale: any transparency -> -1; else ``p > occupied_thresh`` -> 100,
  ``p < free_thresh`` -> 0, else ``rint(100 (p - free) / (occ - free))``;
* raw: ``round(255 shade)`` if it lies in 0..100, else -1 (``negate`` is ignored).

ROS 1 differs in three details, reproduced with ``flavor="ros1"``: scale mode gives
``trunc(99 (p - free) / (occ - free))`` and treats a cell as unknown only when its
last byte (alpha, or blue for an RGB picture, as ROS 1 does) is 0 *and* it lies
between the thresholds; raw mode applies ``negate`` and stores the 8-bit mean as is.

How the result maps onto our three values
-----------------------------------------
OccupancyGrid 100 -> :data:`~map2map.core.grid.OCCUPIED` (0), 0 ->
:data:`~map2map.core.grid.FREE` (255), everything else (-1 and the intermediate
1..99 that scale and raw modes produce) -> :data:`~map2map.core.grid.UNKNOWN` (127):
only cells map_server calls certain become certain. In scale and raw modes, where
the intermediate values carry information, the loaded map keeps them:
``meta["ros_values"]`` is the int8 OccupancyGrid (image order, row 0 at the top)
and ``meta["occupancy_probability"]`` is ``ros_values / 100`` as float32 with NaN
for unknown cells. Both describe the grid as loaded (cropping the map does not
crop them).

Image order
-----------
map_server flips rows so that OccupancyGrid cell 0 is the lower-left; our grid keeps
image order (row 0 at the top) and its origin is the same lower-left corner, so no
flip is needed: ``pixel_to_world(H - 1, 0)`` is the origin plus half a cell.

Examples
--------
>>> import numpy as np, tempfile, pathlib
>>> from map2map.core.grid import OccupancyMap
>>> m = OccupancyMap(np.array([[0, 127], [255, 255]], np.uint8), 0.05, (-1.0, 2.0, 0.5))
>>> path = pathlib.Path(tempfile.mkdtemp()) / "map.yaml"
>>> save_ros_map(m, path).name
'map.pgm'
>>> print(path.read_text().splitlines()[0])
image: map.pgm
>>> load_ros_map(path) == m
True
"""

from __future__ import annotations

import math
import os
from pathlib import Path
from typing import Any

import numpy as np
import yaml

from .._version import __version__
from ..core._io import atomic_paths, ensure_output_dir
from ..core.errors import InputError
from ..core.grid import FREE, OCCUPIED, UNKNOWN, OccupancyMap
from .raster import RasterImage, pgm_bytes, read_image

#: PyYAML's safe loader, libyaml's C parser when PyYAML was built with it (the same
#: documents, about ten times faster: a folder of maps reads each yaml twice)
_SAFE_LOADER = getattr(yaml, "CSafeLoader", yaml.SafeLoader)

__all__ = [
    "MODES",
    "FLAVORS",
    "SAVER_FREE",
    "SAVER_OCCUPIED",
    "SAVER_UNKNOWN",
    "SAVER_OCCUPIED_THRESH",
    "SAVER_FREE_THRESH",
    "load_ros_map",
    "save_ros_map",
    "map_server_values",
    "ros_values_to_grid",
    "check_thresholds",
]

MODES = ("trinary", "scale", "raw")
FLAVORS = ("nav2", "ros1")

#: Pixel values map_saver writes (trinary mode).
SAVER_FREE, SAVER_OCCUPIED, SAVER_UNKNOWN = 254, 0, 205
#: Thresholds map_saver writes into the yaml.
SAVER_OCCUPIED_THRESH, SAVER_FREE_THRESH = 0.65, 0.196


# --------------------------------------------------------------------------- semantics
def check_thresholds(source, occupied_thresh: float, free_thresh: float) -> None:
    """Raise :class:`InputError` unless ``0 <= free_thresh < occupied_thresh <= 1``.

    Parameters
    ----------
    source : path-like or str
        Named in the error (the yaml, or the parameter).
    occupied_thresh, free_thresh : float
        map_server thresholds.

    Examples
    --------
    >>> check_thresholds("map.yaml", 0.65, 0.196)
    """
    for name, v in (("occupied_thresh", occupied_thresh), ("free_thresh", free_thresh)):
        if not isinstance(v, int | float) or isinstance(v, bool) or not math.isfinite(v):
            raise InputError(source, f"{name} must be a number, got {v!r}")
        if not 0.0 <= v <= 1.0:
            raise InputError(source, f"{name} must lie in [0, 1], got {v:g}")
    if free_thresh >= occupied_thresh:
        raise InputError(
            source,
            f"free_thresh ({free_thresh:g}) must be smaller than occupied_thresh "
            f"({occupied_thresh:g})",
        )


def map_server_values(
    img: RasterImage,
    *,
    mode: str = "trinary",
    negate: bool = False,
    occupied_thresh: float = SAVER_OCCUPIED_THRESH,
    free_thresh: float = SAVER_FREE_THRESH,
    flavor: str = "nav2",
) -> np.ndarray:
    """OccupancyGrid values (int8: 100, 0, -1 or 1..99) map_server computes for a picture.

    The result is in image order (row 0 = top row of the picture). See the module
    docstring for the rules.

    Parameters
    ----------
    img : RasterImage
        The picture a yaml names.
    mode : {"trinary", "scale", "raw"}
        map_server mode.
    negate : bool
        Read white as occupied.
    occupied_thresh, free_thresh : float
        Thresholds on the darkness ``p``.
    flavor : {"nav2", "ros1"}
        Whose map_server rules.

    Returns
    -------
    (H, W) int8 array

    Examples
    --------
    >>> from map2map.maps.raster import RasterImage
    >>> grey = np.array([[0, 100, 205, 254]], np.uint8)[:, :, None]
    >>> img = RasterImage(grey, None, 255)
    >>> map_server_values(img).tolist()
    [[100, -1, -1, 0]]
    >>> map_server_values(img, mode="scale").tolist()
    [[100, 91, 0, 0]]
    """
    if mode not in MODES:
        raise ValueError(f"mode must be one of {MODES}, got {mode!r}")
    if flavor not in FLAVORS:
        raise ValueError(f"flavor must be one of {FLAVORS}, got {flavor!r}")
    fn = _values_ros1 if flavor == "ros1" else _values_nav2
    return per_value(img, lambda im: fn(im, mode, bool(negate), occupied_thresh, free_thresh))


def per_value(img: RasterImage, fn):
    """``fn(img)`` for a pixel-wise rule, through a look-up table for grey pictures.

    A grey picture without alpha has at most ``maxval + 1`` distinct pixels, so the
    rule is evaluated once per possible value and the picture indexed into it.

    Parameters
    ----------
    img : RasterImage
        The picture.
    fn : callable
        Pixel-wise rule taking a RasterImage and returning an (H, W) array.

    Returns
    -------
    ndarray
        ``fn(img)``.
    """
    if img.channels.shape[2] != 1 or img.alpha is not None:
        return fn(img)
    dtype = img.channels.dtype
    every = np.arange(np.iinfo(dtype).max + 1, dtype=dtype)[None, :, None]
    lut = fn(RasterImage(every, None, img.maxval))[0]
    return lut[img.channels[:, :, 0]]


def _values_nav2(img: RasterImage, mode, negate, occ_th, free_th) -> np.ndarray:
    """``nav2_map_server::loadMapFromFile``: Magick averages R, G, B (+ alpha in trinary)."""
    ch = img.channels.astype(np.float64)
    rgb_sum = ch.sum(axis=2) * (3.0 / ch.shape[2])  # grey pictures: R = G = B = grey
    if mode == "trinary" and img.alpha is not None:
        avg = (rgb_sum + img.alpha) / 4.0
    else:
        avg = rgb_sum / 3.0
    shade = avg / img.maxval
    out = np.full(shade.shape, -1, np.int8)
    if mode == "raw":
        pct = np.floor(shade * 255.0 + 0.5)  # std::round, values are >= 0
        ok = (pct >= 0) & (pct <= 100)
        out[ok] = pct[ok].astype(np.int8)
        return out
    occ = shade if negate else 1.0 - shade
    occupied = occ_th < occ
    free = occ < free_th
    if mode == "trinary":
        out[occupied] = 100
        out[free & ~occupied] = 0
        return out
    # scale
    between = ~occupied & ~free
    ratio = (occ - free_th) / (occ_th - free_th) * 100.0
    out[between] = np.rint(ratio[between]).astype(np.int8)
    out[occupied] = 100
    out[free & ~occupied] = 0
    if img.alpha is not None:
        out[img.alpha != img.maxval] = -1
    return out


def _to_int8_like_c(x: np.ndarray) -> np.ndarray:
    """C's ``int8_t v = double`` on x86: truncate toward zero, keep the low byte."""
    return np.trunc(x).astype(np.int64).astype(np.uint8).view(np.int8)


def _values_ros1(img: RasterImage, mode, negate, occ_th, free_th) -> np.ndarray:
    """ROS 1 ``map_server::loadMapFromFile`` (SDL image: 8-bit bytes per channel)."""

    def to_bytes(v: np.ndarray) -> np.ndarray:
        if img.maxval == 255:
            return v
        if img.maxval == 65535:  # SDL_image strips 16-bit PNGs to their high byte
            return (v >> 8).astype(np.uint8)
        return (v.astype(np.uint32) * 255 // img.maxval).astype(np.uint8)  # PNM maxval

    ch = to_bytes(img.channels)
    alpha = None if img.alpha is None else to_bytes(img.alpha)
    if ch.shape[2] == 1 and alpha is not None:  # SDL expands grey + alpha to RGBA
        ch = np.repeat(ch, 3, axis=2)
    planes = [ch[:, :, k].astype(np.float64) for k in range(ch.shape[2])]
    if alpha is not None:
        planes.append(alpha.astype(np.float64))
    n_channels = len(planes)
    avg_channels = n_channels if (mode == "trinary" or alpha is None) else n_channels - 1
    color_avg = sum(planes[:avg_channels]) / avg_channels
    last = np.ones_like(color_avg) if n_channels == 1 else planes[-1]  # "alpha" (sic)
    if negate:
        color_avg = 255.0 - color_avg
    if mode == "raw":
        return _to_int8_like_c(color_avg)
    occ = (255.0 - color_avg) / 255.0
    out = np.full(occ.shape, -1, np.int8)
    occupied = occ > occ_th
    free = ~occupied & (occ < free_th)
    out[occupied] = 100
    out[free] = 0
    if mode == "scale":
        between = ~occupied & ~free & (last >= 1.0)
        ratio = (occ - free_th) / (occ_th - free_th)
        out[between] = _to_int8_like_c(99.0 * ratio[between])
    return out


def ros_values_to_grid(values: np.ndarray) -> np.ndarray:
    """OccupancyGrid values -> our grid: 100 occupied, 0 free, anything else unknown.

    Parameters
    ----------
    values : int array
        OccupancyGrid values (-1, 0..100).

    Returns
    -------
    uint8 array
        Same shape, 0, 127 or 255.

    Examples
    --------
    >>> ros_values_to_grid(np.array([100, 0, -1, 42], np.int8)).tolist()
    [0, 255, 127, 127]
    """
    v = np.asarray(values)
    if v.dtype == np.int8:  # one look-up per cell
        lut = np.full(256, UNKNOWN, np.uint8)
        lut[100], lut[0] = OCCUPIED, FREE
        return lut[v.view(np.uint8)]
    out = np.full(v.shape, UNKNOWN, np.uint8)
    out[v == 100] = OCCUPIED
    out[v == 0] = FREE
    return out


# --------------------------------------------------------------------------- reading
def _as_float(v: Any) -> float | None:
    """A finite float from a YAML scalar, or None. Strings such as ``"2e-07"`` count:
    PyYAML (YAML 1.1) reads them as text, yaml-cpp (map_server) as numbers."""
    if isinstance(v, bool):
        return None
    if isinstance(v, str):
        try:
            v = float(v)
        except ValueError:
            return None
    if not isinstance(v, int | float) or not math.isfinite(v):
        return None
    return float(v)


def _number(source, doc: dict, key: str, default: float | None = None) -> float:
    if key not in doc or doc[key] is None:
        if default is None:
            raise InputError(source, f"map yaml has no '{key}'")
        return default
    v = _as_float(doc[key])
    if v is None:
        raise InputError(source, f"'{key}' must be a number, got {doc[key]!r}")
    return v


def read_ros_yaml(path: str | os.PathLike) -> dict[str, Any]:
    """Parse and validate a map_server yaml; returns its settings with defaults filled in.

    Keys of the result: ``image`` (Path, resolved against the yaml's folder),
    ``resolution``, ``origin`` (3-tuple), ``negate`` (bool), ``occupied_thresh``,
    ``free_thresh``, ``mode``.

    Parameters
    ----------
    path : path-like
        The yaml.

    Returns
    -------
    dict

    Raises
    ------
    InputError
        Missing file, not YAML, missing or invalid keys (each named).
    """
    p = Path(path)
    if not p.exists():
        raise InputError(p, "file not found")
    if p.is_dir():
        raise InputError(p, "is a directory, not a map yaml")
    try:
        text = p.read_text(encoding="utf-8")
    except (OSError, UnicodeDecodeError) as exc:
        raise InputError(p, f"cannot read map yaml ({exc})") from None
    try:
        doc = yaml.load(text, Loader=_SAFE_LOADER)           # safe: no Python objects
    except yaml.YAMLError as exc:
        where = getattr(exc, "problem_mark", None)
        at = f" at line {where.line + 1}" if where is not None else ""
        raise InputError(p, f"not valid YAML{at}") from None
    if not isinstance(doc, dict):
        raise InputError(p, "not a map yaml (expected keys image, resolution, origin, ...)")
    image = doc.get("image")
    if image is None or (isinstance(image, str) and not image.strip()):
        raise InputError(p, "map yaml has no 'image'")
    if not isinstance(image, str):
        raise InputError(p, f"'image' must be a file name, got {image!r}")
    image_path = Path(image)
    if not image_path.is_absolute():
        image_path = p.parent / image_path
    resolution = _number(p, doc, "resolution")
    if resolution <= 0:
        raise InputError(p, f"resolution must be > 0, got {resolution:g}")
    origin = doc.get("origin", [0.0, 0.0, 0.0])
    if isinstance(origin, list | tuple):
        origin = [_as_float(v) for v in origin]
    if not isinstance(origin, list) or len(origin) != 3 or None in origin:
        raise InputError(p, f"'origin' must be [x, y, yaw] (3 numbers), got {doc['origin']!r}")
    negate = doc.get("negate", 0)
    if isinstance(negate, bool):
        negate = int(negate)
    if negate not in (0, 1):
        raise InputError(p, f"'negate' must be 0 or 1, got {negate!r}")
    occ = _number(p, doc, "occupied_thresh", SAVER_OCCUPIED_THRESH)
    free = _number(p, doc, "free_thresh", SAVER_FREE_THRESH)
    check_thresholds(p, occ, free)
    mode = doc.get("mode", "trinary")
    if not isinstance(mode, str) or mode.strip().lower() not in MODES:
        raise InputError(p, f"'mode' must be one of {', '.join(MODES)}, got {mode!r}")
    return {
        "image": image_path,
        "resolution": resolution,
        "origin": tuple(float(v) for v in origin),
        "negate": bool(negate),
        "occupied_thresh": occ,
        "free_thresh": free,
        "mode": mode.strip().lower(),
    }


def load_ros_map(
    path: str | os.PathLike,
    *,
    mode: str | None = None,
    negate: bool | None = None,
    occupied_thresh: float | None = None,
    free_thresh: float | None = None,
    flavor: str = "nav2",
) -> OccupancyMap:
    """Load a ROS map_server / Nav2 map (yaml + picture) exactly as map_server does.

    Parameters
    ----------
    path : path-like
        The ``.yaml`` file.
    mode, negate, occupied_thresh, free_thresh : optional
        Override the yaml's values.
    flavor : {"nav2", "ros1"}
        Whose map_server to follow where they differ (scale and raw modes).

    Returns
    -------
    OccupancyMap
        In image order with the yaml's resolution and origin. ``meta`` holds
        ``source``, ``image`` and ``ros`` (the settings used); in scale and raw modes
        also ``ros_values`` and ``occupancy_probability`` (see the module docstring).

    Raises
    ------
    InputError
        Missing or invalid yaml keys, thresholds out of range, image not found or
        not readable.
    """
    if flavor not in FLAVORS:
        raise ValueError(f"flavor must be one of {FLAVORS}, got {flavor!r}")
    p = Path(path)
    cfg = read_ros_yaml(p)
    if mode is not None:
        if mode not in MODES:
            raise InputError(None, f"mode must be one of {', '.join(MODES)}, got {mode!r}")
        cfg["mode"] = mode
    if negate is not None:
        cfg["negate"] = bool(negate)
    if occupied_thresh is not None or free_thresh is not None:
        if occupied_thresh is not None:
            cfg["occupied_thresh"] = float(occupied_thresh)
        if free_thresh is not None:
            cfg["free_thresh"] = float(free_thresh)
        check_thresholds("thresholds", cfg["occupied_thresh"], cfg["free_thresh"])
    img = read_image(cfg["image"], referenced_by=p)
    values = map_server_values(
        img,
        mode=cfg["mode"],
        negate=cfg["negate"],
        occupied_thresh=cfg["occupied_thresh"],
        free_thresh=cfg["free_thresh"],
        flavor=flavor,
    )
    settings = {k: cfg[k] for k in ("mode", "negate", "occupied_thresh", "free_thresh")}
    settings["flavor"] = flavor
    meta: dict[str, Any] = {"source": str(p), "image": str(cfg["image"]), "ros": settings}
    if cfg["mode"] != "trinary":
        meta["ros_values"] = values
        prob = values.astype(np.float32) / 100.0
        prob[(values < 0) | (values > 100)] = np.nan
        meta["occupancy_probability"] = prob
    return OccupancyMap(ros_values_to_grid(values), cfg["resolution"], cfg["origin"], meta)


# --------------------------------------------------------------------------- writing
def _yaml_float(v: float) -> str:
    """Shortest text that reads back as the same float (exact round trip).

    YAML 1.1 readers (PyYAML) need a dot in the mantissa of an exponent form.

    >>> _yaml_float(2e-07), _yaml_float(0.05), _yaml_float(-3.0)
    ('2.0e-07', '0.05', '-3.0')
    """
    text = repr(float(v))
    mant, e, exp = text.partition("e")
    if e and "." not in mant:
        text = f"{mant}.0e{exp}"
    return text


def save_ros_map(
    m: OccupancyMap, yaml_path: str | os.PathLike, *, image_name: str | None = None
) -> Path:
    """Write ``m`` as map_saver does: a binary P5 PGM (254 free, 0 occupied, 205 unknown)
    and a yaml with ``mode: trinary``, ``negate: 0``, thresholds 0.65 / 0.196.

    The picture goes beside the yaml, named after it (``map.yaml`` -> ``map.pgm``)
    unless ``image_name`` says otherwise; the yaml names it relatively, so the pair
    can be moved together. Numbers are written with full precision, so
    :func:`load_ros_map` gives back the identical grid, resolution and origin. Both
    files are written atomically. Returns the path of the picture.

    Parameters
    ----------
    m : OccupancyMap
        The map.
    yaml_path : path-like
        The ``.yaml`` file.
    image_name : str, optional
        File name of the picture, beside the yaml.

    Returns
    -------
    pathlib.Path
        The picture written.

    Examples
    --------
    >>> import tempfile, pathlib
    >>> m = OccupancyMap(np.full((10, 20), 255, np.uint8), 0.05)
    >>> save_ros_map(m, pathlib.Path(tempfile.mkdtemp()) / "map.yaml").name
    'map.pgm'
    """
    yp = Path(yaml_path)
    ensure_output_dir(yp, is_dir=False)
    name = image_name or (yp.stem + ".pgm")
    if Path(name).name != name or not name.lower().endswith(".pgm"):
        raise InputError(name, "image_name must be a plain file name ending in .pgm")
    pgm_path = yp.parent / name
    pixels = np.full(m.shape, SAVER_UNKNOWN, np.uint8)
    pixels[m.free] = SAVER_FREE
    pixels[m.occupied] = SAVER_OCCUPIED
    ox, oy, yaw = m.origin
    text = (
        yaml.safe_dump({"image": name}, default_flow_style=False) + "mode: trinary\n"
        f"resolution: {_yaml_float(m.resolution)}\n"
        f"origin: [{_yaml_float(ox)}, {_yaml_float(oy)}, {_yaml_float(yaw)}]\n"
        f"negate: 0\n"
        f"occupied_thresh: {SAVER_OCCUPIED_THRESH}\n"
        f"free_thresh: {SAVER_FREE_THRESH}\n"
    )
    comment = f"CREATOR: map2map {__version__}; {m.resolution:.3f} m/pix"
    with atomic_paths(yp, pgm_path) as (tmp_yaml, tmp_pgm):
        tmp_pgm.write_bytes(pgm_bytes(pixels, comment))
        tmp_yaml.write_text(text, encoding="utf-8")
    return pgm_path
