"""Room layout of a procedural floor plan: the building outline tiled with rooms.

Steps 1-3 of :mod:`map2map.maps.floorplan` (outline, rooms, irregular outline):
a :class:`_Builder` holds the pixel scale and the one random generator while
an office (corridor spine or ring around a core band) or an apartment (living
zone + hallway, or recursive splitting) is cut into axis-aligned ``_Room``
boxes carrying HouseExpo ``room_category`` names. Coordinates are pixels of
the building interior, ``[0, lx) x [0, ly)``, y down (array rows).

Examples
--------
>>> import numpy as np
>>> b = _Builder(np.random.default_rng(0), res=0.05, t_in=2, t_out=5)
>>> rooms = b.office(400, 240)
>>> len(rooms) > 5, sum(r.area for r in rooms) == 400 * 240
(True, True)
>>> sorted({r.kind for r in rooms})
['corridor', 'room']
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

#: Building kinds the generator knows.
KINDS = ("apartment", "office")

#: Random size ranges ((W min, W max), (H min, H max)) in metres when ``size`` is None.
SIZE_RANGES = {"apartment": ((6.0, 17.0), (6.0, 13.0)), "office": ((12.0, 30.0), (8.0, 20.0))}

#: Typical wall thickness ranges in metres: interior, outer.
INTERIOR_WALL = (0.10, 0.15)
OUTER_WALL = (0.20, 0.30)

DOOR_WIDTH = (0.70, 1.00)
MIN_SIZE_M = 4.0
MAX_PIXELS = 40_000_000
ROBOT_RADIUS = 0.2

_CORRIDOR = "corridor"
_ROOM = "room"


# --------------------------------------------------------------------------- rooms
@dataclass
class _Room:
    x0: int
    y0: int
    x1: int
    y1: int
    label: str = "Room"
    kind: str = _ROOM

    @property
    def w(self) -> int:
        return self.x1 - self.x0

    @property
    def h(self) -> int:
        return self.y1 - self.y0

    @property
    def area(self) -> int:
        return self.w * self.h


def _shared(a: _Room, b: _Room):
    """(vertical, pos, o0, o1) of the boundary shared by two rooms, or None."""
    if a.x1 == b.x0 or b.x1 == a.x0:
        o0, o1 = max(a.y0, b.y0), min(a.y1, b.y1)
        if o1 > o0:
            return True, (a.x1 if a.x1 == b.x0 else a.x0), o0, o1
    if a.y1 == b.y0 or b.y1 == a.y0:
        o0, o1 = max(a.x0, b.x0), min(a.x1, b.x1)
        if o1 > o0:
            return False, (a.y1 if a.y1 == b.y0 else a.y0), o0, o1
    return None


class _Builder:
    """Holds the pixel scale and the random generator while a plan is laid out."""

    def __init__(self, rng: np.random.Generator, res: float, t_in: int, t_out: int):
        self.rng = rng
        self.res = res
        self.t_in = t_in
        self.t_out = t_out
        self.lo = t_in // 2  # interior wall pixels on the low side of a boundary
        self.hi = t_in - self.lo
        self.clear = t_out + max(1, self.px(0.05))  # door distance from segment ends
        self.door_min = math.ceil(DOOR_WIDTH[0] / res - 1e-9)
        self.door_max = max(self.door_min, math.floor(DOOR_WIDTH[1] / res + 1e-9))

    def px(self, metres: float) -> int:
        return int(round(metres / self.res))

    def uniform_px(self, lo_m: float, hi_m: float) -> int:
        return self.px(self.rng.uniform(lo_m, hi_m))

    # ------------------------------------------------------------ splitting
    def split_run(self, length: int, lo_m: float, hi_m: float) -> list[int]:
        """Cut ``length`` pixels into pieces of about ``lo_m..hi_m`` metres; return cut offsets."""
        lo, hi = self.px(lo_m), self.px(hi_m)
        cuts, at = [], 0
        while length - at > hi:
            step = int(self.rng.integers(lo, hi + 1))
            if length - at - step < lo:
                step = (length - at) // 2
            at += step
            cuts.append(at)
        return cuts

    def bsp(self, rect: _Room, n_target: int, min_side_m: float) -> list[_Room]:
        """Recursive splitting of ``rect`` into about ``n_target`` rooms (largest first)."""
        min_side = self.px(min_side_m)
        rooms = [rect]
        for _ in range(4 * n_target):
            if len(rooms) >= n_target:
                break
            order = sorted(range(len(rooms)), key=lambda i: -rooms[i].area)
            for i in order:
                r = rooms[i]
                can_x, can_y = r.w >= 2 * min_side, r.h >= 2 * min_side
                if not (can_x or can_y):
                    continue
                along_x = can_x and (not can_y or r.w >= r.h or self.rng.random() < 0.2)
                span = r.w if along_x else r.h
                frac = self.rng.uniform(0.33, 0.67)
                cut = int(np.clip(round(span * frac), min_side, span - min_side))
                if along_x:
                    a = _Room(r.x0, r.y0, r.x0 + cut, r.y1)
                    b = _Room(r.x0 + cut, r.y0, r.x1, r.y1)
                else:
                    a = _Room(r.x0, r.y0, r.x1, r.y0 + cut)
                    b = _Room(r.x0, r.y0 + cut, r.x1, r.y1)
                rooms[i : i + 1] = [a, b]
                break
            else:
                break
        return rooms

    # ------------------------------------------------------------ layouts
    def band_rooms(self, x0: int, x1: int, y0: int, y1: int, lo_m: float, hi_m: float):
        """Rooms side by side along x in the band ``[x0, x1) x [y0, y1)``."""
        edges = [x0] + [x0 + c for c in self.split_run(x1 - x0, lo_m, hi_m)] + [x1]
        return [_Room(a, y0, b, y1) for a, b in zip(edges[:-1], edges[1:], strict=True)]

    def office(self, lx: int, ly: int) -> list[_Room]:
        """Office rooms on ``[0, lx) x [0, ly)`` (long axis x): corridor spine or ring."""
        rng, px = self.rng, self.px
        cw = self.uniform_px(1.5, 2.2)
        depth_min = px(3.0)
        if ly < depth_min + cw or lx < px(8.0):
            # too small for a corridor: a few offices opening onto each other
            n = max(3, round(lx * ly * self.res**2 / 12))
            return self.label_office(self.bsp(_Room(0, 0, lx, ly), n, 2.0))
        # optional full-depth end rooms (lobby / large meeting room)
        xs, xe = 0, lx
        ends: list[_Room] = []
        if lx >= px(16.0) and rng.random() < 0.6:
            e = self.uniform_px(4.0, 7.0)
            if rng.random() < 0.5:
                ends.append(_Room(0, 0, e, ly, "Lobby"))
                xs = e
            else:
                ends.append(_Room(lx - e, 0, lx, ly, "Meeting_Room"))
                xe = lx - e
        rooms: list[_Room] = []
        if ly >= 2 * px(4.0) + 2 * cw + px(3.0) and xe - xs >= px(10.0):
            # two corridors around a core band, joined by cross corridors at its ends
            dmax = min(6.0, (ly * self.res - 2 * cw * self.res - 3.0) / 2)
            d1 = self.uniform_px(4.0, dmax)
            d2 = self.uniform_px(4.0, dmax)
            ya, yb = d1, ly - d2 - cw  # corridor tops
            rooms += [_Room(xs, ya, xe, ya + cw, "Hallway", _CORRIDOR)]
            rooms += [_Room(xs, yb, xe, yb + cw, "Hallway", _CORRIDOR)]
            rooms += self.band_rooms(xs, xe, 0, ya, 2.8, 5.0)
            rooms += self.band_rooms(xs, xe, yb + cw, ly, 2.8, 5.0)
            cy0, cy1 = ya + cw, yb
            crosses = [xs, xe - cw]
            if xe - xs >= px(24.0):
                crosses.insert(1, (xs + xe - cw) // 2)
            for k, cx in enumerate(crosses):
                rooms.append(_Room(cx, cy0, cx + cw, cy1, "Hallway", _CORRIDOR))
                if k + 1 < len(crosses):
                    rooms += self.band_rooms(cx + cw, crosses[k + 1], cy0, cy1, 2.5, 6.0)
        elif ly >= 2 * depth_min + cw:
            yc = int(rng.integers(depth_min, ly - depth_min - cw + 1))
            rooms.append(_Room(xs, yc, xe, yc + cw, "Hallway", _CORRIDOR))
            rooms += self.band_rooms(xs, xe, 0, yc, 2.6, 5.0)
            rooms += self.band_rooms(xs, xe, yc + cw, ly, 2.6, 5.0)
        else:
            yc = 0 if rng.random() < 0.5 else ly - cw
            rooms.append(_Room(xs, yc, xe, yc + cw, "Hallway", _CORRIDOR))
            y0, y1 = (cw, ly) if yc == 0 else (0, ly - cw)
            rooms += self.band_rooms(xs, xe, y0, y1, 2.6, 5.0)
        rooms = self.merge_open_plan(rooms)
        return self.refine(ends, 50.0, 3.0) + self.label_office(rooms)

    def merge_open_plan(self, rooms: list[_Room]) -> list[_Room]:
        """Sometimes merge neighbouring side rooms into one open-plan office."""
        out: list[_Room] = []
        for r in rooms:
            prev = out[-1] if out else None
            if (
                prev is not None
                and prev.kind == r.kind == _ROOM
                and prev.y0 == r.y0
                and prev.y1 == r.y1
                and prev.x1 == r.x0
                and prev.w + r.w <= self.px(11.0)
                and self.rng.random() < 0.18
            ):
                prev.x1 = r.x1
                prev.label = "Open_Office"
                continue
            out.append(r)
        return out

    def label_office(self, rooms: list[_Room]) -> list[_Room]:
        """Name office rooms: offices, small toilets/storage, a kitchen, a meeting room."""
        side = [r for r in rooms if r.kind == _ROOM and r.label in ("Room", "Open_Office")]
        if not side:
            return rooms
        m2 = self.res**2
        by_area = sorted(side, key=lambda r: r.area)
        for r in side:
            if r.label == "Open_Office":
                r.label = "Office"
                continue
            a = r.area * m2
            r.label = "Office" if a >= 9 else str(self.rng.choice(["Toilet", "Storage", "Office"]))
        if len(side) >= 4:
            by_area[-1].label = (
                "Meeting_Room" if by_area[-1].label == "Office" else by_area[-1].label
            )
            mid = by_area[len(by_area) // 2]
            mid.label = "Kitchen"
            if by_area[0].label not in ("Toilet", "Kitchen"):
                by_area[0].label = "Toilet"
        return rooms

    def apartment(self, lx: int, ly: int) -> list[_Room]:
        """Apartment rooms: living zone + hallway with private rooms, or recursive splitting."""
        rng, px = self.rng, self.px
        hw = self.uniform_px(1.0, 1.4)
        if lx >= px(8.0) and ly >= px(2.4) + hw and rng.random() < 0.65:
            lz = min(int(round(lx * rng.uniform(0.35, 0.5))), px(10.0))
            rooms = self.refine(self.living_zone(0, lz, ly), 45.0)
            # private zone with a hallway along x
            xe = lx
            end: list[_Room] = []
            if lx - lz >= px(9.0) and rng.random() < 0.5:
                e = self.uniform_px(3.0, 4.5)
                end = [_Room(lx - e, 0, lx, ly, "Bedroom")]
                xe = lx - e
            if ly >= 2 * px(2.4) + hw:
                lo_y = max(px(2.4), int(0.3 * (ly - hw)))
                yh = int(rng.integers(lo_y, ly - hw - lo_y + 1))
                bands = [(0, yh), (yh + hw, ly)]
            else:
                yh = 0 if rng.random() < 0.5 else ly - hw
                bands = [(hw, ly)] if yh == 0 else [(0, ly - hw)]
            rooms.append(_Room(lz, yh, xe, yh + hw, "Hallway", _CORRIDOR))
            private: list[_Room] = []
            for y0, y1 in bands:
                private += self.band_rooms(lz, xe, y0, y1, 2.0, 4.2)
            private = self.refine(private + end, 24.0)
            self.label_private(private)
            return rooms + private
        m2 = self.res**2
        n = int(np.clip(round(lx * ly * m2 / rng.uniform(10.0, 16.0)), 3, 12))
        rooms = self.refine(self.bsp(_Room(0, 0, lx, ly), n, 2.0), 40.0)
        by_area = sorted(rooms, key=lambda r: -r.area)
        compact = [r for r in by_area if max(r.w, r.h) < 2.5 * min(r.w, r.h)]
        living = compact[0] if compact else by_area[0]
        by_area.remove(living)
        by_area.insert(0, living)
        living.label = "Living_Room"
        rest = by_area[1:]
        for r in rest:
            r.label = "Bedroom"
        rest[-1].label = "Bathroom"
        if len(rest) >= 5 and rest[-2].area * m2 < 6.0:
            rest[-2].label = str(rng.choice(["Toilet", "Storage", "Bathroom"]))
        # the kitchen opens onto the living room: its neighbour closest to 10 m2
        near = [r for r in rest if r.label == "Bedroom" and _shared(living, r)]
        if len(rest) >= 3 and near:
            min(near, key=lambda r: abs(r.area * m2 - 10.0)).label = "Kitchen"
        for r in rest:
            thin = min(r.w, r.h) <= px(2.2) and max(r.w, r.h) >= 2.5 * min(r.w, r.h)
            if thin and r.label == "Bedroom":
                r.label, r.kind = "Hallway", _CORRIDOR
        return rooms

    def refine(self, rooms: list[_Room], max_area_m2: float, max_aspect: float = 2.6):
        """Split rooms that are too large or too elongated across their long side."""
        out: list[_Room] = []
        queue = list(rooms)
        min_side = self.px(2.2)
        while queue:
            r = queue.pop(0)
            long_side, short_side = max(r.w, r.h), min(r.w, r.h)
            too_big = r.area * self.res**2 > max_area_m2 or long_side > max_aspect * short_side
            if r.kind != _ROOM or not too_big or long_side < 2 * min_side:
                out.append(r)
                continue
            cut = int(np.clip(round(long_side * self.rng.uniform(0.4, 0.6)), min_side,
                              long_side - min_side))  # fmt: skip
            if r.w >= r.h:
                a, b = _Room(r.x0, r.y0, r.x0 + cut, r.y1), _Room(r.x0 + cut, r.y0, r.x1, r.y1)
            else:
                a, b = _Room(r.x0, r.y0, r.x1, r.y0 + cut), _Room(r.x0, r.y0 + cut, r.x1, r.y1)
            a.label = r.label
            b.label = {
                "Living_Room": "Office",
                "Kitchen": "Dining_Room",
                "Lobby": "Office",
                "Meeting_Room": "Office",
            }.get(r.label, r.label)
            queue[:0] = [a, b]
        return out

    def living_zone(self, x0: int, x1: int, ly: int) -> list[_Room]:
        """Living room plus kitchen (and dining room when there is space)."""
        rng, px = self.rng, self.px
        w = x1 - x0
        if w >= px(5.5) and rng.random() < 0.5:
            xs = x0 + int(round(w * rng.uniform(0.55, 0.68)))
            living = _Room(x0, 0, xs, ly, "Living_Room")
            ys = int(round(ly * rng.uniform(0.45, 0.6)))
            side = [_Room(xs, 0, x1, ys, "Kitchen"), _Room(xs, ys, x1, ly, "Dining_Room")]
            if ly < px(6.0):
                side = [_Room(xs, 0, x1, ly, "Kitchen")]
            return [living, *side]
        ys = int(round(ly * rng.uniform(0.55, 0.7)))
        living = _Room(x0, 0, x1, ys, "Living_Room")
        if w >= px(6.0):
            xs = x0 + int(round(w * rng.uniform(0.4, 0.6)))
            return [living, _Room(x0, ys, xs, ly, "Kitchen"), _Room(xs, ys, x1, ly, "Dining_Room")]
        return [living, _Room(x0, ys, x1, ly, "Kitchen")]

    def label_private(self, private: list[_Room]) -> None:
        """Name the rooms along an apartment hallway: bedrooms, the smallest as wet rooms."""
        m2 = self.res**2
        by_area = sorted(private, key=lambda r: r.area)
        for r in private:
            r.label = "Bedroom"
        by_area[0].label = "Bathroom"
        if len(by_area) >= 4 and by_area[1].area * m2 < 8:
            by_area[1].label = "Toilet" if by_area[1].area * m2 < 5 else "Bathroom"
        if len(by_area) >= 6:
            by_area[2].label = "Storage" if by_area[2].area * m2 < 7 else "Office"


def px_ceil(metres: float, res: float) -> int:
    """Pixels that hold ``metres`` (rounded up, exact multiples kept).

    Parameters
    ----------
    metres : float
        Length.
    res : float
        Metres per pixel.

    Returns
    -------
    int

    Examples
    --------
    >>> px_ceil(0.5, 0.05), px_ceil(0.51, 0.05)
    (10, 11)
    """
    return math.ceil(metres / res - 1e-9)


def _connected(n: int, edges, skip: int = -1) -> bool:
    nodes = [k for k in range(n) if k != skip]
    if not nodes:
        return False
    seen, stack = {nodes[0]}, [nodes[0]]
    while stack:
        k = stack.pop()
        for i, j in edges:
            if skip in (i, j):
                continue
            for u, v in ((i, j), (j, i)):
                if u == k and v not in seen:
                    seen.add(v)
                    stack.append(v)
    return len(seen) == len(nodes)


def _drop_corner_room(b: _Builder, rooms: list[_Room], lx: int, ly: int, edges) -> list[_Room]:
    """Remove one small corner room (L-shaped outline) if the rest stays connected."""
    total = lx * ly
    cands = []
    for k, r in enumerate(rooms):
        corner = (r.x0 == 0 or r.x1 == lx) and (r.y0 == 0 or r.y1 == ly)
        spans = r.w == lx or r.h == ly
        if r.kind != _ROOM or not corner or spans or r.area > 0.28 * total:
            continue
        if r.label in ("Living_Room", "Lobby"):
            continue
        if _connected(len(rooms), edges, skip=k):
            cands.append(k)
    n_rooms = sum(r.kind == _ROOM for r in rooms)
    if not cands or n_rooms <= 3:
        return rooms
    k = int(b.rng.choice(cands))
    return rooms[:k] + rooms[k + 1 :]
