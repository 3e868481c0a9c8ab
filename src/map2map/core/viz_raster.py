"""Raster figures without matplotlib: map panels, paths, markers and text (OpenCV + Pillow).

Importing matplotlib costs about 0.4 CPU seconds per process and drawing a
three-panel figure another 0.2; a command that runs thousands of times
(``map2map simulate`` building a data set) draws its figure here instead, in a few
hundredths of a second. The conventions are those of :mod:`map2map.core.viz`: a panel
shows an image (a map) in its pixel coordinates (x = column, y = row, pixel
centres at integers, as ``imshow`` draws), maps in the colours of
:data:`MAP_COLOURS`, with a metric scale bar. Lines are anti-aliased
(``cv2.LINE_AA``, sub-pixel positions); text uses Pillow's default scalable font.

Examples
--------
>>> import numpy as np, tempfile, pathlib
>>> from map2map.core.grid import OccupancyMap
>>> m = OccupancyMap(np.full((40, 60), 255, np.uint8), 0.05)
>>> p = Panel(map_to_rgb(m), title="a room", resolution=m.resolution)
>>> p.line(np.array([5.0, 30.0]), np.array([5.0, 50.0]), colour=(0.2, 0.6, 0.2))
>>> p.markers([5.0], [5.0], colour=(0.2, 0.6, 0.2))
>>> p.legend([("path", (0.2, 0.6, 0.2), "-")])
>>> path = pathlib.Path(tempfile.mkdtemp()) / "m.png"
>>> save_panels([p], path, title="one panel")
>>> path.stat().st_size > 0
True
"""

from __future__ import annotations

import math
import os
from collections.abc import Sequence
from functools import lru_cache

import cv2
import numpy as np

from ._io import atomic_path
from .grid import FREE, OCCUPIED, UNKNOWN, OccupancyMap

__all__ = ["MAP_COLOURS", "map_to_rgb", "map_to_rgb8", "rgb8", "nice_length", "Panel",
           "save_panels"]  # fmt: skip

#: RGB colours of the three cell states.
MAP_COLOURS = {
    FREE: (1.0, 1.0, 1.0),
    OCCUPIED: (0.10, 0.10, 0.12),
    UNKNOWN: (0.78, 0.82, 0.88),
}

Colour = tuple[float, float, float]

_SUB = 4  # sub-pixel bits of cv2 drawing coordinates
_TITLE_PX = 16
_SMALL_PX = 12


def map_to_rgb(m: OccupancyMap | np.ndarray) -> np.ndarray:
    """(H, W, 3) float image: free white, occupied near-black, unknown pale blue-grey.

    Parameters
    ----------
    m : OccupancyMap or (H, W) uint8 array
        A map or its cell values (0, 127, 255).

    Returns
    -------
    (H, W, 3) ndarray of float
        RGB in [0, 1] (:data:`MAP_COLOURS`).

    Examples
    --------
    >>> map_to_rgb(np.array([[0, 127, 255]], np.uint8))[0, :, 0].round(2).tolist()
    [0.1, 0.78, 1.0]
    """
    data = m.data if isinstance(m, OccupancyMap) else np.asarray(m)
    rgb = np.empty((*data.shape, 3), float)
    rgb[:] = MAP_COLOURS[UNKNOWN]
    rgb[data == FREE] = MAP_COLOURS[FREE]
    rgb[data == OCCUPIED] = MAP_COLOURS[OCCUPIED]
    return rgb


def rgb8(colour: Colour) -> np.ndarray:
    """A float colour as the uint8 RGB a :class:`Panel` makes of it (round half up).

    Examples
    --------
    >>> rgb8((1.0, 0.5, 0.0)).tolist()
    [255, 128, 0]
    """
    return _to_uint8(np.asarray(colour, float).reshape(1, 1, 3))[0, 0]


def map_to_rgb8(m: OccupancyMap | np.ndarray) -> np.ndarray:
    """:func:`map_to_rgb` as the uint8 image a :class:`Panel` makes of it, by table look-up:
    the same pixels without a float image of 24 bytes per cell (a 12 MP map).

    Examples
    --------
    >>> d = np.array([[0, 127, 255, 3]], np.uint8)
    >>> bool((map_to_rgb8(d) == _to_uint8(map_to_rgb(d))).all())
    True
    """
    data = m.data if isinstance(m, OccupancyMap) else np.asarray(m)
    lut = np.empty((256, 3), np.uint8)
    lut[:] = rgb8(MAP_COLOURS[UNKNOWN])
    lut[FREE] = rgb8(MAP_COLOURS[FREE])
    lut[OCCUPIED] = rgb8(MAP_COLOURS[OCCUPIED])
    return lut[data.astype(np.uint8, copy=False)]


