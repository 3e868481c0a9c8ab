"""Model_AB's resolution raising (thesis sec. 3.1): from the network's coarse output (64 x
64 for the shipped weights) to a map at the plan's resolution whose walls look like a SLAM
map's, not like the plan's.

The thesis raises Model_32's output to the input's resolution and removes the blur
(:mod:`map2map.learn.ba.postprocess` does it for Model_BA, whose targets are plans with thick
walls). Model_AB's targets are SLAM maps, and a SLAM map's walls are what the laser traced:
the faces of the walls that border mapped free space, about two pixels thick (the
simulated maps of the datasets: 2.1 px at 256 px), with unknown space behind a face where
no ray reached. A 64 px output upsampled to 256 px cannot draw that: one output cell is 4
plan pixels, so its walls are 4-6 px thick blocks (docs/synthesize.md: 5.8 px against the
simulated 2.1 px, the realism table's worst ratio). :func:`render_slam` does, in this order:

1. **Class memberships** of the grey output ``g`` (occupied 0, unknown 127, free 255), the
   triangular "probabilities" ``p_occ = clip((127 - g) / 127)``, ``p_free = clip((g - 127)
   / 128)``, ``p_unk = 1 - p_occ - p_free`` (their argmax is exactly
   :func:`snap`).
2. **Bilinear upsampling** of the three memberships to the output size (``cv2.INTER_LINEAR``,
   pixel centres aligned; ``INTER_AREA`` when shrinking) and **snapping** to the class of
   the largest. Upsampling the memberships, not the grey values, keeps a wall cell next to
   a free cell meeting it directly: their grey blend passes through 127 and would leave a
   band of false unknown between every wall and its room.
3. **Faces**: the distance ``d`` of every pixel to the nearest free pixel (Euclidean
   distance transform). An occupied pixel is kept as a wall if ``d <= wall_px``: the band
   of the given thickness along every face that borders free space. ``wall_px`` is the
   training targets' wall thickness (:func:`~map2map.learn.ba.postprocess.wall_thickness_px`
   of the SLAM maps, measured when the model was trained and stored in its header as
   ``target_wall_px``; :data:`DEFAULT_WALL_PX` for weights without it), scaled to the
   output frame. Every occupied pixel touching free space (``d = 1``) is kept, so no wall
   that has a face is lost.
4. **Wall interiors and unseen walls -> unknown**: an occupied pixel farther than
   ``wall_px`` from free space is the inside of a thick wall, or a wall with no free space
   beside it at all; no laser ray ends there, and a SLAM map shows it unknown.

Free and unknown space are those of step 2. :func:`render_plain` is the previous output
(snap at the network's resolution, nearest-neighbour upsampling): ``map2map synthesize
--render plain``.

**LIDAR traces** (:class:`TraceParams`, ``synthesize(..., traces="lidar")``, the default
of :func:`~map2map.learn.ab.synthesize.synthesize` since session 11; :func:`render_slam`
alone draws none of them unless asked; issue #15, docs/synthesize.md "Rendering what a
LIDAR leaves", where the defaults were tuned on gen900 val): what a LIDAR + SLAM run
leaves on a grid map beyond the wall faces, measured on the simulated maps of the
datasets and drawn here, seeded (:func:`trace_rng`):

* a **metric wall band**: a simulated map's walls are the spread of the hits across the
  wall (range noise, the particle filter's pose scatter, the 0.05 m grid), a width in
  metres: in a square of ``r`` m/px it is ``floor_px + wall_m / r`` px (gen900 val, run
  1: ``1.24 + 0.043 / r``, residual 0.13 px; a fixed px thickness misses it, and that
  spread is what the ``thickness`` statistic's W(run 2, run 1) of 0.02 px asks for).
  :func:`band_px`;
* a **ragged back edge**: the band's depth is the band plus ``U(0, rough_px)``, drawn
  from a field correlated along the wall over ``rough_sigma_px`` (hits scattered behind
  the face by the pose error of the scans that saw that stretch; with ``rough_px = 1`` a
  fractional band is drawn with the right mean thickness instead of being floored to
  whole pixels);
* **stray hits** (:func:`stray_hits`): isolated 1-3 px hits off the walls that no later
  ray cleared: behind a face, in unknown space (a scan inserted at a wrong pose; its
  rays pass the wall and its hits land beyond it) or inside mapped free space (random and
  short returns, eq. of the beam model's ``p_rand``/``p_short``). Per map a Poisson count
  with a log-normal rate (most runs leave few, some many).

Examples
--------
A 16 px output with a 2-cell thick wall between two rooms, raised to 64 px (4 px a cell):
the 8 px wall becomes two 2 px faces with unknown between them.

>>> g = np.full((16, 16), 255.0, np.float32); g[:, 7:9] = 0.0
>>> r = render_slam(g, 64, wall_px=2.0)
>>> row = r.map[32]
>>> int((row == 0).sum()), int((row == 127).sum())
(4, 4)
"""

