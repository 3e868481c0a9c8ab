"""A picture of one map that a person can read at a glance.

Free, occupied and unknown cells in the colours of :mod:`map2map.core.viz`, a metric
scale bar, a legend, and a title giving the size in metres, the resolution and
the free area. Room names are written in when the map carries them (HouseExpo).

Examples
--------
>>> import numpy as np, tempfile, pathlib
>>> from map2map.core.grid import OccupancyMap
>>> data = np.full((60, 80), 255, np.uint8); data[0] = data[-1] = 0; data[:, :5] = 127
>>> path = pathlib.Path(tempfile.mkdtemp()) / "map.png"
>>> save_map_figure(OccupancyMap(data, 0.05), path, title="Example")
>>> path.stat().st_size > 1000
True
>>> map_summary(OccupancyMap(data, 0.05))
'4.0 x 3.0 m, 5 cm/px (80 x 60 px), free 10.9 m²'
"""

from __future__ import annotations

import os

import numpy as np

from ..core.grid import FREE, OCCUPIED, UNKNOWN, OccupancyMap

__all__ = ["save_map_figure", "map_summary"]


def map_summary(m: OccupancyMap) -> str:
    """One line: size in metres, resolution, pixels and free area.

    Parameters
    ----------
    m : OccupancyMap

    Returns
    -------
    str

    Examples
    --------
    >>> import numpy as np
    >>> m = OccupancyMap(np.full((20, 40), 255, np.uint8), 0.05)
    >>> map_summary(m)
    '2.0 x 1.0 m, 5 cm/px (40 x 20 px), free 2.0 m²'
    >>> map_summary(OccupancyMap(m.data, 0.05, meta={"resolution_assumed": True}))
    '40 x 20 px, no metric scale (read at 0.05 m/px), free 800 px'
    """
    if not m.scale_known:
        return (f"{m.width} x {m.height} px, no metric scale (read at "
                f"{m.resolution:g} m/px), free {int(m.free.sum())} px")
    w_m, h_m = m.size_m
    res = m.resolution
    res_text = f"{res * 100:.3g} cm/px" if res < 1 else f"{res:.3g} m/px"
    free_m2 = float(m.free.sum()) * res * res
    return f"{w_m:.1f} x {h_m:.1f} m, {res_text} ({m.width} x {m.height} px), free {free_m2:.1f} m²"


def display_map(m: OccupancyMap, max_pixels: int = 1200) -> OccupancyMap:
    """The map reduced by whole blocks to at most ``max_pixels`` per side, walls kept.

    Showing a large map on a few hundred screen pixels with nearest-neighbour
    sampling drops one-pixel walls; here each block of ``k x k`` cells becomes one
    cell that is occupied if any cell is, else free if any cell is, else unknown.

    Parameters
    ----------
    m : OccupancyMap
        The map.
    max_pixels : int
        Largest side of the result, pixels.

    Returns
    -------
    OccupancyMap
        ``m`` itself when it fits, else the reduced map (resolution times the block
        size, same world extent).

    Examples
    --------
    >>> big = OccupancyMap(np.full((10, 10), 255, np.uint8), 0.1)
    >>> big.data[:, 3] = 0
    >>> small = display_map(big, max_pixels=5)
    >>> small.shape, small.resolution, small.data[0].tolist()
    ((5, 5), 0.2, [255, 0, 255, 255, 255])
    """
    k = int(np.ceil(max(m.shape) / max_pixels))
    if k <= 1:
        return m
    h, w = m.shape
    padded = m.pad(bottom=(-h) % k, right=(-w) % k)
    hb, wb = padded.height // k, padded.width // k
    blocks = padded.data.reshape(hb, k, wb, k)
    occupied = (blocks == OCCUPIED).any(axis=(1, 3))
    free = (blocks == FREE).any(axis=(1, 3))
    return OccupancyMap.from_masks(free, occupied, padded.resolution * k, padded.origin, m.meta)


def _label_rooms(ax, m: OccupancyMap) -> None:
    """Write HouseExpo room categories at the centre of their free space."""
    from scipy import ndimage as ndi

    from .houseexpo import room_labels

    try:
        labels, names = room_labels(m)
    except (ValueError, KeyError, TypeError):
        return
    if not names:
        return
    idx = np.arange(1, len(names) + 1)
    sizes = np.asarray(ndi.sum_labels(np.ones(m.shape), labels, idx))
    big = sizes * m.resolution**2 >= 0.5  # room enough to write in
    if not big.any():
        return
    centres = ndi.center_of_mass(np.ones(m.shape), labels, idx[big])
    for k, (r, c) in zip(np.flatnonzero(big), centres, strict=True):
        name = names[k]
        ax.text(
            c,
            r,
            name.replace("_", " "),
            ha="center",
            va="center",
            fontsize=7,
            color="#2b4c7e",
            bbox={"boxstyle": "round,pad=0.15", "fc": "white", "ec": "none", "alpha": 0.6},
        )


def save_map_figure(
    m: OccupancyMap,
    path: str | os.PathLike,
    title: str | None = None,
    *,
    rooms: bool = True,
    dpi: int = 120,
) -> None:
    """Draw ``m`` and save the figure atomically (format from the suffix: png, pdf, svg).

    Parameters
    ----------
    m : OccupancyMap
    path : path-like
    title : str, optional
        First title line (default: the map's source file name, if known).
    rooms : bool
        Write room names when the map has HouseExpo room categories.
    """
    from matplotlib.patches import Patch

    from ..core.viz import MAP_COLOURS, draw_map, new_figure, save_figure

    if title is None:
        source = m.meta.get("source")
        title = os.path.basename(str(source)) if source else "map"
    shown = display_map(m)
    fig, ax = new_figure(shown)
    draw_map(ax, shown, title=f"{title}\n{map_summary(m)}")
    if rooms and m.meta.get("rooms"):
        _label_rooms(ax, shown)
    handles = [
        Patch(facecolor=MAP_COLOURS[FREE], edgecolor="0.4", label="free"),
        Patch(facecolor=MAP_COLOURS[OCCUPIED], edgecolor="0.4", label="occupied"),
        Patch(facecolor=MAP_COLOURS[UNKNOWN], edgecolor="0.4", label="unknown"),
    ]
    ax.legend(
        handles=handles,
        loc="upper center",
        bbox_to_anchor=(0.5, 0.0),
        ncol=3,
        fontsize=8,
        frameon=False,
        handlelength=1.2,
        borderpad=0.4,
    )
    # enough dots for every displayed cell (the map spans about 4 inches)
    dpi = int(np.clip(max(shown.shape) / 4.0, dpi, 300))
    save_figure(fig, path, dpi=dpi)
