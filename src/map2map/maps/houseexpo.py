"""HouseExpo floor plans (JSON) rasterised into occupancy maps.

A HouseExpo plan (Li et al., 2019; derived from SUNCG) is ONE polygon ``verts`` in
metres tracing the free space of a whole apartment; interior walls are thin slits
of that polygon. The file also holds ``bbox`` (``{"min": [x, y], "max": [x, y]}``),
``room_num`` and ``room_category`` (``{"Kitchen": [[x1, y1, x2, y2], ...], ...}``).

HouseExpo's plans are the CAD maps the thesis trains on (section 4.1); turning them
into grids is the appendix paper's first step of map matching (section 3.2: the
as-planned drawing is exported at the SLAM map's resolution and its cells quantified
to occupied 0, open 255, unexplored 127).

Rasterisation (:func:`rasterise_houseexpo`)
-------------------------------------------
1. Inside the polygon is free, the rest of the bounding box occupied, and a margin
   around the box unknown. Cells are classified by their centres
   (:func:`~map2map.maps.rasterize.fill_exact`), which is unbiased for walls thicker
   than two pixels.
2. Thin walls survive. Plain centre sampling drops a wall narrower than a pixel
   wherever it passes between two rows of centres, opening holes between rooms.
   The wall region (bounding box minus polygon) is opened morphologically
   (``shapely`` buffer by -r then +r, mitred, r = one pixel); what the opening
   removes are the walls thinner than two pixels. Those thin parts are drawn
   conservatively: filled, and their outlines traced through every pixel they cross
   (:func:`~map2map.maps.rasterize.trace`), so each thin wall is an unbroken
   barrier even for 8-connected free space. Thick walls keep their true width. (An
   invalid, self-touching polygon, whose zero-width slits have no area, gets its
   whole outline traced instead.)
3. Free space never touches unknown space: unknown cells next to free ones become
   occupied (where the polygon runs along the bounding box, the outer wall has no
   width in the file).

Frame
-----
The picture is laid out as HouseExpo's own renderer draws it: column = x, row = y
(rows grow with y, so the first row holds the smallest y), so our maps have the
orientation of HouseExpo's published renders. A ROS frame (y up) therefore
sees the plan's y axis reversed: world ``(x, y) = (x_json, -y_json)`` and headings
``-theta_json``; :func:`houseexpo_to_world` converts poses, e.g. the trajectories
shipped with HouseExpo.

Examples
--------
>>> doc = {"verts": [[0, 0], [2, 0], [2, 1], [0, 1]], "bbox": {"min": [0, 0], "max": [2, 1]},
...        "room_category": {"Kitchen": [[0, 0, 2, 1]]}}
>>> m = rasterise_houseexpo(doc, resolution=0.1, margin=0.2)
>>> m.shape, int(m.free.sum())
((14, 24), 200)
>>> labels, names = room_labels(m)
>>> names, int((labels == 1).sum())
(['Kitchen'], 200)
"""

from __future__ import annotations

import json
import math
import os
from pathlib import Path
from typing import Any

import cv2
import numpy as np
from shapely.geometry import Polygon, box

from ..core.errors import InputError
from ..core.grid import FREE, OCCUPIED, UNKNOWN, OccupancyMap
from ..core.limits import check_map_size
from .rasterize import fill_exact, thin_parts, trace

__all__ = [
    "is_houseexpo",
    "plan_poses_to_world",
    "DEFAULT_RESOLUTION",
    "DEFAULT_MARGIN",
    "load_houseexpo",
    "rasterise_houseexpo",
    "room_labels",
    "houseexpo_to_world",
]

DEFAULT_RESOLUTION = 0.05
#: Unknown margin around the bounding box (HouseExpo's renders pad 25 px at 1 cm).
DEFAULT_MARGIN = 0.25


def houseexpo_to_world(x, y, theta=None):
    """HouseExpo plan coordinates -> world (ROS, y up) coordinates of our maps.

    The conversion is its own inverse.

    Parameters
    ----------
    x, y : float or array-like
        Plan coordinates (y down).
    theta : float or array-like, optional
        Headings in radians.

    Returns
    -------
    tuple
        ``(x, -y)``, or ``(x, -y, -theta)`` when ``theta`` is given.

    Examples
    --------
    >>> houseexpo_to_world(1.0, 2.0, 0.5)
    (1.0, -2.0, -0.5)
    """
    wx = np.asarray(x, float) if np.ndim(x) else float(x)
    wy = -np.asarray(y, float) if np.ndim(y) else -float(y)
    if theta is None:
        return wx, wy
    wt = -np.asarray(theta, float) if np.ndim(theta) else -float(theta)
    return wx, wy, wt


