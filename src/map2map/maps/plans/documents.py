"""Plan documents: the layout JSON of ``map2map plan --meta``, and the map rebuilt from it.

Examples
--------
>>> from map2map.maps.plans.generate import generate_floorplan
>>> m = generate_floorplan(2, size=(6, 5))
>>> doc = plan_document(m, seed=2, size=(6, 5))
>>> doc["regenerate"]["seed"], len(doc["map_sha256"])
(2, 64)
"""

from __future__ import annotations

import numpy as np

from ...core.errors import InputError
from ...core.grid import OccupancyMap
from .generate import generate_floorplan

__all__ = ["plan_document", "plan_from_document"]


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

    Parameters
    ----------
    plan : OccupancyMap
        A map from :func:`~map2map.maps.floorplan.generate_floorplan`.
    seed : int
        The seed it was generated with.
    kind : {"apartment", "office"}
        Its building kind.
    size : (W, H) in metres, optional
        The size asked for (None: drawn by the generator).
    furniture : bool
        Whether it was furnished.

    Returns
    -------
    dict
        JSON-ready layout document.

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

    Parameters
    ----------
    doc : dict
        A document from :func:`plan_document` (read from JSON).
    resolution : float, optional
        Metres per pixel of the rebuilt map; default the saved one.
    source : path-like, optional
        The file the document came from, named in error messages.

    Returns
    -------
    OccupancyMap
        The rebuilt plan with its ``meta``.

    Raises
    ------
    InputError
        No or corrupt generator arguments, or a plan that differs from the saved one.

    Examples
    --------
    >>> m = generate_floorplan(4, size=(6, 5))
    >>> plan_from_document(plan_document(m, seed=4, size=(6, 5)), resolution=0.1).resolution
    0.1
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
