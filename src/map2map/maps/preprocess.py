"""Preprocessing of CAD and SLAM maps for learning (thesis section 4.1).

Before training, the thesis processed every CAD/SLAM image pair by

1. squaring and resizing to 256 x 256 (uniform dataset size),
2. changing the CAD pixel values to the SLAM ones (only deformations matter,
   not colour differences),
3. thickening the occupied edges of the CAD maps (thick walls survive the
   progressive, low-resolution-first architecture),
4. cropping the CAD maps to have less grey (unknown) area.

Each step is one function here, on an :class:`~map2map.core.grid.OccupancyMap`
(the metric frame stays right: resolution and origin are updated so every cell
keeps its world position) or on a bare ``uint8`` array; :func:`preprocess`
chains them.

Examples
--------
>>> import numpy as np
>>> from map2map.core.grid import OccupancyMap
>>> data = np.full((60, 120), 255, np.uint8)
>>> data[:, 59] = 0                                   # a 1-pixel wall
>>> out = preprocess(OccupancyMap(data, 0.05), size=32)
>>> out.shape, round(out.resolution, 4), bool((out.data == 0).any())
((32, 32), 0.1875, True)
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import cv2
import numpy as np

from ..core.errors import InputError
from ..core.grid import FREE, OCCUPIED, UNKNOWN, OccupancyMap

__all__ = [
    "wall_thickness_px",
    "MARGIN_PX",
    "ContentSquare",
    "content_square",
    "reduce_plan",
    "square_resize",
    "harmonise",
    "thicken",
    "crop_to_content",
    "preprocess",
    "save_preprocess_figure",
]

#: Grey values that mean "unknown" in the formats we meet: thesis/SLAM 127,
#: HouseExpo render canvas 128, ROS map_saver 205.
UNKNOWN_CODES = (127, 128, 205)


def _as_map(m: OccupancyMap | np.ndarray, what: str) -> tuple[OccupancyMap, bool]:
    if isinstance(m, OccupancyMap):
        return m, False
    arr = np.asarray(m)
    if arr.ndim != 2 or arr.dtype != np.uint8:
        raise InputError(
            what, f"expected a 2-D uint8 map, got {arr.dtype} array of shape {arr.shape}"
        )
    try:
        return OccupancyMap(arr, 1.0), True
    except ValueError as exc:
        raise InputError(what, f"{exc} (run harmonise() first)") from None


def _check_int(value, name: str, minimum: int) -> int:
    try:
        iv = int(value)
    except (TypeError, ValueError):
        raise InputError(name, f"{name} must be an integer, got {value!r}") from None
    if iv != value or iv < minimum:
        raise InputError(name, f"{name} must be an integer >= {minimum}, got {value!r}")
    return iv


def harmonise(
    m: OccupancyMap | np.ndarray,
    *,
    occupied_below: int = 64,
    free_above: int = 191,
    unknown_values: tuple[int, ...] = UNKNOWN_CODES,
) -> OccupancyMap | np.ndarray:
    """CAD pixel values -> SLAM values: occupied 0, unknown 127, free 255.

    Grey, RGB or RGBA images are accepted (colour is averaged; fully
    transparent pixels become unknown). The exact codes in ``unknown_values``
    (HouseExpo's 128 canvas, ROS's 205) become unknown; the rest is
    thresholded: ``<= occupied_below`` occupied, ``>= free_above`` free,
    anything between (anti-aliasing, grey canvases) unknown.

    Returns the same kind of object it was given (an OccupancyMap is returned
    as a copy, its frame unchanged).

    Parameters
    ----------
    m : OccupancyMap or ndarray
        A map, or an image (H, W), (H, W, 3) or (H, W, 4) of any integer values.
    occupied_below : int
        Values ``<=`` this are occupied.
    free_above : int
        Values ``>=`` this are free.
    unknown_values : tuple of int
        Exact codes that mean unknown.

    Returns
    -------
    OccupancyMap or (H, W) uint8 array
        Same kind as ``m``, values 0, 127, 255 only.

    Examples
    --------
    >>> harmonise(np.array([[0, 30, 128, 205, 230, 255]], np.uint8)).tolist()
    [[0, 0, 127, 127, 255, 255]]
    """
    if isinstance(m, OccupancyMap):
        return m.copy()
    arr = np.asarray(m)
    transparent = None
    if arr.ndim == 3 and arr.shape[2] in (3, 4):
        if arr.shape[2] == 4:
            transparent = arr[..., 3] == 0
        scale = 255.0 if arr.dtype.kind == "f" and arr.max(initial=0) <= 1.0 else 1.0
        grey = np.rint(arr[..., :3].astype(float).mean(axis=2) * scale)
    elif arr.ndim == 2:
        scale = 255.0 if arr.dtype.kind == "f" and arr.max(initial=0) <= 1.0 else 1.0
        grey = np.rint(arr.astype(float) * scale)
    else:
        raise InputError("image", f"expected a grey, RGB or RGBA image, got shape {arr.shape}")
    if not 0 <= occupied_below < free_above <= 255:
        raise InputError(
            "thresholds",
            f"need 0 <= occupied_below < free_above <= 255, got {occupied_below}, {free_above}",
        )
    grey = np.clip(grey, 0, 255)
    out = np.full(grey.shape, UNKNOWN, np.uint8)
    out[grey <= occupied_below] = OCCUPIED
    out[grey >= free_above] = FREE
    out[np.isin(grey, unknown_values)] = UNKNOWN
    if transparent is not None:
        out[transparent] = UNKNOWN
    return out


def square_resize(m: OccupancyMap | np.ndarray, size: int = 256) -> OccupancyMap | np.ndarray:
    """Pad to a square with unknown (content centred), then resize to ``size x size``.

    The aspect ratio is kept (padding, never stretching). Downscaling is done
    per class: the fraction of occupied, free and unknown input pixels under
    each output pixel is computed with area interpolation, and a pixel is
    occupied when its occupied fraction reaches ``0.5 / f`` (``f`` input
    pixels per output pixel) -- the share a 1-pixel wall always leaves in at
    least one output pixel, so thin walls survive any reduction. Otherwise
    the majority of free vs unknown wins. Upscaling is nearest-neighbour.
    Values stay in {0, 127, 255}.

    The resolution becomes ``resolution * side / size`` and the origin is the
    padded square's lower-left corner, so each world point keeps its content.

    Parameters
    ----------
    m : OccupancyMap or (H, W) uint8 array
        Map values in {0, 127, 255}.
    size : int
        Output side in pixels.

    Returns
    -------
    OccupancyMap or (size, size) uint8 array
        Same kind as ``m``.

    Examples
    --------
    >>> m = OccupancyMap(np.full((50, 100), 255, np.uint8), 0.1)
    >>> s = square_resize(m, 64)
    >>> s.shape, s.resolution, s.origin
    ((64, 64), 0.15625, (0.0, -2.5, 0.0))
    """
    m, bare = _as_map(m, "map")
    size = _check_int(size, "size", 1)
    h, w = m.shape
    side = max(h, w)
    top, left = (side - h) // 2, (side - w) // 2
    sq = m.pad(top=top, bottom=side - h - top, left=left, right=side - w - left)
    f = side / size
    if f <= 1.0:
        data = cv2.resize(sq.data, (size, size), interpolation=cv2.INTER_NEAREST)
    else:
        frac = {
            v: cv2.resize(
                (sq.data == v).astype(np.float32), (size, size), interpolation=cv2.INTER_AREA
            )
            for v in (OCCUPIED, FREE, UNKNOWN)
        }
        data = np.where(frac[FREE] >= frac[UNKNOWN], FREE, UNKNOWN).astype(np.uint8)
        data[frac[OCCUPIED] >= 0.5 / f - 1e-6] = OCCUPIED
    out = sq.copy(data=data, resolution=sq.resolution * f)
    return out.data if bare else out


def thicken(m: OccupancyMap | np.ndarray, k: int, *, into_unknown: bool = False):
    """Thicken occupied edges by ``k`` pixels (square dilation, thesis sec. 4.1).

    Walls grow by ``k`` pixels on each side into free space. By default they do
    not grow into unknown cells, so the building outline and the unknown
    outside stay where they were (``into_unknown=True`` grows everywhere).

    Parameters
    ----------
    m : OccupancyMap or (H, W) uint8 array
        Map values in {0, 127, 255}.
    k : int
        Pixels added on each side of every wall (0: unchanged).
    into_unknown : bool
        Let walls grow into unknown cells too.

    Returns
    -------
    OccupancyMap or (H, W) uint8 array
        Same kind as ``m``.

    Examples
    --------
    >>> a = np.full((5, 9), 255, np.uint8); a[:, 4] = 0
    >>> (thicken(a, 1) == 0).sum(axis=1).tolist()
    [3, 3, 3, 3, 3]
    """
    m, bare = _as_map(m, "map")
    k = _check_int(k, "thicken", 0)
    if k == 0:
        out = m.copy()
    else:
        kernel = np.ones((2 * k + 1, 2 * k + 1), np.uint8)
        grown = cv2.dilate(m.occupied.astype(np.uint8), kernel).astype(bool)
        if not into_unknown:
            grown &= ~m.unknown
        data = m.data.copy()
        data[grown] = OCCUPIED
        out = m.copy(data=data)
    return out.data if bare else out


def crop_to_content(m: OccupancyMap | np.ndarray, margin_px: int = 0):
    """Crop to the known (non-unknown) cells plus ``margin_px`` unknown pixels around.

    The margin is exact: the map is padded with unknown where the content is
    closer to the border than ``margin_px``. The origin moves so every kept
    cell stays at its world position. An all-unknown map is returned unchanged.

    Parameters
    ----------
    m : OccupancyMap or (H, W) uint8 array
        Map values in {0, 127, 255}.
    margin_px : int
        Unknown pixels kept (or added) around the known cells.

    Returns
    -------
    OccupancyMap or ndarray
        Same kind as ``m``.

    Examples
    --------
    >>> m = OccupancyMap(np.full((100, 100), 127, np.uint8), 0.1)
    >>> m.data[40:50, 20:30] = 255
    >>> c = crop_to_content(m, 2)
    >>> c.shape, np.round(c.origin, 6).tolist()
    ((14, 14), [1.8, 4.8, 0.0])
    """
    m, bare = _as_map(m, "map")
    margin_px = _check_int(margin_px, "margin", 0)
    box = m.content_bbox()
    if box is None:
        out = m.copy()
    else:
        r0, r1, c0, c1 = box
        h, w = m.shape
        out = m.crop(max(0, r0 - margin_px), min(h, r1 + margin_px),
                     max(0, c0 - margin_px), min(w, c1 + margin_px))  # fmt: skip
        out = out.pad(
            top=max(0, margin_px - r0),
            bottom=max(0, r1 + margin_px - h),
            left=max(0, margin_px - c0),
            right=max(0, c1 + margin_px - w),
        )
    return out.data if bare else out


def preprocess(
    m: OccupancyMap | np.ndarray,
    size: int = 256,
    thicken: int = 0,  # noqa: F811 - the argument shadows the function on purpose (CLI name)
    crop: bool = False,
    margin: int = 4,
) -> OccupancyMap | np.ndarray:
    """The thesis sec. 4.1 preprocessing chain: values, (crop), square + resize, thicken.

    1. :func:`harmonise` -- pixel values to SLAM values (a no-op on maps);
    2. :func:`crop_to_content` with ``margin`` pixels, when ``crop`` -- the
       thesis crops the grey area away as its last cleaning step; here it comes
       before squaring so the output stays ``size x size``;
    3. :func:`square_resize` to ``size``;
    4. :func:`thicken` occupied edges by ``thicken`` output pixels.

    Parameters
    ----------
    m : OccupancyMap or ndarray
        A map, or a CAD picture's pixel values.
    size : int
        Output side in pixels (the thesis uses 256).
    thicken : int
        Wall thickening in output pixels (0: none).
    crop : bool
        Crop to the known cells first.
    margin : int
        Unknown margin in pixels kept when cropping.

    Returns
    -------
    OccupancyMap or (size, size) uint8 array
        Same kind as ``m``.

    Examples
    --------
    >>> from map2map.maps.floorplan import generate_floorplan
    >>> p = preprocess(generate_floorplan(1, size=(12, 8)), size=128, thicken=1, crop=True)
    >>> p.shape, sorted(np.unique(p.data).tolist())
    ((128, 128), [0, 127, 255])
    """
    bare = not isinstance(m, OccupancyMap)
    size = _check_int(size, "size", 1)
    k = _check_int(thicken, "thicken", 0)
    margin = _check_int(margin, "margin", 0)
    out = harmonise(m)
    if bare:
        out = OccupancyMap(out, 1.0)
    if crop:
        out = crop_to_content(out, margin)
    out = square_resize(out, size)
    out = _thicken(out, k)
    return out.data if bare else out


_thicken = thicken


def save_preprocess_figure(
    before: OccupancyMap, after: OccupancyMap, path, title: str | None = None
) -> None:
    """Side-by-side figure of a map before and after :func:`preprocess` (atomic save).

    Parameters
    ----------
    before, after : OccupancyMap
        The input and output of :func:`preprocess`.
    path : path-like
        Output figure; the format comes from the suffix.
    title : str, optional
        Figure title.

    Examples
    --------
    >>> import tempfile, pathlib
    >>> m = OccupancyMap(np.full((40, 80), 255, np.uint8), 0.05)
    >>> path = pathlib.Path(tempfile.mkdtemp()) / "prep.png"
    >>> save_preprocess_figure(m, preprocess(m, size=32), path)
    >>> path.stat().st_size > 0
    True
    """
    from ..core.viz import draw_map, new_figure, save_figure
    from .render import map_summary

    fig, axes = new_figure(before, ncols=2)
    draw_map(axes[0], before, title=f"input\n{map_summary(before)}")
    draw_map(axes[1], after, title=f"preprocessed\n{map_summary(after)}")
    if title:
        fig.suptitle(title, fontsize=11)
    save_figure(fig, path)


#: Largest side (pixels) the demo runs the model at.
MAX_SIDE = 320


def reduce_plan(plan: OccupancyMap, max_side: int = MAX_SIDE) -> OccupancyMap:
    """Reduce a plan by the smallest integer factor that fits ``max_side``.

    A reduced cell is occupied if any of its pixels is, else free if any is free, else
    unknown, so that walls and doors survive.

    Parameters
    ----------
    plan : OccupancyMap
        The plan.
    max_side : int
        Largest side, pixels, of the result.

    Returns
    -------
    OccupancyMap
        ``plan`` itself when it already fits, else the reduced copy (resolution times
        the factor, same origin).

    Examples
    --------
    >>> m = OccupancyMap(np.full((700, 500), 255, np.uint8), 0.05)
    >>> r = reduce_plan(m)
    >>> r.shape, round(r.resolution, 9)
    ((234, 167), 0.15)
    """
    f = int(np.ceil(max(plan.shape) / max_side))
    if f <= 1:
        return plan
    h, w = plan.shape
    hh, ww = -(-h // f) * f, -(-w // f) * f
    data = np.full((hh, ww), UNKNOWN, np.uint8)
    data[hh - h :, :w] = plan.data  # pad at the top/right so the origin corner stays put
    blocks = data.reshape(hh // f, f, ww // f, f)
    occ = (blocks == OCCUPIED).any(axis=(1, 3))
    free = (blocks == FREE).any(axis=(1, 3))
    out = np.full(occ.shape, UNKNOWN, np.uint8)
    out[free] = FREE
    out[occ] = OCCUPIED
    return OccupancyMap(out, plan.resolution * f, plan.origin, dict(plan.meta))


#: Crop margin, pixels at the dataset's size (``learn.training.synthetic``, ``dataset build``).
MARGIN_PX = 4


@dataclass
class ContentSquare:
    """The known part of a map padded to a square, as the dataset crops its maps.

    ``data`` is the ``side x side`` square (unknown outside the map); its top-left pixel is
    the map's pixel (``row0``, ``col0``), which may lie outside the map (negative)."""

    data: np.ndarray
    row0: int
    col0: int
    side: int