def is_houseexpo(m: OccupancyMap) -> bool:
    """Whether ``m`` was read from a HouseExpo JSON plan (its coordinates have y down).

    Parameters
    ----------
    m : OccupancyMap

    Returns
    -------
    bool

    Examples
    --------
    >>> doc = {"verts": [[0, 0], [2, 0], [2, 1], [0, 1]], "bbox": {"min": [0, 0], "max": [2, 1]}}
    >>> is_houseexpo(rasterise_houseexpo(doc, resolution=0.1))
    True
    """
    return m.meta.get("frame") == "houseexpo"


def plan_poses_to_world(poses: np.ndarray) -> np.ndarray:
    """(N, 2) points or (N, 3) poses in HouseExpo's plan frame -> the map's world (ROS) frame.

    What a user gives for a HouseExpo plan (start, goal, waypoints, a trajectory) is in
    HouseExpo's own coordinates, as its trajectory files are; every job converts it here.

    Parameters
    ----------
    poses : (N, 2) or (N, 3) array-like
        Points or poses in HouseExpo plan coordinates.

    Returns
    -------
    ndarray
        Same shape, world coordinates.

    Examples
    --------
    >>> plan_poses_to_world(np.array([[1.0, 2.0, 0.5]])).tolist()
    [[1.0, -2.0, -0.5]]
    """
    out = np.array(poses, float, copy=True)
    out[:, 1] *= -1
    if out.shape[1] == 3:
        out[:, 2] *= -1
    return out


# --------------------------------------------------------------------------- parsing
def _validate(doc: Any, source) -> tuple[np.ndarray, tuple[float, float, float, float]]:
    if not isinstance(doc, dict):
        raise InputError(source, "not a HouseExpo plan (expected a JSON object with 'verts')")
    if "verts" not in doc:
        raise InputError(source, "HouseExpo plan has no 'verts'")
    try:
        verts = np.asarray(doc["verts"], dtype=float)
    except (TypeError, ValueError):
        raise InputError(source, "'verts' must be a list of [x, y] pairs") from None
    if verts.ndim != 2 or verts.shape[1] != 2:
        raise InputError(source, "'verts' must be a list of [x, y] pairs")
    if not np.isfinite(verts).all():
        raise InputError(source, "'verts' holds non-finite coordinates")
    if len(verts) > 1 and np.array_equal(verts[0], verts[-1]):
        verts = verts[:-1]  # explicitly closed ring
    if len(np.unique(verts, axis=0)) < 3:
        raise InputError(source, f"'verts' needs at least 3 distinct vertices, got {len(verts)}")
    if abs(Polygon(verts).area) <= 0:
        raise InputError(source, "'verts' encloses no area")
    lo, hi = verts.min(axis=0), verts.max(axis=0)
    bb = doc.get("bbox")
    if bb is not None:
        try:
            bmin = np.asarray(bb["min"], float)
            bmax = np.asarray(bb["max"], float)
            if bmin.shape != (2,) or bmax.shape != (2,) or not np.isfinite([bmin, bmax]).all():
                raise ValueError
        except (TypeError, KeyError, ValueError):
            raise InputError(source, "'bbox' must be {'min': [x, y], 'max': [x, y]}") from None
        lo, hi = np.minimum(lo, bmin), np.maximum(hi, bmax)
    return verts, (float(lo[0]), float(lo[1]), float(hi[0]), float(hi[1]))


