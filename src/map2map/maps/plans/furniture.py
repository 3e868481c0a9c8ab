"""Furniture of a procedural floor plan (step 6 of :mod:`map2map.maps.floorplan`).

Beds, wardrobes, sofas, counters, desks, tables and columns are occupied blocks
drawn per room category (:data:`_FURNITURE`); a wall item stands flush against
one wall, a free-standing one keeps away from walls, every side either touches
an obstacle or leaves at least 0.5 m free (no slot narrower than the robot), and
no block stands within 1.1 m of a door.

Examples
--------
>>> import numpy as np
>>> from map2map.maps.plans.layout import _Builder, _Room
>>> from map2map.maps.plans.raster import _rasterise
>>> b = _Builder(np.random.default_rng(2), res=0.05, t_in=2, t_out=4)
>>> rooms = [_Room(0, 0, 100, 80, "Bedroom")]
>>> data = _rasterise(b, rooms, [], [], (90, 110), margin=5)
>>> placed = _furnish(b, data, rooms, [], margin=5)
>>> [p["kind"] for p in placed]
['bed', 'wardrobe']
"""

from __future__ import annotations

import numpy as np

from ...core.grid import FREE, OCCUPIED
from .doors import _door_zone
from .layout import _Builder, px_ceil

_FURNITURE = {
    # label: list of (name, along-wall length range m, depth range m, against wall?)
    "Bedroom": [
        ("bed", (1.4, 1.8), (1.9, 2.1), True),
        ("wardrobe", (1.0, 2.0), (0.55, 0.65), True),
    ],
    "Living_Room": [
        ("sofa", (1.8, 2.6), (0.85, 1.0), True),
        ("cabinet", (1.0, 2.0), (0.4, 0.5), True),
        ("table", (0.8, 1.4), (0.8, 1.0), False),
    ],
    "Kitchen": [
        ("counter", (1.5, 3.0), (0.6, 0.65), True),
        ("table", (0.8, 1.2), (0.7, 0.9), False),
    ],
    "Dining_Room": [
        ("table", (1.2, 1.8), (0.8, 1.0), False),
        ("cabinet", (1.0, 1.6), (0.4, 0.5), True),
    ],
    "Office": [
        ("desk", (1.4, 1.6), (0.7, 0.8), True),
        ("desk", (1.4, 1.6), (0.7, 0.8), True),
        ("cabinet", (0.8, 1.2), (0.4, 0.5), True),
    ],
    "Meeting_Room": [
        ("table", (2.0, 3.5), (1.0, 1.4), False),
        ("cabinet", (1.0, 1.6), (0.4, 0.5), True),
    ],
    "Lobby": [("counter", (1.5, 2.5), (0.6, 0.8), True), ("column", (0.4, 0.5), (0.4, 0.5), False)],
    "Storage": [("shelf", (0.8, 1.6), (0.4, 0.5), True)],
}


def _furnish(b: _Builder, data: np.ndarray, rooms, links, margin: int) -> list[dict]:
    """Place furniture blocks in ``data`` (in place); return what was placed.

    A wall item (bed, wardrobe, desk...) stands flush against one wall of its
    room, its ``along`` side parallel to that wall; a free-standing item (table,
    column) keeps away from walls. Every side of a block either touches a
    wall/another block or leaves at least 0.5 m free, so no pocket narrower
    than the robot appears, and no block stands within 1.1 m of a door.
    """
    rng = b.rng
    clear = px_ceil(0.5, b.res)
    blocked = np.zeros(data.shape, bool)
    o = margin
    for lk in links:
        x0, y0, x1, y1 = _door_zone(lk, b, b.px(1.1))
        blocked[max(0, o + y0) : o + y1, max(0, o + x0) : o + x1] = True
    placed = []
    for k, r in enumerate(rooms):
        items = list(_FURNITURE.get(r.label, []))
        if r.label in ("Office", "Lobby") and r.area * b.res**2 >= 35:
            items += [("column", (0.4, 0.5), (0.4, 0.5), False)] * 2
        # the room's free box before outer walls; clipped to what is free below
        fx0, fy0 = o + r.x0 + b.hi, o + r.y0 + b.hi
        fx1, fy1 = o + r.x1 - b.lo, o + r.y1 - b.lo
        for name, along_m, depth_m, wall in items:
            if rng.random() < 0.2:
                continue
            for _ in range(12):
                along, depth = b.uniform_px(*along_m), b.uniform_px(*depth_m)
                side = int(rng.integers(4))  # 0 top, 1 bottom, 2 left, 3 right wall
                iw, ih = (along, depth) if side < 2 else (depth, along)
                if fx1 - fx0 < iw + 2 or fy1 - fy0 < ih + 2:
                    continue
                x = int(rng.integers(fx0, fx1 - iw + 1))
                y = int(rng.integers(fy0, fy1 - ih + 1))
                if wall:
                    x, y = _push(data, x, y, iw, ih, side)
                x, y = _close_gaps(data, x, y, iw, ih, clear)
                box = (x, y, x + iw, y + ih)
                if not _fits(data, blocked, *box, clear):
                    continue
                data[box[1] : box[3], box[0] : box[2]] = OCCUPIED
                blocked[max(0, y - clear) : box[3] + clear, max(0, x - clear) : box[2] + clear] = 1
                placed.append({"kind": name, "room": k, "px": box})
                break
    return placed