def content_square(m: OccupancyMap, data_size: int) -> ContentSquare | None:
    """The map's content box plus a margin of :data:`MARGIN_PX` pixels at the dataset's
    size ``data_size``, padded to a square with unknown cells and centred on the content
    (the crop the dataset build makes); None for a map without known cells.

    Examples
    --------
    >>> from map2map.core.grid import OccupancyMap
    >>> d = np.full((50, 80), UNKNOWN, np.uint8); d[10:20, 10:70] = FREE
    >>> sq = content_square(OccupancyMap(d, 0.05), 256)
    >>> sq.side, sq.row0, sq.col0, sq.data.shape
    (62, -16, 9, (62, 62))
    """
    bbox = m.content_bbox()
    if bbox is None:
        return None
    r0, r1, c0, c1 = bbox
    side = max(r1 - r0, c1 - c0)
    margin = math.ceil(MARGIN_PX * side / max(1, data_size - 2 * MARGIN_PX))
    side += 2 * margin
    row0 = r0 - (side - (r1 - r0)) // 2
    col0 = c0 - (side - (c1 - c0)) // 2
    sq = np.full((side, side), UNKNOWN, np.uint8)
    H, W = m.shape
    rs, re = max(0, row0), min(H, row0 + side)
    cs, ce = max(0, col0), min(W, col0 + side)
    sq[rs - row0:re - row0, cs - col0:ce - col0] = m.data[rs:re, cs:ce]
    return ContentSquare(sq, row0, col0, side)


def wall_thickness_px(maps: np.ndarray, limit: int = 64) -> float:
    """Median wall thickness (pixels) of ternary maps: occupied area / centre-line length.

    Examples
    --------
    >>> m = np.full((1, 40, 40), 255, np.uint8); m[0, 10:13, 5:35] = 0
    >>> round(wall_thickness_px(m), 1)       # a 3-px wall (its centre line is a bit short)
    3.1
    """
    from skimage.morphology import skeletonize

    out = []
    for m in np.asarray(maps)[:limit]:
        occ = m == OCCUPIED
        skel = skeletonize(occ).sum()
        if skel:
            out.append(occ.sum() / skel)
    return float(np.median(out)) if out else 1.0