def load_houseexpo(
    path: str | os.PathLike,
    *,
    resolution: float | None = None,
    margin: float = DEFAULT_MARGIN,
) -> OccupancyMap:
    """Read a HouseExpo JSON plan and rasterise it (see :func:`rasterise_houseexpo`).

    ``resolution`` defaults to :data:`DEFAULT_RESOLUTION`. The layout JSON that
    ``map2map plan --meta`` writes is recognised and rebuilt as that plan
    (:func:`map2map.maps.floorplan.plan_from_document`, default its own resolution).

    Parameters
    ----------
    path : path-like
        The JSON plan.
    resolution : float, optional
        Metres per pixel.
    margin : float
        Unknown border around the outline, metres.

    Returns
    -------
    OccupancyMap
        Walls occupied, the polygon's inside free, outside unknown; ``meta`` as
        :func:`rasterise_houseexpo` (``source``, ``houseexpo_id``, ``room_num``,
        ``room_category``, ``rooms``, ``frame``).

    Raises
    ------
    InputError
        File missing, not JSON, no ``verts`` or fewer than 3 vertices, resolution
        not > 0.
    """
    p = Path(path)
    if not p.exists():
        raise InputError(p, "file not found")
    try:
        doc = json.loads(p.read_text(encoding="utf-8"))
    except (OSError, UnicodeDecodeError) as exc:
        raise InputError(p, f"cannot read file ({exc})") from None
    except json.JSONDecodeError as exc:
        raise InputError(p, f"not valid JSON (line {exc.lineno}: {exc.msg})") from None
    if isinstance(doc, dict) and "verts" not in doc and "regenerate" in doc:
        # the layout that ``map2map plan --meta`` writes: rebuild that plan
        from .plans.documents import plan_from_document

        return plan_from_document(doc, resolution=resolution, source=p)
    if resolution is None:
        resolution = DEFAULT_RESOLUTION
    return rasterise_houseexpo(doc, resolution=resolution, margin=margin, source=p)


# --------------------------------------------------------------------------- drawing
def _to_px(xy: np.ndarray, x0: float, y0: float, res: float, pad: int) -> np.ndarray:
    """Plan metres -> continuous pixel coordinates (u = column, v = row)."""
    xy = np.asarray(xy, float)
    return np.stack([(xy[:, 0] - x0) / res + pad, (xy[:, 1] - y0) / res + pad], axis=1)


def _rings(geom) -> list[np.ndarray]:
    out = []
    for poly in getattr(geom, "geoms", [geom]):
        if poly.is_empty or poly.geom_type != "Polygon":
            continue
        out.append(np.asarray(poly.exterior.coords))
        out.extend(np.asarray(r.coords) for r in poly.interiors)
    return out


def thin_wall_parts(polygon: Polygon, bounds, resolution: float):
    """The parts of the wall region (bounds minus polygon) thinner than two pixels.

    Parameters
    ----------
    polygon : shapely Polygon
        The plan's free region, in metres.
    bounds : (minx, miny, maxx, maxy)
        The canvas in the same coordinates.
    resolution : float
        Metres per pixel: parts thinner than ``2 * resolution`` are returned.

    Returns
    -------
    shapely geometry
    """
    return thin_parts(box(*bounds).difference(polygon), 2.0 * resolution)


