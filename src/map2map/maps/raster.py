"""Raster image files as arrays: reading any PNG/PGM/JPG/TIFF/BMP, writing 8-bit grey.

The map loaders (:mod:`map2map.maps.ros`, :mod:`map2map.maps.image`) need the raw
pixel values of a picture, with its bit depth and alpha channel, exactly as stored,
so that map_server's thresholds can be applied to them. OpenCV decodes every common
format (8- and 16-bit, grey, grey+alpha, RGB, RGBA, palette); this module only turns
its answers and its failures into :class:`~map2map.core.errors.InputError`.

Examples
--------
>>> import numpy as np, tempfile, pathlib
>>> path = pathlib.Path(tempfile.mkdtemp()) / "grey.pgm"
>>> write_grey_image(np.array([[0, 127], [205, 254]], np.uint8), path)
>>> img = read_image(path)
>>> img.values.tolist(), img.maxval, img.alpha is None
([[0, 127], [205, 254]], 255, True)
"""

from __future__ import annotations

import contextlib
import os
from dataclasses import dataclass
from pathlib import Path

import cv2
import numpy as np

from ..core._io import atomic_path
from ..core.errors import InputError
from ..core.limits import check_map_size

__all__ = [
    "RasterImage",
    "read_image",
    "write_grey_image",
    "write_pgm",
    "pgm_bytes",
    "IMAGE_SUFFIXES",
]

#: File suffixes read as plain raster images (lower case).
IMAGE_SUFFIXES = (".png", ".pgm", ".ppm", ".pnm", ".jpg", ".jpeg", ".tif", ".tiff", ".bmp")


@dataclass
class RasterImage:
    """Pixel values of an image file, in image order (row 0 = top).

    Attributes
    ----------
    channels : (H, W, C) array
        Colour channels in the file's order converted to R, G, B (C = 3), or the
        single grey channel (C = 1). ``uint8`` or ``uint16`` as stored.
    alpha : (H, W) array or None
        The alpha channel (0 = transparent, ``maxval`` = opaque), None if absent.
    maxval : int
        255 for 8-bit images, 65535 for 16-bit ones.
    """

    channels: np.ndarray
    alpha: np.ndarray | None
    maxval: int

    @property
    def shape(self) -> tuple[int, int]:
        return self.channels.shape[:2]  # type: ignore[return-value]

    @property
    def values(self) -> np.ndarray:
        """(H, W) grey values: the single channel, or the mean of R, G and B (float)."""
        if self.channels.shape[2] == 1:
            return self.channels[:, :, 0]
        return self.channels.mean(axis=2)


@contextlib.contextmanager
def _quiet_opencv():
    """Silence OpenCV's own warnings while decoding (we report failures ourselves)."""
    logging = getattr(getattr(cv2, "utils", None), "logging", None)
    if logging is None:  # pragma: no cover - very old OpenCV
        yield
        return
    old = logging.getLogLevel()
    logging.setLogLevel(logging.LOG_LEVEL_SILENT)
    try:
        yield
    finally:
        logging.setLogLevel(old)


def _pnm_maxval(head: bytes) -> int | None:
    """The declared maximum value of a P2/P3/P5/P6 (PGM/PPM) header, else None.

    >>> _pnm_maxval(b"P5\\n# a comment\\n3 2\\n100\\n"), _pnm_maxval(b"\\x89PNG")
    (100, None)
    """
    if len(head) < 2 or head[:1] != b"P" or head[1:2] not in b"2356":
        return None
    tokens: list[bytes] = []
    for line in head[2:].split(b"\n"):
        tokens += line.split(b"#", 1)[0].split()
        if len(tokens) >= 3:
            break
    try:
        value = int(tokens[2])
    except (IndexError, ValueError):
        return None
    return value if 0 < value < 65536 else None


def header_shape(head: bytes) -> tuple[int, int] | None:
    """(rows, columns) declared by a PGM/PPM or PNG header, else None.

    Read from the first bytes of the file, so that a map too large for the command
    (:func:`map2map.core.limits.check_map_size`) is refused before it is decoded.

    >>> header_shape(b"P5\\n# comment\\n50000 40000\\n255\\n")
    (40000, 50000)
    >>> import struct
    >>> png = b"\\x89PNG\\r\\n\\x1a\\n" + struct.pack(">I", 13) + b"IHDR"
    >>> header_shape(png + struct.pack(">II", 7, 3))
    (3, 7)
    >>> header_shape(b"GIF89a") is None
    True
    """
    if head[:8] == b"\x89PNG\r\n\x1a\n" and head[12:16] == b"IHDR" and len(head) >= 24:
        w, h = int.from_bytes(head[16:20], "big"), int.from_bytes(head[20:24], "big")
        return h, w
    if len(head) < 2 or head[:1] != b"P" or head[1:2] not in b"123456":
        return None
    tokens: list[bytes] = []
    for line in head[2:].split(b"\n"):
        tokens += line.split(b"#", 1)[0].split()
        if len(tokens) >= 2:
            break
    try:
        w, h = int(tokens[0]), int(tokens[1])
    except (IndexError, ValueError):
        return None
    return h, w


