"""The square a map goes through Model_BA in (steps 1-2 of
:mod:`~map2map.learn.ba.autocorrect`): the content square, turned so its walls run along
the axes (:func:`dominant_angle`, :func:`prepare`), and for a large map the
half-overlapping tiles it is cut into and stitched back from (:func:`tile_grid`,
:func:`stitch_tiles`)."""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numba import njit

from ...core.grid import OCCUPIED, UNKNOWN, OccupancyMap
from ...maps.preprocess import ContentSquare, content_square

__all__ = ["Prepared", "prepare", "dominant_angle", "tile_grid", "stitch_tiles",
           "MIN_SKEW_DEG", "TILE_SHRINK"]

#: ``large="tile"``: the tiles' shrink is at most this (the training plans: 0.57-2.3,
#: median 1.1, 5-95 %).
TILE_SHRINK = 2.0



MIN_SKEW_DEG = 3.0  # smaller rotations are left alone


def dominant_angle(data: np.ndarray) -> tuple[float, float]:
    """Dominant wall direction (degrees in (-45, 45], image coordinates) and its coherence
    (0: no preferred direction, 1: all walls parallel or perpendicular): the circular mean
    of four times the gradient angle of the blurred wall mask, weighted by magnitude.

    Examples
    --------
    >>> import cv2
    >>> img = np.full((200, 200), 255, np.uint8)
    >>> _ = cv2.rectangle(img, (50, 60), (150, 140), 0, 1)
    >>> rot = cv2.warpAffine(img, cv2.getRotationMatrix2D((100, 100), 20, 1), (200, 200),
    ...                      flags=cv2.INTER_NEAREST, borderValue=255)
    >>> a, coherence = dominant_angle(rot)
    >>> round(a), coherence > 0.5
    (-20, True)
    """
    import cv2

    occ = cv2.GaussianBlur((np.asarray(data) == OCCUPIED).astype(np.float32), (0, 0), 2.0)
    gx = cv2.Sobel(occ, cv2.CV_32F, 1, 0, ksize=3)
    gy = cv2.Sobel(occ, cv2.CV_32F, 0, 1, ksize=3)
    zr, zi, total = _quadrupled_gradient_sum(gx, gy)
    if total <= 0:
        return 0.0, 0.0
    return float(np.degrees(np.arctan2(zi, zr) / 4)), float(np.hypot(zr, zi) / total)


@njit(cache=True, nogil=True)
def _quadrupled_gradient_sum(gx: np.ndarray, gy: np.ndarray) -> tuple[float, float, float]:
    """sum(|g| exp(4i angle(g))) as (real, imaginary) and sum(|g|), in float64, without
    trigonometry: with g = |g| (c + i s), exp(4i angle) = (c + i s)^4."""
    zr = zi = total = 0.0
    for i in range(gx.shape[0]):
        for j in range(gx.shape[1]):
            x, y = float(gx[i, j]), float(gy[i, j])
            m2 = x * x + y * y
            if m2 == 0.0:
                continue
            m = np.sqrt(m2)
            c2 = (x * x - y * y) / m2  # cos 2a, sin 2a
            s2 = 2.0 * x * y / m2
            zr += m * (c2 * c2 - s2 * s2)  # cos 4a = cos^2 2a - sin^2 2a
            zi += m * (2.0 * c2 * s2)
            total += m
    return zr, zi, total


def rotate_square(data: np.ndarray, angle: float) -> np.ndarray:
    import cv2

    n = data.shape[0]
    rot = cv2.getRotationMatrix2D(((n - 1) / 2, (n - 1) / 2), angle, 1.0)
    return cv2.warpAffine(data, rot, (n, n), flags=cv2.INTER_NEAREST, borderValue=UNKNOWN)


@dataclass
class Prepared:
    """A map's content square (:func:`~map2map.maps.preprocess.content_square`) and
    the square the model sees: the same, or turned by ``angle`` degrees (padded by
    ``pad`` pixels a side first, so nothing is cut) to bring its walls onto the axes."""

    square: ContentSquare
    angle: float
    pad: int
    model: np.ndarray

    @property
    def side(self) -> int:
        return self.square.side


