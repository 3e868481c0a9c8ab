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

The steps live in :mod:`map2map.maps.plans`, one concept a module: ``layout``
(outline and rooms, steps 1-3), ``doors`` (step 4), ``raster`` (notches and
walls, steps 3 and 5), ``furniture`` (step 6), ``check`` (step 7),
``generate`` (the generator as a sequence of those steps), ``documents``
(layout JSON, :func:`plan_document` / :func:`plan_from_document`) and
``figures``. This module keeps the public names in one place.
"""

from __future__ import annotations

from .plans.check import Connectivity, connectivity
from .plans.documents import plan_document, plan_from_document
from .plans.figures import draw_floorplan, save_floorplan_figure
from .plans.generate import generate_floorplan
from .plans.layout import (
    DOOR_WIDTH,
    INTERIOR_WALL,
    KINDS,
    MAX_PIXELS,
    MIN_SIZE_M,
    OUTER_WALL,
    ROBOT_RADIUS,
    SIZE_RANGES,
    px_ceil,
)

__all__ = [
    "generate_floorplan",
    "plan_document",
    "plan_from_document",
    "connectivity",
    "Connectivity",
    "draw_floorplan",
    "save_floorplan_figure",
    "KINDS",
    "SIZE_RANGES",
    "INTERIOR_WALL",
    "OUTER_WALL",
    "DOOR_WIDTH",
    "MIN_SIZE_M",
    "MAX_PIXELS",
    "ROBOT_RADIUS",
    "px_ceil",
]