def nice_length(target_m: float) -> float:
    """A round length (1, 2, 5 x 10^k metres) close to ``target_m``, not above it.

    Parameters
    ----------
    target_m : float
        Wanted length in metres (> 0).

    Returns
    -------
    float
        1, 2 or 5 times a power of ten, at most ``target_m``.

    Examples
    --------
    >>> nice_length(3.7), nice_length(0.3)
    (2.0, 0.2)
    """
    if target_m <= 0:
        return 1.0
    exp = np.floor(np.log10(target_m))
    for step in (5.0, 2.0, 1.0):
        if step * 10**exp <= target_m:
            return float(step * 10**exp)
    return float(10**exp)


@lru_cache(maxsize=8)
def _font(size: int):
    from PIL import ImageFont

    try:
        return ImageFont.load_default(size=size)  # scalable (Pillow >= 10.1 with FreeType)
    except (TypeError, OSError, ImportError):  # pragma: no cover - old or minimal Pillow
        return ImageFont.load_default()


def _rgb255(colour: Colour) -> tuple[int, int, int]:
    return tuple(int(round(255 * float(np.clip(v, 0.0, 1.0)))) for v in colour[:3])


def _to_uint8(image: np.ndarray) -> np.ndarray:
    img = np.asarray(image)
    if img.ndim == 2:
        img = np.repeat(img[:, :, None], 3, axis=2)
    if img.dtype != np.uint8:
        img = (np.clip(img, 0.0, 1.0) * 255.0 + 0.5).astype(np.uint8)
    return img[:, :, :3]


