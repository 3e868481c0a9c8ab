"""Model_AB's resolution raising (thesis sec. 3.1): from the network's coarse output (64 x
64 for the shipped weights) to a map at the plan's resolution whose walls look like a SLAM
map's, not like the plan's.

The thesis raises Model_32's output to the input's resolution and removes the blur
(:mod:`map2map.learn.postprocess` does it for Model_BA, whose targets are plans with thick
walls). Model_AB's targets are SLAM maps, and a SLAM map's walls are what the laser traced:
the faces of the walls that border mapped free space, about two pixels thick (the
simulated maps of the datasets: 2.1 px at 256 px), with unknown space behind a face where
no ray reached. A 64 px output upsampled to 256 px cannot draw that: one output cell is 4
plan pixels, so its walls are 4-6 px thick blocks (docs/learn_ab.md: 5.8 px against the
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
   training targets' wall thickness (:func:`~map2map.learn.postprocess.wall_thickness_px`
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

from ..core.grid import FREE, OCCUPIED, UNKNOWN

__all__ = ["RENDERS", "DEFAULT_WALL_PX", "SlamRender", "snap", "class_memberships",
           "render_slam", "render_plain", "render", "save_render_figure"]

#: ``synthesize --render`` choices: SLAM-like walls (default) or the previous output.
RENDERS = ("slam", "plain")
#: Wall thickness (px of a 256 px dataset square) for weights whose header lacks
#: ``target_wall_px`` (the simulated maps of the datasets measure 2.07 px).
DEFAULT_WALL_PX = 2.0


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


def render_slam(grey: np.ndarray, size: int, wall_px: float = DEFAULT_WALL_PX) -> SlamRender:
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
    if free.any():
        d = ndimage.distance_transform_edt(~free)
        drop = occ & (d > t + 1e-6)
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
           wall_px: float = DEFAULT_WALL_PX) -> np.ndarray:
    """:func:`render_slam` (``how="slam"``) or :func:`render_plain` (``"plain"``), as a map.

    Examples
    --------
    >>> g = np.full((4, 4), 255.0); g[:, 0] = 0.0
    >>> render(g, 16, "plain").shape, render(g, 16, "slam", 1.0)[5, :6].tolist()
    ((16, 16), [127, 127, 127, 0, 255, 255])
    """
    if how == "slam":
        return render_slam(grey, size, wall_px).map
    if how == "plain":
        return render_plain(grey, size)
    raise ValueError(f"render must be one of {RENDERS}, got {how!r}")


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

    from ..core._io import atomic_path

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