def _gaps(data, x, y, iw, ih) -> tuple[int, int, int, int]:
    """Free cells between the box and the first obstacle: left, right, up, down (mid-lines)."""
    h, w = data.shape
    row = data[min(max(y + ih // 2, 0), h - 1)]
    col = data[:, min(max(x + iw // 2, 0), w - 1)]
    return (
        _run(row[: max(x, 0)][::-1]),
        _run(row[x + iw :]),
        _run(col[: max(y, 0)][::-1]),
        _run(col[y + ih :]),
    )


def _push(data, x, y, iw, ih, side) -> tuple[int, int]:
    """Slide the box until it touches the wall on ``side`` (0 top, 1 bottom, 2 left, 3 right)."""
    left, right, up, down = _gaps(data, x, y, iw, ih)
    if side == 0:
        return x, y - up
    if side == 1:
        return x, y + down
    if side == 2:
        return x - left, y
    return x + right, y


def _close_gaps(data, x, y, iw, ih, clear) -> tuple[int, int]:
    """Slide the box flush against any obstacle closer than ``clear`` (no narrow slots)."""
    left, right, up, down = _gaps(data, x, y, iw, ih)
    if 0 < left < clear:
        x -= left
    elif 0 < right < clear:
        x += right
    if 0 < up < clear:
        y -= up
    elif 0 < down < clear:
        y += down
    return x, y


def _run(values: np.ndarray) -> int:
    """Number of leading FREE values."""
    nz = np.flatnonzero(values != FREE)
    return int(nz[0]) if nz.size else int(values.size)


def _fits(data, blocked, x0, y0, x1, y1, clear) -> bool:
    """The box is free and each side either touches non-free cells or has ``clear`` free around."""
    h, w = data.shape
    if x0 < 1 or y0 < 1 or x1 > w - 1 or y1 > h - 1:
        return False
    if x0 < 0 or y0 < 0 or x1 > w or y1 > h:
        return False
    if (data[y0:y1, x0:x1] != FREE).any() or blocked[y0:y1, x0:x1].any():
        return False
    sides = (
        (slice(y0, y1), slice(max(0, x0 - clear), x0), slice(y0, y1), slice(x0 - 1, x0)),
        (slice(y0, y1), slice(x1, x1 + clear), slice(y0, y1), slice(x1, x1 + 1)),
        (slice(max(0, y0 - clear), y0), slice(x0, x1), slice(y0 - 1, y0), slice(x0, x1)),
        (slice(y1, y1 + clear), slice(x0, x1), slice(y1, y1 + 1), slice(x0, x1)),
    )
    flush = [bool((data[nr, nc] != FREE).all()) for _, _, nr, nc in sides]
    if (flush[0] and flush[1]) or (flush[2] and flush[3]):
        return False  # wall to wall: it would cut the room in two
    ys = (slice(max(0, y0 - clear), y0), slice(y1, y1 + clear))  # above, below
    xs = (slice(max(0, x0 - clear), x0), slice(x1, x1 + clear))  # left, right
    # corners between two open sides must be open too (no wall corner closing a slot)
    corners = [(ys[v], xs[u]) for v in (0, 1) for u in (0, 1) if not flush[2 + v] and not flush[u]]
    bands = [(s[0], s[1]) for s, touching in zip(sides, flush, strict=True) if not touching]
    for br, bc in bands + corners:
        band = data[br, bc]
        if band.size == 0 or (band != FREE).any() or blocked[br, bc].any():
            return False
    return True
