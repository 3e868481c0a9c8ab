"""Procedural floor plans: seeded apartments and offices like HouseExpo's.

The generator is the embedded default behind the demo and the source of
unlimited training plans (thesis section 4.1 trains on HouseExpo CAD maps; this
module draws plans of the same kind without any download).

How a plan is built (every step draws from one ``numpy.random.Generator``
seeded by ``seed``, so the same seed gives the same bytes):

1. **Outline.** A ``W x H`` metre rectangle (random per kind, or given).
2. **Rooms.** The rectangle is tiled with axis-aligned rooms:

   * *office*: a corridor spine along the long axis with rooms on both sides
     (one side when the building is shallow); deep buildings (>= 15 m) get two
     parallel corridors joined by cross corridors around a core of toilets,
     storage and meeting rooms; optional full-depth rooms at the ends
     (lobby, meeting room) and open-plan offices with columns;
   * *apartment*: either a living zone (living room, kitchen, dining room) at
     one end and a hallway through the private zone with bedrooms and
     bathrooms on its sides, or recursive splitting (BSP) of the outline.

   Rooms get HouseExpo ``room_category`` names (``Living_Room``, ``Kitchen``,
   ``Bedroom``, ``Bathroom``, ``Office``, ``Hallway``...).
3. **Irregular outlines** (sometimes): a corner room is dropped (L shape) or a
   corner of a room is cut away (notch).
4. **Doors.** A randomised Prim spanning tree over the room adjacency graph
   (corridors and living rooms preferred as hubs) puts one door, 0.7-1.0 m
   wide, on each tree edge, plus a few extra doors that close loops.
   Corridor ends and living/dining connections become wide openings.
5. **Raster.** Interior walls (0.10-0.15 m) are centred on room boundaries,
   outer walls (0.20-0.30 m) lie inside the outline, everything outside the
   building is unknown, with a small unknown margin around it.
6. **Furniture** (optional): beds, wardrobes, sofas, counters, desks, tables
   and columns as occupied blocks that either touch a wall or keep at least
   0.5 m clear on every side, and never stand in front of a door.
7. **Check and repair.** The free space eroded by the robot disc must be one
   connected component and every free pixel must be reachable (see
   :func:`connectivity`); small unreachable pockets are filled, anything worse
   makes the generator draw again from the same generator.

Examples
--------
>>> plan = generate_floorplan(3, kind="office", size=(16, 10))
>>> plan.size_m[0] > 16, plan.resolution
(True, 0.05)
>>> connectivity(plan).ok
True
>>> sorted({r["category"] for r in plan.meta["rooms"]})[:2]
['Hallway', 'Kitchen']
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import cv2
import numpy as np

from ..core.errors import InputError
from ..core.grid import FREE, OCCUPIED, UNKNOWN, OccupancyMap

__all__ = [
    "generate_floorplan",
    "plan_document",
    "plan_from_document",
    "connectivity",
    "Connectivity",
    "draw_floorplan",
    "save_floorplan_figure",
    "KINDS",
]

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


# --------------------------------------------------------------------------- checks
@dataclass(frozen=True)
class Connectivity:
    """Reachability of a map's free space for a disc robot.

    Attributes
    ----------
    components : int
        Connected components (4-connected) of the robot's configuration space,
        i.e. free pixels whose distance to the nearest non-free pixel exceeds
        the robot radius.
    unreachable : (H, W) bool array
        Free pixels farther than ``robot_radius * sqrt(2)`` (+ half a pixel)
        from the largest component: no robot pose can sweep them.
    """

    components: int
    unreachable: np.ndarray

    @property
    def ok(self) -> bool:
        """One component and no unreachable free pixel."""
        return self.components == 1 and not bool(self.unreachable.any())


def connectivity(m: OccupancyMap, robot_radius: float = ROBOT_RADIUS) -> Connectivity:
    """Check that the free space is one connected component for a disc robot.

    The robot centre may stand on free pixels whose (exact Euclidean) distance
    to the nearest non-free pixel exceeds ``robot_radius``; these form the
    configuration space. A free pixel counts as reachable when it lies within
    ``robot_radius * sqrt(2)`` of the largest configuration-space component:
    the body of a disc robot cannot reach the corner pixel of a square room
    (it is ``r * sqrt(2)`` from the nearest centre), so a tolerance of exactly
    ``r`` would declare every rectangular room unreachable, while a pocket
    behind a gap narrower than the robot still fails.

    Examples
    --------
    >>> data = np.zeros((40, 60), np.uint8)
    >>> data[5:35, 5:28] = data[5:35, 32:55] = 255      # two rooms, no door
    >>> connectivity(OccupancyMap(data, 0.05)).components
    2
    >>> data[15:31, 28:32] = 255                          # a 0.8 m door
    >>> connectivity(OccupancyMap(data, 0.05)).ok
    True
    """
    free = m.data == FREE
    if not free.any():
        return Connectivity(0, free)
    r_px = robot_radius / m.resolution
    dist = cv2.distanceTransform(free.astype(np.uint8), cv2.DIST_L2, cv2.DIST_MASK_PRECISE)
    core = dist > r_px
    n, labels, stats, _ = cv2.connectedComponentsWithStats(core.astype(np.uint8), connectivity=4)
    if n <= 1:
        return Connectivity(0, free)
    biggest = 1 + int(np.argmax(stats[1:, cv2.CC_STAT_AREA]))
    away = cv2.distanceTransform(
        (labels != biggest).astype(np.uint8), cv2.DIST_L2, cv2.DIST_MASK_PRECISE
    )
    unreachable = free & (away > r_px * math.sqrt(2.0) + 0.5)
    return Connectivity(n - 1, unreachable)


# --------------------------------------------------------------------------- layout
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


@dataclass
class _Link:
    """A door or opening through the wall shared by rooms ``a`` and ``b``."""

    a: int
    b: int
    vertical: bool  # the wall is vertical (x = pos), the passage runs along y
    pos: int  # wall line (shared boundary coordinate)
    s0: int  # passage extent along the wall
    s1: int
    door: bool


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
        near = [r for r in rest if r.label == "Bedroom" and self.shared(living, r)]
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

    # ------------------------------------------------------------ graph
    def shared(self, a: _Room, b: _Room):
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

    def passage(self, rooms: list[_Room], i: int, j: int, seg, want_open: bool) -> _Link | None:
        """The door (or opening) that best fits the wall shared by rooms i and j."""
        vertical, pos, o0, o1 = seg
        a, b = rooms[i], rooms[j]
        corridor = _CORRIDOR in (a.kind, b.kind)
        room_span = lambda r: (r.y0, r.y1) if vertical else (r.x0, r.x1)  # noqa: E731
        # a corridor whose whole end is the shared segment: open it fully
        full = any(r.kind == _CORRIDOR and room_span(r) == (o0, o1) for r in (a, b))
        usable = (o1 - o0) - 2 * self.clear
        if full and (want_open or usable < self.door_min):
            return _Link(i, j, vertical, pos, o0 + self.hi, o1 - self.lo, door=False)
        if want_open and usable >= px_ceil(1.2, self.res):
            width = int(
                self.rng.integers(px_ceil(1.2, self.res), max(usable, px_ceil(1.2, self.res)) + 1)
            )
            width = min(width, usable, self.px(3.0))
            s0 = o0 + self.clear + int(self.rng.integers(0, usable - width + 1))
            return _Link(i, j, vertical, pos, s0, s0 + width, door=False)
        if usable < self.door_min:
            return None
        width = int(self.rng.integers(self.door_min, min(self.door_max, usable) + 1))
        slack = usable - width
        # doors sit near a corner more often than in the middle of a wall
        u = self.rng.random()
        off = int(round(slack * (u * 0.25 if self.rng.random() < 0.5 else 1 - u * 0.25)))
        if corridor and self.rng.random() < 0.5:
            off = int(self.rng.integers(0, slack + 1))
        s0 = o0 + self.clear + off
        return _Link(i, j, vertical, pos, s0, s0 + width, door=True)

    def graph(self, rooms: list[_Room]) -> dict[tuple[int, int], tuple]:
        """Pairs of rooms that can be linked: (i, j) -> shared boundary segment.

        A pair qualifies when its shared wall takes a door away from the wall
        ends, or when a corridor ends on it (the whole end can be opened).
        """
        edges = {}
        for i in range(len(rooms)):
            for j in range(i + 1, len(rooms)):
                seg = self.shared(rooms[i], rooms[j])
                if seg is None:
                    continue
                vertical, _, o0, o1 = seg
                door_fits = o1 - o0 - 2 * self.clear >= self.door_min
                corridor_end = any(
                    r.kind == _CORRIDOR and ((r.y0, r.y1) if vertical else (r.x0, r.x1)) == (o0, o1)
                    for r in (rooms[i], rooms[j])
                )
                if door_fits or corridor_end:
                    edges[i, j] = seg
        return edges


def px_ceil(metres: float, res: float) -> int:
    return math.ceil(metres / res - 1e-9)


_HUB_COST = {
    "Hallway": 0.0,
    "Living_Room": 0.4,
    "Lobby": 0.4,
    "Dining_Room": 1.0,
    "Kitchen": 1.5,
    "Meeting_Room": 2.0,
}
_PRIVATE = {"Bathroom", "Toilet", "Storage"}
_OPEN_PAIRS = {
    frozenset({"Living_Room", "Dining_Room"}): 0.9,
    frozenset({"Kitchen", "Dining_Room"}): 0.5,
    frozenset({"Living_Room", "Kitchen"}): 0.4,
    frozenset({"Living_Room", "Hallway"}): 0.7,
    frozenset({"Dining_Room", "Hallway"}): 0.5,
    frozenset({"Hallway"}): 1.0,
    frozenset({"Lobby", "Hallway"}): 0.8,
}


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


def _plan_links(b: _Builder, rooms: list[_Room], edges) -> list[_Link] | None:
    """Randomised Prim spanning tree over the room graph, plus a few loop-closing doors."""
    n = len(rooms)
    rng = b.rng
    cost = {}
    for (i, j), _seg in edges.items():
        li, lj = rooms[i].label, rooms[j].label
        c = _HUB_COST.get(li, 3.0) + _HUB_COST.get(lj, 3.0) + rng.random()
        if li in _PRIVATE or lj in _PRIVATE:
            c += 2.0
        cost[i, j] = c
    hubs = sorted(range(n), key=lambda k: (_HUB_COST.get(rooms[k].label, 3.0), -rooms[k].area))
    in_tree = {hubs[0]}
    tree: list[tuple[int, int]] = []
    degree = [0] * n
    while len(in_tree) < n:
        best = None
        for (i, j), c in cost.items():
            if (i in in_tree) == (j in in_tree):
                continue
            # keep bathrooms and storage as leaves
            inner = i if i in in_tree else j
            if rooms[inner].label in _PRIVATE and degree[inner] >= 1:
                c += 10.0
            if best is None or c < best[0]:
                best = (c, (i, j))
        if best is None:
            return None
        i, j = best[1]
        tree.append((i, j))
        degree[i] += 1
        degree[j] += 1
        in_tree.update((i, j))
    extra = []
    for key in sorted(set(cost) - set(tree)):
        li, lj = rooms[key[0]].label, rooms[key[1]].label
        if li in _PRIVATE or lj in _PRIVATE:
            continue
        pair = frozenset({li, lj})
        p = 0.9 if pair in _OPEN_PAIRS else (0.12 if _CORRIDOR in (rooms[key[0]].kind,) else 0.08)
        if pair == frozenset({"Hallway"}):
            p = 1.0
        if rng.random() < p:
            extra.append(key)
    links = []
    for i, j in tree + extra:
        pair = frozenset({rooms[i].label, rooms[j].label})
        want_open = rng.random() < _OPEN_PAIRS.get(pair, 0.0)
        link = b.passage(rooms, i, j, edges[i, j], want_open)
        if link is None:
            if (i, j) in tree:
                return None
            continue
        links.append(link)
    return links


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


# --------------------------------------------------------------------------- raster
def _door_zone(link: _Link, b: _Builder, depth: int) -> tuple[int, int, int, int]:
    """(x0, y0, x1, y1) of the passage plus ``depth`` pixels into both rooms."""
    pad = b.px(0.15)
    if link.vertical:
        return link.pos - depth, link.s0 - pad, link.pos + depth, link.s1 + pad
    return link.s0 - pad, link.pos - depth, link.s1 + pad, link.pos + depth


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


# --------------------------------------------------------------------------- public
def _size_for(kind: str, size, rng: np.random.Generator) -> tuple[float, float]:
    if size is None:
        (wl, wh), (hl, hh) = SIZE_RANGES[kind]
        wm, hm = rng.uniform(wl, wh), rng.uniform(hl, hh)
        if rng.random() < 0.35:
            wm, hm = hm, wm
        return float(wm), float(hm)
    try:
        wm, hm = (float(v) for v in size)
    except (TypeError, ValueError):
        raise InputError(
            "size", f"size must be two numbers (W, H) in metres, got {size!r}"
        ) from None
    if not (math.isfinite(wm) and math.isfinite(hm)):
        raise InputError("size", f"size must be finite, got {size!r}")
    if min(wm, hm) < MIN_SIZE_M:
        raise InputError(
            "size",
            f"a building needs at least {MIN_SIZE_M:g} x {MIN_SIZE_M:g} m, got {wm:g} x {hm:g} m",
        )
    return wm, hm


def generate_floorplan(
    seed: int | np.random.Generator = 0,
    kind: str = "apartment",
    size: tuple[float, float] | None = None,
    resolution: float = 0.05,
    furniture: bool = False,
    wall_thickness: float | tuple[float, float] | None = None,
    *,
    margin: float = 0.3,
    robot_radius: float = ROBOT_RADIUS,
) -> OccupancyMap:
    """A random apartment or office floor plan as an occupancy map.

    Parameters
    ----------
    seed : int or numpy.random.Generator
        Seed of the only random generator used; the same seed gives identical bytes.
    kind : {"apartment", "office"}
        Apartment (living zone + hallway with bedrooms, or recursive splitting)
        or office (corridor spine with rooms on both sides, core band).
    size : (W, H) in metres, optional
        Outer size of the building (outer wall faces); random per kind when
        None (apartments about 6-17 x 6-13 m, offices 12-30 x 8-20 m).
        Each side must be at least 4 m.
    resolution : float
        Metres per pixel, in [0.01, 0.25].
    furniture : bool
        Add furniture-like occupied blocks (beds, desks, tables, columns...)
        that never cut the free space apart.
    wall_thickness : float or (interior, outer), optional
        Wall thickness in metres. A single number is the interior thickness
        (outer walls twice as thick). Default: random per plan in 0.10-0.15 m
        (interior) and 0.20-0.30 m (outer). Walls are at least 1 pixel
        (interior) and 2 pixels (outer) thick.
    margin : float
        Unknown border around the building, metres.
    robot_radius : float
        Radius of the robot for which the free space must be one connected,
        fully reachable component (see :func:`connectivity`).

    Returns
    -------
    OccupancyMap
        Walls 0, interior 255, outside 127, origin ``(0, 0, 0)`` at the lower-left
        corner of the margin. ``meta`` holds, like a loaded HouseExpo plan,
        ``rooms`` (``category``, ``kind`` room/corridor, ``bbox`` in the
        HouseExpo frame ``[x0, y0, x1, y1]`` with y pointing down (``y = -world
        y``), ``world_bbox`` ``[xmin, ymin, xmax, ymax]`` in world metres,
        ``area``) and ``room_category`` (category -> list of HouseExpo-frame
        boxes); and ``doors`` / ``openings`` (world centre ``x``, ``y``, ``width``
        in metres, ``orientation`` of the wall, the two room indices),
        ``furniture`` (kind, room index, ``bbox`` in world metres),
        ``building_bbox`` (world), the seed, kind, size and wall thickness.

    Raises
    ------
    InputError
        Unknown kind, size below 4 m, resolution out of range.

    Examples
    --------
    >>> a = generate_floorplan(7, size=(10, 8))
    >>> b = generate_floorplan(7, size=(10, 8))
    >>> a == b and a.data.tobytes() == b.data.tobytes()
    True
    >>> a.meta["size_m"], a.shape        # 0.3 m unknown margin on each side
    ([10.0, 8.0], (172, 212))
    >>> all(0.7 <= d["width"] <= 1.0 for d in a.meta["doors"])
    True
    """
    if kind not in KINDS:
        raise InputError(
            "kind", f"unknown building kind {kind!r}; choose one of {', '.join(KINDS)}"
        )
    try:
        res = float(resolution)
    except (TypeError, ValueError):
        raise InputError("resolution", f"resolution must be a number, got {resolution!r}") from None
    if not math.isfinite(res) or res <= 0:
        raise InputError("resolution", f"resolution must be positive, got {resolution!r}")
    if not 0.01 <= res <= 0.25:
        raise InputError(
            "resolution", f"resolution must be between 0.01 and 0.25 m per pixel, got {res:g}"
        )
    if isinstance(seed, np.random.Generator):
        rng = seed
    else:
        if isinstance(seed, bool) or not isinstance(seed, (int, np.integer)) or seed < 0:
            raise InputError("seed", f"seed must be a non-negative integer, got {seed!r}")
        rng = np.random.default_rng(int(seed))
    wm, hm = _size_for(kind, size, rng)
    lx, ly = int(round(wm / res)), int(round(hm / res))
    mpx = max(2, int(round(margin / res)))
    if (lx + 2 * mpx) * (ly + 2 * mpx) > MAX_PIXELS:
        raise InputError(
            "size", f"{wm:g} x {hm:g} m at {res:g} m/px is too large ({lx} x {ly} pixels)"
        )
    if wall_thickness is None:
        t_in_m, t_out_m = rng.uniform(*INTERIOR_WALL), rng.uniform(*OUTER_WALL)
    elif np.ndim(wall_thickness) == 0:
        t_in_m, t_out_m = float(wall_thickness), 2 * float(wall_thickness)
    else:
        t_in_m, t_out_m = (float(v) for v in wall_thickness)
    if not (0 < t_in_m <= 0.5 and 0 < t_out_m <= 0.6):
        raise InputError("wall_thickness", f"wall thickness out of range: {wall_thickness!r}")
    t_in = max(1, int(round(t_in_m / res)))
    t_out = max(2, int(round(t_out_m / res)), t_in)
    b = _Builder(rng, res, t_in, t_out)
    shape = (ly + 2 * mpx, lx + 2 * mpx)

    for _attempt in range(50):
        transpose = ly > lx
        ax, ay = (ly, lx) if transpose else (lx, ly)
        rooms = b.office(ax, ay) if kind == "office" else b.apartment(ax, ay)
        if sum(r.kind == _ROOM for r in rooms) < 3:
            continue
        if transpose:
            rooms = [_Room(r.y0, r.x0, r.y1, r.x1, r.label, r.kind) for r in rooms]
        if rng.random() < 0.5:  # mirror left-right
            rooms = [_Room(lx - r.x1, r.y0, lx - r.x0, r.y1, r.label, r.kind) for r in rooms]
        if rng.random() < 0.5:  # mirror top-bottom
            rooms = [_Room(r.x0, ly - r.y1, r.x1, ly - r.y0, r.label, r.kind) for r in rooms]
        edges = b.graph(rooms)
        if not _connected(len(rooms), edges):
            continue
        if rng.random() < 0.3:
            rooms = _drop_corner_room(b, rooms, lx, ly, edges)
            edges = b.graph(rooms)
        links = _plan_links(b, rooms, edges)
        if links is None:
            continue
        notches = _notches(b, rooms, links, lx, ly)
        data = _rasterise(b, rooms, links, notches, shape, mpx)
        placed = _furnish(b, data, rooms, links, mpx) if furniture else []
        m = OccupancyMap(data, res, (0.0, 0.0, 0.0))
        check = connectivity(m, robot_radius)
        if check.components != 1:
            continue
        if check.unreachable.any():
            # small pockets (behind furniture, in a corner) are filled; big ones mean a retry
            if check.unreachable.sum() * res**2 > 0.5:
                continue
            data[check.unreachable] = OCCUPIED
        m.meta.update(
            _meta(b, rooms, links, notches, placed, shape, mpx, seed, kind, (lx, ly), res)
        )
        return m
    raise RuntimeError(
        f"could not generate a connected {kind} for seed {seed!r}"
    )  # pragma: no cover


def _meta(b: _Builder, rooms, links, notches, placed, shape, mpx, seed, kind, lxy, res) -> dict:
    hc = shape[0]

    def world_box(x0, y0, x1, y1, offset=mpx):
        return [
            round((x0 + offset) * res, 6),
            round((hc - (y1 + offset)) * res, 6),
            round((x1 + offset) * res, 6),
            round((hc - (y0 + offset)) * res, 6),
        ]

    room_meta, category = [], {}
    for r in rooms:
        box = world_box(r.x0, r.y0, r.x1, r.y1)
        plan_box = [box[0], -box[3], box[2], -box[1]]  # HouseExpo frame: x, -y (y down)
        room_meta.append(
            {
                "category": r.label,
                "kind": r.kind,
                "bbox": plan_box,
                "world_bbox": box,
                "area": round(r.area * res**2, 4),
            }
        )
        category.setdefault(r.label, []).append(plan_box)
    doors, openings = [], []
    for lk in links:
        if lk.vertical:
            x, y = (lk.pos + mpx) * res, (hc - (lk.s0 + lk.s1) / 2 - mpx) * res
        else:
            x, y = ((lk.s0 + lk.s1) / 2 + mpx) * res, (hc - lk.pos - mpx) * res
        item = {
            "x": round(x, 6),
            "y": round(y, 6),
            "width": round((lk.s1 - lk.s0) * res, 6),
            "orientation": "vertical" if lk.vertical else "horizontal",
            "rooms": [lk.a, lk.b],
        }
        (doors if lk.door else openings).append(item)
    furn = [
        {"kind": p["kind"], "room": p["room"], "bbox": world_box(*p["px"], offset=0)}
        for p in placed
    ]
    seed_val = int(seed) if isinstance(seed, (int, np.integer)) else None
    return {
        "generator": "map2map.maps.floorplan",
        "seed": seed_val,
        "kind": kind,
        "size_m": [round(lxy[0] * res, 6), round(lxy[1] * res, 6)],
        "building_bbox": world_box(0, 0, lxy[0], lxy[1]),
        "wall_thickness": {"interior": round(b.t_in * res, 6), "outer": round(b.t_out * res, 6)},
        "room_num": len(rooms),
        "rooms": room_meta,
        "room_category": category,
        "doors": doors,
        "openings": openings,
        "notches": [world_box(*n) for n in notches],
        "furniture": furn,
    }


# ----------------------------------------------------------------- layout documents
def _digest(m: OccupancyMap) -> str:
    import hashlib

    h = hashlib.sha256(f"{m.shape[0]}x{m.shape[1]}@{m.resolution!r}".encode())
    h.update(np.ascontiguousarray(m.data).tobytes())
    return h.hexdigest()


def plan_document(
    plan: OccupancyMap,
    *,
    seed: int,
    kind: str = "apartment",
    size: tuple[float, float] | None = None,
    furniture: bool = False,
) -> dict:
    """The layout JSON of ``map2map plan --meta``, readable back as a map.

    ``plan.meta`` (rooms, doors, openings, furniture, HouseExpo-style
    ``room_category``) plus what rebuilds the map: the generator's arguments
    (``regenerate``) and a digest of the map (``map_sha256``), so that
    :func:`plan_from_document` (what ``map2map convert apt.json`` calls) either
    rebuilds exactly the map that was saved or refuses.

    Examples
    --------
    >>> m = generate_floorplan(4, size=(6, 5))
    >>> doc = plan_document(m, seed=4, size=(6, 5))
    >>> plan_from_document(doc) == m
    True
    """
    doc = dict(plan.meta)
    doc["regenerate"] = {
        "seed": int(seed),
        "kind": kind,
        "size": None if size is None else [float(v) for v in size],
        "resolution": float(plan.resolution),
        "furniture": bool(furniture),
    }
    doc["map_sha256"] = _digest(plan)
    return doc


def plan_from_document(doc: dict, resolution: float | None = None, source=None) -> OccupancyMap:
    """Rebuild the map of a :func:`plan_document` (``resolution`` defaults to the saved one).

    At the saved resolution the rebuilt map must match the saved digest; at another
    resolution the layout must keep its room count and size. A document written
    by a map2map whose generator made a different plan from the same arguments is
    refused (:class:`InputError`) rather than read as a different building.
    """
    args = doc.get("regenerate")
    if not isinstance(args, dict):
        raise InputError(
            source,
            "a map2map plan layout without its generator arguments (written by an older "
            "map2map): convert the map file saved with it instead",
        )
    try:
        seed, kind = int(args["seed"]), str(args["kind"])
        size = None if args.get("size") is None else tuple(float(v) for v in args["size"])
        saved_res = float(args["resolution"])
        furniture = bool(args.get("furniture", False))
    except (KeyError, TypeError, ValueError):
        raise InputError(source, "the plan layout's 'regenerate' arguments are corrupt") from None
    res = saved_res if resolution is None else float(resolution)
    m = generate_floorplan(seed, kind=kind, size=size, resolution=res, furniture=furniture)
    other = (
        "this map2map generates a different plan from the layout's arguments (it was "
        "written by another version): convert the map file saved with it instead"
    )
    if res == saved_res:
        if doc.get("map_sha256") != _digest(m):
            raise InputError(source, other)
    elif m.meta.get("room_num") != doc.get("room_num") or not np.allclose(
        m.meta.get("size_m"), doc.get("size_m", [0, 0]), atol=2 * max(res, saved_res)
    ):
        raise InputError(source, other)
    return m


# --------------------------------------------------------------------------- figures
_SHORT = {"Living_Room": "Living", "Dining_Room": "Dining", "Meeting_Room": "Meeting"}


def draw_floorplan(ax, m: OccupancyMap, *, title: str | None = None, doors: bool = True) -> None:
    """Draw a plan with its room labels (and door marks) from ``m.meta``.

    Works for the generator's plans and for rasterised HouseExpo plans (room
    boxes in ``meta["rooms"]`` or ``meta["room_category"]``, HouseExpo frame).
    """
    from ..core.viz import draw_map

    draw_map(ax, m, title=title)
    rooms = m.meta.get("rooms") or [
        {"category": k, "bbox": box}
        for k, boxes in (m.meta.get("room_category") or {}).items()
        for box in boxes
    ]
    fs = 7 if len(rooms) > 12 else 8
    for r in rooms:
        if "world_bbox" in r:
            x0, y0, x1, y1 = r["world_bbox"]
        else:  # HouseExpo frame (y down) -> world
            x0, y0, x1, y1 = r["bbox"][0], -r["bbox"][3], r["bbox"][2], -r["bbox"][1]
        row, col = m.world_to_pixel_float((x0 + x1) / 2, (y0 + y1) / 2)
        name = r.get("category", "")
        label = _SHORT.get(name, name).replace("_", " ")
        w, h = x1 - x0, y1 - y0
        ax.text(
            float(col),
            float(row),
            label,
            ha="center",
            va="center",
            fontsize=fs,
            rotation=90 if h > 1.5 * w and w < 3.0 else 0,
            color="#1f4e79",
            clip_on=True,
        )
    if doors:
        for d in m.meta.get("doors", []):
            row, col = m.world_to_pixel_float(d["x"], d["y"])
            ax.plot(float(col), float(row), marker="s", ms=2.5, color="#c0392b", ls="none")


def save_floorplan_figure(m: OccupancyMap, path, title: str | None = None) -> None:
    """Save a figure of a plan with room labels and door marks (format from the suffix, atomic).

    Examples
    --------
    >>> import tempfile, pathlib
    >>> path = pathlib.Path(tempfile.mkdtemp()) / "plan.png"
    >>> save_floorplan_figure(generate_floorplan(1, size=(8, 6)), path, title="apartment")
    >>> path.stat().st_size > 10_000
    True
    """
    from ..core.viz import new_figure, save_figure
    from .render import map_summary

    fig, ax = new_figure(m, panel_inches=8.0)
    n_doors = len(m.meta.get("doors", []))
    summary = map_summary(m) + (f", {n_doors} doors (red)" if n_doors else "")
    draw_floorplan(ax, m, title=f"{title}\n{summary}" if title else summary)
    save_figure(fig, path)