from __future__ import annotations

import os
from dataclasses import dataclass

import numpy as np
from scipy import ndimage

from ...core.grid import FREE, OCCUPIED, UNKNOWN

__all__ = ["RENDERS", "TRACES", "DEFAULT_WALL_PX", "SlamRender", "TraceParams", "snap",
           "class_memberships", "render_slam", "render_plain", "render", "band_px",
           "trace_params", "trace_rng", "rough_field", "stray_hits", "save_render_figure"]

#: ``synthesize --render`` choices: SLAM-like walls (default) or the previous output.
RENDERS = ("slam", "plain")
#: Wall thickness (px of a 256 px dataset square) for weights whose header lacks
#: ``target_wall_px`` (the simulated maps of the datasets measure 2.07 px).
DEFAULT_WALL_PX = 2.0
#: ``synthesize --traces`` choices: none (the walls of the render only) or lidar
#: (:class:`TraceParams`).
TRACES = ("none", "lidar")
_STREAM = 0x7ACE5


@dataclass(frozen=True)
class TraceParams:
    """What a LIDAR + SLAM leaves beyond the wall faces (module doc, "LIDAR traces").

    Parameters
    ----------
    floor_px : float
        Band thickness at any resolution (px of the output square): the one pixel a
        hit cell keeps after the square's resize. 1.2 was tuned for the session-9
        weights while the room drift's parametric field squeezed walls by ~15 %; with
        :class:`~map2map.learn.ab.room_drift.RoomDriftParams` ``conserve=True`` 0.85 draws
        the simulated thickness (session 12); 1.05 for the weights shipped in session
        13, whose network walls are ~0.15 px thicker (docs/synthesize.md). With
        ``coverage="rays"`` 0.85 (2026-11-27: on 120 dev plans the ``thickness`` ranks'
        P(low) / P(high) were 0.10 / 0.67 at 1.05, 0.28 / 0.45 at 0.9 and 0.46 / 0.30
        at 0.8; on the frozen test 0.35 / 0.33 at 0.85).
    wall_m : float
        Metric part of the band [m]: ``floor_px + wall_m / resolution`` px.
    rough_px : float
        Extra depth of the band's back edge, ``U(0, rough_px)`` px, drawn per pixel
        from a field correlated along the wall (:func:`rough_field`).
    rough_sigma_px : float
        Correlation length [px] of that field (the stretch of wall one scan's pose error
        moves together; 0: independent per pixel).
    inset_px : float
        Faces moved this far into the network's wall cells (:func:`render_slam`): the
        network places a face at the edge of its coarse wall cell, a LIDAR at the
        wall's surface, on average inside that cell.
    strays : float
        Mean number of stray hits per map.
    stray_spread : float
        Log-normal spread of a map's stray rate (``exp(spread * z - spread^2 / 2)``).
    stray_free : float
        Share of the stray hits placed in mapped free space (the rest behind faces).
    stray_m : tuple of float
        Range [m] of a behind-face hit's distance past the face.
    stray_big : float
        Share of the stray hits 2-3 px large (the rest single pixels).
    """

    floor_px: float = 1.05
    wall_m: float = 0.055
    rough_px: float = 1.0
    rough_sigma_px: float = 4.0
    inset_px: float = 1.0
    strays: float = 7.0
    stray_spread: float = 0.8
    stray_free: float = 0.45
    stray_m: tuple = (0.2, 0.9)
    stray_big: float = 0.35

    def __post_init__(self):
        vals = (self.floor_px, self.wall_m, self.rough_px, self.rough_sigma_px, self.inset_px,
                self.strays, self.stray_spread)
        if not all(np.isfinite(v) and v >= 0 for v in vals):
            raise ValueError("trace parameters must be finite and >= 0")
        if not (0 <= self.stray_free <= 1 and 0 <= self.stray_big <= 1):
            raise ValueError("stray_free and stray_big are shares in [0, 1]")
        lo, hi = self.stray_m
        if not 0 <= lo <= hi:
            raise ValueError(f"stray_m must be 0 <= lo <= hi, got {self.stray_m}")


