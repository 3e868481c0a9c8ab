"""Figures shared by every stage: map colours, metric scale bar, atomic saving.

Every figure in map2map is drawn in *pixel* coordinates of the map it shows
(x = column, y = row, origin top-left, as ``imshow`` draws), with a metric scale
bar, so that overlays from any stage line up without conversions.

Examples
--------
>>> import numpy as np, tempfile, pathlib
>>> from map2map.core.grid import OccupancyMap
>>> m = OccupancyMap(np.full((40, 60), 255, np.uint8), 0.05)
>>> fig, ax = new_figure(m)
>>> draw_map(ax, m)
>>> path = pathlib.Path(tempfile.mkdtemp()) / "m.png"
>>> save_figure(fig, path)
>>> path.stat().st_size > 0
True
"""

from __future__ import annotations

import os

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
from matplotlib.axes import Axes  # noqa: E402
from matplotlib.figure import Figure  # noqa: E402

from ._io import atomic_path  # noqa: E402
from .grid import OccupancyMap  # noqa: E402
from .viz_raster import MAP_COLOURS, map_to_rgb  # noqa: E402  (colours shared with raster figures)
from .viz_raster import nice_length as _nice_length  # noqa: E402

__all__ = ["MAP_COLOURS", "map_to_rgb", "draw_map", "add_scale_bar", "new_figure", "save_figure"]

def add_scale_bar(ax: Axes, resolution: float, width_px: int, *, colour: str = "black") -> None:
    """Draw a metric scale bar (about a fifth of the width) in the lower-left corner.

    Parameters
    ----------
    ax : matplotlib.axes.Axes
        Axes showing the map in pixel coordinates.
    resolution : float
        Metres per pixel.
    width_px : int
        Width of the map in pixels (the bar is about a fifth of it).
    colour : str
        Bar and label colour.
    """
    from matplotlib.offsetbox import AnchoredOffsetbox, AuxTransformBox, TextArea, VPacker
    from matplotlib.patches import Rectangle

    length_m = _nice_length(0.2 * width_px * resolution)
    length_px = length_m / resolution
    label = f"{length_m:g} m" if length_m >= 1 else f"{length_m * 100:g} cm"
    bar = AuxTransformBox(ax.transData)
    bar.add_artist(Rectangle((0, 0), length_px, 0, ec=colour, lw=3, fc="none"))
    text = TextArea(label, textprops={"color": colour, "fontsize": 9})
    box = VPacker(children=[text, bar], align="center", pad=0, sep=3)
    anchored = AnchoredOffsetbox(loc="lower left", child=box, pad=0.4, borderpad=0.6, frameon=True)
    anchored.patch.set_alpha(0.7)
    ax.add_artist(anchored)


def draw_map(
    ax: Axes,
    m: OccupancyMap,
    *,
    title: str | None = None,
    scale_bar: bool = True,
    alpha: float = 1.0,
) -> None:
    """Show a map in pixel coordinates with the three-state colours and a scale bar.

    Parameters
    ----------
    ax : matplotlib.axes.Axes
        Where to draw.
    m : OccupancyMap
        The map (free white, occupied dark, unknown grey).
    title : str, optional
        Axes title.
    scale_bar : bool
        Draw a metric scale bar (:func:`add_scale_bar`), when the map has a metric scale
        (:attr:`~map2map.core.grid.OccupancyMap.scale_known`).
    alpha : float
        Opacity of the image.
    """
    ax.imshow(map_to_rgb(m), interpolation="nearest", alpha=alpha)
    ax.set_xlim(-0.5, m.width - 0.5)
    ax.set_ylim(m.height - 0.5, -0.5)
    ax.set_xticks([])
    ax.set_yticks([])
    if title:
        ax.set_title(title, fontsize=10)
    if scale_bar and m.scale_known:
        add_scale_bar(ax, m.resolution, m.width)


def new_figure(m: OccupancyMap | None = None, ncols: int = 1, panel_inches: float = 5.0):
    """A figure with ``ncols`` panels sized to the map's aspect ratio.

    Parameters
    ----------
    m : OccupancyMap, optional
        Map whose aspect ratio (clipped to 0.3-3) sizes the panels; square when None.
    ncols : int
        Number of panels side by side.
    panel_inches : float
        Width of one panel in inches.

    Returns
    -------
    fig : matplotlib.figure.Figure
    axes : Axes or array of Axes
        One Axes when ``ncols == 1``, else an array of ``ncols``.

    Examples
    --------
    >>> fig, axes = new_figure(ncols=2)
    >>> len(axes)
    2
    >>> import matplotlib.pyplot as plt; plt.close(fig)
    """
    aspect = 1.0 if m is None else m.height / max(m.width, 1)
    aspect = float(np.clip(aspect, 0.3, 3.0))
    fig, axes = plt.subplots(
        1, ncols, figsize=(panel_inches * ncols, panel_inches * aspect + 0.6), squeeze=False
    )
    axes = axes[0]
    return fig, (axes[0] if ncols == 1 else axes)


def save_figure(fig: Figure, path: str | os.PathLike, dpi: int = 120) -> None:
    """Save atomically as PNG (by the path's suffix) and close the figure.

    Parameters
    ----------
    fig : matplotlib.figure.Figure
        The figure (closed afterwards).
    path : path-like
        Output file; the format comes from its suffix (PNG when none).
    dpi : int
        Resolution of raster formats.
    """
    try:
        fig.tight_layout()
    except Exception:  # noqa: BLE001 - layout is cosmetic
        pass
    fmt = os.path.splitext(os.fspath(path))[1].lstrip(".") or "png"
    with atomic_path(path) as tmp:
        fig.savefig(tmp, dpi=dpi, format=fmt)
    plt.close(fig)