def read_image(path: str | os.PathLike, *, referenced_by: str | os.PathLike | None = None):
    """Read an image file as :class:`RasterImage`, raising :class:`InputError` on failure.

    Parameters
    ----------
    path : path-like
        The image file.
    referenced_by : path-like, optional
        The file that named this image (e.g. a ROS yaml), quoted in error messages.

    Returns
    -------
    RasterImage
        The pixels and what the file said about them (bit depth, alpha, maxval, text).
    """
    p = Path(path)
    via = f" (named by {os.fspath(referenced_by)})" if referenced_by is not None else ""
    if not p.exists():
        raise InputError(p, f"image file not found{via}")
    if p.is_dir():
        raise InputError(p, f"is a directory, not an image file{via}")
    try:
        raw = np.fromfile(p, np.uint8)
    except OSError as exc:
        raise InputError(p, f"cannot read image file ({exc.strerror}){via}") from None
    if raw.size == 0:
        raise InputError(p, f"image file is empty{via}")
    declared = header_shape(raw[:512].tobytes())
    if declared is not None:  # refuse a map too large for the command before decoding
        check_map_size(declared, p)
    with _quiet_opencv():
        try:
            img = cv2.imdecode(raw, cv2.IMREAD_UNCHANGED)
        except cv2.error:
            img = None
    if img is None or img.size == 0:
        raise InputError(p, f"not a readable image (corrupt or unsupported format){via}")
    if declared is None:
        check_map_size(img.shape[:2], p)
    if img.dtype == np.uint8:
        maxval = 255
    elif img.dtype == np.uint16:
        maxval = 65535
    else:
        raise InputError(p, f"unsupported pixel type {img.dtype} (need 8- or 16-bit){via}")
    pnm_max = _pnm_maxval(raw[:512].tobytes())
    if pnm_max is not None:  # PGM/PPM may declare any maximum; OpenCV does not rescale
        maxval = pnm_max
    if img.ndim == 2:
        return RasterImage(img[:, :, None], None, maxval)
    nch = img.shape[2]
    if nch == 1:
        return RasterImage(img, None, maxval)
    if nch == 2:  # grey + alpha (OpenCV normally expands this to BGRA)
        return RasterImage(img[:, :, :1], img[:, :, 1], maxval)
    if nch == 3:
        return RasterImage(img[:, :, ::-1], None, maxval)
    if nch == 4:
        return RasterImage(img[:, :, 2::-1], img[:, :, 3], maxval)
    raise InputError(p, f"unsupported number of channels: {nch}{via}")


def write_pgm(values: np.ndarray, path: str | os.PathLike, comment: str | None = None) -> None:
    """Write an 8-bit binary (P5) PGM atomically, as ROS map_saver does.

    Parameters
    ----------
    values : (H, W) uint8 array
        Grey values.
    path : path-like
        Output file.
    comment : str, optional
        A ``#`` comment line after the magic number.

    Examples
    --------
    >>> import tempfile, pathlib
    >>> path = pathlib.Path(tempfile.mkdtemp()) / "m.pgm"
    >>> write_pgm(np.array([[0, 254]], np.uint8), path, comment="demo")
    >>> path.read_bytes()
    b'P5\\n# demo\\n2 1\\n255\\n\\x00\\xfe'
    """
    data = pgm_bytes(values, comment)
    with atomic_path(path) as tmp:
        tmp.write_bytes(data)


def pgm_bytes(values: np.ndarray, comment: str | None = None) -> bytes:
    """The bytes of an 8-bit binary (P5) PGM file holding ``values``.

    Parameters
    ----------
    values : (H, W) uint8 array
        Grey values.
    comment : str, optional
        A ``#`` comment line after the magic number.

    Returns
    -------
    bytes

    Examples
    --------
    >>> pgm_bytes(np.array([[0, 255]], np.uint8))
    b'P5\\n2 1\\n255\\n\\x00\\xff'
    """
    v = np.ascontiguousarray(values, np.uint8)
    if v.ndim != 2:
        raise ValueError("PGM needs a 2-D array")
    header = "P5\n"
    if comment:
        header += f"# {comment}\n"
    header += f"{v.shape[1]} {v.shape[0]}\n255\n"
    return header.encode("ascii") + v.tobytes()


def write_grey_image(values: np.ndarray, path: str | os.PathLike) -> None:
    """Write an 8-bit grey image atomically; the format follows the suffix (PGM is P5).

    Parameters
    ----------
    values : (H, W) uint8 array
        Grey values.
    path : path-like
        Output file (``.pgm``, ``.png``, ...).
    """
    p = Path(path)
    v = np.ascontiguousarray(values, np.uint8)
    if p.suffix.lower() == ".pgm":
        write_pgm(v, p)
        return
    try:
        ok, buf = cv2.imencode(p.suffix.lower() or ".png", v)
    except cv2.error:
        ok = False
    if not ok:
        raise InputError(p, f"cannot write an image with suffix {p.suffix!r}")
    with atomic_path(p) as tmp:
        tmp.write_bytes(buf.tobytes())
