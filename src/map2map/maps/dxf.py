"""DXF floor plans (read with ``ezdxf``) rasterised into occupancy maps.

This is the appendix paper's first step of map matching (section 3.2): the
as-planned CAD drawing is exported at the SLAM map's resolution and its cells are
quantified to occupied 0, open 255 and unexplored 127.

What is drawn
-------------
LINE, LWPOLYLINE, POLYLINE, ARC, CIRCLE, ELLIPSE, SPLINE and MLINE entities on the
chosen layers become walls ``wall_thickness`` metres thick (polylines drawn with a
larger constant width keep that width) (curves are flattened to within
a quarter pixel, polyline bulges included); HATCH and SOLID entities are filled as
solid wall, except a pattern hatch with room for a 1 m disc (a tiled floor,
``meta["floor_hatches"]``). Block references (INSERT) are expanded, nested ones too;
an entity on layer ``0`` inside a block takes the layer of its INSERT, as in CAD
programs. Text, dimensions and other annotation are ignored.

A door drawn as CAD draws it, a swing arc of 80-100 degrees and radius 0.5-1.3 m with
its leaf from the hinge, is left out (counted in ``meta["door_entities"]``): drawn as
walls they would close the doorway.

Most CAD plans draw a wall as its two faces. A straight piece with another running
parallel to it on one side, nearer than ``min_free_width`` along at least half of
it, is such a face: it is widened towards its wall only, the cavity between the faces
is filled exactly, and a short line closing the cavity at a door (a jamb) is widened
into the wall, not into the doorway; the faces stay where they are drawn. A line
drawn alone is a wall's centre line, widened both ways.

What is free
------------
Space enclosed by walls is free, the outside is unknown. The outside is found by a
flood fill from the border of the raster; for the fill, openings narrower than
``close_gaps`` metres (doors, windows: default 1.0 m) are sealed by joining every
loose end of a line to the nearest other line within that distance, and the ends of
different lines within it to each other (a door between two jambs), so that an open
entrance door does not let the outside flood the flat. The seals only decide
inside from outside: the door openings themselves stay free. Enclosed pockets
narrower than ``min_free_width`` (the inside of a wall drawn as two lines, a column
drawn as a circle) are wall.

Units
-----
Drawing units come from the header ``$INSUNITS`` or the ``units`` option (``mm``,
``cm``, ``m``, ``in``, ``ft``); a unitless drawing is read as metres
(``meta["units_assumed"]``). The map's world frame is the drawing's, in metres
(CAD's y axis points up, like ROS): ``origin`` is the lower-left corner of the
raster, ``margin`` plus half a wall outside the drawing's extent.

Examples
--------
>>> import ezdxf, tempfile, pathlib
>>> doc = ezdxf.new(units=6)  # metres
>>> msp = doc.modelspace()
>>> _ = msp.add_lwpolyline([(0, 0), (4, 0), (4, 3), (0, 3)], close=True)
>>> path = pathlib.Path(tempfile.mkdtemp()) / "room.dxf"
>>> doc.saveas(path)
>>> m = load_dxf(path, resolution=0.05, wall_thickness=0.1)
>>> m.shape, m.origin[:2]
((82, 102), (-0.55, -0.55))
>>> round(float(m.free.sum()) * 0.05**2, 1)  # 4 x 3 m minus half a wall each side
11.3
"""

from __future__ import annotations

import math
import os
from collections import Counter
from collections.abc import Iterable, Iterator
from contextlib import contextmanager
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import cv2
import numpy as np
import shapely
from scipy.spatial import cKDTree
from shapely.geometry import LineString, Point, Polygon

from ..core.errors import InputError
from ..core.grid import FREE, OCCUPIED, UNKNOWN, OccupancyMap
from ..core.limits import check_map_size
from .rasterize import fill_exact, thin_parts, trace
from .units import UNITS

__all__ = [
    "save_segments_dxf",
    "UNITS",
    "DEFAULT_RESOLUTION",
    "DEFAULT_WALL_THICKNESS",
    "load_dxf",
    "save_dxf",
    "dxf_layers",
]

DEFAULT_RESOLUTION = 0.05
DEFAULT_WALL_THICKNESS = 0.1
#: Largest raster (pixels) load_dxf builds before asking for other units/resolution.
MAX_PIXELS = 100_000_000

_LINEAR = {"LINE", "LWPOLYLINE", "POLYLINE", "ARC", "CIRCLE", "ELLIPSE", "SPLINE"}
_FILLED = {"HATCH", "SOLID", "TRACE"}


def _polygon_rings(geoms) -> list:
    """Exterior and interior rings of (multi)polygons."""
    out = []
    parts = []
    for geom in np.atleast_1d(np.asarray(geoms, dtype=object)):
        parts.extend(getattr(geom, "geoms", [geom]))
    for poly in parts:
        if poly.is_empty or poly.geom_type != "Polygon":
            continue
        out.append(poly.exterior)
        out.extend(poly.interiors)
    return out


def _open_ends(strokes: list[np.ndarray], skip: set[int] = frozenset()
               ) -> tuple[np.ndarray, np.ndarray]:
    """The two ends ``(N, 2)`` of every open stroke (not closed, at least two points,
    not in ``skip``), first then last, and the stroke each belongs to ``(N,)``."""
    own = [i for i, s_ in enumerate(strokes)
           if i not in skip and len(s_) > 1 and (s_[0] != s_[-1]).any()]
    ends = np.array([[strokes[i][0], strokes[i][-1]] for i in own], float).reshape(-1, 2)
    return ends, np.repeat(np.asarray(own, np.int64), 2)


def _gap_seals(strokes: list[np.ndarray], gap: float) -> list[np.ndarray]:
    """Segments closing openings narrower than ``gap`` (door and window openings).

    Every loose end of an open stroke is joined to the nearest point of any other
    stroke (or to the other end of its own) closer than ``gap``. The seals only tell
    inside from outside; they are not drawn as wall.
    """
    if gap <= 0 or not strokes:
        return []
    geoms = [LineString(s_) if len(s_) > 1 else Point(s_[0]) for s_ in strokes]
    ends_arr, owner_arr = _open_ends(strokes)
    if not len(ends_arr):
        return []
    points = shapely.points(ends_arr)
    tree = shapely.STRtree(geoms)
    pi, gi = tree.query(points, predicate="dwithin", distance=gap)
    other = owner_arr[pi] != gi
    pi, gi = pi[other], gi[other]
    # the other end of the point's own stroke also counts (a room outline left open)
    own = np.arange(len(ends_arr)) ^ 1
    d_own = np.linalg.norm(ends_arr - ends_arr[own], axis=1)
    best = np.full(len(ends_arr), np.inf)
    target = np.full((len(ends_arr), 2), np.nan)
    if pi.size:
        lines = shapely.shortest_line(points[pi], np.asarray(geoms, dtype=object)[gi])
        dist = shapely.length(lines)
        far = shapely.get_coordinates(shapely.get_point(lines, 1))
        order = np.lexsort((dist, pi))
        first = np.unique(pi[order], return_index=True)[1]
        sel = order[first]
        best[pi[sel]] = dist[sel]
        target[pi[sel]] = far[sel]
    use_own = (d_own < gap) & (d_own < best) & (d_own > 0)
    target[use_own] = ends_arr[own[use_own]]
    best[use_own] = d_own[use_own]
    keep = np.isfinite(best) & (best > 0)
    return [np.array([ends_arr[k], target[k]]) for k in np.flatnonzero(keep)]


