"""Doors and openings of a procedural floor plan (step 4 of :mod:`map2map.maps.floorplan`).

The room adjacency graph (:func:`_graph`: pairs of rooms whose shared wall takes
a door, or that a corridor ends on) gets a randomised Prim spanning tree
(:func:`_plan_links`: corridors and living rooms preferred as hubs, bathrooms and
storage kept as leaves) with one ``_Link`` per tree edge, plus a few extra
links that close loops. A link is a door 0.7-1.0 m wide, near a wall corner
more often than in the middle, or a wide opening (corridor ends,
living/dining/kitchen connections).

Examples
--------
>>> import numpy as np
>>> from map2map.maps.plans.layout import _Builder, _Room
>>> b = _Builder(np.random.default_rng(1), res=0.05, t_in=2, t_out=5)
>>> rooms = [_Room(0, 0, 80, 100, "Living_Room"), _Room(80, 0, 160, 100, "Bedroom")]
>>> edges = _graph(b, rooms)
>>> list(edges)
[(0, 1)]
>>> [(lk.a, lk.b, lk.vertical, lk.pos) for lk in _plan_links(b, rooms, edges)]
[(0, 1, True, 80)]
"""

from __future__ import annotations

from dataclasses import dataclass

from .layout import _CORRIDOR, _Builder, _Room, _shared, px_ceil


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


def _passage(
    bld: _Builder, rooms: list[_Room], i: int, j: int, seg, want_open: bool
) -> _Link | None:
    """The door (or opening) that best fits the wall shared by rooms i and j."""
    vertical, pos, o0, o1 = seg
    a, b = rooms[i], rooms[j]
    corridor = _CORRIDOR in (a.kind, b.kind)
    room_span = lambda r: (r.y0, r.y1) if vertical else (r.x0, r.x1)  # noqa: E731
    # a corridor whose whole end is the shared segment: open it fully
    full = any(r.kind == _CORRIDOR and room_span(r) == (o0, o1) for r in (a, b))
    usable = (o1 - o0) - 2 * bld.clear
    if full and (want_open or usable < bld.door_min):
        return _Link(i, j, vertical, pos, o0 + bld.hi, o1 - bld.lo, door=False)
    if want_open and usable >= px_ceil(1.2, bld.res):
        width = int(bld.rng.integers(px_ceil(1.2, bld.res), max(usable, px_ceil(1.2, bld.res)) + 1))
        width = min(width, usable, bld.px(3.0))
        s0 = o0 + bld.clear + int(bld.rng.integers(0, usable - width + 1))
        return _Link(i, j, vertical, pos, s0, s0 + width, door=False)
    if usable < bld.door_min:
        return None
    width = int(bld.rng.integers(bld.door_min, min(bld.door_max, usable) + 1))
    slack = usable - width
    # doors sit near a corner more often than in the middle of a wall
    u = bld.rng.random()
    off = int(round(slack * (u * 0.25 if bld.rng.random() < 0.5 else 1 - u * 0.25)))
    if corridor and bld.rng.random() < 0.5:
        off = int(bld.rng.integers(0, slack + 1))
    s0 = o0 + bld.clear + off
    return _Link(i, j, vertical, pos, s0, s0 + width, door=True)


def _graph(bld: _Builder, rooms: list[_Room]) -> dict[tuple[int, int], tuple]:
    """Pairs of rooms that can be linked: (i, j) -> shared boundary segment.

    A pair qualifies when its shared wall takes a door away from the wall
    ends, or when a corridor ends on it (the whole end can be opened).
    """
    edges = {}
    for i in range(len(rooms)):
        for j in range(i + 1, len(rooms)):
            seg = _shared(rooms[i], rooms[j])
            if seg is None:
                continue
            vertical, _, o0, o1 = seg
            door_fits = o1 - o0 - 2 * bld.clear >= bld.door_min
            corridor_end = any(
                r.kind == _CORRIDOR and ((r.y0, r.y1) if vertical else (r.x0, r.x1)) == (o0, o1)
                for r in (rooms[i], rooms[j])
            )
            if door_fits or corridor_end:
                edges[i, j] = seg
    return edges


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
        link = _passage(b, rooms, i, j, edges[i, j], want_open)
        if link is None:
            if (i, j) in tree:
                return None
            continue
        links.append(link)
    return links


def _door_zone(link: _Link, b: _Builder, depth: int) -> tuple[int, int, int, int]:
    """(x0, y0, x1, y1) of the passage plus ``depth`` pixels into both rooms."""
    pad = b.px(0.15)
    if link.vertical:
        return link.pos - depth, link.s0 - pad, link.pos + depth, link.s1 + pad
    return link.s0 - pad, link.pos - depth, link.s1 + pad, link.pos + depth
