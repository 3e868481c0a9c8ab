"""DXF floor plans (read with ``ezdxf``) rasterised into occupancy maps.

What is drawn
-------------
LINE, LWPOLYLINE, POLYLINE, ARC, CIRCLE, ELLIPSE and SPLINE entities on the chosen
layers become walls ``wall_thickness`` metres thick (curves are flattened to within
a quarter pixel, polyline bulges included); HATCH and SOLID entities are filled as
solid wall. Block references (INSERT) are expanded, nested ones too; an entity on
layer ``0`` inside a block takes the layer of its INSERT, as in CAD programs. Text,
dimensions and other annotation are ignored.

What is free
------------
Space enclosed by walls is free, the outside is unknown. The outside is found by a
flood fill from the border of the raster; for the fill, openings narrower than
``close_gaps`` metres (doors, windows: default 1.0 m) are sealed by joining every
loose end of a line to the nearest other line within that distance, so that an
open entrance door does not let the outside flood the flat. The seals only decide
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
from pathlib import Path
from typing import Any

import numpy as np
import shapely
from scipy import ndimage as ndi
from shapely.geometry import LineString, Point

from ..errors import InputError
from .grid import FREE, OCCUPIED, UNKNOWN, OccupancyMap
from .rasterize import fill_exact, trace

__all__ = [
    "UNITS",
    "DEFAULT_RESOLUTION",
    "DEFAULT_WALL_THICKNESS",
    "load_dxf",
    "dxf_layers",
]

#: Unit names accepted by ``units`` and their size in metres.
UNITS = {"mm": 0.001, "cm": 0.01, "m": 1.0, "in": 0.0254, "ft": 0.3048}
DEFAULT_RESOLUTION = 0.05
DEFAULT_WALL_THICKNESS = 0.1
#: Largest raster (pixels) load_dxf builds before asking for other units/resolution.
MAX_PIXELS = 100_000_000

_LINEAR = {"LINE", "LWPOLYLINE", "POLYLINE", "ARC", "CIRCLE", "ELLIPSE", "SPLINE"}
_FILLED = {"HATCH", "SOLID", "TRACE"}


def _polygon_rings(geom) -> list:
    """Exterior and interior rings of a (multi)polygon."""
    out = []
    for poly in getattr(geom, "geoms", [geom]):
        if poly.is_empty or poly.geom_type != "Polygon":
            continue
        out.append(poly.exterior)
        out.extend(poly.interiors)
    return out


def _gap_seals(strokes: list[np.ndarray], gap: float) -> list[np.ndarray]:
    """Segments closing openings narrower than ``gap`` (door and window openings).

    Every loose end of an open stroke is joined to the nearest point of any other
    stroke (or to the other end of its own) closer than ``gap``. The seals only tell
    inside from outside; they are not drawn as wall.
    """
    if gap <= 0 or not strokes:
        return []
    geoms = [LineString(s_) if len(s_) > 1 else Point(s_[0]) for s_ in strokes]
    ends, owner = [], []
    for i, s_ in enumerate(strokes):
        if len(s_) > 1 and not np.allclose(s_[0], s_[-1]):
            ends.extend([s_[0], s_[-1]])
            owner.extend([i, i])
    if not ends:
        return []
    ends_arr = np.asarray(ends)
    owner_arr = np.asarray(owner)
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
    """Names of the layers defined in a DXF file."""
    doc = _read(Path(path))
    return sorted(layer.dxf.name for layer in doc.layers)


def _walk(entities: Iterable, layer: str | None = None, depth: int = 0) -> Iterator[tuple]:
    """(entity, effective layer) of every entity, INSERTs expanded recursively."""
    for e in entities:
        own = e.dxf.get("layer", "0")
        eff = layer if (layer is not None and own == "0") else own
        if e.dxftype() == "INSERT":
            if depth >= 16:
                continue
            try:
                children = list(e.virtual_entities())
            except Exception:  # noqa: BLE001 - a broken block is skipped, not fatal
                continue
            yield from _walk(children, eff, depth + 1)
        else:
            yield e, eff


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
    resolution: float = DEFAULT_RESOLUTION,
    wall_thickness: float = DEFAULT_WALL_THICKNESS,
    layers: Iterable[str] | None = None,
    units: str | None = None,
    margin: float = 0.5,
    close_gaps: float = 1.0,
    min_free_width: float = 0.3,
) -> OccupancyMap:
    """Rasterise a DXF floor plan (method in the module docstring).

    Parameters
    ----------
    path : path-like
        The ``.dxf`` file.
    resolution : float
        Metres per pixel.
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

    Raises
    ------
    InputError
        File missing or not DXF, unknown layer or unit, no drawable entity on the
        chosen layers, parameters out of range, raster too large.
    """
    p = Path(path)
    for name, v, lo in (
        ("resolution", resolution, 0.0),
        ("wall thickness", wall_thickness, 0.0),
        ("margin", margin, -1.0),
        ("close_gaps", close_gaps, -1.0),
        ("min_free_width", min_free_width, -1.0),
    ):
        if not isinstance(v, int | float) or not math.isfinite(v) or v <= lo or v < 0:
            bound = "> 0" if lo == 0.0 else ">= 0"
            raise InputError(f"--{name.replace(' ', '-')}", f"{name} must be {bound}, got {v!r}")
    if units is not None and units not in UNITS:
        raise InputError("--units", f"units must be one of {', '.join(UNITS)}, got {units!r}")
    doc = _read(p)

    import ezdxf.units

    meta: dict[str, Any] = {"source": str(p)}
    if units is not None:
        scale = UNITS[units]
        meta["units"] = units
    else:
        code = int(doc.header.get("$INSUNITS", 0) or 0)
        if code == 0:
            scale = 1.0
            meta["units"] = "m"
            meta["units_assumed"] = True
        else:
            try:
                scale = ezdxf.units.conversion_factor(code, ezdxf.units.InsertUnits.Meters)
            except Exception:  # noqa: BLE001 - unknown code
                raise InputError(p, f"unknown $INSUNITS code {code}; give the units") from None
            meta["units"] = ezdxf.units.decode(code) if hasattr(ezdxf.units, "decode") else code

    available = {layer.dxf.name.lower(): layer.dxf.name for layer in doc.layers}
    wanted = None
    if layers is not None:
        wanted = {str(name).lower() for name in layers}
        missing = sorted(n for n in wanted if n not in available)
        if missing:
            raise InputError(
                p,
                f"no layer named {', '.join(missing)} "
                f"(layers: {', '.join(sorted(available.values()))})",
            )

    res_units = resolution / scale  # one pixel in drawing units
    strokes: list[np.ndarray] = []
    fills: list[np.ndarray] = []
    counts: Counter = Counter()
    skipped: Counter = Counter()
    used_layers: set[str] = set()
    for e, layer in _walk(doc.modelspace()):
        kind = e.dxftype()
        if wanted is not None and layer.lower() not in wanted:
            continue
        if kind not in _LINEAR and kind not in _FILLED:
            skipped[kind] += 1
            continue
        try:
            pieces, filled = _polylines(e, res_units / 4)
        except Exception:  # noqa: BLE001 - degenerate or unsupported geometry
            skipped[kind] += 1
            continue
        if not pieces:
            skipped[kind] += 1
            continue
        counts[kind] += 1
        used_layers.add(layer)
        (fills if filled else strokes).extend(pieces)
        if filled:
            strokes.extend(pieces)  # outlines too, so thin fills are not lost
    if not strokes:
        chosen = "the chosen layers" if wanted is not None else "any layer"
        raise InputError(
            p,
            "no drawable entities (LINE, LWPOLYLINE, POLYLINE, ARC, CIRCLE, HATCH, ...) "
            f"on {chosen}",
        )

    allpts = np.concatenate(strokes) * scale  # metres
    lo, hi = allpts.min(axis=0), allpts.max(axis=0)
    border = margin + 0.5 * max(wall_thickness, resolution)
    ox, oy = lo[0] - border, lo[1] - border
    w = int(math.ceil((hi[0] - lo[0] + 2 * border) / resolution - 1e-9))
    h = int(math.ceil((hi[1] - lo[1] + 2 * border) / resolution - 1e-9))
    if w * h > MAX_PIXELS:
        raise InputError(
            p,
            f"the map would be {w} x {h} pixels at {resolution:g} m/px (drawing "
            f"{(hi[0] - lo[0]) / scale:.4g} x {(hi[1] - lo[1]) / scale:.4g} units of "
            f"{scale:g} m); give the right --units or a coarser --resolution",
        )

    def to_px(pts: np.ndarray) -> np.ndarray:
        """Drawing units -> continuous pixel coordinates (u = column, v = row)."""
        return np.stack(
            [(pts[:, 0] * scale - ox) / resolution, h - (pts[:, 1] * scale - oy) / resolution],
            axis=1,
        )

    # walls: every stroke widened to wall_thickness (square caps close corners), exact at
    # pixel centres, plus the stroke itself traced through every pixel it crosses so that
    # no wall has a hole whatever its width; fills (hatches, solids) even-odd
    px_strokes = [to_px(s_) for s_ in strokes]
    lines = [LineString(s_) if len(s_) > 1 else Point(s_[0]) for s_ in px_strokes]
    half = 0.5 * wall_thickness / resolution
    body = shapely.union_all(
        shapely.buffer(lines, half, cap_style="square", join_style="mitre", mitre_limit=2.0)
    )
    shapely.prepare(body)
    rings = [np.asarray(r.coords) for r in _polygon_rings(body)]
    wall = fill_exact((h, w), rings, lambda pts: shapely.contains_xy(body, pts[:, 0], pts[:, 1]))
    wall |= trace((h, w), px_strokes)
    if fills:
        px_fills = [to_px(f) for f in fills]
        wall |= fill_exact((h, w), px_fills) | trace((h, w), px_fills, closed=True)

    # inside vs outside: flood the outside, with openings narrower than close_gaps sealed
    barrier = wall | trace((h, w), _gap_seals(px_strokes, close_gaps / resolution))
    labels, n = ndi.label(~barrier)  # 4-connected: 8-connected walls stop it
    border = np.unique(np.concatenate([labels[0], labels[-1], labels[:, 0], labels[:, -1]]))
    outside = np.isin(labels, border[border > 0])
    free = ~wall & ~outside
    # pockets too narrow to be space (cavities of double-line walls, small columns)
    if min_free_width > 0 and free.any():
        flabels, fn = ndi.label(free, np.ones((3, 3), bool))
        dist = ndi.distance_transform_edt(free)
        widest = ndi.maximum(dist, flabels, np.arange(1, fn + 1))
        narrow = np.flatnonzero(2 * np.asarray(widest) * resolution < min_free_width) + 1
        pockets = np.isin(flabels, narrow)
        free &= ~pockets
        wall |= pockets
    data = np.full((h, w), UNKNOWN, np.uint8)
    data[free] = FREE
    data[wall] = OCCUPIED
    meta.update(
        {
            "layers": sorted(used_layers),
            "entities": dict(counts),
            "skipped_entities": dict(skipped),
            "wall_thickness": float(wall_thickness),
            "metres_per_unit": float(scale),
        }
    )
    return OccupancyMap(data, float(resolution), (float(ox), float(oy), 0.0), meta)