def _end_seals(strokes: list[np.ndarray], gap: float) -> list[np.ndarray]:
    """Segments joining the ends of different open strokes closer than ``gap``.

    A door in a wall drawn as two lines lies between the two short lines (jambs) that
    close the wall's cavity on either side; their ends touch the faces, so
    :func:`_gap_seals` finds no loose end there, and the outside would flood the
    building through the door. Joining end to end seals it (and, harmlessly, the ends
    that meet inside walls). The seals only tell inside from outside.

    >>> jambs = [np.array([[7.0, 0.0], [7.0, 4.0]]), np.array([[25.0, 0.0], [25.0, 4.0]])]
    >>> [s.tolist() for s in _end_seals(jambs, 18.2)]
    [[[7.0, 0.0], [25.0, 0.0]], [[7.0, 4.0], [25.0, 4.0]]]

    Whichever order the strokes come in: an end beside a crowd of nine others is
    sealed to them (it finds them among its nearest; each of them finds only the crowd).

    >>> crowd = [np.array([[0.1 * k, 0.0], [0.1 * k, -100.0 - 30 * k]]) for k in range(1, 10)]
    >>> lone = np.array([[0.0, 5.0], [0.0, 200.0]])
    >>> len(_end_seals([lone] + crowd, 10.0)) == len(_end_seals(crowd + [lone], 10.0))
    True
    """
    if gap <= 0 or len(strokes) < 2:
        return []
    e, o = _open_ends(strokes)
    if len(e) < 2:
        return []
    # each end to its nearest few within the gap (not every pair: a drawing of many
    # short lines, exploded text or hatching, would give millions)
    k = min(9, len(e))
    d, j = cKDTree(e).query(e, k=k, distance_upper_bound=gap)
    i = np.repeat(np.arange(len(e)), k)
    d, j = d.ravel(), j.ravel()
    ok = np.isfinite(d) & (d > 0)
    i, j = i[ok], j[ok]
    ok = o[i] != o[j]
    # a pair either end finds among its nearest (one end in a crowd of ends may find
    # the other while the other finds only the crowd), each once
    pairs = np.unique(np.sort(np.stack([i[ok], j[ok]], 1), axis=1), axis=0)
    return [np.array([e[a], e[b]]) for a, b in pairs]


def _read(path: Path):
    import ezdxf
    from ezdxf import recover

    if not path.exists():
        raise InputError(path, "file not found")
    if path.is_dir():
        raise InputError(path, "is a directory, not a DXF file")
    try:
        try:
            doc = ezdxf.readfile(path)
        except ezdxf.DXFStructureError:  # damaged: let ezdxf's recover mode try
            doc, _auditor = recover.readfile(path)
    except OSError as exc:
        if exc.errno is None:  # ezdxf's own "is not a DXF file"
            raise InputError(path, "not a readable DXF file (no DXF structure)") from None
        raise InputError(path, f"cannot read file ({exc.strerror})") from None
    except (ezdxf.DXFStructureError, ezdxf.DXFError, UnicodeDecodeError, ValueError) as exc:
        raise InputError(path, f"not a readable DXF file ({exc})") from None
    return doc


def dxf_layers(path: str | os.PathLike) -> list[str]:
    """Names of the layers defined in a DXF file.

    Parameters
    ----------
    path : path-like
        The ``.dxf`` file.

    Returns
    -------
    list of str
        Sorted.

    Raises
    ------
    InputError
        File missing or not DXF.
    """
    doc = _read(Path(path))
    return sorted(layer.dxf.name for layer in doc.layers)


def _walk(entities: Iterable, layer: str | None = None, depth: int = 0) -> Iterator[tuple]:
    """(entity, effective layer) of every entity, INSERTs and MLINEs expanded recursively."""
    for e in entities:
        own = e.dxf.get("layer", "0")
        eff = layer if (layer is not None and own == "0") else own
        if e.dxftype() in ("INSERT", "MLINE"):  # blocks; multi-line walls as their lines
            if depth >= 16:
                continue
            try:
                children = list(e.virtual_entities())
            except Exception:  # noqa: BLE001 - a broken block is skipped, not fatal
                continue
            yield from _walk(children, eff, depth + 1)
        else:
            yield e, eff


def _even_odd_region(loops: list[np.ndarray]):
    """The region the loops of one hatch enclose by the even-odd rule (shapely)."""
    region = shapely.Polygon()
    for loop in loops:
        if len(loop) >= 3:
            region = shapely.symmetric_difference(region, shapely.make_valid(Polygon(loop)))
    return region


def _drawn_width(e) -> float:
    """The constant width a (LW)POLYLINE is drawn with, in drawing units (0 if none)."""
    kind = e.dxftype()
    if kind == "LWPOLYLINE":
        return float(e.dxf.get("const_width", 0.0) or 0.0)
    if kind == "POLYLINE":
        return float(e.dxf.get("default_start_width", 0.0) or 0.0)
    return 0.0


def _polylines(e, tolerance: float) -> tuple[list[np.ndarray], bool]:
    """Flattened vertex arrays (drawing units, x/y) of an entity and whether it is filled."""
    from ezdxf import path as ezpath

    kind = e.dxftype()
    if kind == "HATCH":
        paths = list(ezpath.from_hatch(e))
        filled = True
    else:
        paths = [ezpath.make_path(e)]
        filled = kind in _FILLED
    out = []
    for p in paths:
        for sub in p.sub_paths() if p.has_sub_paths else [p]:
            pts = np.array([(v.x, v.y) for v in sub.flattening(tolerance, segments=4)], float)
            if len(pts) >= 2 and np.isfinite(pts).all():
                out.append(pts)
    return out, filled


