"""HouseExpo-style irregular floor plans: solid blocks, slanted corners, slit walls.

HouseExpo (Li et al., 2019) draws a plan as ONE polygon of free space; everything
else inside its bounding box is occupied, so a plan is mostly *solid* occupied
blocks with thin interior walls (slits of the polygon) and a few slanted walls.
Such plans defeated an alignment that scored occupied cells (a solid block lies on
another at any scale, issue 11); :func:`irregular_plan` makes them without the
HouseExpo data: rooms as a chain of rectangles sharing walls, one or two corners
cut at 45 degrees, a doorway in every shared wall, the rest of the bounding box
occupied and unknown around it.
"""

from __future__ import annotations

import cv2
import numpy as np

from ..core.grid import FREE, OCCUPIED, UNKNOWN

__all__ = ["irregular_plan"]


def irregular_plan(seed: int | np.random.Generator = 0, resolution: float = 0.05) -> np.ndarray:
    """A HouseExpo-style plan (uint8: occupied 0, free 255, unknown 127).

    Parameters
    ----------
    seed : int or numpy.random.Generator
        The only source of randomness: the same seed gives the same bytes.
    resolution : float
        Metres per pixel.

    Returns
    -------
    numpy.ndarray
        The plan, a few pixels of unknown around its bounding box.

    Examples
    --------
    >>> plan = irregular_plan(0)
    >>> plan.dtype, sorted(set(plan.ravel().tolist()))
    (dtype('uint8'), [0, 127, 255])
    >>> bool((irregular_plan(0) == plan).all())
    True
    """
    from shapely.geometry import Polygon, box
    from shapely.ops import unary_union

    rng = np.random.default_rng(seed)

    def px(m: float) -> float:
        return m / resolution

    rooms = []
    x, y = 0.0, 0.0
    for _ in range(rng.integers(4, 8)):
        w, h = rng.uniform(2.5, 6.0, 2)
        rooms.append(box(px(x), px(y), px(x + w), px(y + h)))
        if rng.random() < 0.5:
            x += w
            y += rng.uniform(-0.3, 0.3) * h
        else:
            y += h
            x += rng.uniform(-0.3, 0.3) * w
    free = unary_union(rooms)
    # a diagonal corner or two (bay windows, HouseExpo's slanted walls)
    for _ in range(rng.integers(1, 3)):
        x0, y0, x1, y1 = free.bounds
        cx, cy = rng.choice([x0, x1]), rng.choice([y0, y1])
        d = px(rng.uniform(1.0, 2.5))
        sx, sy = (1 if cx == x0 else -1), (1 if cy == y0 else -1)
        free = free.difference(Polygon([(cx, cy), (cx + sx * d, cy), (cx, cy + sy * d)]))
    if free.geom_type != "Polygon":
        free = max(free.geoms, key=lambda g: g.area)
    x0, y0, x1, y1 = free.bounds
    pad = 10
    W, H = int(x1 - x0) + 2 * pad, int(y1 - y0) + 2 * pad
    shift = np.array([pad - x0, pad - y0])
    data = np.full((H, W), UNKNOWN, np.uint8)
    data[pad - 3 : H - pad + 3, pad - 3 : W - pad + 3] = OCCUPIED  # bounding box: occupied
    ring = (np.asarray(free.exterior.coords) + shift).round().astype(np.int32)
    cv2.fillPoly(data, [ring], FREE)
    for hole in free.interiors:
        cv2.fillPoly(data, [(np.asarray(hole.coords) + shift).round().astype(np.int32)], OCCUPIED)
    # slit interior walls: each room's outline inside the free space, with a doorway
    inner = free.buffer(-2.0)
    for room in rooms[1:]:
        seg = room.exterior.intersection(inner)
        for line in getattr(seg, "geoms", [seg]):
            if line.is_empty or line.geom_type != "LineString":
                continue
            c = np.asarray(line.coords) + shift
            for p, q in zip(c[:-1], c[1:], strict=True):
                L = float(np.hypot(*(q - p)))
                if L < px(1.2):
                    continue
                t0 = rng.uniform(0.1, 0.9 - px(0.9) / L)
                t1 = t0 + px(0.9) / L
                for u, v in ((0.0, t0), (t1, 1.0)):
                    a_ = (p + u * (q - p)).round().astype(int)
                    b_ = (p + v * (q - p)).round().astype(int)
                    cv2.line(data, tuple(map(int, a_)), tuple(map(int, b_)), OCCUPIED, 2)
    return data