class Panel:
    """One panel: an image scaled to about ``size`` pixels, with drawings on top.

    Parameters
    ----------
    image : (H, W, 3) array
        RGB, float in [0, 1] or uint8 (e.g. :func:`map_to_rgb`).
    title : str
        Drawn above the panel.
    resolution : float, optional
        Metres per image pixel: draws a scale bar in the lower-left corner.
    size : int
        Target width of the panel (the height follows the aspect ratio, capped
        at ``1.5 * size``). Small images are enlarged by a whole factor (crisp
        pixels), large ones reduced by area averaging.
    """

    def __init__(
        self,
        image: np.ndarray,
        *,
        title: str = "",
        resolution: float | None = None,
        size: int = 540,
    ):
        img = _to_uint8(image)
        h, w = img.shape[:2]
        s = min(size / max(w, 1), 1.5 * size / max(h, 1))
        if s >= 1:
            k = max(1, int(math.floor(s)))
            img = cv2.resize(img, (w * k, h * k), interpolation=cv2.INTER_NEAREST)
        else:
            img = cv2.resize(
                img, (max(1, round(w * s)), max(1, round(h * s))), interpolation=cv2.INTER_AREA
            )
        self.image = np.ascontiguousarray(img)
        self.sx = self.image.shape[1] / w
        self.sy = self.image.shape[0] / h
        self.title = title
        self.texts: list[tuple[float, float, str, int, tuple[int, int, int]]] = []
        self._overlays: list = []  # scale bar, legend: drawn last, over the lines
        if resolution:
            self._overlays.append(lambda: self._scale_bar(float(resolution), w))

    # ------------------------------------------------------------ geometry
    def _xy(self, rows, cols) -> np.ndarray:
        """Panel pixel coordinates (x, y) of image coordinates (pixel centres at integers)."""
        r = np.asarray(rows, float).ravel()
        c = np.asarray(cols, float).ravel()
        return np.column_stack([(c + 0.5) * self.sx, (r + 0.5) * self.sy])

    @staticmethod
    def _fixed(pts: np.ndarray) -> np.ndarray:
        return np.round(pts * (1 << _SUB)).astype(np.int32)

    def _blend(self, draw, alpha: float) -> None:
        if alpha >= 1.0:
            draw(self.image)
            return
        layer = self.image.copy()
        draw(layer)
        cv2.addWeighted(layer, alpha, self.image, 1.0 - alpha, 0.0, dst=self.image)

    def line(
        self,
        rows,
        cols,
        *,
        colour: Colour,
        width: float = 1.5,
        dashed: bool = False,
        alpha: float = 1.0,
    ) -> None:
        """A polyline through image coordinates ``(rows, cols)``; NaN points break it.

        Parameters
        ----------
        rows, cols : array-like
            Image coordinates (fractional allowed) of the vertices.
        colour : (r, g, b)
            Floats in [0, 1].
        width : float
            Line width, panel pixels.
        dashed : bool
            Dashed line.
        alpha : float
            Opacity.
        """
        pts = self._xy(rows, cols)
        ok = np.isfinite(pts).all(axis=1)
        # runs of finite points
        edges = np.flatnonzero(np.diff(np.concatenate([[0], ok.astype(np.int8), [0]])))
        runs = [pts[a:b] for a, b in zip(edges[::2], edges[1::2], strict=True) if b - a >= 2]
        thick = max(1, int(round(width)))
        if dashed:
            runs = [d for run in runs for d in _dashes(run, 4.0 * thick + 2, 2.5 * thick + 1)]
        if not runs:
            return
        polys = [self._fixed(r) for r in runs]
        col = _rgb255(colour)

        def draw(img):
            cv2.polylines(img, polys, False, col, thick, cv2.LINE_AA, _SUB)

        self._blend(draw, alpha)

    def markers(
        self, rows, cols, *, colour: Colour, marker: str = "o", size: float = 5.0, width: int = 2
    ) -> None:
        """Filled discs (``"o"``) or crosses (``"x"``) of diameter ``size`` panel pixels.

        Parameters
        ----------
        rows, cols : array-like
            Image coordinates of the markers.
        colour : (r, g, b)
            Floats in [0, 1].
        marker : {"o", "x"}
            Disc or cross.
        size : float
            Diameter, panel pixels.
        width : float
            Stroke width of a cross, panel pixels.
        """
        pts = self._xy(rows, cols)
        pts = pts[np.isfinite(pts).all(axis=1)]
        col = _rgb255(colour)
        half = size / 2.0
        for x, y in pts:
            if marker == "x":
                for dx, dy in ((half, half), (half, -half)):
                    a = self._fixed(np.array([[x - dx, y - dy]]))[0]
                    b = self._fixed(np.array([[x + dx, y + dy]]))[0]
                    cv2.line(self.image, tuple(a), tuple(b), col, width, cv2.LINE_AA, _SUB)
            else:
                c = self._fixed(np.array([[x, y]]))[0]
                r = int(round(half * (1 << _SUB)))
                cv2.circle(self.image, tuple(c), r, col, -1, cv2.LINE_AA, _SUB)

    def text(self, x: float, y: float, s: str, *, size: int = _SMALL_PX, colour=(0, 0, 0)):
        """Text with its top-left corner at panel pixel ``(x, y)``.

        Parameters
        ----------
        x, y : float
            Panel pixels.
        s : str
            The text.
        size : int
            Text height, pixels.
        colour : (r, g, b)
            Floats in [0, 1].
        """
        self.texts.append((x, y, s, size, _rgb255(colour)))

    def _box(self, x0: int, y0: int, x1: int, y1: int, alpha: float = 0.8) -> None:
        h, w = self.image.shape[:2]
        x0, x1 = max(0, x0), min(w, x1)
        y0, y1 = max(0, y0), min(h, y1)
        if x1 <= x0 or y1 <= y0:
            return
        roi = self.image[y0:y1, x0:x1]
        roi[:] = (roi * (1.0 - alpha) + 255.0 * alpha).astype(np.uint8)
        cv2.rectangle(self.image, (x0, y0), (x1 - 1, y1 - 1), (160, 160, 160), 1)

    def _scale_bar(self, resolution: float, width_px: int) -> None:
        length_m = nice_length(0.2 * width_px * resolution)
        bar = int(round(length_m / resolution * self.sx))
        label = f"{length_m:g} m" if length_m >= 1 else f"{length_m * 100:g} cm"
        h = self.image.shape[0]
        pad = 6
        tw = _font(_SMALL_PX).getbbox(label)[2]
        box_w = max(bar, tw) + 2 * pad
        box_h = _SMALL_PX + 3 + 3 + 2 * pad + 2
        x0, y1 = 6, h - 6
        self._box(x0, y1 - box_h, x0 + box_w, y1)
        bx = x0 + (box_w - bar) // 2
        by = y1 - pad - 2
        cv2.rectangle(self.image, (bx, by - 2), (bx + bar, by), (0, 0, 0), -1)
        self.text(x0 + (box_w - tw) / 2, y1 - box_h + pad - 2, label)

    def legend(self, entries: Sequence[tuple[str, Colour, str]]) -> None:
        """A legend box in the upper-right corner: ``(label, colour, style)`` with style
        ``"-"`` (line), ``"--"`` (dashed line), ``"o"`` or ``"x"`` (marker).

        Parameters
        ----------
        entries : sequence of (label, colour, style)
            One row each.
        """
        if entries:
            self._overlays.append(lambda: self._legend(list(entries)))

    def finish(self) -> np.ndarray:
        """Draw the overlays (scale bar, legend) and return the panel image.

        Returns
        -------
        (H, W, 3) uint8 array
        """
        for draw in self._overlays:
            draw()
        self._overlays = []
        return self.image

    def _legend(self, entries: list[tuple[str, Colour, str]]) -> None:
        font = _font(_SMALL_PX)
        pad, sample, row = 6, 22, _SMALL_PX + 5
        tw = max(font.getbbox(label)[2] for label, _, _ in entries)
        w = pad * 3 + sample + tw
        h = pad * 2 + row * len(entries)
        x1 = self.image.shape[1] - 6
        x0, y0 = x1 - w, 6
        self._box(x0, y0, x1, y0 + h)
        for k, (label, colour, style) in enumerate(entries):
            yc = y0 + pad + row * k + row / 2
            xs = np.array([x0 + pad, x0 + pad + sample], float)
            col = _rgb255(colour)
            if style in ("-", "--"):
                seg = np.column_stack([xs, [yc, yc]])
                runs = _dashes(seg, 6.0, 4.0) if style == "--" else [seg]
                cv2.polylines(
                    self.image, [self._fixed(r) for r in runs], False, col, 2, cv2.LINE_AA, _SUB
                )
            else:
                rr = (yc / self.sy) - 0.5
                cc = (xs.mean() / self.sx) - 0.5
                self.markers([rr], [cc], colour=colour, marker=style, size=7)
            self.text(x0 + 2 * pad + sample, yc - _SMALL_PX / 2 - 2, label)