def load_dxf(
    path: str | os.PathLike,
    *,
    resolution: float | None = None,
    wall_thickness: float = DEFAULT_WALL_THICKNESS,
    layers: Iterable[str] | None = None,
    units: str | None = None,
    margin: float = 0.5,
    close_gaps: float = 1.0,
    min_free_width: float = 0.3,
    door_swings: bool = True,
) -> OccupancyMap:
    """Rasterise a DXF floor plan (method in the module docstring).

    Parameters
    ----------
    path : path-like
        The ``.dxf`` file.
    resolution : float, optional
        Metres per pixel; default the one :func:`save_dxf` stored in the file, else
        :data:`DEFAULT_RESOLUTION` (0.05).
    wall_thickness : float
        Width in metres given to every line (at least one pixel).
    layers : iterable of str, optional
        Layers to draw (case-insensitive); default all.
    units : {"mm", "cm", "m", "in", "ft"}, optional
        Drawing units; default from ``$INSUNITS``.
    margin : float
        Unknown border around the drawing, metres.
    close_gaps : float
        Openings narrower than this (metres) are closed when telling inside from
        outside; 0 disables.
    min_free_width : float
        Enclosed pockets narrower than this (metres) are wall.
    door_swings : bool
        Leave out the doors' swing arcs (80-100 degrees, radius 0.5-1.3 m) and their
        leaves, which CAD draws in the doorway (:func:`_door_swings`); False draws every
        arc as a wall.

    Returns
    -------
    OccupancyMap
        Walls occupied, the space they enclose free, the outside unknown; origin at the
        lower-left corner of the margin, in drawing metres. ``meta`` holds ``source``,
        ``units`` (``units_assumed`` when ``$INSUNITS`` was unset), the ``layers`` drawn,
        ``entities`` / ``skipped_entities`` / ``door_entities`` (door swings and leaves
        left out) counts per DXF type, ``face_lines``, ``wall_thickness`` and
        ``metres_per_unit``.

    Raises
    ------
    InputError
        File missing or not DXF, unknown layer or unit, no drawable entity on the
        chosen layers, parameters out of range, raster too large.

    Examples
    --------
    >>> import tempfile, pathlib, ezdxf
    >>> doc = ezdxf.new(units=6)
    >>> _ = doc.modelspace().add_lwpolyline([(0, 0), (3, 0), (3, 2), (0, 2)], close=True)
    >>> path = pathlib.Path(tempfile.mkdtemp()) / "room.dxf"
    >>> doc.saveas(path)
    >>> m = load_dxf(path, margin=0.2)
    >>> m.meta["units"], m.meta["entities"], round(float(m.free.sum()) * 0.05**2, 1)
    ('m', {'LWPOLYLINE': 1}, 5.5)
    """
    p = Path(path)
    _check_numbers(resolution, wall_thickness, margin, close_gaps, min_free_width, units)
    doc = _read(p)
    frame = _stored_frame(doc)
    if resolution is None:
        resolution = frame[0] if frame is not None else DEFAULT_RESOLUTION
    scale, meta = _drawing_units(doc, units, p)
    meta = {"source": str(p), **meta}
    wanted = _wanted_layers(doc, layers, p)
    drawing = _collect(doc, wanted, resolution / scale, scale, wall_thickness, p, door_swings)
    ox, oy, w, h = _grid_frame(drawing, scale, resolution, margin, wall_thickness, frame, p)

    def to_px(pts: np.ndarray) -> np.ndarray:
        """Drawing units -> continuous pixel coordinates (u = column, v = row)."""
        return np.stack(
            [(pts[:, 0] * scale - ox) / resolution, h - (pts[:, 1] * scale - oy) / resolution],
            axis=1,
        )

    px_strokes = [to_px(s_) for s_ in drawing.strokes]
    px_fills = [[to_px(f) for f in loops] for loops in drawing.fills]
    sides = _face_sides(px_strokes, drawing.widths, wall_thickness, min_free_width,
                        resolution)
    wall, outlines = _walls((h, w), px_strokes, drawing.widths, px_fills, resolution, sides,
                            min_free_width / resolution)
    wall, free = _inside(wall, outlines, close_gaps, min_free_width, resolution)
    data = np.full((h, w), UNKNOWN, np.uint8)
    data[free] = FREE
    data[wall] = OCCUPIED
    meta.update(
        {
            "layers": sorted(drawing.used_layers),
            "entities": dict(drawing.counts),
            "skipped_entities": dict(drawing.skipped),
            "door_entities": dict(drawing.doors),
            "floor_hatches": int(drawing.floors),
            "wall_thickness": float(wall_thickness),
            "face_lines": int(sum(np.count_nonzero(x) for x in sides)),
            "metres_per_unit": float(scale),
        }
    )
    return OccupancyMap(data, float(resolution), (float(ox), float(oy), 0.0), meta)


def _check_numbers(resolution, wall_thickness, margin, close_gaps, min_free_width, units) -> None:
    """Refuse non-finite or out-of-range parameters of :func:`load_dxf` (InputError).

    Examples
    --------
    >>> _check_numbers(None, 0.1, 0.5, 1.0, 0.3, "cm")
    >>> _check_numbers(0.05, -1, 0.5, 1.0, 0.3, None)
    Traceback (most recent call last):
    ...
    map2map.core.errors.InputError: ...wall thickness must be > 0, got -1
    """
    for name, v, positive in (
        ("resolution", DEFAULT_RESOLUTION if resolution is None else resolution, True),
        ("wall_thickness", wall_thickness, True),
        ("margin", margin, False),
        ("close_gaps", close_gaps, False),
        ("min_free_width", min_free_width, False),
    ):
        ok = isinstance(v, int | float) and math.isfinite(v) and (v > 0 if positive else v >= 0)
        if not ok:
            what = "wall thickness" if name == "wall_thickness" else name
            raise InputError(name, f"{what} must be {'> 0' if positive else '>= 0'}, got {v!r}")
    if units is not None and units not in UNITS:
        raise InputError("units", f"units must be one of {', '.join(UNITS)}, got {units!r}")


def _drawing_units(doc, units: str | None, p: Path) -> tuple[float, dict[str, Any]]:
    """(metres per drawing unit, ``units`` metadata) from ``units`` or ``$INSUNITS``."""
    import ezdxf.units

    if units is not None:
        return UNITS[units], {"units": units}
    code = int(doc.header.get("$INSUNITS", 0) or 0)
    if code == 0:
        return 1.0, {"units": "m", "units_assumed": True}
    try:
        scale = ezdxf.units.conversion_factor(code, ezdxf.units.InsertUnits.Meters)
    except Exception:  # noqa: BLE001 - unknown code
        raise InputError(p, f"unknown $INSUNITS code {code}; give the units") from None
    return scale, {"units": ezdxf.units.decode(code) if hasattr(ezdxf.units, "decode") else code}


def _wanted_layers(doc, layers: Iterable[str] | None, p: Path) -> set[str] | None:
    """Lower-case names of the chosen layers (None: all); an unknown name is refused."""
    if layers is None:
        return None
    available = {layer.dxf.name.lower(): layer.dxf.name for layer in doc.layers}
    wanted = {str(name).lower() for name in layers}
    missing = sorted(n for n in wanted if n not in available)
    if missing:
        raise InputError(
            p,
            f"no layer named {', '.join(missing)} "
            f"(layers: {', '.join(sorted(available.values()))})",
        )
    return wanted


