"""Model_32's post-processing (thesis sec. 3.1): from the 32 x 32 output (or the 64 x 64
one of the default model) back to the input's resolution, without the blur.

The network sees and writes 32 x 32 maps; a map at 256 px (or at its own resolution)
needs 8x (or more) upsampling, and plain upsampling gives grey, blurred walls.
:func:`postprocess` does exactly this, in this order:

1. **Upsampling** -- bilinear (``cv2.INTER_LINEAR``, pixel centres aligned) of the grey
   output to the working frame ``(H, W)``; a wall cell of the 32 map becomes a dark band
   centred on that cell.
2. **Snapping** to the three map values: ``< 96`` occupied (a third of the way from
   occupied 0 to free 255, past the occupied/unknown midpoint because blur only ever
   lightens a wall: a thin dark line of the output is a wall, not unknown space),
   ``>= 191`` free (halfway between unknown and free), unknown in between.
3. **Straightening of walls** (``straighten=True``,
   :func:`map2map.maps.segments.straight_segments`): the occupied pixels are thinned to
   their centre lines (``skimage.morphology.skeletonize``), the centre lines are cut into
   straight segments (probabilistic Hough transform, ``cv2.HoughLinesP``, segments at
   least half a model cell long); a segment within ``10`` degrees of horizontal or vertical
   is made exactly horizontal/vertical at its mean coordinate; collinear overlapping
   segments are merged; a segment end that stops short of (or overshoots) a
   perpendicular wall by less than a model cell is moved onto it, so corners and
   T-junctions close.
4. **Guided refinement** (when the input map is given as ``guide``): a model cell is
   ``f = H / s`` pixels (``s`` the model's size), so the network cannot place a wall
   closer than about ``f / 2``.
   Each axis-aligned segment is moved (across its direction only, by at most ``f / 2``)
   onto the mean position of the input map's occupied pixels in that band, when they
   cover at least 30 % of its length. The input's walls are bent, noisy and doubled in
   places; averaging them along a straight segment keeps only their mean position.
5. **Redrawing**: the segments are drawn with the thickness of the training targets'
   walls (``wall_px``, measured on the dataset at training time and scaled to the frame),
   occupied blobs of step 2 that no segment explains (columns, furniture) are kept when at
   least one model cell in area. Free and unknown come from the output with its wall
   cells replaced by their nearest non-wall cell, upsampled the same way and split at 191
   (halfway between unknown 127 and free 255): the grey halo that upsampling leaves beside
   every wall is not taken for unknown space. Last, unknown pockets enclosed by free space
   and walls become free (a plan has no unknown inside the building).

The result is a three-valued map plus its wall segments (pixel coordinates of the
working frame, ``x`` = column, ``y`` = row), which ``map2map autocorrect --dxf`` writes as
vector lines.

Examples
--------
>>> import numpy as np
>>> small = np.full((32, 32), 255.0, np.float32)
>>> small[10, 4:28] = 0.0                           # one horizontal wall at row 10
>>> out, seg = postprocess(small, (256, 256), wall_px=3)
>>> out.shape, sorted(np.unique(out).tolist())
((256, 256), [0, 255])
>>> seg.shape[1], bool(np.all(seg[:, 1] == seg[:, 3]))  # x0 y0 x1 y1, horizontal
(4, True)
"""

from __future__ import annotations

import cv2
import numpy as np
from scipy import ndimage

from ..core.grid import FREE, OCCUPIED, UNKNOWN
from ..maps.segments import straight_segments

__all__ = ["postprocess", "wall_thickness_px", "straight_segments"]

#: Grey level below which an upsampled output pixel is wall (step 2).
WALL_BELOW = 96
#: Grey level from which it is free rather than unknown (step 2).
FREE_FROM = 191


def wall_thickness_px(maps: np.ndarray, limit: int = 64) -> float:
    """Median wall thickness (pixels) of ternary maps: occupied area / centre-line length.

    Examples
    --------
    >>> m = np.full((1, 40, 40), 255, np.uint8); m[0, 10:13, 5:35] = 0
    >>> round(wall_thickness_px(m), 1)       # a 3-px wall (its centre line is a bit short)
    3.1
    """
    from skimage.morphology import skeletonize

    out = []
    for m in np.asarray(maps)[:limit]:
        occ = m == OCCUPIED
        skel = skeletonize(occ).sum()
        if skel:
            out.append(occ.sum() / skel)
    return float(np.median(out)) if out else 1.0


