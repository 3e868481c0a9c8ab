"""Plain pictures as maps: PNG, PGM, JPG, TIFF, BMP (8- or 16-bit, grey, RGB, RGBA).

A picture carries no metric frame, so the resolution is a parameter (default
0.05 m/px) and the origin defaults to ``(0, 0, 0)`` (the lower-left corner of the
picture at the world origin). Occupancy follows map_server's trinary rule with the
given thresholds (see :mod:`map2map.maps.ros`): ``p = 1 - shade`` (``shade`` =
mean of the colour channels over the maximum value; ``p = shade`` with ``negate``),
``p > occupied_thresh`` -> occupied, ``p < free_thresh`` -> free, else unknown.
Unlike map_server's trinary mode, the alpha channel is not averaged in: a pixel
less than half opaque is unknown, which is what a transparent background means.
Our own files (0 / 127 / 255) load back unchanged with the default thresholds.

Pictures written by :func:`save_image_map` are 8-bit grey in our values (0 occupied,
127 unknown, 255 free). PNG files also carry the resolution and origin in a text
chunk (``map2map`` key) and PGM files in a header comment, which
:func:`load_image_map` reads back when no resolution is given, so a PNG/PGM round
trip keeps the metric frame.

Examples
--------
>>> import numpy as np, tempfile, pathlib
>>> from map2map.core.grid import OccupancyMap
>>> m = OccupancyMap(np.array([[0, 127, 255]], np.uint8), 0.1, (2.0, 3.0, 0.0))
>>> path = pathlib.Path(tempfile.mkdtemp()) / "map.png"
>>> save_image_map(m, path)
>>> back = load_image_map(path)
>>> back == m, back.resolution, back.origin
(True, 0.1, (2.0, 3.0, 0.0))
>>> load_image_map(path, resolution=0.5).resolution
0.5
"""

from __future__ import annotations

import math
import os
import re
import struct
import zlib
from pathlib import Path
from typing import Any

import cv2
import numpy as np

from ..core._io import atomic_path
from ..core.errors import InputError
from ..core.grid import FREE, OCCUPIED, UNKNOWN, OccupancyMap
from .raster import IMAGE_SUFFIXES, RasterImage, pgm_bytes, read_image
from .ros import SAVER_FREE_THRESH, SAVER_OCCUPIED_THRESH, check_thresholds, per_value

__all__ = [
    "DEFAULT_RESOLUTION",
    "WRITE_SUFFIXES",
    "IMAGE_SUFFIXES",
    "image_to_grid",
    "load_image_map",
    "save_image_map",
]

#: Metres per pixel assumed for a picture when none is given or stored in it.
DEFAULT_RESOLUTION = 0.05
#: Suffixes :func:`save_image_map` writes.
WRITE_SUFFIXES = (".png", ".pgm")

_FRAME_KEY = "map2map"
_FRAME_RE = re.compile(r"map2map resolution=(?P<res>\S+) origin=(?P<x>\S+),(?P<y>\S+),(?P<yaw>\S+)")


def image_to_grid(
    img: RasterImage,
    *,
    occupied_thresh: float = SAVER_OCCUPIED_THRESH,
    free_thresh: float = SAVER_FREE_THRESH,
    negate: bool = False,
) -> np.ndarray:
    """Our three values from a picture's pixels (rule in the module docstring).

    Parameters
    ----------
    img : RasterImage
        A picture from :func:`map2map.maps.raster.read_image`.
    occupied_thresh, free_thresh : float
        map_server thresholds on the darkness ``p = (maxval - value) / maxval``.
    negate : bool
        Read white as occupied.

    Returns
    -------
    (H, W) uint8 array
        0, 127 or 255.

    Examples
    --------
    >>> from map2map.maps.raster import RasterImage
    >>> img = RasterImage(np.array([[0, 89, 90, 127, 205, 206, 255]], np.uint8)[:, :, None],
    ...                   None, 255)
    >>> image_to_grid(img).tolist()
    [[0, 0, 127, 127, 127, 255, 255]]
    """
    check_thresholds("thresholds", occupied_thresh, free_thresh)
    return per_value(img, lambda im: _grid_rule(im, occupied_thresh, free_thresh, negate))


def _grid_rule(img: RasterImage, occupied_thresh, free_thresh, negate) -> np.ndarray:
    shade = img.channels.astype(np.float64).mean(axis=2) / img.maxval
    p = shade if negate else 1.0 - shade
    out = np.full(p.shape, UNKNOWN, np.uint8)
    out[p > occupied_thresh] = OCCUPIED
    out[p < free_thresh] = FREE
    if img.alpha is not None:
        out[img.alpha.astype(np.float64) < 0.5 * img.maxval] = UNKNOWN
    return out


def _frame_text(m: OccupancyMap) -> str:
    ox, oy, yaw = m.origin
    return f"map2map resolution={m.resolution!r} origin={ox!r},{oy!r},{yaw!r}"