@dataclass
class _Drawing:
    """What :func:`_collect` found: strokes (drawing units) to widen, filled loops, tallies."""

    strokes: list[np.ndarray] = field(default_factory=list)  # widened to walls
    widths: list[float] = field(default_factory=list)  # their wall thickness, metres
    fills: list[list[np.ndarray]] = field(default_factory=list)  # loops of each filled entity
    counts: Counter = field(default_factory=Counter)
    skipped: Counter = field(default_factory=Counter)
    doors: Counter = field(default_factory=Counter)  # door swings and leaves left out
    floors: int = 0  # pattern hatches as wide as a room (floor tiles), left out
    used_layers: set[str] = field(default_factory=set)


#: A door's swing as CAD draws it: an arc of 80-100 degrees (the leaf's path), radius
#: 0.5-1.3 m (a door leaf), centred on the hinge.
DOOR_SWEEP_DEG = (80.0, 100.0)
DOOR_RADIUS_M = (0.5, 1.3)


def _door_swings(items: list[tuple], scale: float) -> set[int]:
    """Indices of ``items`` (``(kind, entity, pieces, filled)``, drawing units) that
    draw a door: each swing arc (:data:`DOOR_SWEEP_DEG`, :data:`DOOR_RADIUS_M`) and
    its leaf, a line or a thin outline from the hinge (within a tenth of the radius of
    the arc's centre) to one end of the arc, inside the swing's circle. Drawn as walls
    they would close the doorway and cut a quarter disc out of the room.

    >>> import ezdxf
    >>> doc = ezdxf.new(units=6); msp = doc.modelspace()
    >>> arc = msp.add_arc((1.0, 0.0), 0.9, 0, 90)                  # swing, hinge at (1, 0)
    >>> leaf = msp.add_line((1.0, 0.0), (1.0, 0.9))                # the open leaf
    >>> wall = msp.add_line((1.0, 0.0), (5.0, 0.0))                # the wall beyond the hinge
    >>> items = [(e.dxftype(), e, _polylines(e, 0.01)[0], False) for e in (arc, leaf, wall)]
    >>> sorted(_door_swings(items, 1.0))
    [0, 1]
    """
    lo, hi = DOOR_SWEEP_DEG
    rlo, rhi = DOOR_RADIUS_M
    out: set[int] = set()
    leaves = [j for j, it in enumerate(items)
              if not it[3] and it[0] in ("LINE", "LWPOLYLINE", "POLYLINE")]
    tree = None
    from ezdxf.math import OCS

    for i, (kind, e, pieces, filled) in enumerate(items):     # entities, not pixels
        if kind != "ARC" or filled:
            continue
        r = float(e.dxf.radius)
        sweep = (float(e.dxf.end_angle) - float(e.dxf.start_angle)) % 360.0
        if not (lo <= sweep <= hi and rlo <= r * scale <= rhi):
            continue
        # in the drawing's frame: a door block inserted mirrored gives an arc whose
        # centre and angles are in its own (flipped) coordinate system
        c = np.array(OCS(e.dxf.extrusion).to_wcs(e.dxf.center))[:2]
        ends = np.array([pieces[0][0], pieces[-1][-1]], float)
        out.add(i)
        if tree is None:       # the lines' extents, indexed once (a plan has thousands)
            boxes = [np.concatenate(items[j][2]) for j in leaves]
            tree = shapely.STRtree(shapely.box(*np.array(
                [[*b.min(0), *b.max(0)] for b in boxes]).T)) if leaves else None
        if tree is None:
            continue
        # a leaf lies inside the swing's circle: candidates whose extent meets its box
        near = tree.query(shapely.box(*(c - 1.05 * r), *(c + 1.05 * r)))
        for j in (leaves[k] for k in near):
            pts = np.concatenate(items[j][2])
            d = np.hypot(*(pts - c).T)
            if d.min() > 0.1 * r or d.max() > 1.05 * r or d.max() < 0.8 * r:
                continue
            near_end = np.hypot(pts[:, None, 0] - ends[None, :, 0],
                                pts[:, None, 1] - ends[None, :, 1]).min()
            if near_end <= 0.15 * r:
                out.add(j)
    return out


#: A pattern hatch (not a solid fill) with room for a disc this wide (metres) anywhere
#: draws a floor (tiles, parquet), not a wall: walls and columns are thinner.
FLOOR_HATCH_M = 1.0


def _floor_pattern(e, loops: list[np.ndarray], scale: float) -> bool:
    """Whether a HATCH draws a floor: a pattern fill whose region (even-odd) holds a
    disc :data:`FLOOR_HATCH_M` wide. Filled as wall it turned a tiled room into a block
    of wall; a solid fill (the poche of a wall or a column) is always a wall.

    >>> import ezdxf
    >>> msp = ezdxf.new(units=6).modelspace()
    >>> h = msp.add_hatch(); h.set_pattern_fill("ANSI37", scale=0.5)
    >>> _ = h.paths.add_polyline_path([(0, 0), (5, 0), (5, 6), (0, 6)], is_closed=True)
    >>> _floor_pattern(h, _polylines(h, 0.01)[0], 1.0)
    True
    >>> w = msp.add_hatch(); w.set_pattern_fill("ANSI31", scale=0.5)
    >>> _ = w.paths.add_polyline_path([(0, 0), (5, 0), (5, 0.3), (0, 0.3)], is_closed=True)
    >>> _floor_pattern(w, _polylines(w, 0.01)[0], 1.0)        # a hatched wall, 0.3 m
    False
    """
    if int(e.dxf.get("solid_fill", 1) or 0):
        return False
    region = _even_odd_region(loops)
    return not shapely.buffer(region, -0.5 * FLOOR_HATCH_M / scale).is_empty


def _collect(doc, wanted, res_units: float, scale: float, wall_thickness: float, p,
             doors: bool = True) -> _Drawing:
    """Every drawable entity of the chosen layers as polylines (INSERTs expanded); with
    ``doors``, door swings and their leaves left out (:func:`_door_swings`)."""
    out = _Drawing()
    items = []
    for e, layer in _walk(doc.modelspace()):
        kind = e.dxftype()
        if wanted is not None and layer.lower() not in wanted:
            continue
        if kind not in _LINEAR and kind not in _FILLED:
            out.skipped[kind] += 1
            continue
        try:
            pieces, filled = _polylines(e, res_units / 4)
        except Exception:  # noqa: BLE001 - degenerate or unsupported geometry
            out.skipped[kind] += 1
            continue
        if not pieces:
            out.skipped[kind] += 1
            continue
        items.append((kind, e, pieces, filled, layer))
    swings = _door_swings([it[:4] for it in items], scale) if doors else set()
    for k, (kind, e, pieces, filled, layer) in enumerate(items):
        if k in swings:
            out.doors[kind] += 1
            continue
        if kind == "HATCH" and _floor_pattern(e, pieces, scale):
            out.floors += 1
            continue
        out.counts[kind] += 1
        out.used_layers.add(layer)
        if filled:
            out.fills.append(pieces)
        else:
            out.strokes.extend(pieces)
            out.widths.extend([max(wall_thickness, _drawn_width(e) * scale)] * len(pieces))
    if not out.strokes and not out.fills:
        chosen = "the chosen layers" if wanted is not None else "any layer"
        raise InputError(
            p,
            "no drawable entities (LINE, LWPOLYLINE, POLYLINE, ARC, CIRCLE, HATCH, ...) "
            f"on {chosen}",
        )
    return out