def trace_params(traces) -> TraceParams | None:
    """``"none"`` / ``None`` -> None, ``"lidar"`` -> :class:`TraceParams` (), or the
    given TraceParams.

    Examples
    --------
    >>> trace_params("none") is None, trace_params("lidar").wall_m
    (True, 0.055)
    """
    if traces is None or isinstance(traces, TraceParams):
        return traces
    if traces == "none":
        return None
    if traces == "lidar":
        return TraceParams()
    raise ValueError(f"traces must be one of {TRACES} or TraceParams, got {traces!r}")


def trace_rng(seed: int, k: int) -> np.random.Generator:
    """The LIDAR-trace generator of hypothesis (or plan) ``k`` under ``seed`` (its own
    stream, apart from the drift's and the exploration's).

    Examples
    --------
    >>> float(trace_rng(0, 1).random()) == float(trace_rng(0, 1).random())
    True
    """
    return np.random.default_rng(np.random.SeedSequence(int(seed), spawn_key=(_STREAM, int(k))))


def rough_field(shape, rng: np.random.Generator, sigma_px: float) -> np.ndarray:
    """A ``U(0, 1)`` field, correlated over ``sigma_px`` (Gaussian-smoothed white noise
    mapped through the normal CDF; ``sigma_px = 0``: independent pixels).

    Examples
    --------
    >>> f = rough_field((64, 64), trace_rng(0, 0), 4.0)
    >>> bool(0 <= f.min() and f.max() <= 1), abs(float(f.mean()) - 0.5) < 0.1
    (True, True)
    """
    from scipy.special import ndtr

    z = rng.standard_normal(shape)
    if sigma_px > 0:
        z = ndimage.gaussian_filter(z, sigma_px, mode="wrap")
        z /= max(float(z.std()), 1e-12)
    return ndtr(z)


def band_px(resolution: float, params: TraceParams) -> float:
    """The wall band [px] of a square of ``resolution`` m/px (module doc).

    Examples
    --------
    >>> round(band_px(0.05, TraceParams(floor_px=1.0, wall_m=0.05)), 2)
    2.0
    """
    return float(params.floor_px + params.wall_m / float(resolution))


def snap(grey: np.ndarray) -> np.ndarray:
    """Grey values -> the nearest of occupied 0, unknown 127, free 255.

    Examples
    --------
    >>> snap(np.array([10.0, 100.0, 200.0])).tolist()
    [0, 127, 255]
    """
    out = np.full(np.shape(grey), UNKNOWN, np.uint8)
    out[grey < 63.5] = OCCUPIED
    out[grey > 191.0] = FREE
    return out


def class_memberships(grey: np.ndarray) -> np.ndarray:
    """(H, W) grey map -> (H, W, 3) float32 memberships of occupied, unknown, free (step 1).

    Examples
    --------
    >>> class_memberships(np.array([[0.0, 127.0, 255.0, 191.0]])).round(2).tolist()[0]
    [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0], [0.0, 0.5, 0.5]]
    """
    g = np.asarray(grey, np.float32)
    occ = np.clip((UNKNOWN - g) / UNKNOWN, 0.0, 1.0)
    free = np.clip((g - UNKNOWN) / (FREE - UNKNOWN), 0.0, 1.0)
    return np.stack([occ, 1.0 - occ - free, free], axis=-1).astype(np.float32)