def rasterise_houseexpo(
    doc: dict,
    *,
    resolution: float = DEFAULT_RESOLUTION,
    margin: float = DEFAULT_MARGIN,
    thin_walls: bool = True,
    source: str | os.PathLike | None = None,
) -> OccupancyMap:
    """Rasterise a parsed HouseExpo plan (method in the module docstring).

    Parameters
    ----------
    doc : dict
        The JSON object (``verts``, optional ``bbox``, ``room_category``, ``id``).
    resolution : float
        Metres per pixel (default 0.05).
    margin : float
        Width in metres of the unknown band around the bounding box.
    thin_walls : bool
        Keep walls thinner than two pixels (default). False gives plain centre
        sampling, which loses them; it exists for comparison.
    source : path-like, optional
        Named in error messages.

    Returns
    -------
    OccupancyMap
        ``meta``: ``source``, ``houseexpo_id``, ``room_num``, ``room_category`` (as in
        the file), ``rooms`` (list of ``{"category", "bbox"}``, plan metres) and
        ``frame`` (``"houseexpo"``: see :func:`houseexpo_to_world`).
    """
    src = source if source is not None else "HouseExpo plan"
    if not (isinstance(resolution, int | float) and math.isfinite(resolution) and resolution > 0):
        raise InputError("resolution", f"resolution must be > 0, got {resolution!r}")
    if not (isinstance(margin, int | float) and math.isfinite(margin) and margin >= 0):
        raise InputError("margin", f"margin must be >= 0, got {margin!r}")
    verts, bounds = _validate(doc, src)
    x0, y0, x1, y1 = bounds
    res = float(resolution)
    pad = int(math.ceil(margin / res - 1e-9))
    w_in = max(1, int(math.ceil((x1 - x0) / res - 1e-9)))
    h_in = max(1, int(math.ceil((y1 - y0) / res - 1e-9)))
    h, w = h_in + 2 * pad, w_in + 2 * pad
    check_map_size((h, w), src)  # before any allocation of the map's size

    free = fill_exact((h, w), [_to_px(verts, x0, y0, res, pad)])
    inside_box = np.zeros((h, w), bool)
    inside_box[pad : pad + h_in, pad : pad + w_in] = True
    walls = np.zeros((h, w), bool)
    if thin_walls:
        polygon = Polygon(verts)
        if polygon.is_valid:
            rings = [
                _to_px(r, x0, y0, res, pad) for r in _rings(thin_wall_parts(polygon, bounds, res))
            ]
            walls = fill_exact((h, w), rings) | trace((h, w), rings)
        else:  # zero-width slits have no area: trace the whole outline
            walls = trace((h, w), [_to_px(verts, x0, y0, res, pad)], closed=True)
    data = np.full((h, w), UNKNOWN, np.uint8)
    data[inside_box] = OCCUPIED
    data[free & ~walls] = FREE
    data[walls] = OCCUPIED
    # free space is closed: unknown cells touching free ones are wall
    near_free = cv2.dilate((data == FREE).astype(np.uint8), np.ones((3, 3), np.uint8)) > 0
    data[near_free & (data == UNKNOWN)] = OCCUPIED

    rooms = []
    cats = doc.get("room_category") or {}
    if isinstance(cats, dict):
        for name, boxes in cats.items():
            for b in boxes if isinstance(boxes, list) else []:
                try:
                    bx = [float(v) for v in b]
                except (TypeError, ValueError):
                    continue
                if len(bx) == 4 and all(math.isfinite(v) for v in bx):
                    rooms.append({"category": str(name), "bbox": bx})
    origin = (x0 - pad * res, -(y0 - pad * res) - h * res, 0.0)
    meta = {
        "source": str(source) if source is not None else None,
        "houseexpo_id": doc.get("id"),
        "room_num": doc.get("room_num"),
        "room_category": cats,
        "rooms": rooms,
        "frame": "houseexpo",
    }
    return OccupancyMap(data, res, origin, meta)


def room_labels(m: OccupancyMap) -> tuple[np.ndarray, list[str]]:
    """Room label image of a rasterised HouseExpo plan.

    Returns ``(labels, names)``: ``labels`` is an (H, W) int32 array, 0 outside
    every room box or off free space, ``k >= 1`` for room ``meta["rooms"][k - 1]``
    whose category is ``names[k - 1]``. Where room boxes overlap (they do in
    HouseExpo), the smaller box wins. Works on cropped or padded maps too: boxes are
    placed through the map's world frame.

    Parameters
    ----------
    m : OccupancyMap
        A plan read by :func:`load_houseexpo` (or a crop of it).

    Returns
    -------
    labels : (H, W) int32 array
    names : list of str
    """
    rooms = m.meta.get("rooms") or []
    labels = np.zeros(m.shape, np.int32)
    if m.origin[2] != 0.0:
        raise ValueError("room_labels needs an unrotated map (yaw 0)")
    order = sorted(
        range(len(rooms)),
        key=lambda k: (
            -abs(
                (rooms[k]["bbox"][2] - rooms[k]["bbox"][0])
                * (rooms[k]["bbox"][3] - rooms[k]["bbox"][1])
            )
        ),
    )
    for k in order:
        bx = rooms[k]["bbox"]
        wx, wy = houseexpo_to_world(np.array([bx[0], bx[2]]), np.array([bx[1], bx[3]]))
        rows, cols = m.world_to_pixel_float(wx, wy)
        r0, r1 = int(math.ceil(rows.min())), int(math.floor(rows.max()))
        c0, c1 = int(math.ceil(cols.min())), int(math.floor(cols.max()))
        r0, c0 = max(r0, 0), max(c0, 0)
        r1, c1 = min(r1, m.height - 1), min(c1, m.width - 1)
        if r1 >= r0 and c1 >= c0:
            labels[r0 : r1 + 1, c0 : c1 + 1] = k + 1
    labels[~m.free] = 0
    return labels, [r["category"] for r in rooms]