def _stored_frame(path: Path) -> tuple[float, tuple[float, float, float]] | None:
    """Resolution and origin that :func:`save_image_map` stored in the file, if any."""
    text = None
    suffix = path.suffix.lower()
    try:
        if suffix == ".png":
            from PIL import Image

            with Image.open(path) as im:
                text = im.info.get(_FRAME_KEY)  # tEXt before the pixels: no decoding
        elif suffix == ".pgm":
            with open(path, "rb") as fh:
                head = fh.read(512).decode("ascii", "replace")
            text = "\n".join(line for line in head.splitlines() if line.startswith("#"))
    except Exception:  # noqa: BLE001 - a frame we cannot read is simply absent
        return None
    if not text:
        return None
    match = _FRAME_RE.search(text)
    if not match:
        return None
    try:
        res = float(match["res"])
        origin = (float(match["x"]), float(match["y"]), float(match["yaw"]))
    except ValueError:
        return None
    if not (math.isfinite(res) and res > 0 and all(math.isfinite(v) for v in origin)):
        return None
    return res, origin


def load_image_map(
    path: str | os.PathLike,
    *,
    resolution: float | None = None,
    origin: tuple[float, float, float] | None = None,
    occupied_thresh: float | None = None,
    free_thresh: float | None = None,
    negate: bool | None = None,
) -> OccupancyMap:
    """Load a plain picture as a map.

    Parameters
    ----------
    path : path-like
        PNG, PGM, JPG, TIFF or BMP file.
    resolution : float, optional
        Metres per pixel. Default: the value stored by :func:`save_image_map`, else
        :data:`DEFAULT_RESOLUTION` (then ``meta["resolution_assumed"]`` is True).
    origin : (x, y, yaw), optional
        Default: the stored origin, else ``(0, 0, 0)``.
    occupied_thresh, free_thresh, negate : optional
        map_server thresholds (default 0.65, 0.196, False).

    Returns
    -------
    OccupancyMap
        ``meta`` records the source and what was assumed.

    Raises
    ------
    InputError
        File missing or not a readable picture, resolution not > 0, thresholds
        out of [0, 1] or ``free_thresh >= occupied_thresh``.
    """
    p = Path(path)
    occ = SAVER_OCCUPIED_THRESH if occupied_thresh is None else float(occupied_thresh)
    free = SAVER_FREE_THRESH if free_thresh is None else float(free_thresh)
    check_thresholds("thresholds", occ, free)
    if resolution is not None and not (math.isfinite(resolution) and resolution > 0):
        raise InputError("resolution", f"resolution must be > 0, got {resolution:g}")
    img = read_image(p)
    stored = _stored_frame(p)
    meta: dict[str, Any] = {"source": str(p)}
    if resolution is None:
        if stored is not None:
            resolution = stored[0]
        else:
            resolution = DEFAULT_RESOLUTION
            meta["resolution_assumed"] = True
    if origin is None:
        origin = stored[1] if stored is not None else (0.0, 0.0, 0.0)
    data = image_to_grid(img, occupied_thresh=occ, free_thresh=free, negate=bool(negate))
    return OccupancyMap(data, float(resolution), tuple(origin), meta)


def save_image_map(m: OccupancyMap, path: str | os.PathLike) -> None:
    """Write ``m`` as an 8-bit grey PNG or PGM in our values (0 / 127 / 255), atomically.

    The resolution and origin go into a PNG text chunk or a PGM comment.

    Parameters
    ----------
    m : OccupancyMap
        The map.
    path : path-like
        ``.png`` or ``.pgm`` file.

    Examples
    --------
    >>> import tempfile, pathlib
    >>> m = OccupancyMap(np.full((10, 20), 255, np.uint8), 0.1, (1.0, 2.0, 0.0))
    >>> path = pathlib.Path(tempfile.mkdtemp()) / "m.png"
    >>> save_image_map(m, path)
    >>> load_image_map(path) == m
    True
    """
    p = Path(path)
    suffix = p.suffix.lower()
    if suffix not in WRITE_SUFFIXES:
        raise InputError(
            p, f"cannot write a map picture as {suffix or 'no suffix'!r}; use .png or .pgm"
        )
    if suffix == ".pgm":
        data = pgm_bytes(m.data, comment=_frame_text(m))
        with atomic_path(p) as tmp:
            tmp.write_bytes(data)
        return
    ok, buf = cv2.imencode(".png", np.ascontiguousarray(m.data))
    if not ok:  # pragma: no cover - OpenCV encodes any uint8 array
        raise InputError(p, "PNG encoding failed")
    data = _with_text_chunk(buf.tobytes(), _FRAME_KEY, _frame_text(m))
    with atomic_path(p) as tmp:
        tmp.write_bytes(data)


def _with_text_chunk(png: bytes, key: str, text: str) -> bytes:
    """Insert a ``tEXt`` chunk right after the IHDR chunk of a PNG file."""
    body = b"tEXt" + key.encode("latin-1") + b"\0" + text.encode("latin-1")
    chunk = struct.pack(">I", len(body) - 4) + body + struct.pack(">I", zlib.crc32(body))
    ihdr_end = 8 + 4 + 4 + 13 + 4  # signature, length, type, IHDR data, CRC
    return png[:ihdr_end] + chunk + png[ihdr_end:]