@dataclass
class SlamRender:
    """What :func:`render_slam` made, with its intermediate step for figures.

    Attributes
    ----------
    map : (S, S) uint8
        The rendered map (occupied 0, unknown 127, free 255).
    snapped : (S, S) uint8
        Step 2: the upsampled memberships snapped, before the walls are thinned.
    wall_px : float
        The wall thickness used (px of the output frame).
    interior : int
        Occupied pixels of step 2 turned unknown (wall interiors, unseen walls).
    """

    map: np.ndarray
    snapped: np.ndarray
    wall_px: float
    interior: int


def _upsample(p: np.ndarray, size: int) -> np.ndarray:
    import cv2

    how = cv2.INTER_LINEAR if size >= max(p.shape[:2]) else cv2.INTER_AREA
    return cv2.resize(p, (size, size), interpolation=how)


def render_slam(grey: np.ndarray, size: int, wall_px: float = DEFAULT_WALL_PX,
                rough_px: float = 0.0, rng: np.random.Generator | None = None,
                rough_sigma_px: float = 0.0, inset_px: float = 0.0) -> SlamRender:
    """The network's grey output -> a ``size x size`` map with SLAM-like walls (module doc).

    Parameters
    ----------
    grey : (r, r) float
        Model_AB's output in grey values (0 occupied .. 255 free).
    size : int
        Side of the output square (pixels of the plan's square).
    wall_px : float
        Wall thickness in output pixels (at least 1 is used): occupied pixels within this
        distance of free space are kept.
    rough_px : float
        Ragged back edge: each occupied pixel is kept within ``wall_px + U(0, rough_px)``
        of free space (:class:`TraceParams`; 0: the plain band).
    rng : numpy.random.Generator, optional
        Draws the edge (required when ``rough_px > 0``).
    rough_sigma_px : float
        Correlation length of the edge (:func:`rough_field`).
    inset_px : float
        Faces moved this far into the network's walls (:class:`TraceParams`): occupied
        pixels within ``inset_px`` of free space become free before the band is drawn,
        where the wall has pixels deeper than that (a thinner wall is left whole).

    Returns
    -------
    SlamRender

    Examples
    --------
    >>> g = np.full((8, 8), 255.0, np.float32); g[:, :2] = 0.0      # a thick wall, left
    >>> r = render_slam(g, 32, wall_px=2.0)
    >>> sorted(set(r.map[16, :12].tolist()))                       # unknown | 2 px | free
    [0, 127, 255]
    >>> int((r.map[16] == 0).sum())
    2
    """
    p = _upsample(class_memberships(grey), int(size))
    cls = np.argmax(p, axis=-1)
    snapped = np.choose(cls, np.array([OCCUPIED, UNKNOWN, FREE], np.uint8)).astype(np.uint8)
    free = cls == 2
    occ = cls == 0
    t = max(1.0, float(wall_px))
    out = snapped.copy()
    if inset_px > 0 and free.any():
        d0 = ndimage.distance_transform_edt(~free)
        # only walls with a core deeper than the inset: a thin wall is not erased
        core = occ & (d0 > inset_px + 1e-6)
        grow = occ & (d0 <= inset_px + 1e-6) & ndimage.binary_dilation(
            core, np.ones((3, 3), bool), iterations=int(np.ceil(inset_px)) + 1)
        out[grow] = FREE
        free, occ = free | grow, occ & ~grow
    if free.any():
        d = ndimage.distance_transform_edt(~free)
        lim = t + 1e-6
        if rough_px > 0:
            if rng is None:
                raise ValueError("rough_px > 0 needs an rng")
            lim = lim + rough_px * rough_field(d.shape, rng, rough_sigma_px)
        drop = occ & (d > lim)
    else:
        drop = occ
    out[drop] = UNKNOWN
    return SlamRender(out, snapped, t, int(np.count_nonzero(drop)))