def _grid_frame(d: _Drawing, scale, resolution, margin, wall_thickness, frame, p):
    """(origin x, origin y, width, height) of the raster around the drawing.

    A map2map export (:func:`save_dxf` stored its frame) goes back onto the grid it was
    written from; a raster over :data:`MAX_PIXELS` is refused.
    """
    allpts = np.concatenate(d.strokes + [loop for loops in d.fills for loop in loops]) * scale
    lo, hi = allpts.min(axis=0), allpts.max(axis=0)
    border = margin + 0.5 * max([wall_thickness, resolution, *d.widths])
    ox, oy = lo[0] - border, lo[1] - border
    quarter_turns = frame is not None and abs(math.remainder(frame[3], math.pi / 2)) < 1e-9
    if quarter_turns and frame[0] == resolution and scale == 1.0:
        # a map2map export: back onto the grid it was written from
        ox = frame[1] + math.floor((ox - frame[1]) / resolution) * resolution
        oy = frame[2] + math.floor((oy - frame[2]) / resolution) * resolution
    w = int(math.ceil((hi[0] + border - ox) / resolution - 1e-9))
    h = int(math.ceil((hi[1] + border - oy) / resolution - 1e-9))
    if w * h > MAX_PIXELS:
        raise InputError(
            p,
            f"the map would be {w} x {h} pixels at {resolution:g} m/px (drawing "
            f"{(hi[0] - lo[0]) / scale:.4g} x {(hi[1] - lo[1]) / scale:.4g} units of "
            f"{scale:g} m); give the right `units` or a coarser `resolution`",
        )
    check_map_size((h, w), p)  # the running command's budget (core.limits)
    return ox, oy, w, h


def _face_sides(px_strokes, widths, wall_thickness: float, min_free_width: float,
                resolution: float) -> list[np.ndarray]:
    """Per stroke, per straight piece (between consecutive vertices), the side its
    wall lies on when the piece is one face of a wall drawn as two lines: +1 left, -1
    right (of its direction, in pixel coordinates ``(u, v)``: left is ``(-dv, du)``), 0
    a line drawn alone (a wall's centre line, widened both ways).

    Most CAD plans draw a wall as its two faces. Widened both ways like a centre line,
    each face moved half ``wall_thickness`` into its room (a room 10 m wide between
    0.2 m walls drawn as two lines each read 9.9 m at 0.1 m, every face a pixel off at
    5 cm). A piece is a face when another piece runs parallel to it (within 5 degrees)
    on one side only, nearer than ``min_free_width`` (the pockets that narrow are wall,
    :func:`_inside`) and along at least half of it. A piece shorter than that whose
    two ends are ends of faces (a jamb closing the cavity at a door) is widened into
    the cavity only: not into the doorway. A stroke whose drawn width exceeds
    ``wall_thickness`` (a polyline with a constant width) keeps it.

    Examples
    --------
    >>> outer = np.array([[2.0, 2], [38, 2], [38, 28], [2, 28], [2, 2]])
    >>> inner = np.array([[6.0, 6], [34, 6], [34, 24], [6, 24], [6, 6]])
    >>> [s.tolist() for s in _face_sides([outer, inner], [0.1, 0.1], 0.1, 0.3, 0.05)]
    [[1, 1, 1, 1], [-1, -1, -1, -1]]
    """
    out = [np.zeros(max(len(st) - 1, 0), np.int64) for st in px_strokes]
    owner, a, b = [], [], []
    for i, st in enumerate(px_strokes):
        if len(st) < 2 or widths[i] > wall_thickness + 1e-9:
            continue
        for j in range(len(st) - 1):
            if np.hypot(*(st[j + 1] - st[j])) > 1e-6:
                owner.append((i, j))
                a.append(st[j])
                b.append(st[j + 1])
    if len(owner) < 2:
        return out
    a, b = np.asarray(a, float), np.asarray(b, float)
    d = b - a
    L = np.hypot(d[:, 0], d[:, 1])
    u = d / L[:, None]
    reach = min_free_width / resolution
    tree = shapely.STRtree(shapely.linestrings(np.stack([a, b], 1)))
    qi, qj = tree.query(shapely.linestrings(np.stack([a, b], 1)), predicate="dwithin",
                        distance=reach)
    keep = qi != qj
    qi, qj = qi[keep], qj[keep]
    par = np.abs(u[qi, 0] * u[qj, 1] - u[qi, 1] * u[qj, 0]) < math.sin(math.radians(5.0))

    def across(p):  # signed offset of points p[k] from piece qi[k]'s line, + on its left
        q = p - a[qi]
        return u[qi, 0] * q[:, 1] - u[qi, 1] * q[:, 0]

    s0, s1 = across(a[qj]), across(b[qj])
    near = (np.sign(s0) == np.sign(s1)) & (np.minimum(np.abs(s0), np.abs(s1)) > 0.5) & (
        np.maximum(np.abs(s0), np.abs(s1)) < reach)
    t0 = ((a[qj] - a[qi]) * u[qi]).sum(1)
    t1 = ((b[qj] - a[qi]) * u[qi]).sum(1)
    lap = np.clip(np.maximum(t0, t1), 0, L[qi]) - np.clip(np.minimum(t0, t1), 0, L[qi])
    ok = par & near & (lap >= 0.5 * L[qi])
    side = np.zeros(len(owner), np.int64)
    left = np.zeros(len(owner), bool)
    right = np.zeros(len(owner), bool)
    left[qi[ok & (s0 > 0)]] = True
    right[qi[ok & (s0 < 0)]] = True
    side[left & ~right] = 1
    side[right & ~left] = -1
    # a cap: a short piece that closes a cavity between two faces (a door's jamb): both
    # its ends on ends of faces; widened into the cavity only, not into the doorway
    face = side != 0
    if face.any():
        fe = np.concatenate([a[face], b[face]])          # face ends, and the other end
        far = np.concatenate([b[face], a[face]])
        tree_e = shapely.STRtree(shapely.points(fe))
        for k in np.flatnonzero(~face & (L <= reach)):   # a few short pieces
            hits = [tree_e.query(shapely.Point(*q), predicate="dwithin", distance=0.5)
                    for q in (a[k], b[k])]
            if not (len(hits[0]) and len(hits[1])):
                continue
            q = far[np.concatenate(hits)] - a[k]
            off = u[k, 0] * q[:, 1] - u[k, 1] * q[:, 0]
            if (off > 0.5).all():
                side[k] = 1
            elif (off < -0.5).all():
                side[k] = -1
    for k, (i, j) in enumerate(owner):
        out[i][j] = side[k]
    return out


