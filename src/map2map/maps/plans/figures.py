"""Figures of floor plans: room labels and door marks drawn from ``m.meta``.

Examples
--------
>>> import matplotlib
>>> matplotlib.use("Agg")
>>> import matplotlib.pyplot as plt
>>> from map2map.maps.plans.generate import generate_floorplan
>>> fig, ax = plt.subplots()
>>> draw_floorplan(ax, generate_floorplan(1, size=(8, 6)))
>>> len(ax.texts) > 2
True
>>> plt.close(fig)
"""

from __future__ import annotations

from ...core.grid import OccupancyMap

__all__ = ["draw_floorplan", "save_floorplan_figure"]


_SHORT = {"Living_Room": "Living", "Dining_Room": "Dining", "Meeting_Room": "Meeting"}


def draw_floorplan(ax, m: OccupancyMap, *, title: str | None = None, doors: bool = True) -> None:
    """Draw a plan with its room labels (and door marks) from ``m.meta``.

    Works for the generator's plans and for rasterised HouseExpo plans (room
    boxes in ``meta["rooms"]`` or ``meta["room_category"]``, HouseExpo frame).

    Parameters
    ----------
    ax : matplotlib.axes.Axes
        Where to draw (pixel coordinates, as :func:`map2map.core.viz.draw_map`).
    m : OccupancyMap
        The plan; room boxes and doors come from ``m.meta``.
    title : str, optional
        Axes title.
    doors : bool
        Mark door centres (red squares).
    """
    from ...core.viz import draw_map

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

    Parameters
    ----------
    m : OccupancyMap
        The plan.
    path : path-like
        Output figure; the format comes from the suffix.
    title : str, optional
        First title line (a summary of the map follows).

    Examples
    --------
    >>> import tempfile, pathlib
    >>> from map2map.maps.floorplan import generate_floorplan
    >>> path = pathlib.Path(tempfile.mkdtemp()) / "plan.png"
    >>> save_floorplan_figure(generate_floorplan(1, size=(8, 6)), path, title="apartment")
    >>> path.stat().st_size > 10_000
    True
    """
    from ...core.viz import new_figure, save_figure
    from ..render import map_summary

    fig, ax = new_figure(m, panel_inches=8.0)
    n_doors = len(m.meta.get("doors", []))
    summary = map_summary(m) + (f", {n_doors} doors (red)" if n_doors else "")
    draw_floorplan(ax, m, title=f"{title}\n{summary}" if title else summary)
    save_figure(fig, path)