def render_plain(grey: np.ndarray, size: int) -> np.ndarray:
    """The previous output: snapped at the network's resolution, nearest-neighbour
    upsampling to ``size x size`` (walls one output cell thick, or more).

    Examples
    --------
    >>> render_plain(np.array([[0.0, 255.0]]).repeat(2, 0), 4)[0].tolist()
    [0, 0, 255, 255]
    """
    import cv2

    return cv2.resize(snap(grey), (int(size), int(size)), interpolation=cv2.INTER_NEAREST)


def render(grey: np.ndarray, size: int, how: str = "slam",
           wall_px: float = DEFAULT_WALL_PX, traces: TraceParams | None = None,
           rng: np.random.Generator | None = None) -> np.ndarray:
    """:func:`render_slam` (``how="slam"``) or :func:`render_plain` (``"plain"``), as a map.

    Examples
    --------
    >>> g = np.full((4, 4), 255.0); g[:, 0] = 0.0
    >>> render(g, 16, "plain").shape, render(g, 16, "slam", 1.0)[5, :6].tolist()
    ((16, 16), [127, 127, 127, 0, 255, 255])
    """
    if how == "slam":
        if traces is None:
            return render_slam(grey, size, wall_px).map
        return render_slam(grey, size, wall_px, traces.rough_px, rng, traces.rough_sigma_px,
                           traces.inset_px).map
    if how == "plain":
        return render_plain(grey, size)
    raise ValueError(f"render must be one of {RENDERS}, got {how!r}")


def stray_hits(m: np.ndarray, rng: np.random.Generator, resolution: float,
               params: TraceParams) -> np.ndarray:
    """Map ``m`` with stray LIDAR hits added (module doc): a Poisson number of 1-3 px
    occupied dots, each either behind a random wall face (along the direction away from
    its nearest free pixel, ``stray_m`` metres past it) or at a random free pixel at least
    3 px from any wall; a dot is only drawn where it lands on unknown (behind a face) or
    free (in a room) space, never on a wall.

    Parameters
    ----------
    m : (H, W) uint8
        Ternary map.
    rng : numpy.random.Generator
        :func:`trace_rng`.
    resolution : float
        Metres per pixel of ``m``.
    params : TraceParams

    Returns
    -------
    (H, W) uint8

    Examples
    --------
    >>> m = np.full((40, 40), 127, np.uint8); m[5:35, 5:20] = 255; m[5:35, 20:22] = 0
    >>> out = stray_hits(m, trace_rng(0, 0), 0.05, TraceParams(strays=20, stray_spread=0))
    >>> bool(((out == 0) & (m != 0)).any()), bool(((out != m) & (m == 0)).any())
    (True, False)
    """
    m = np.asarray(m, np.uint8)
    out = m.copy()
    free, occ = m == FREE, m == OCCUPIED
    rate = params.strays * np.exp(params.stray_spread * rng.standard_normal()
                                  - 0.5 * params.stray_spread**2)
    n = int(rng.poisson(rate))
    if n == 0 or not free.any() or not occ.any():
        return out
    H, W = m.shape
    in_free = rng.random(n) < params.stray_free
    dist = rng.uniform(*params.stray_m, n) / float(resolution)
    u = rng.random(n)
    big = rng.random(n) < params.stray_big
    nb = rng.integers(0, 8, (n, 2))
    face = occ & ndimage.binary_dilation(free, np.ones((3, 3), bool))
    fy, fx = np.nonzero(face)
    # in a room: a free pixel at least 3 px from every wall
    room = free & (ndimage.distance_transform_edt(~occ) > 3)
    ry, rx = np.nonzero(room)
    if len(fy):
        _, (iy, ix) = ndimage.distance_transform_edt(~free, return_indices=True)
        # behind a face: from a face pixel, away from its nearest free pixel
        k = (u * len(fy)).astype(int).clip(0, len(fy) - 1)
        py, px = fy[k], fx[k]
        vy, vx = py - iy[py, px], px - ix[py, px]
        norm = np.maximum(np.hypot(vy, vx), 1e-9)
        by, bx = py + vy / norm * dist, px + vx / norm * dist
    elif len(ry):                       # no wall borders free space: room hits only
        by, bx = np.zeros(n), np.zeros(n)
        in_free[:] = True
    else:
        return out
    if len(ry):
        j = (u * len(ry)).astype(int).clip(0, len(ry) - 1)
        by = np.where(in_free, ry[j], by)
        bx = np.where(in_free, rx[j], bx)
    else:
        in_free[:] = False
    ty, tx = np.rint(by).astype(int), np.rint(bx).astype(int)
    ok = (ty >= 0) & (ty < H) & (tx >= 0) & (tx < W)
    ty, tx, in_free, big, nb = ty[ok], tx[ok], in_free[ok], big[ok], nb[ok]
    want = np.where(in_free, FREE, UNKNOWN)
    ok = m[ty, tx] == want
    out[ty[ok], tx[ok]] = OCCUPIED
    # 2-3 px hits: one or two of the 8 neighbours, on the same kind of space
    steps = np.array([(-1, -1), (-1, 0), (-1, 1), (0, -1), (0, 1), (1, -1), (1, 0), (1, 1)])
    for c in range(2):
        sel = ok & big & ((c == 0) | (nb[:, 1] % 2 == 0))
        sy = (ty + steps[nb[:, c], 0]).clip(0, H - 1)
        sx = (tx + steps[nb[:, c], 1]).clip(0, W - 1)
        sel &= m[sy, sx] == want
        out[sy[sel], sx[sel]] = OCCUPIED
    return out