def _cavities(shape, px_strokes, width_px: float) -> np.ndarray:
    """The cavities of walls drawn as two lines, filled exactly: the regions the
    strokes enclose (noded and polygonised) that are narrower than ``width_px``
    everywhere (an inward buffer of half of it leaves nothing), at pixel centres.

    The faces' one-sided bodies end flat at each corner; the corner square of a wall
    between two such faces is the cavity's, and 8-connected through a corner pixel to
    the room it would otherwise stay free.

    >>> outer = np.array([[2.0, 2], [38, 2], [38, 28], [2, 28], [2, 2]])
    >>> inner = np.array([[6.0, 6], [34, 6], [34, 24], [6, 24], [6, 6]])
    >>> m = _cavities((30, 40), [outer, inner], 6.0)
    >>> int(m.sum()), bool(m[3, 3]), bool(m[15, 20])
    (432, True, False)
    """
    lines = [LineString(st) for st in px_strokes if len(st) > 1]
    if len(lines) < 2:
        return np.zeros(shape, bool)
    noded = shapely.node(shapely.multilinestrings(lines))
    polys = shapely.get_parts(shapely.polygonize(shapely.get_parts(noded)))
    narrow = [q for q in polys if shapely.buffer(q, -0.5 * width_px).is_empty]
    if not narrow:
        return np.zeros(shape, bool)
    rings = [np.asarray(r.coords) for r in _polygon_rings(narrow)]
    return fill_exact(shape, rings, rule="evenodd")


def _free_ends(px_strokes, lines, skip: set[int], half: np.ndarray,
               tol: float = 0.5) -> list[tuple[int, np.ndarray]]:
    """``(index, stroke)`` of every open stroke (not in ``skip``) with an end that meets
    no other stroke within ``tol`` pixels (a door's jamb, a stub wall), each end that
    does meet one pushed out by the stroke's ``half`` width along it: widened with flat
    caps, the stroke then has a square cap where it meets another line (closing the
    corner) and none at its free end.

    >>> a = np.array([[0.0, 0.0], [10.0, 0.0]]); b = np.array([[10.0, 0.0], [10.0, 8.0]])
    >>> lines = [LineString(a), LineString(b)]
    >>> [(i, s.tolist()) for i, s in _free_ends([a, b], lines, set(), np.array([1.0, 1.0]))]
    [(0, [[0.0, 0.0], [11.0, 0.0]]), (1, [[10.0, -1.0], [10.0, 8.0]])]
    """
    ends, owner = _open_ends(px_strokes, skip)
    cand = owner[::2].tolist()
    if len(px_strokes) < 2:
        return [(i, px_strokes[i]) for i in cand]
    out: list[tuple[int, np.ndarray]] = []
    if not len(cand):
        return out
    q, g = shapely.STRtree(lines).query(shapely.points(ends), predicate="dwithin",
                                        distance=tol)
    joined = np.zeros(len(ends), bool)
    joined[q[g != owner[q]]] = True                   # an end on another stroke
    for c, i in enumerate(cand):                      # strokes, not pixels
        st = px_strokes[i]
        if joined[2 * c] and joined[2 * c + 1]:
            continue
        ext = st.astype(float).copy()
        for k, (e, nb) in enumerate(((0, 1), (len(st) - 1, len(st) - 2))):
            d = st[e] - st[nb]
            n = float(np.hypot(*d))
            if joined[2 * c + k] and n > 1e-9:
                ext[e] = st[e] + half[i] * d / n
        out.append((i, ext))
    return out


def _walls(shape, px_strokes, widths, px_fills, resolution, sides=None, cavity_px=None):
    """(wall mask, outlines for gap sealing) of the strokes and fills, in pixels.

    Every stroke is widened to its thickness (square caps where it meets another line
    close the corners; a free end, at a door or of a stub, is not extended), exact at
    pixel centres (nonzero rule: the union of the widened strokes), plus the stroke itself
    traced through every pixel it crosses so that no wall has a hole whatever its
    width; fills (hatches, solids) by the even-odd rule, outlines traced. A stroke with
    a ``sides`` entry of +1 or -1 (one face of a wall drawn as two lines,
    :func:`_face_sides`, per piece) is widened to that side only (left or right of its
    direction), so that the face stays where it is drawn, and the cavities narrower
    than ``cavity_px`` that such faces enclose are filled (:func:`_cavities`).

    Examples
    --------
    >>> stroke = np.array([[2.0, 5.0], [18.0, 5.0]])       # 16 px long, 2 px wide
    >>> wall, outlines = _walls((10, 20), [stroke], [0.1], [], 0.05)
    >>> int(wall.sum()), len(outlines)
    (32, 1)
    """
    wall = np.zeros(shape, bool)
    outlines = list(px_strokes)
    if px_strokes:
        lines = [LineString(s_) if len(s_) > 1 else Point(s_[0]) for s_ in px_strokes]
        half = 0.5 * np.asarray(widths) / resolution
        bodies = shapely.buffer(lines, half, cap_style="square", join_style="mitre",
                                mitre_limit=2.0)
        faced = [] if sides is None else [i for i, x in enumerate(sides) if np.any(x)]
        for i, st in _free_ends(px_strokes, lines, set(faced), half):  # jambs, stubs
            # a square cap where the line meets another (it closes the corner), none at
            # a free end: the wall ends where its line does, a doorway keeps its width
            bodies[i] = shapely.buffer(LineString(st), half[i], cap_style="flat",
                                       join_style="mitre", mitre_limit=2.0)
        for i in faced:                           # strokes with faces of two-line walls
            # piece by piece (GEOS fills a closed ring's whole inside when buffered to one
            # side): a face widened to its wall's side only, other pieces both ways; the
            # corners between two faces are the cavity's, filled as a pocket
            st = px_strokes[i]
            parts = []
            for j in range(len(st) - 1):
                if np.hypot(*(st[j + 1] - st[j])) <= 1e-9:
                    continue
                piece = LineString(st[j:j + 2])
                if sides[i][j]:
                    parts.append(shapely.buffer(piece, 2.0 * half[i] * float(sides[i][j]),
                                                single_sided=True))
                else:
                    parts.append(shapely.buffer(piece, half[i], cap_style="square"))
            bodies[i] = shapely.union_all(parts)
        bodies = shapely.orient_polygons(bodies)
        rings = [np.asarray(r.coords) for r in _polygon_rings(bodies)]
        # the trace (no holes in a thin wall) takes a face of a two-line wall a quarter
        # pixel into its wall: on a pixel boundary it would take its room's pixel
        traced = [st for i, st in enumerate(px_strokes) if i not in faced]
        for i in faced:
            st = px_strokes[i]
            for j in range(len(st) - 1):
                d = st[j + 1] - st[j]
                n = np.hypot(*d)
                if n <= 1e-9:
                    continue
                left = np.array([-d[1], d[0]]) / n
                traced.append(st[j:j + 2] + 0.25 * float(sides[i][j]) * left)
        wall = fill_exact(shape, rings, rule="nonzero") | trace(shape, traced)
        if faced and cavity_px:
            wall |= _cavities(shape, px_strokes, cavity_px)
    if px_fills:
        # each entity even-odd (holes), all of them together as a union; only parts
        # thinner than two pixels are traced, so solid walls keep their true width
        region = shapely.union_all([_even_odd_region(loops) for loops in px_fills])
        region_rings = [
            np.asarray(r.coords) for r in _polygon_rings(shapely.orient_polygons(region))
        ]
        wall |= fill_exact(shape, region_rings, rule="nonzero")
        thin = [np.asarray(r.coords) for r in _polygon_rings(thin_parts(region, 2.0))]
        wall |= trace(shape, thin, closed=True)
        outlines += region_rings  # their outlines count for gap sealing
    return wall, outlines