def _refine(segs: np.ndarray, guide_occ: np.ndarray, shift: float) -> np.ndarray:
    """Move axis-aligned segments across onto the mean of the guide's walls (step 4)."""
    out = segs.copy()
    H, W = guide_occ.shape
    d = int(np.ceil(shift))
    for s in out:
        horiz, vert = s[1] == s[3], s[0] == s[2]
        if horiz == vert:
            continue
        if horiz:
            c = s[1]
            lo, hi = int(max(0, min(s[0], s[2]))), int(min(W, max(s[0], s[2]) + 1))
            r0, r1 = int(max(0, np.floor(c) - d)), int(min(H, np.ceil(c) + d + 1))
            band = guide_occ[r0:r1, lo:hi]
            offs = np.arange(r0, r1)
            counts = band.sum(axis=1)
        else:
            c = s[0]
            lo, hi = int(max(0, min(s[1], s[3]))), int(min(H, max(s[1], s[3]) + 1))
            r0, r1 = int(max(0, np.floor(c) - d)), int(min(W, np.ceil(c) + d + 1))
            band = guide_occ[lo:hi, r0:r1]
            offs = np.arange(r0, r1)
            counts = band.sum(axis=0)
        length = max(1, hi - lo)
        covered = band.any(axis=0 if horiz else 1).sum() if band.size else 0
        if covered < 0.3 * length or counts.sum() == 0:
            continue
        new = float(np.sum(offs * counts) / counts.sum())
        if abs(new - c) <= shift:
            if horiz:
                s[1] = s[3] = new
            else:
                s[0] = s[2] = new
    return out


def postprocess(output: np.ndarray, shape: tuple[int, int], guide: np.ndarray | None = None,
                *, wall_px: float = 2.0, straighten: bool = True
                ) -> tuple[np.ndarray, np.ndarray]:
    """Model output (grey, [0, 255], model size) -> (ternary uint8 map of ``shape``,
    wall segments (K, 4) in its pixels); the steps are in the module docstring.

    Parameters
    ----------
    output : ndarray (s, s) float
        The generator's output as grey values (:func:`map2map.learn.networks.from_unit`).
    shape : (H, W)
        The working frame to return to.
    guide : ndarray (H, W) uint8, optional
        The input map in that frame (step 4).
    wall_px : float
        Thickness of the redrawn walls, pixels of the frame.
    straighten : bool
        Steps 3-5; False stops after snapping.
    """
    H, W = shape
    low = np.asarray(output, np.float32)
    up = cv2.resize(low, (W, H), interpolation=cv2.INTER_LINEAR)
    walls = up < WALL_BELOW
    # free vs unknown from the output with its wall cells replaced by their nearest
    # non-wall cell: a wall's grey halo (between 64 and 191 after upsampling) is not unknown
    low_walls = low < WALL_BELOW
    if low_walls.any() and not low_walls.all():
        _, (ri, ci) = ndimage.distance_transform_edt(low_walls, return_indices=True)
        low = low[ri, ci]
    up_space = cv2.resize(low, (W, H), interpolation=cv2.INTER_LINEAR)
    data = np.where(up_space >= FREE_FROM, FREE, UNKNOWN).astype(np.uint8)
    if not straighten:
        data[walls] = OCCUPIED
        return data, np.zeros((0, 4))
    cell = H / low.shape[0]
    segs = straight_segments(walls, cell)
    if guide is not None and len(segs):
        segs = _refine(segs, np.asarray(guide) == OCCUPIED, cell / 2)
    drawn = np.zeros((H, W), np.uint8)
    t = max(1, int(round(wall_px)))
    for x0, y0, x1, y1 in segs:
        cv2.line(drawn, (int(round(x0)), int(round(y0))), (int(round(x1)), int(round(y1))),
                 1, thickness=t)
    if t % 2 == 0 and len(segs):  # cv2 draws odd widths; even ones get one more pixel row
        drawn = cv2.dilate(drawn, np.ones((2, 2), np.uint8))
    near = cv2.dilate(drawn, np.ones((3, 3), np.uint8), iterations=max(1, int(cell)))
    blobs, n = ndimage.label(walls & ~near.astype(bool))
    if n:
        area = np.bincount(blobs.ravel())
        keep = np.flatnonzero(area >= cell * cell)
        keep = keep[keep > 0]
        data[np.isin(blobs, keep)] = OCCUPIED
    wall = drawn.astype(bool)
    data[wall] = OCCUPIED
    # a plan has no unknown pockets inside the building: fill what walls and free enclose
    inside = ndimage.binary_fill_holes((data == FREE) | (data == OCCUPIED))
    data[inside & (data == UNKNOWN)] = FREE
    return data, segs

