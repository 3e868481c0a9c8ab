"""Anchored walls (step 4b of :mod:`~map2map.learn.ba.postprocess`): the input's own walls
straightened at full resolution on the median of their observed faces, at the map's own
wall angle, with the network's walls that back them joined in; and the parameters of the
step (:class:`AnchorParams`)."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ...core.grid import FREE
from .faces import (
    align_faces,
    collinear_faces,
    drawn_runs,
    faces_kernel,
    paint_walls,
    surface_masks,
    thicken_two_sided,
)

__all__ = ["AnchorParams", "ANCHOR", "anchored_walls", "map_tilt"]


@dataclass(frozen=True)
class AnchorParams:
    """The scales of step 4b (anchored walls) in pixels of the dataset's 256 px maps
    (multiplied by ``data_px``), each with the measurement that set it.

    Examples
    --------
    >>> from dataclasses import replace
    >>> replace(ANCHOR, join=0.0).join, ANCHOR.join
    (0.0, 16.0)
    """

    #: Straight segments of the input's walls are at least this long (step 3 on it).
    cell: float = 4.0
    #: Observed faces are looked for within this of a segment.
    band: float = 3.0
    #: A network wall farther than this from every input wall over 70 % of its length
    #: is a wall the robot never saw.
    new: float = 4.0
    #: Faces closer than this are put on one line (0: off).
    align: float = 0.0
    #: Observed faces whose lines lie within this of each other are put on their
    #: length-weighted mean line (:func:`~map2map.learn.ba.faces.collinear_faces`; 0: off).
    collinear: float = 3.0
    #: Walls seen from both sides are grown to this thickness (rounded;
    #: :func:`~map2map.learn.ba.faces.thicken_two_sided`; 0: off).
    min_thick: float = 5.0
    #: Unknown pockets of the anchored output that free space or walls enclose go back to
    #: free where the input shows free (False: off).
    fill_pockets: bool = True
    #: Pixels each observed face moves out into its free space.
    grow: float = 0.0
    #: Largest map wall angle (degrees) the anchored faces follow (:func:`anchored_walls`).
    tilt_max_deg: float = 6.0
    #: Gaps across which collinear pieces of an input wall are joined when the input shows
    #: the wall there and a perpendicular wall ends in the gap (a T-junction, where the
    #: Hough transform cuts a wall; :func:`~map2map.maps.segments.join_supported`; 0: off).
    #: Measured: gen1500 val 96 -> 97 of 101 maps improved, test 95 -> 95 of 99 (without
    #: the T-junction condition: test 91, not kept).
    join: float = 16.0
    #: Free components of the input smaller than this (squared) are unknown.
    speck: float = 30.0
    #: With ``open_frontiers``: a network wall with more than this share of its length
    #: without seen space on one side is left out (:func:`~map2map.learn.ba.pieces.frontier_walls`).
    frontier_share: float = 0.5


#: The parameters step 4b uses (replace it with :func:`dataclasses.replace` to tune).
ANCHOR = AnchorParams()


def _axis_aligned(segs: np.ndarray) -> np.ndarray:
    """Which segments (x0, y0, x1, y1) are horizontal or vertical (those step 4b uses)."""
    s = np.asarray(segs, float).reshape(-1, 4)
    return (s[:, 1] == s[:, 3]) != (s[:, 0] == s[:, 2])


def _join_backing(walls: np.ndarray, faces: np.ndarray, backing: np.ndarray,
                  reach: float) -> list[tuple[int, int]]:
    """Walls of the network that back an input wall seen from one side, joined to it
    (in place): each ``backing`` wall's box is stretched across to the nearest observed
    face in front of it (same orientation, within ``reach`` of the backing wall's box
    middle, the two side by side along at least half of the shorter), so that face and band
    are drawn as one wall, not as two with a gap between them.

    ``walls`` (K, 6): horiz, r0, r1, lo, hi, stop_at_free; ``faces`` (K, 2) the observed
    faces (-1: none) of the same walls. Returns the pairs (backing wall, face wall)
    joined."""
    pairs = []
    one = (faces[:, 0] >= 0) != (faces[:, 1] >= 0)          # seen from one side only
    face = np.where(faces[:, 0] >= 0, faces[:, 0], faces[:, 1])
    behind = np.where(faces[:, 0] >= 0, 1, -1)             # where its body lies
    for k in np.flatnonzero(backing & ~(faces >= 0).any(axis=1)):
        h, r0, r1, lo, hi = walls[k, :5]
        c = (r0 + r1) / 2.0
        dist = behind * (c - face)                          # backing wall behind the face
        overlap = np.minimum(walls[:, 4], hi) - np.maximum(walls[:, 3], lo)
        ok = one & ~backing & (walls[:, 0] == h) & (dist > 0) & (dist <= reach) \
            & (overlap >= 0.5 * np.minimum(hi - lo, walls[:, 4] - walls[:, 3]))
        if ok.any():
            j = np.flatnonzero(ok)[np.argmin(dist[ok])]
            if behind[j] > 0:
                walls[k, 1] = min(r0, face[j])
            else:
                walls[k, 2] = max(r1, face[j])
            pairs.append((int(k), int(j)))
    return pairs


def _cut_runs(runs: np.ndarray, pairs: list[tuple[int, int]], walls: np.ndarray) -> np.ndarray:
    """Runs (k, j0, j1) of :func:`drawn_runs` without the stretches of a face wall that a
    backing wall joined to it covers along (its centre line there is the joined wall's:
    one wall, one line)."""
    runs = [tuple(r) for r in runs]
    for k, j in pairs:
        lo, hi = walls[k, 3], walls[k, 4]
        out = []
        for r in runs:
            if r[0] != j or r[2] < lo or r[1] > hi:
                out.append(r)
                continue
            if r[1] < lo - 1:
                out.append((j, r[1], lo - 1))
            if r[2] > hi + 1:
                out.append((j, hi + 1, r[2]))
        runs = out
    return np.array(runs, np.int64).reshape(-1, 3)


def _observed_faces(guide: np.ndarray, segs: np.ndarray, band: float, min_cover: float,
                    tilt: bool) -> tuple[np.ndarray, ...]:
    """The guide's observed faces of each axis-aligned segment, before any rule moves
    them (:func:`anchored_walls`' first step): ``(horiz, faces (K, 2), lo, hi, centre,
    slope)``; a face is -1 where none was found."""
    H, W = guide.shape
    up, dn, lf, rt = surface_masks(guide)
    s = np.asarray(segs, float).reshape(-1, 4)
    horiz, vert = s[:, 1] == s[:, 3], s[:, 0] == s[:, 2]
    s, horiz = s[horiz != vert], horiz[horiz != vert]  # axis-aligned segments only
    c = np.where(horiz, s[:, 1], s[:, 0])
    # np.round as Python's round on these floats: both round half to even
    lo = np.round(np.where(horiz, np.minimum(s[:, 0], s[:, 2]),
                           np.minimum(s[:, 1], s[:, 3]))).astype(np.int64)
    hi = np.round(np.where(horiz, np.maximum(s[:, 0], s[:, 2]),
                           np.maximum(s[:, 1], s[:, 3]))).astype(np.int64)
    lim = np.where(horiz, H, W)
    a = np.maximum(0, np.floor(c - band)).astype(np.int64)
    b = np.minimum(lim - 1, np.ceil(c + band)).astype(np.int64)
    slope = np.zeros(len(s))
    f, fit = faces_kernel(up, dn, lf, rt, horiz, a, b, lo, hi, float(min_cover), slope)
    if tilt:
        g = map_tilt(np.where(horiz, fit[:, 0], -fit[:, 0]), hi - lo + 1, fit[:, 1] > 0)
        if g != 0.0:
            slope = np.where(horiz, g, -g)
            f, _ = faces_kernel(up, dn, lf, rt, horiz, a, b, lo, hi, float(min_cover),
                                 slope)
    return horiz, f, lo, hi, c, slope


def anchored_walls(guide: np.ndarray, segs: np.ndarray, *, band: float, wall_px: float,
                   min_cover: float = 0.3, align: float = 0.0, grow: int = 0,
                   tilt: bool = True, collinear: float = 0.0,
                   min_thick: int = 0, backing: np.ndarray | None = None,
                   reach: float = 0.0) -> tuple[np.ndarray, np.ndarray]:
    """Walls of axis-aligned segments placed on the guide's observed surfaces (step 4b).

    For each segment, the guide's (input map's) wall surfaces facing free space within
    ``band`` pixels across it are found column by column (row by row for a vertical
    one); when they cover at least ``min_cover`` of its length, the wall face on that
    side is put at their **median** position (a straight face through the noisy,
    observed one). A wall seen from both sides spans its two faces; a wall seen from one
    side gets ``wall_px`` of thickness behind its face, stopping at space the input saw
    free; a wall with no observed face keeps the segment's position and ``wall_px``.

    With ``tilt`` (default), the faces are straight lines at the **map's own wall
    angle** rather than along the pixel grid: a SLAM map is turned against its plan by
    its heading error (the metric's rigid alignment turns 22 of the 38 val maps of the
    gen6300 build by 1 to 7.6 degrees; :func:`~map2map.learn.ba.autocorrect.autocorrect`
    deskews anchored maps only beyond 6), and a face made exactly horizontal on a wall
    turned by 2 degrees leaves it, across a 100 px wall, up to 1.7 px off at its ends.
    The angle is one for the map (the building's walls are parallel or perpendicular,
    so one rotation turns them all): each segment's observed faces get a least-squares slope
    (trimmed once at 1.5 px), and the length-weighted median over the segments (a
    vertical wall's slope counted with its sign turned) is the map's, limited to
    :data:`ANCHOR.tilt_max_deg`; the faces are then found again along lines of that
    slope and drawn along them, rasterised (the shift across a wall at position ``j``
    is ``round(slope (j - m))``, ``m`` its middle). A map whose walls run along the grid
    gets slope 0: the walls of ``tilt=False``.

    With ``align > 0``, faces of one orientation and side within ``align`` pixels of each
    other (pieces of one wall line cut by doors, bent apart by drift) are put on one
    line, their length-weighted median. ``grow`` moves every observed face that many
    pixels out into the free space it faces (a plan drawn with thicker walls than the
    laser sees). Both were measured worse (docs/autocorrect.md) and are off by default.

    With ``collinear > 0``, observed faces whose lines lie within ``collinear`` pixels of
    each other go to their length-weighted mean line (:func:`collinear_faces`); with
    ``min_thick > 0``, walls seen from both sides thinner than ``min_thick`` pixels are
    grown to it (:func:`thicken_two_sided`). Their defaults (0) are the walls before
    2026-11-25's "Moving drifted walls"; :func:`postprocess` passes
    ``ANCHOR.collinear`` and ``ANCHOR.min_thick``.

    ``backing`` (bool per segment) marks the network's walls that back an input wall:
    each is drawn from the nearest face seen from one side in front of it (within
    ``reach`` pixels of its middle) to its own far side, as one wall with it
    (:func:`_join_backing`), and that face's wall has no centre line of its own there.

    Returns
    -------
    mask : ndarray (H, W) bool
        The walls.
    centre : ndarray (R, 4)
        Their centre lines (x0, y0, x1, y1) in pixels where they were drawn
        (:func:`drawn_runs`): a wall cut by free space gives several, one drawn
        nowhere none.

    Examples
    --------
    >>> g = np.full((20, 30), 255, np.uint8)
    >>> g[9:11, 2:28] = 0; g[11, 2:28:3] = 0            # a noisy wall: faces rows 9, 10
    >>> m, c = anchored_walls(g, np.array([[2.0, 11.0, 27.0, 11.0]]), band=3, wall_px=2)
    >>> sorted(set(np.nonzero(m)[0].tolist())), np.round(c[0], 1).tolist()
    ([9, 10], [2.0, 9.5, 27.0, 9.5])
    >>> t = np.full((40, 80), 255, np.uint8)             # a wall turned by 2 degrees
    >>> for x in range(5, 75): t[18 + int(round((x - 40) * np.tan(np.radians(2)))), x] = 0
    >>> seg = np.array([[5.0, 18.0, 74.0, 18.0]])
    >>> m, c = anchored_walls(t, seg, band=3, wall_px=1)
    >>> int((m & (t != 0)).sum()), np.round(c[0], 1).tolist()   # 1 of 70 pixels off
    (1, [5.0, 16.8, 74.0, 19.2])
    >>> m, c = anchored_walls(t, seg, band=3, wall_px=1, tilt=False)
    >>> int((m & (t != 0)).sum())                      # along the grid: 41 off
    41
    """
    H, W = guide.shape
    free = guide == FREE
    t = max(1, int(round(wall_px)))
    horiz, f, lo, hi, c, slope = _observed_faces(guide, segs, band, min_cover, tilt)
    if collinear > 0:
        f = f.copy()
        for k in (0, 1):
            seen = f[:, k] >= 0
            f[seen, k] = collinear_faces(horiz[seen], np.full(seen.sum(), k), f[seen, k],
                                         lo[seen], hi[seen], slope[seen], collinear)
    if min_thick > 0:
        both = (f[:, 0] >= 0) & (f[:, 1] >= 0) & (f[:, 0] <= f[:, 1])
        f = f.copy()
        f[both, 0], f[both, 1] = thicken_two_sided(f[both, 0], f[both, 1], min_thick)
    found = [[bool(h), None if f0 < 0 else int(f0) - grow, None if f1 < 0 else int(f1) + grow,
              int(lo_), int(hi_), float(c_)]
             for h, (f0, f1), lo_, hi_, c_ in zip(horiz, f, lo, hi, c, strict=True)]
    if align > 0:
        align_faces(found, align)
    boxes = []
    for horiz_k, f0, f1, lo_k, hi_k, c_k in found:
        if f0 is not None and f1 is not None and f0 <= f1:
            r0, r1, ext = f0, f1, False
        elif f0 is not None:
            r0, r1, ext = f0, f0 + t - 1, True
        elif f1 is not None:
            r0, r1, ext = f1 - t + 1, f1, True
        else:
            r0 = int(round(c_k - (t - 1) / 2))
            r1, ext = r0 + t - 1, True
        boxes.append((horiz_k, r0, r1, lo_k, hi_k, ext))
    walls = np.array(boxes, np.int64).reshape(-1, 6)
    joined = _join_backing(walls, f, np.asarray(backing, bool)[_axis_aligned(segs)], reach) \
        if backing is not None and len(walls) else []
    mask = np.zeros((H, W), bool)  # painting is an OR: order is free
    args = (walls[:, 0].astype(bool), walls[:, 1], walls[:, 2], walls[:, 3], walls[:, 4],
            walls[:, 5].astype(bool), np.asarray(slope, float))
    paint_walls(mask, free, *args)
    # the centre lines where each wall was drawn: a wall that stops at free space is cut
    # there, one that was drawn nowhere (a network wall across a room seen empty) has none
    runs, across = drawn_runs(free, *args)
    if joined:
        runs = _cut_runs(runs, joined, walls)
    k, j0, j1 = runs[:, 0], runs[:, 1].astype(float), runs[:, 2].astype(float)
    across = across[k]
    mid = (walls[k, 3] + walls[k, 4]) / 2.0
    q = np.asarray(slope, float)[k]
    c0, c1 = across + q * (j0 - mid), across + q * (j1 - mid)
    h = walls[k, 0].astype(bool)
    centres = np.where(h[:, None], np.stack([j0, c0, j1, c1], 1),
                       np.stack([c0, j0, c1, j1], 1))
    return mask, centres.reshape(-1, 4)


def map_tilt(slopes: np.ndarray, lengths: np.ndarray, ok: np.ndarray | None = None) -> float:
    """The map's common wall slope (pixels across per pixel along, horizontal walls'
    sign): the length-weighted median of the segments' fitted slopes (``ok`` those
    with a fit), limited to :data:`ANCHOR.tilt_max_deg`; 0 without any.

    Examples
    --------
    >>> float(map_tilt(np.array([0.03, 0.035, 0.5, 0.0]), np.array([50, 80, 5, 10]),
    ...                np.array([True, True, True, False])))
    0.035
    """
    q = np.asarray(slopes, float)
    w = np.asarray(lengths, float)
    if ok is not None:
        q, w = q[ok], w[ok]
    if not len(q) or w.sum() <= 0:
        return 0.0
    o = np.argsort(q, kind="stable")
    cum = np.cumsum(w[o])
    med = float(q[o][np.searchsorted(cum, cum[-1] / 2)])
    m = float(np.tan(np.radians(ANCHOR.tilt_max_deg)))
    return float(np.clip(med, -m, m))


#: Anchoring scales in pixels of the dataset's 256 px maps (multiplied by ``data_px``).
