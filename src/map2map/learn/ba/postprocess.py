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
4b. **Anchored walls** (``anchor=True``, the default when a ``guide`` is given; replaces
   steps 4-5): a SLAM map's wall faces are already where the laser hit them, within a
   pixel or so of the plan's, and a 64 px network cannot place a wall better than a few
   pixels of a 256 map (docs/autocorrect.md measures it). So the walls are the input's own,
   straightened at full resolution: its wall pixels are cut into straight segments
   (step 3 on the input, ``ANCHOR.cell`` = 4 dataset pixels), and each wall is drawn
   with its faces at the **median** position of the input's faces along it
   (:func:`anchored_walls`, within ``ANCHOR.band`` = 3 dataset pixels): a noisy, jagged
   face becomes one straight face where it was seen; a wall seen from one side only
   gets the training targets' thickness behind its face (the plan's thick walls, so
   wall recall rises), never into space the input saw free. The network decides what
   the input does not show: its straight walls lying farther than ``ANCHOR.new`` (4
   dataset pixels) from any input wall over 70 % of their length are added (walls the
   robot never saw); one whose band (the network draws walls several model cells thick)
   comes within ``ANCHOR.new`` of an input wall seen from one side is that wall's body
   behind its face (the plans' thick outer walls) and is drawn with it as one wall,
   from the face to the band's far side (:func:`_join_backing`; drawn apart, the two
   were the demo's doubled outer walls, issue #14). Input wall pixels that no straight
   wall explains (corners, short
   pieces) are kept where the network has a wall within a model cell (elsewhere they
   are clutter: furniture, people); those a straight wall replaces take the value of
   their nearest non-wall pixel. Free and unknown space come from the input, except
   free space the network calls unknown more than two model cells from any wall (laser
   streaks through windows and open doors), which becomes unknown. Two more rules,
   measured on Table 5.3 (``git show e59abf4^:docs/learn.md``, "Why 43 % of the maps were
   not improved"): free islands of the input smaller than ``ANCHOR.speck`` (30 dataset
   pixels squared) become unknown first (:func:`drop_free_specks`: rays that slipped
   through or past a wall, mostly beyond the outer walls; kept, they gave the anchored
   walls faces the plan does not have), and the faces are straight lines at the map's own
   wall angle, not along the pixel grid (``tilt``, :func:`anchored_walls`: a SLAM map is
   turned against its plan by its heading error, and a face made exactly horizontal on a
   wall turned by 2 degrees leaves it up to 1.7 px off across 100 px). Two more, for the
   walls that SLAM drift displaced (``git show e59abf4^:docs/learn.md``, "Moving drifted
   walls"): faces of one orientation and side whose lines lie within ``ANCHOR.collinear``
   (3 dataset pixels) of each other go to their length-weighted mean line
   (:func:`collinear_faces`: the pieces of one wall line, which the plan draws
   collinear), and a wall seen from both sides thinner than ``ANCHOR.min_thick`` (5
   dataset pixels) is grown to it, both faces out by the same amount
   (:func:`thicken_two_sided`: an occupancy grid traces walls thinner than the plan's).
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
vector lines. With anchored walls the segments are exactly the walls drawn (issue #14):
each wall's centre line where that wall painted pixels on it, within a pixel
(:func:`drawn_runs`; a wall that stops at free space is cut there, one drawn nowhere
has none), plus the straight pieces of the input's wall pixels kept as they are
(:func:`drawn_pieces`).

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

from ...core.grid import FREE, OCCUPIED, UNKNOWN
from ...maps.segments import join_supported, straight_segments
from .anchor import ANCHOR, anchored_walls
from .pieces import drawn_pieces, drop_free_specks, frontier_walls

__all__ = ["postprocess", "WALL_BELOW", "FREE_FROM"]

#: Grey level below which an upsampled output pixel is wall (step 2).
WALL_BELOW = 96
#: Grey level from which it is free rather than unknown (step 2).
FREE_FROM = 191


def _refine(segs: np.ndarray, guide_occ: np.ndarray, shift: float) -> np.ndarray:
    """Move axis-aligned segments across onto the mean of the guide's walls (step 4)."""
    out = segs.copy()
    d = int(np.ceil(shift))
    for s in out:
        horiz, vert = s[1] == s[3], s[0] == s[2]
        if horiz == vert:
            continue
        # a vertical segment is a horizontal one of the transposed guide
        occ, (a, b, c) = (guide_occ, s[[0, 2, 1]]) if horiz else (guide_occ.T, s[[1, 3, 0]])
        H, W = occ.shape
        lo, hi = int(max(0, min(a, b))), int(min(W, max(a, b) + 1))
        r0, r1 = int(max(0, np.floor(c) - d)), int(min(H, np.ceil(c) + d + 1))
        band = occ[r0:r1, lo:hi]
        counts = band.sum(axis=1)
        covered = band.any(axis=0).sum() if band.size else 0
        if covered < 0.3 * max(1, hi - lo) or counts.sum() == 0:
            continue
        new = float(np.sum(np.arange(r0, r1) * counts) / counts.sum())
        if abs(new - c) <= shift:
            s[[1, 3] if horiz else [0, 2]] = new
    return out


def _fill_holes(mask: np.ndarray) -> np.ndarray:
    """``scipy.ndimage.binary_fill_holes(mask)`` (the background 4-connected to the
    border stays, the rest is filled), by one OpenCV labelling: five times faster.

    >>> m = np.zeros((5, 5), bool); m[1:4, 1:4] = True; m[2, 2] = False
    >>> bool(_fill_holes(m)[2, 2]), bool(_fill_holes(m)[0, 0])
    (True, False)
    """
    m = np.asarray(mask, bool)
    n, lab = cv2.connectedComponents((~m).view(np.uint8), connectivity=4)
    border = np.zeros(n, bool)
    border[np.concatenate([lab[0], lab[-1], lab[:, 0], lab[:, -1]])] = True
    return m | ~border[lab]


def _anchored(output_segs: np.ndarray, guide: np.ndarray, wall_px: float, data_px: float,
              net_walls: np.ndarray | None = None, net_space: np.ndarray | None = None,
              cell: float = 8.0, thick_px: float | None = None,
              open_frontiers: bool = False) -> tuple[np.ndarray, np.ndarray]:
    """Step 4 in ``anchor`` mode: the guide's own walls straightened at full resolution,
    plus the network's walls the guide does not show (module docstring)."""
    thick_px = data_px if thick_px is None else thick_px
    guide = drop_free_specks(guide, ANCHOR.speck * data_px * data_px)
    occ = guide == OCCUPIED
    own = straight_segments(occ, ANCHOR.cell * data_px)
    if ANCHOR.join > 0:
        own = join_supported(own, occ, max(1.5, ANCHOR.cell * data_px / 4),
                             ANCHOR.join * data_px, junction=ANCHOR.cell * data_px)
    segs = own
    backing = None
    if len(output_segs):
        d = cv2.distanceTransform((~occ).astype(np.uint8), cv2.DIST_L2, 5) if occ.any() \
            else np.full(occ.shape, np.inf)
        o = np.asarray(output_segs, float).reshape(-1, 4)
        t = np.linspace(0.0, 1.0, 32)
        ys = np.clip(np.round(o[:, 1, None] + t * (o[:, 3, None] - o[:, 1, None])).astype(int),
                     0, occ.shape[0] - 1)
        xs = np.clip(np.round(o[:, 0, None] + t * (o[:, 2, None] - o[:, 0, None])).astype(int),
                     0, occ.shape[1] - 1)
        far = np.mean(d[ys, xs] > ANCHOR.new * data_px, axis=1) > 0.7
        apart = far
        if net_walls is not None and net_walls.any():
            # the network draws a wall as a band several model cells thick: measured
            # from the band's edge, not from its centre line (half its thickness away),
            # a network wall over an input wall is that wall, not a second one beside it
            # (drawn apart, the two are the doubled walls of issue #14); where the input
            # saw the wall from one side only, the band shows how far its body reaches
            # behind the face (the plans' outer walls are thicker than the rest)
            half = cv2.distanceTransform(net_walls.astype(np.uint8), cv2.DIST_L2, 5)
            apart = np.mean(d[ys, xs] - half[ys, xs] > ANCHOR.new * data_px, axis=1) > 0.7
        if open_frontiers:
            # a wall of the network's alone (not the body behind an input wall) at the
            # edge of the known area or beyond it is not evidence: left out
            far &= ~(apart & frontier_walls(o, guide, ANCHOR.new * data_px))
        new = o[far]
        if len(new):
            segs = np.concatenate([own, new])
            backing = np.concatenate([np.zeros(len(own), bool), ~apart[far]])
    mask, centres = anchored_walls(guide, segs, band=ANCHOR.band * data_px, wall_px=wall_px,
                                   align=ANCHOR.align * data_px,
                                   grow=int(round(ANCHOR.grow * data_px)),
                                   collinear=ANCHOR.collinear * data_px,
                                   min_thick=int(round(ANCHOR.min_thick * thick_px)),
                                   backing=backing, reach=max(1, int(round(wall_px)))
                                   + (ANCHOR.band + ANCHOR.new) * data_px)
    # the input's walls: replaced by their nearest non-wall value where a straight wall
    # explains them, kept where none does (corners, short pieces, what Hough missed).
    # (Free within 2 px, else unknown, was measured worse: 48 vs 56 of 104 improved --
    # it opens free pixels beside the straight faces, i.e. new wall faces.)
    if occ.any() and not occ.all():
        ri, ci = ndimage.distance_transform_edt(occ, return_distances=False,
                                                return_indices=True)
        data = np.asarray(guide)[ri, ci]
    else:
        data = np.asarray(guide).copy()
    near = cv2.dilate(mask.astype(np.uint8), np.ones((5, 5), np.uint8)) > 0
    keep = occ & ~near
    if net_walls is not None and net_space is not None:
        # the network cleans what the input shows but a plan does not: unexplained wall
        # pixels (clutter, furniture) are kept only within a model cell of its walls, and
        # free space it calls unknown (laser streaks through windows and doors) becomes
        # unknown when farther than two model cells from any wall
        k = 2 * int(np.ceil(cell)) + 1
        keep &= cv2.dilate(net_walls.astype(np.uint8), np.ones((k, k), np.uint8)) > 0
        far = cv2.distanceTransform((~(net_walls | mask)).astype(np.uint8), cv2.DIST_L2, 5)
        data[(data == FREE) & (net_space == UNKNOWN) & (far > 2 * cell)] = UNKNOWN
    data[keep] = OCCUPIED
    data[mask] = OCCUPIED
    if ANCHOR.fill_pockets:
        # ... but not a pocket the input shows free and free space or walls enclose (the
        # network's unknown inside a room, e.g. where it imagined a wall): a plan has none
        pocket = _fill_holes(data != UNKNOWN) & (data == UNKNOWN)
        data[pocket & (guide == FREE)] = FREE
    # the input's wall pixels kept as they are (no straight wall replaced them) are walls
    # of the output too: their straight pieces, where drawn, go with the straight walls
    kept = keep & ~mask
    pieces = straight_segments(kept, ANCHOR.cell * data_px) if kept.any() \
        else np.zeros((0, 4))
    return data, np.concatenate([centres, drawn_pieces(pieces, data == OCCUPIED)])


def postprocess(output: np.ndarray, shape: tuple[int, int], guide: np.ndarray | None = None,
                *, wall_px: float = 2.0, straighten: bool = True, anchor: bool = True,
                data_px: float = 1.0, thick_px: float | None = None,
                open_frontiers: bool = False) -> tuple[np.ndarray, np.ndarray]:
    """Model output (grey, [0, 255], model size) -> (ternary uint8 map of ``shape``,
    wall segments (K, 4) in its pixels); the steps are in the module docstring.

    Parameters
    ----------
    output : ndarray (s, s) float
        The generator's output as grey values (:func:`map2map.learn.nets.networks.from_unit`).
    shape : (H, W)
        The working frame to return to.
    guide : ndarray (H, W) uint8, optional
        The input map in that frame (step 4).
    wall_px : float
        Thickness of the redrawn walls, pixels of the frame.
    straighten : bool
        Steps 3-5; False stops after snapping.
    anchor : bool
        With a ``guide``: step 4b (anchored walls) instead of 4-5.
    data_px : float
        Pixels of the frame per pixel of the dataset's maps (scales step 4b).
    thick_px : float, optional
        The same, for the thickness two-sided walls are grown to in step 4b
        (``ANCHOR.min_thick``; default ``data_px``): with ``wall_px`` what
        :func:`~map2map.learn.ba.autocorrect.autocorrect`'s ``thickness`` sets.
    open_frontiers : bool
        Step 4b leaves out the network's walls at the edge of the input's known area or
        beyond it (:func:`frontier_walls`).
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
    if guide is not None and anchor:
        return _anchored(segs, np.asarray(guide), wall_px, data_px, walls, data, cell,
                         thick_px, open_frontiers)
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