def prepare(m: OccupancyMap, data_size: int, deskew: bool,
            min_skew: float = MIN_SKEW_DEG) -> Prepared | None:
    """The content square of ``m`` and its deskewed version (step 1 of
    :mod:`~map2map.learn.ba.autocorrect`), or None for a map without known cells.

    Examples
    --------
    >>> from map2map.core.grid import OccupancyMap
    >>> d = np.full((40, 40), UNKNOWN, np.uint8); d[5:35, 5:35] = 255; d[5, 5:35] = 0
    >>> p = prepare(OccupancyMap(d, 0.05), 256, deskew=True)
    >>> p.side, p.angle, p.model is p.square.data
    (32, 0.0, True)
    """
    sq = content_square(m, data_size)
    if sq is None:
        return None
    angle, coherence = dominant_angle(sq.data) if deskew else (0.0, 0.0)
    if abs(angle) < min_skew or coherence < 0.3:
        return Prepared(sq, 0.0, 0, sq.data)
    t = math.radians(abs(angle))
    pad = math.ceil(sq.side * (math.cos(t) + math.sin(t) - 1) / 2)
    big = np.pad(sq.data, pad, constant_values=UNKNOWN)
    return Prepared(sq, angle, pad, rotate_square(big, angle))


def unrotate_segments(segs: np.ndarray, angle: float, n: int) -> np.ndarray:
    import cv2

    if not len(segs):
        return segs
    inv = cv2.getRotationMatrix2D(((n - 1) / 2, (n - 1) / 2), -angle, 1.0)
    pts = segs.reshape(-1, 2)
    back = pts @ inv[:, :2].T + inv[:, 2]
    return back.reshape(-1, 4)


def tile_grid(n: int, data_size: int, max_shrink: float = TILE_SHRINK) -> tuple[int, int]:
    """``(count, stride)`` of the tiles that cover a square of ``n`` pixels: ``count``
    tiles per axis, each ``2 * stride`` pixels, one every ``stride`` (half-overlapping),
    so they cover ``(count + 1) * stride >= n``; the fewest with tiles of at most
    ``max_shrink`` times ``data_size``.

    Examples
    --------
    >>> tile_grid(1600, 256)            # a 6.25x map: 6 x 6 tiles of 458 px (1.8x)
    (6, 229)
    >>> tile_grid(300, 256)             # small enough: one tile
    (1, 150)
    """
    half = max_shrink * data_size / 2
    count = max(1, math.ceil(n / half) - 1)
    return count, math.ceil(n / (count + 1))


def cut_tiles(model_sq: np.ndarray, count: int, stride: int) -> list[np.ndarray]:
    """The ``count x count`` tiles of :func:`tile_grid` (row by row), the square padded
    with unknown to ``(count + 1) * stride``."""
    L = (count + 1) * stride
    big = np.full((L, L), UNKNOWN, np.uint8)
    n = model_sq.shape[0]
    big[:n, :n] = model_sq
    return [big[i * stride:(i + 2) * stride, j * stride:(j + 2) * stride]
            for i in range(count) for j in range(count)]


def stitch_tiles(outputs: np.ndarray, count: int) -> np.ndarray:
    """The network's outputs of :func:`cut_tiles` (``count**2`` maps of ``s x s``) as one
    output of ``(count + 1) * s / 2`` cells: of each tile its centre half across each
    axis (and the border out to the edge at the first and last tiles), where a tile's
    network saw context on all sides.

    Examples
    --------
    >>> o = np.stack([np.full((4, 4), k, np.float32) for k in range(4)])
    >>> stitch_tiles(o, 2).astype(int)[::2, ::2].tolist()   # every other cell
    [[0, 0, 1], [0, 0, 1], [2, 2, 3]]
    """
    s = outputs.shape[-1]
    h, q = s // 2, s // 4
    out = np.empty(((count + 1) * h, (count + 1) * h), np.float32)
    for i in range(count):
        r0 = 0 if i == 0 else i * h + q          # rows of the stitched grid kept ...
        r1 = (count + 1) * h if i == count - 1 else i * h + q + h
        for j in range(count):
            c0 = 0 if j == 0 else j * h + q
            c1 = (count + 1) * h if j == count - 1 else j * h + q + h
            out[r0:r1, c0:c1] = outputs[i * count + j][r0 - i * h:r1 - i * h,
                                                       c0 - j * h:c1 - j * h]
    return out