def _inside(wall, outlines, close_gaps: float, min_free_width: float, resolution: float):
    """(wall, free) masks: the space the walls enclose, narrow pockets made wall.

    The outside is flooded from the border with openings narrower than ``close_gaps``
    sealed (from loose line ends, :func:`_gap_seals`, and between the ends of
    different lines, :func:`_end_seals`); free components that vanish under erosion by
    a disk of diameter ``min_free_width`` (cavities of double-line walls, small
    columns) become wall.

    Examples
    --------
    >>> wall = np.zeros((20, 20), bool)
    >>> wall[2, 2:18] = wall[17, 2:18] = wall[2:18, 2] = wall[2:18, 17] = True
    >>> wall2, free = _inside(wall, [], 1.0, 0.3, 0.05)
    >>> int(free.sum())
    196
    """
    shape = wall.shape
    barrier = wall | trace(shape, _gap_seals(outlines, close_gaps / resolution))
    barrier |= trace(shape, _end_seals(outlines, close_gaps / resolution))
    n, labels = cv2.connectedComponents((~barrier).astype(np.uint8), connectivity=4)
    rim = np.unique(np.concatenate([labels[0], labels[-1], labels[:, 0], labels[:, -1]]))
    outside = np.isin(labels, rim[rim > 0])
    free = ~wall & ~outside
    d = int(round(min_free_width / resolution))
    if d >= 2 and free.any():
        n_free, flabels = cv2.connectedComponents(free.astype(np.uint8), connectivity=8)
        disk = cv2.getStructuringElement(cv2.MORPH_ELLIPSE, (d, d))
        core = cv2.erode(free.astype(np.uint8), disk, borderValue=0) > 0
        roomy = np.zeros(n_free, bool)
        roomy[np.unique(flabels[core])] = True
        pockets = free & ~roomy[flabels]
        free = free & ~pockets
        wall = wall | pockets
    return wall, free


# --------------------------------------------------------------------------- writing
_FRAME_VAR = "map2map_frame"


def occupied_polygons(m: OccupancyMap):
    """The occupied cells as (multi)polygons with pixel-exact outlines, in world metres.

    Runs of occupied cells along each row become rectangles whose coverage union
    (``shapely.coverage_union_all``) is the occupied region; its outline follows the
    cell edges exactly.

    Parameters
    ----------
    m : OccupancyMap
        The map.

    Returns
    -------
    shapely Polygon or MultiPolygon
        In continuous pixel coordinates ``(u = column, v = row)``; empty when nothing
        is occupied.

    Examples
    --------
    >>> data = np.full((4, 5), 255, np.uint8); data[1, 1:4] = 0
    >>> occupied_polygons(OccupancyMap(data, 0.05)).bounds
    (1.0, 1.0, 4.0, 2.0)
    """
    padded = np.pad(m.occupied, ((0, 0), (1, 1))).astype(np.int8)
    step = np.diff(padded, axis=1)
    rows, starts = np.nonzero(step == 1)
    _, ends = np.nonzero(step == -1)
    if rows.size == 0:
        return shapely.MultiPolygon()
    region = shapely.coverage_union_all(shapely.box(starts, rows, ends, rows + 1))
    return shapely.simplify(region, 0)  # drop the run boundaries' collinear vertices


def save_dxf(m: OccupancyMap, path: str | os.PathLike, *, layer: str = "WALLS") -> None:
    """Write the occupied cells of a map as a DXF drawing (metres) for CAD programs.

    Walls become one solid HATCH on ``layer`` whose boundary loops follow the cell
    edges, pulled 1 % of a cell inside the walls so that a reader sampling cell
    centres, or tracing the outlines, finds exactly the same cells. The drawing is
    in world coordinates (the map's origin and yaw applied). The map's frame is
    stored in the header (custom property ``map2map_frame``), so :func:`load_dxf`
    reads it back on the same grid: the occupied cells come back unchanged, and free
    space is re-derived as the space the walls enclose (unknown cells inside the
    walls come back free, free cells open to the outside come back unknown).

    Parameters
    ----------
    m : OccupancyMap
        The map; only its occupied cells are drawn.
    path : path-like
        The ``.dxf`` file, written atomically.
    layer : str
        Layer of the hatch.

    Examples
    --------
    >>> import tempfile, pathlib
    >>> data = np.full((40, 60), 255, np.uint8)
    >>> data[[0, -1], :] = 0; data[:, [0, -1]] = 0
    >>> m = OccupancyMap(data, 0.05, (1.0, 2.0, 0.0))
    >>> path = pathlib.Path(tempfile.mkdtemp()) / "walls.dxf"
    >>> save_dxf(m, path)
    >>> back = load_dxf(path, margin=0)
    >>> back.crop(*back.content_bbox()) == m
    True
    """
    region = shapely.buffer(occupied_polygons(m), -0.01, join_style="mitre")
    loops = []
    for ring in _polygon_rings(region):
        uv = np.asarray(ring.coords)[:-1]
        # continuous pixel coordinates (u, v) -> fractional cell indices -> world
        x, y = m.pixel_to_world(uv[:, 1] - 0.5, uv[:, 0] - 0.5)
        loops.append(np.stack([x, y], axis=1))
    ox, oy, yaw = m.origin
    _write_drawing(path, layer, frame=f"{m.resolution!r} {ox!r} {oy!r} {yaw!r}",
                   loops=loops)