def _dashes(pts: np.ndarray, on: float, off: float) -> list[np.ndarray]:
    """Split a polyline (panel pixels) into dashes ``on`` long with ``off`` gaps."""
    seg = np.hypot(*np.diff(pts, axis=0).T)
    s = np.concatenate([[0.0], np.cumsum(seg)])
    total = float(s[-1])
    if total <= 0:
        return []
    period = on + off
    starts = np.arange(0.0, total, period)
    ends = np.minimum(starts + on, total)
    out = []
    for a, b in zip(starts, ends, strict=True):
        inner = np.flatnonzero((s > a) & (s < b))
        ts = np.concatenate([[a], s[inner], [b]])
        xy = np.column_stack([np.interp(ts, s, pts[:, 0]), np.interp(ts, s, pts[:, 1])])
        out.append(xy)
    return out


def save_panels(
    panels: Sequence[Panel], path: str | os.PathLike, *, title: str | None = None
) -> None:
    """Lay panels out in a row with their titles (and an overall ``title``) and write a
    PNG atomically.

    Parameters
    ----------
    panels : sequence of Panel
        Drawn left to right, top-aligned.
    path : path-like
        The PNG file (written through a temporary name).
    title : str, optional
        Drawn above all panels.

    Examples
    --------
    >>> import tempfile, pathlib
    >>> path = pathlib.Path(tempfile.mkdtemp()) / "panels.png"
    >>> img = map_to_rgb(np.full((20, 30), 255, np.uint8))
    >>> save_panels([Panel(img, title="a"), Panel(img, title="b")], path, title="two")
    >>> path.read_bytes()[1:4]
    b'PNG'
    """
    from PIL import Image, ImageDraw

    pad = 12
    title_h = _TITLE_PX + 12 if any(p.title for p in panels) else 0
    sup_h = _TITLE_PX + 16 if title else 0
    ph = max(p.image.shape[0] for p in panels)
    width = pad + sum(p.image.shape[1] + pad for p in panels)
    height = sup_h + title_h + ph + pad + (0 if sup_h else pad)
    canvas = np.full((height, width, 3), 255, np.uint8)
    places = []
    x = pad
    for p in panels:
        h, w = p.image.shape[:2]
        y = (sup_h or pad) + title_h
        canvas[y : y + h, x : x + w] = p.finish()
        cv2.rectangle(canvas, (x - 1, y - 1), (x + w, y + h), (0, 0, 0), 1)
        places.append((x, y))
        x += w + pad
    img = Image.fromarray(canvas)
    draw = ImageDraw.Draw(img)

    def centred(cx, y, s, size):
        font = _font(size)
        draw.text((cx - font.getlength(s) / 2, y), s, fill=(0, 0, 0), font=font)

    if title:
        centred(width / 2, 8, title, _TITLE_PX)
    for p, (x0, y0) in zip(panels, places, strict=True):
        if p.title:
            size = _TITLE_PX
            while size > 9 and _font(size).getlength(p.title) > p.image.shape[1]:
                size -= 1
            centred(x0 + p.image.shape[1] / 2, y0 - title_h + 3, p.title, size)
        for tx, ty, s, size, col in p.texts:
            draw.text((x0 + tx, y0 + ty), s, fill=col, font=_font(size))
    ok, buf = cv2.imencode(".png", np.asarray(img)[:, :, ::-1])
    if not ok:  # pragma: no cover - OpenCV always encodes uint8 RGB
        raise RuntimeError("PNG encoding failed")
    with atomic_path(path) as tmp:
        tmp.write_bytes(buf.tobytes())
