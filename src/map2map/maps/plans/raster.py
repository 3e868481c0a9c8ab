"""Raster of a procedural floor plan (steps 3 and 5 of :mod:`map2map.maps.floorplan`).

Notches cut a corner off a corner room (:func:`_notches`); :func:`_rasterise`
draws the layout on the canvas: interior walls centred on room boundaries,
outer walls inside the outline, everything outside the building unknown.

Examples
--------
>>> import numpy as np
>>> from map2map.maps.plans.layout import _Builder, _Room
>>> b = _Builder(np.random.default_rng(0), res=0.05, t_in=2, t_out=4)
>>> data = _rasterise(b, [_Room(0, 0, 40, 30)], [], [], (40, 50), margin=5)
>>> int((data == 255).sum()), int((data == 0).sum()), int((data == 127).sum())
(704, 496, 800)
"""

from __future__ import annotations

import cv2
import numpy as np

from ...core.grid import FREE, OCCUPIED, UNKNOWN
from .doors import _door_zone
from .layout import _ROOM, _Builder


def _notches(b: _Builder, rooms, links, lx: int, ly: int) -> list[tuple[int, int, int, int]]:
    """Cut a rectangle off an outer corner of a corner room (at most two)."""
    rng = b.rng
    out: list[tuple[int, int, int, int]] = []
    if rng.random() > 0.35:
        return out
    zones = [_door_zone(lk, b, b.px(1.2)) for lk in links]
    order = rng.permutation(len(rooms))
    for k in order:
        r = rooms[k]
        if r.kind != _ROOM or r.label in ("Bathroom", "Toilet", "Storage"):
            continue
        at_x = 0 if r.x0 == 0 else (lx if r.x1 == lx else None)
        at_y = 0 if r.y0 == 0 else (ly if r.y1 == ly else None)
        if at_x is None or at_y is None or min(r.w, r.h) < b.px(3.0):
            continue
        nw = max(b.px(0.8), int(r.w * rng.uniform(0.2, 0.4)))
        nh = max(b.px(0.8), int(r.h * rng.uniform(0.2, 0.4)))
        x0, x1 = (r.x0, r.x0 + nw) if at_x == 0 else (r.x1 - nw, r.x1)
        y0, y1 = (r.y0, r.y0 + nh) if at_y == 0 else (r.y1 - nh, r.y1)
        if any(_overlap((x0, y0, x1, y1), z) for z in zones):
            continue
        out.append((x0, y0, x1, y1))
        if len(out) == 2 or rng.random() < 0.6:
            break
    return out


def _overlap(p, q) -> bool:
    return p[0] < q[2] and q[0] < p[2] and p[1] < q[3] and q[1] < p[3]


def _rasterise(b: _Builder, rooms, links, notches, shape, margin: int):
    """Occupancy data (canvas) of the layout: walls 0, rooms 255, outside 127."""
    hc, wc = shape
    building = np.zeros(shape, np.uint8)
    free = np.zeros(shape, np.uint8)
    o = margin
    for r in rooms:
        building[o + r.y0 : o + r.y1, o + r.x0 : o + r.x1] = 1
        free[o + r.y0 + b.hi : o + r.y1 - b.lo, o + r.x0 + b.hi : o + r.x1 - b.lo] = 1
    for lk in links:
        if lk.vertical:
            free[o + lk.s0 : o + lk.s1, o + lk.pos - b.lo : o + lk.pos + b.hi] = 1
        else:
            free[o + lk.pos - b.lo : o + lk.pos + b.hi, o + lk.s0 : o + lk.s1] = 1
    for x0, y0, x1, y1 in notches:
        building[o + y0 : o + y1, o + x0 : o + x1] = 0
    kernel = np.ones((2 * b.t_out + 1, 2 * b.t_out + 1), np.uint8)
    inner = cv2.erode(building, kernel, borderType=cv2.BORDER_CONSTANT, borderValue=0)
    data = np.full(shape, UNKNOWN, np.uint8)
    data[building.astype(bool)] = OCCUPIED
    data[(free & inner).astype(bool)] = FREE
    return data