def save_segments_dxf(segments: np.ndarray, path: str | os.PathLike, *, layer: str = "WALLS",
                      width: float | None = None, arcs: np.ndarray | None = None,
                      arc_of: np.ndarray | None = None) -> None:
    """Write wall segments (world metres: x0, y0, x1, y1) as DXF ``LINE`` entities and
    curved walls as ``ARC`` entities (what ``map2map autocorrect --dxf`` writes).

    The drawing is in metres (``$INSUNITS`` 6); ``width`` (metres, optional) is stored as
    each line's constant width through a ``LWPOLYLINE`` instead (an arc's through
    bulges), so CAD shows the wall thickness.

    ``arcs`` (M, 5): ``xc, yc, r, start, sweep`` (metres; degrees counter-clockwise,
    :func:`map2map.maps.curves.arcs_to_world`; a sweep of 360 is a ``CIRCLE``);
    ``arc_of`` (N,): per segment, the arc it is a chord of (not written: the arc is), or
    -1.

    Examples
    --------
    >>> import tempfile, pathlib, ezdxf
    >>> p = pathlib.Path(tempfile.mkdtemp()) / "walls.dxf"
    >>> save_segments_dxf(np.array([[0.0, 0.0, 4.0, 0.0], [4.0, 0.0, 4.0, 3.0]]), p)
    >>> len(ezdxf.readfile(p).modelspace().query("LINE"))
    2
    >>> save_segments_dxf(np.array([[4.0, 0.0, 4.0, 3.0], [2.0, 0.0, 0.0, 2.0]]), p,
    ...                   arcs=np.array([[0.0, 0.0, 2.0, 0.0, 90.0]]), arc_of=[-1, 0])
    >>> [e.dxftype() for e in ezdxf.readfile(p).modelspace()]
    ['LINE', 'ARC']
    """
    segments = np.asarray(segments, float).reshape(-1, 4)
    arcs = np.zeros((0, 5)) if arcs is None else np.asarray(arcs, float).reshape(-1, 5)
    if arc_of is not None:
        arc_of = np.asarray(arc_of, int).reshape(-1)
        if len(arc_of) != len(segments):
            raise ValueError(f"arc_of needs one entry per segment ({len(segments)}), "
                             f"not {len(arc_of)}")
        segments = segments[arc_of < 0]
    _write_drawing(path, layer, segments=segments, width=width, arcs=arcs)


def _write_drawing(path: str | os.PathLike, layer: str, *, frame: str | None = None,
                   loops: list[np.ndarray] = (), segments: np.ndarray | None = None,
                   width: float | None = None, arcs: np.ndarray = ()) -> None:
    """The one DXF writer: a drawing in metres with ``layer``, the map frame stored when
    given, closed ``loops`` as one solid hatch, ``segments`` as lines and ``arcs`` (``xc,
    yc, r, start, sweep``, degrees) as arcs or circles (polylines of constant ``width``
    when given, the arcs' as bulges); written atomically.

    The same drawing gives the same bytes: ezdxf's creation and update dates, its
    "written by" stamps and the drawing's two GUIDs are written as ezdxf's fixed values
    (``ezdxf.options.write_fixed_meta_data_for_testing``, set for this write only)
    instead of the clock and random numbers.
    """
    with _fixed_dxf_metadata():
        _write_drawing_now(path, layer, frame=frame, loops=loops, segments=segments,
                           width=width, arcs=arcs)


@contextmanager
def _fixed_dxf_metadata():
    """ezdxf writes fixed dates, stamps and GUIDs inside the block (its option restored
    after)."""
    import ezdxf

    before = ezdxf.options.write_fixed_meta_data_for_testing
    ezdxf.options.write_fixed_meta_data_for_testing = True
    try:
        yield
    finally:
        ezdxf.options.write_fixed_meta_data_for_testing = before


def _write_drawing_now(path, layer, *, frame, loops, segments, width, arcs) -> None:
    import ezdxf

    from ..core._io import atomic_path

    doc = ezdxf.new(units=6)  # metres
    doc.header["$INSUNITS"] = 6
    if frame is not None:
        doc.header.custom_vars.append(_FRAME_VAR, frame)
    if layer not in doc.layers:
        doc.layers.add(layer)
    msp = doc.modelspace()
    if len(loops):
        hatch = msp.add_hatch(color=7, dxfattribs={"layer": layer})
        hatch.set_solid_fill(color=7)
        for loop in loops:
            hatch.paths.add_polyline_path(loop.tolist(), is_closed=True)
    for x0, y0, x1, y1 in () if segments is None else segments:
        if width:
            msp.add_lwpolyline([(x0, y0), (x1, y1)], dxfattribs={"layer": layer,
                                                                 "const_width": width})
        else:
            msp.add_line((x0, y0), (x1, y1), dxfattribs={"layer": layer})
    for xc, yc, r, start, sweep in arcs:
        _add_arc(msp, (xc, yc), r, start, sweep, layer, width)
    with atomic_path(path) as tmp:
        doc.saveas(tmp)


def _add_arc(msp, centre, r: float, start: float, sweep: float, layer: str,
             width: float | None) -> None:
    """An arc (degrees counter-clockwise from ``start``): ``ARC`` or ``CIRCLE``, or with
    ``width`` a ``LWPOLYLINE`` of constant width whose pieces (at most 90 degrees each)
    bulge along the circle."""
    attribs = {"layer": layer}
    closed = sweep >= 360.0 - 1e-9
    if not width:
        if closed:
            msp.add_circle(centre, r, dxfattribs=attribs)
        else:
            msp.add_arc(centre, r, start, math.fmod(start + sweep, 360.0), dxfattribs=attribs)
        return
    n = max(1, math.ceil(sweep / 90.0 - 1e-9))
    a = np.radians(start + np.linspace(0.0, sweep, n + 1))
    bulge = math.tan(math.radians(sweep / n) / 4)
    pts = [(centre[0] + r * math.cos(t), centre[1] + r * math.sin(t), bulge)
           for t in a[:-1 if closed else None]]
    if not closed:
        pts[-1] = (*pts[-1][:2], 0.0)
    msp.add_lwpolyline(pts, format="xyb", close=closed,
                       dxfattribs={**attribs, "const_width": width})


def _stored_frame(doc) -> tuple[float, float, float, float] | None:
    """(resolution, x, y, yaw) that :func:`save_dxf` stored, if any."""
    try:
        text = doc.header.custom_vars.get(_FRAME_VAR)
        values = tuple(float(v) for v in str(text).split()) if text else ()
    except (AttributeError, ValueError):
        return None
    if len(values) != 4 or not all(math.isfinite(v) for v in values) or values[0] <= 0:
        return None
    return values  # type: ignore[return-value]
