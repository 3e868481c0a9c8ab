"""The floor-plan generator: :func:`generate_floorplan` as a sequence of steps.

Each step is one function of this package (see :mod:`map2map.maps.floorplan` for
the whole recipe): arguments checked (:func:`_check_args`), outline size drawn
(:func:`_size_for`) and walls sized (:func:`_wall_pixels`), rooms laid out and
oriented (:func:`_layout_rooms`), doors planned (:mod:`.doors`), notches cut and
the layout rasterised (:mod:`.raster`), furniture placed (:mod:`.furniture`),
reachability checked and repaired (:func:`_check_and_repair`), and the metadata
written (:func:`_meta`). Every step draws from one generator, in this order.

Examples
--------
>>> m = generate_floorplan(5, kind="office", size=(14, 9))
>>> m.meta["kind"], m.meta["room_num"] > 5
('office', True)
"""

from __future__ import annotations

import math

import numpy as np

from ...core.errors import InputError
from ...core.grid import OCCUPIED, OccupancyMap
from .check import connectivity
from .doors import _graph, _Link, _plan_links
from .furniture import _furnish
from .layout import (
    _ROOM,
    INTERIOR_WALL,
    KINDS,
    MAX_PIXELS,
    MIN_SIZE_M,
    OUTER_WALL,
    ROBOT_RADIUS,
    SIZE_RANGES,
    _Builder,
    _connected,
    _drop_corner_room,
    _Room,
)
from .raster import _notches, _rasterise

__all__ = ["generate_floorplan"]


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
    res, rng = _check_args(seed, kind, resolution)
    wm, hm = _size_for(kind, size, rng)
    lx, ly = int(round(wm / res)), int(round(hm / res))
    mpx = max(2, int(round(margin / res)))
    if (lx + 2 * mpx) * (ly + 2 * mpx) > MAX_PIXELS:
        raise InputError(
            "size", f"{wm:g} x {hm:g} m at {res:g} m/px is too large ({lx} x {ly} pixels)"
        )
    b = _Builder(rng, res, *_wall_pixels(wall_thickness, rng, res))
    shape = (ly + 2 * mpx, lx + 2 * mpx)
    for _attempt in range(50):
        layout = _layout_rooms(b, kind, lx, ly)
        if layout is None:
            continue
        rooms, links = layout
        notches = _notches(b, rooms, links, lx, ly)
        data = _rasterise(b, rooms, links, notches, shape, mpx)
        placed = _furnish(b, data, rooms, links, mpx) if furniture else []
        m = OccupancyMap(data, res, (0.0, 0.0, 0.0))
        if not _check_and_repair(m, robot_radius):
            continue
        m.meta.update(
            _meta(b, rooms, links, notches, placed, shape, mpx, seed, kind, (lx, ly), res)
        )
        return m
    raise RuntimeError(
        f"could not generate a connected {kind} for seed {seed!r}"
    )  # pragma: no cover


def _check_args(seed, kind: str, resolution) -> tuple[float, np.random.Generator]:
    """Checked ``(resolution, generator)`` of :func:`generate_floorplan`'s arguments.

    Examples
    --------
    >>> res, rng = _check_args(3, "office", 0.05)
    >>> res, type(rng).__name__
    (0.05, 'Generator')
    >>> _check_args(3, "castle", 0.05)
    Traceback (most recent call last):
    ...
    map2map.core.errors.InputError: ...unknown building kind 'castle'...
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
        return res, seed
    if isinstance(seed, bool) or not isinstance(seed, (int, np.integer)) or seed < 0:
        raise InputError("seed", f"seed must be a non-negative integer, got {seed!r}")
    return res, np.random.default_rng(int(seed))


def _wall_pixels(wall_thickness, rng: np.random.Generator, res: float) -> tuple[int, int]:
    """(interior, outer) wall thickness in pixels, drawn when ``wall_thickness`` is None.

    Examples
    --------
    >>> _wall_pixels(0.1, np.random.default_rng(0), 0.05)
    (2, 4)
    """
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
    return t_in, t_out


def _orient(rooms: list[_Room], lx: int, ly: int, transpose: bool, rng) -> list[_Room]:
    """Rooms laid out along the long axis turned back to ``lx x ly`` and randomly mirrored."""
    if transpose:
        rooms = [_Room(r.y0, r.x0, r.y1, r.x1, r.label, r.kind) for r in rooms]
    if rng.random() < 0.5:  # mirror left-right
        rooms = [_Room(lx - r.x1, r.y0, lx - r.x0, r.y1, r.label, r.kind) for r in rooms]
    if rng.random() < 0.5:  # mirror top-bottom
        rooms = [_Room(r.x0, ly - r.y1, r.x1, ly - r.y0, r.label, r.kind) for r in rooms]
    return rooms


def _layout_rooms(
    b: _Builder, kind: str, lx: int, ly: int
) -> tuple[list[_Room], list[_Link]] | None:
    """One attempt at rooms (steps 2-3) and their doors (step 4); None to draw again.

    Examples
    --------
    >>> b = _Builder(np.random.default_rng(0), 0.05, 2, 5)
    >>> rooms, links = _layout_rooms(b, "apartment", 200, 160)
    >>> len(links) >= len(rooms) - 1
    True
    """
    transpose = ly > lx
    ax, ay = (ly, lx) if transpose else (lx, ly)
    rooms = b.office(ax, ay) if kind == "office" else b.apartment(ax, ay)
    if sum(r.kind == _ROOM for r in rooms) < 3:
        return None
    rooms = _orient(rooms, lx, ly, transpose, b.rng)
    edges = _graph(b, rooms)
    if not _connected(len(rooms), edges):
        return None
    if b.rng.random() < 0.3:
        rooms = _drop_corner_room(b, rooms, lx, ly, edges)
        edges = _graph(b, rooms)
    links = _plan_links(b, rooms, edges)
    if links is None:
        return None
    return rooms, links


def _check_and_repair(m: OccupancyMap, robot_radius: float) -> bool:
    """Step 7: True when the free space is one reachable component; small pockets filled.

    Unreachable free pockets of at most 0.5 m^2 in all (behind furniture, in a corner)
    are made occupied in place; anything worse means another attempt.

    Examples
    --------
    >>> data = np.zeros((40, 60), np.uint8)
    >>> data[5:35, 5:55] = 255
    >>> _check_and_repair(OccupancyMap(data, 0.05), 0.2)
    True
    """
    check = connectivity(m, robot_radius)
    if check.components != 1:
        return False
    if check.unreachable.any():
        if check.unreachable.sum() * m.resolution**2 > 0.5:
            return False
        m.data[check.unreachable] = OCCUPIED
    return True


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