def save_render_figure(grey: np.ndarray, result: SlamRender, path: str | os.PathLike,
                       plan: np.ndarray | None = None, title: str = "",
                       reference: np.ndarray | None = None) -> None:
    """The steps side by side: (plan |) network output | previous output (plain) |
    upsampled memberships snapped | SLAM-like walls (wall pixels turned unknown in red)
    (| ``reference``, a simulated SLAM map of the plan).

    Examples
    --------
    >>> import tempfile, pathlib
    >>> g = np.full((16, 16), 255.0, np.float32); g[:, 6:9] = 0.0
    >>> p = pathlib.Path(tempfile.mkdtemp()) / "r.png"
    >>> save_render_figure(g, render_slam(g, 64, 2.0), p, reference=np.zeros((64, 64)))
    >>> p.stat().st_size > 1000
    True
    """
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from ...core._io import atomic_path

    size = result.map.shape[0]
    dropped = (result.snapped == OCCUPIED) & (result.map != OCCUPIED)
    over = np.dstack([result.map] * 3).astype(np.uint8)
    over[dropped] = (220, 60, 60)
    panels = [] if plan is None else [(plan, "plan (input)")]
    panels += [(np.asarray(grey), f"network output ({grey.shape[0]} px)"),
               (render_plain(grey, size), "plain: snap + nearest"),
               (result.snapped, "memberships bilinear, snapped"),
               (over, f"SLAM walls ({result.wall_px:.1f} px faces; red -> unknown)")]
    if reference is not None:
        panels.append((reference, "simulated SLAM map (reference)"))
    fig, axes = plt.subplots(1, len(panels), figsize=(3.2 * len(panels), 3.6), squeeze=False)
    for ax, (img, name) in zip(axes[0], panels, strict=True):
        ax.imshow(img, cmap="gray", vmin=0, vmax=255, interpolation="nearest")
        ax.set_title(name, fontsize=8)
        ax.set_xticks([])
        ax.set_yticks([])
    fig.suptitle(title or "Model_AB resolution raising (thesis 3.1)", fontsize=9)
    fig.tight_layout()
    with atomic_path(path) as tmp:
        fig.savefig(tmp, dpi=100, format="png")
    plt.close(fig)
