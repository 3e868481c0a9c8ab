"""The plan drawer: wall evidence -> straight walls drawn as a plan draws them.

Every auto-correction ends here (issue #32): whatever says where the walls are (the SLAM
map's own wall pixels, or the sub-pixel wall points a network moved), :func:`draw_plan`
turns it into straight segments and a three-valued map that looks like a CAD plan:

1. **Evidence.** Wall points ``(x, y)`` in continuous pixel coordinates (the centre of
   pixel ``(r, c)`` is ``(c + 0.5, r + 0.5)``, :mod:`map2map.core.grid`), with optional
   weights; a boolean raster is handed over as its pixel centres (:func:`wall_points`).
2. **Dominant direction** (:func:`dominant_angle`): the structure tensor's orientations
   of the evidence, folded modulo 90 degrees, give a coarse angle; the angle whose
   projections of the points onto both axes are sharpest (sum of squares of their
   smoothed density, 0.1 degree steps) refines it. A map whose walls run at 20 degrees
   keeps them at 20: the two orthogonal families are found in the frame turned by that
   angle. An angle that turns a line across the map by at most ``snap_px`` is 0.
   A wing of the map whose walls run more than 5 degrees off the rest (a particle
   filter's heading error that lasted while the robot mapped it) is a further direction
   family (:func:`map2map.maps.directions.angle_families`, at most ``families``): its
   wall points go through steps 3-7 in a frame turned by its own angle, and the
   families' corners and junctions are closed in the map's frame. With ``cover`` the
   input's own wall pixels decide the families (a corrector's evidence may hold its
   walls in the main directions only): the museum walls at 45 degrees of the FHW map
   are a family, not dashes found by step 6.
3. **Wall pieces** of each family: the evidence, rasterised in the turned frame, closed
   along the family's direction (holes up to ``bridge`` long: a dotted wall) and opened
   with a line of ``L = max(thickest + 2, min_len / resolution)`` pixels, keeps only the
   pixels lying in
   a straight run at least ``L`` long along that direction (specks, ray-end blobs and the
   other family's walls go; so do the pixels of a wall across it as thick as ``L``,
   whose runs across are at least ``2 L`` and twice their runs along: a pixel of two
   walls belongs to the longer); each 8-connected component is a piece, its line the
   weighted mean of its points across (sub-pixel), its extent its first and last pixel.
4. **Wall lines**: pieces whose lines lie within ``tol`` of each other (clusters at most
   ``tol`` wide) are one wall line. Consecutive pieces of a line are joined into one
   segment unless the input shows a **door** between them: a run of at least
   ``door_min`` positions in the gap where the input is free all across the wall band
   (``thickness / 2 + 1`` pixels either side of the line) and the free space on both
   sides belongs to a room (:func:`_rooms`: a free region of at least ``min_room``
   square metres, once every other gap is closed, whose outline runs along walls for at
   least ``enclosed`` of its length; a fan of laser rays beyond an outer wall is bounded
   by unknown space, not walls). Gaps longer than ``max_gap`` stay open.
5. **Corners and T-junctions** (:func:`map2map.maps.segments._join`): an end stopping
   short of, or overshooting, a perpendicular wall by at most ``reach`` moves onto it.
   Segments without a stretch of ``L`` beyond the perpendicular walls they cross (ticks
   and blobs on a wall, also across a wall a real map shows as two faces, sticking out
   of both; pieces the snapping shrank to nothing) go, and so do segments with less
   than ``main_min`` of main evidence (the weight-1 points: with an input's own wall
   pixels handed over at a lower weight beside a corrector's walls, a line only the
   input shows is clutter the corrector dropped; those pixels still join the
   corrector's walls). A segment beside a door shorter than ``2 L`` (a **jamb**) needs
   only ``jamb_min`` beyond the walls it stands on, of evidence of any weight; its end
   at the door stays where the door begins, and it is drawn on the line of the wall
   beyond the door (:func:`_onto_line`): a door is not widened to the corner.
6. **Other directions**, only where evidence is strong: evidence that no family wall
   explains is thinned and cut by a probabilistic Hough transform; lines at least
   ``other_min`` metres long, more than 4 degrees off both families, are kept.
7. **Placing** (:func:`_place`): each wall's line is refitted to its own points near it
   (:func:`_refit`); a long wall that SLAM drift turned a little follows its least-
   squares line (``lean_px``), and a wall seen from one side keeps its seen face (its
   thickness grows away from the free side; a side is free where a room lies, not where laser rays
   passed through an outer wall into the unknown outside). With ``cover`` (the input's
   own wall pixels), a wall whose line leaves a straight run of the input beside it (at
   least ``cover_run`` long) by more than half the thickness plus ``cover_tol`` moves as
   little as it must to keep the run inside (:mod:`map2map.maps.cover`): a wall the
   input shows whole is not drawn leaving it at one end. Ends are then moved onto the
   lines they meet again (:func:`_snap_ends`), so corners stay closed. Where a segment's
   centre line runs over the input's free space more than ``tol`` plus a quarter of the
   thickness from any evidence (for more than ``reach`` at an end, where corners close
   across free space), with no speck of free space on either side, it is cut there
   (:func:`_cut_free`): the input saw through the drawn wall (a tick's ends beyond its
   evidence, a line joined across a corridor whose sides are no rooms by their outline).
   A wall the input saw from **both sides** (an interior wall: free space within
   half the thickness plus 2 pixels of its line on both sides, along at least half of
   it) is drawn between the faces the input saw, grown by ``grow_px`` on each side,
   the plans' convention (:func:`_two_sided`): an interior wall is thinner than the
   outer walls whose thickness the others are drawn at. A map's interior walls are
   drawn at one thickness (``one_interior``), the median of those the input shows
   sharply: a wall SLAM blurred or saved twice measures thicker than it is.
8. **Drawing** (:func:`render_plan`): free and unknown space come from the input map, its
   occupied pixels taking the value of their nearest non-occupied pixel; free regions
   that are not rooms (small ones, ray fans; the largest free region always counts as a
   room) become unknown; then every segment is drawn
   as a rectangle of ``thickness`` pixels across (exactly within 10 degrees of the grid's
   axes, drawn column by column; within half a pixel at other angles), extended by half
   the thickness at both ends so corners close; an end no other wall reaches (a door's
   side) only covers its last pixel (:func:`_free_ends_in`), so doors keep the input's
   width. Unknown slivers a wall drawn off the input's wall leaves between itself and a
   room (at most a wall thickness across, ``sliver``, and at least 3 pixels) become free
   (:func:`_slivers`). Nothing else is occupied.
   Before the walls are drawn, two walls whose free ends stop short of their common
   corner by up to ``corner_reach`` (beyond the corner snap's ``reach``) are drawn on to
   it where the input's free space does not run out between them: a corner the robot
   never saw (:func:`_close_corners`).
9. **Bridges** (:func:`_bridges`, :func:`map2map.maps.cover.bridge_gaps`): where the
   input shows a wall as a straight run of wall pixels at least ``bridge_run`` long (in
   a family's frame, or the grid's) and the drawn walls cover it on both sides of a
   gap (a corner counts: a perpendicular wall ending within half a thickness and a
   pixel of the run's end) with no drawn wall within ``bridge_beside`` thicknesses
   (two) across along at least
   ``bridge_share`` (half) of it, nor one within ``bridge_same`` (1 m) with none of the
   input's free space between it and the run (the same wall) (a jog too
   short beyond the walls it joins to keep as a wall of its own, two pieces of a
   leaning wall drawn on two lines), a segment
   along the run's own pixels closes the gap, as thin as the thinner wall it joins, and
   the map is drawn again. The input's wall is continuous there, so no door closes; a
   wall drawn beside the run (between the two lines of a wall SLAM saved twice) is not
   doubled. A run's end left open for more than ``bridge_ends`` (0.35 m), and a run no
   drawn wall covers at all, are drawn the same way (a jamb, a stub at a T-junction or
   an outer wall piece the cleaning dropped).
10. **Curved walls** (:mod:`map2map.maps.curves`, ``curve_min``): the input's wall
    runs, cut at their corners, that circles fit and that together turn by a third of
    a circle around one room (a rotunda, an apse) are drawn along their circles as
    chains of short chords (within a quarter pixel of the circle), replacing the
    straight walls drawn along them; a wall that SLAM drift bent, or a real map's wavy
    wall, stays straight. (This runs before the bridges of step 9, which see the arcs
    as drawn walls.)

:func:`save_plan_dxf` writes the same segments through the one DXF writer
(:func:`map2map.maps.dxf.save_segments_dxf`), so raster and drawing agree.

Examples
--------
>>> import numpy as np
>>> m = np.full((60, 80), 127, np.uint8); m[10:50, 10:70] = 255
>>> m[10:12, 10:70] = 0; m[48:50, 10:70] = 0; m[10:50, 10:12] = 0; m[10:50, 68:70] = 0
>>> m[10:12, 30:33] = 127                       # a hole in the top wall: no door
>>> d = draw_plan(m == 0, m, 0.05, 2)
>>> len(d.segments), float(d.angle)
(4, 0.0)
>>> bool((d.map[10:12, 30:33] == 0).all())      # the wall is drawn through the hole
True
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import cv2
import numpy as np

from ..core.geometry import point_segment_distances, segment_samples
from ..core.grid import FREE, OCCUPIED, UNKNOWN, OccupancyMap
from ..core.parallel import process_map
from ..core.runs import open_runs, pixels, run_through
from .cover import bridge_gaps, keep_runs_inside
from .curves import arcs_to_world, curved_walls
from .directions import angle_families, orientation, sharp_angle
from .directions import splat as _splat
from .segments import _join

__all__ = ["DrawOptions", "PlanDrawing", "default_wall_thickness", "wall_points",
           "dominant_angle", "draw_plan", "draw_plan_map", "draw_plan_maps", "render_plan",
           "wall_raster", "enclosed_unknown", "save_plan_dxf", "PLAN_WALL_M"]

#: Wall thickness (metres) that :func:`default_wall_thickness` draws, before the plans'
#: pixel of thickening on each side (``DrawOptions.grow_px``): the plans' convention for a
#: wall seen from one side only (an outer wall; :func:`_two_sided` measures the others).
#: The generated plans' outer walls are 0.20-0.30 m thick, their interior ones 0.10-0.15 m
#: (:mod:`map2map.maps.plans.layout`), drawn at 0.05 m/px; the dataset build resizes each
#: plan to 256 px (area-averaged where it shrinks, keeping a pixel that is at least half
#: wall) and thickens its walls by a pixel. On 320 plans of a dataset built by ``map2map
#: dataset build`` (seed 20261205), the outer walls' median thickness
#: (:func:`map2map.evaluate.drawing.median_wall_thickness` on the skeleton next to
#: unknown) fits 0.206 m / resolution + 1.98 px (least squares over 0.026-0.115 m/px),
#: the same as the demo plan's 6 px at 0.05 m/px. Until 2026-11-29 the drawer drew
#: 0.30 m without the thickening: on average 0.8 px too thin on maps coarser than
#: 0.08 m/px. ``bench_drawing`` on two fresh builds (seeds 20261222, 20261223): thickness
#: within 1 px on 90 -> 91 % and 92 -> 91 % of maps (the plans' outer walls vary by more
#: than 3 px at the finest resolutions), the mean miss 0.75 -> 0.59 and 0.70 -> 0.60 px.
PLAN_WALL_M = 0.20


def default_wall_thickness(resolution: float, grow_px: float = 1.0) -> int:
    """Pixels a plan's wall seen from one side is drawn with at ``resolution`` (m/px):
    :data:`PLAN_WALL_M` plus ``grow_px`` on each side, rounded, at least 2.

    >>> default_wall_thickness(0.075), default_wall_thickness(0.05), default_wall_thickness(0.2)
    (5, 6, 3)
    >>> default_wall_thickness(0.05, grow_px=0)
    4
    """
    return max(2, int(round(PLAN_WALL_M / float(resolution) + 2 * float(grow_px))))


@dataclass(frozen=True)
class DrawOptions:
    """Tolerances of :func:`draw_plan` in metres (converted with the map's resolution;
    ``tol`` and ``reach`` are at least 1.5 and 2 pixels).

    Attributes
    ----------
    tol : float
        Pieces whose lines lie this close across are one wall line.
    min_len : float
        Shortest straight wall piece kept.
    bridge : float
        Holes along a wall up to about this long are bridged before pieces are cut (a
        dotted wall is one piece; doors are wider than ``door_min``).
    thickest : float
        Thickest wall of the input (the opening length exceeds it, so a thick wall is
        never read as a short wall across it).
    max_gap : float
        Longest gap joined between two pieces of one line.
    door_min : float
        Narrowest free passage through a gap that keeps it open.
    min_room : float
        Square metres: smallest free region a door leads into; smaller free regions
        (ray fans, specks) become unknown in the drawn map.
    reach : float
        Corner and T-junction snapping distance.
    other_min : float
        Shortest wall drawn off the two dominant directions.
    snap_px : float
        A dominant angle that turns a line across the map's longer side by at most this
        many pixels is 0 (a map drawn along the grid has no one-pixel steps).
    enclosed : float
        A room's outline runs along walls for at least this share of its length; free
        regions that do not (laser-ray fans outside the building, bounded by unknown)
        lead through no door and become unknown in the drawn map.
    keep_faces : bool
        A wall seen from one side keeps its seen face (:func:`_place`); off for wall
        points that already lie on the walls' centre lines.
    cut_free : bool
        Cut segments where the input's free space runs through them, away from any
        evidence (:func:`_cut_free`).
    main_min : float
        A segment needs at least ``main_min / resolution`` main-evidence points (those of
        at least half the largest weight; with equal weights every point is main).
    families : int
        Most direction families (:func:`map2map.maps.directions.angle_families`): a wing
        of the map whose walls run more than 5 degrees off the rest is drawn in its own
        frame (1: one dominant direction for the whole map, as before session 28).
    jamb_min : float
        A segment beside a door shorter than twice the shortest piece (a jamb) needs a
        stretch of only this much beyond the walls it stands on, of evidence of any
        weight, where others need the shortest piece (``min_len``, at
        least ``thickest`` plus two pixels): a door is not drawn wider than the input
        shows it.
    cover_run, cover_tol : float
        With :func:`draw_plan`'s ``cover``: the input's straight wall runs at least
        ``cover_run`` long lie within the drawn wall's half thickness plus ``cover_tol``
        of its line (:func:`map2map.maps.cover.keep_runs_inside`; ``cover_run`` 0: off).
    two_sided : bool
        A wall the input saw from both sides is drawn between the faces it saw, grown
        by ``grow_px`` on each side, at most the drawing's thickness (:func:`_two_sided`);
        off: every wall at the one thickness, centred on its evidence.
    grow_px : float
        Pixels (not metres) a two-sided wall is drawn beyond each face the input saw:
        the plans' convention, whose walls the dataset grows by a pixel on each side
        into free space (``map2map dataset build``'s ``thicken``, thesis sec. 4.1).
    one_interior : bool
        With ``two_sided``: every interior wall of a map is drawn at one thickness, the
        median of those the input shows thinner than the drawing (at least two), centred
        between its faces; off: each at its own measured thickness.
    lean_px : float or None
        A wall at least ``other_min`` long whose points' least-squares line leans by at
        least this many pixels over its length (under 6 degrees) follows that line,
        where SLAM drift turned it (:func:`_place`). None: every wall of a family runs
        exactly in its direction, unless ``cover`` turns it to keep the input's run
        inside. Measured 2026-11-28 (Table 5.3 ``--models none``): None lowers the error
        per map (dev: on 101 maps, raises it on 49; a fresh build, seed 20261216: 187
        against 135, medians 0.902 / 0.911 -> 0.871 / 0.888 px) but drops or cuts walls
        drift turned by a few degrees where a straight line runs over the input's free
        space (fresh build: broken input runs 123 -> 141, opened 64 -> 74; a courtyard
        wall of 000040 gone), so 1.5 stays the default.
    bridge_run, bridge_share, bridge_beside : float
        With :func:`draw_plan`'s ``cover``: a straight run of the input's wall pixels at
        least ``bridge_run`` long that the drawn walls leave open between two of them
        is closed by a segment along it (module doc, step 9; 0: off), where along at
        least ``bridge_share`` of the gap no drawn wall lies within ``bridge_beside``
        thicknesses across (a wall drawn beside the run, straight where drift turned
        it or between the two lines of a wall saved twice, is not doubled). Measured
        2026-11-28 (``bench_drawing --model none``; Table 5.3 ``--models none``) on a
        dev build (seed 20261205, 320 maps): input runs of 1 m or more broken 46 -> 27,
        opened 25 -> 6; on a second (seed 20261216, 640 maps) 123 -> 74, opened 64 ->
        16; on a fresh build measured once (seed 20261219, 640 maps) 104 -> 63, opened
        61 -> 18, Table 5.3's median unchanged (0.881 / 0.897 px; per map lower on 8,
        higher on 16 of 438, wall recall higher on 23). ``bridge_run`` 0.5 raised the
        error on 19 of 207 dev maps (lower on 5): a bridge along a short run is more
        often a wall the plan does not have. With ``bridge_beside`` 1 by eye about a
        third of the bridges doubled a wall drawn a little more than a thickness beside
        the run (CHANGELOG.md, 2026-11-28; the commits of session 35).
    bridge_same : float
        Metres. Nor is a gap bridged where a drawn wall lies within this distance across
        with (almost: at most a quarter of the pixels) none of the input's free space
        between it and the run: the two are one wall, however far apart the drawer put
        them (0: off). Measured 2026-11-29: it changes none of 320 dev maps' drawings
        (seed 20261205) and 5 of 640 on a fresh build (seed 20261220: wedges, an
        interior wall drift split into two lines with unknown between, whose second
        line a bridge drew again). On the Halmstad maps (``table53_real --model none``)
        it removes the second line of E5_10's outer wall: the input shows it as two
        lines 1.1-1.3 m apart (read at 0.05 m/px) with unknown between; the drawer draws
        one wall between them and a bridge added the inner, leaning line again. The
        layout's wall is that inner line, so the wall Chamfer against the layout rises
        (6.73 -> 6.80 px), as does the metric's Error (4.30 -> 4.62 px; median of the
        18 maps 4.04 -> 4.20).
    bridge_ends : float
        Metres. A straight wall run of the input (at least ``bridge_run`` long) that the
        drawn walls leave open for more than this at an end (beyond the last column a
        drawn wall covers), or along its whole length, is drawn along its own pixels
        there too, under the same tests as a bridge (no drawn wall beside it, not the
        same wall as one drawn); 0: off. Equal to ``reach``: a wall end the corner snap
        cut back (an overshoot) stays cut. The cleaning drops input wall pixels no
        straight wall explains, and with them short walls the plan has (jambs, stubs
        at T-junctions, an outer wall piece between two corners); these come back.
        Measured once on a fresh build (seed 20261226, 640 maps, against 0: off): runs
        shortened at an end 598 -> 299, broken 40 -> 43; Table 5.3 (447 maps) 0.831 ->
        0.834 px, wall recall higher on all 92 maps that move, the matched error higher
        on 58 and lower on 36; Halmstad 13 -> 14 of 18 improved (16 with the rule
        that draws one line of a wall saved twice, ``cover._one_of_each_wall``).
    sliver : float
        Unknown regions between a drawn wall and a room (touching both, not the map's
        border) at most this many of the drawing's wall thicknesses across, and at least
        3 pixels, become free (:func:`_slivers`): the input's wall pixels and the unknown
        beyond them where the wall was drawn a little off the input's face, or the
        unobserved inside of a wall SLAM saved twice that the drawer drew on one of its
        lines. A plan has no unknown stripes along its walls inside a room; 0: 3 pixels
        only (as before 2026-11-29).
    corner_reach : float
        Metres. Two walls more than 30 degrees apart whose free ends both stop short of
        their crossing by more than half a thickness and a pixel and at most this much
        are drawn on to it, where the input's free space does not run out between them
        (at most a quarter of the extensions over free pixels): a room's corner the
        robot never saw, free space cut across it by unknown (:func:`_close_corners`);
        0: off. On the dev build (seed 20261205, 320 maps) it closes corners on 91
        maps; opened runs 3 -> 1. Measured once on a fresh build (seed 20261230, 432
        maps, against 0): Table 5.3's medians unchanged (0.874 / 0.891 px), wall recall
        higher on 112 maps, Chamfer lower on 94, the matched error lower on 50 and
        higher on 71 (p = 0.07, mean +0.003 px): the walls it adds are the plan's, where
        drift put them.
    curve_min : float
        Metres. The input's wall runs (cut at corners) that a circle of radius 1-10 m
        fits within 0.75 px RMS over at least this length, bending by at least 3 px,
        are drawn along their circle as chains of chords where the arcs around one room
        turn by a third of a circle together (:func:`map2map.maps.curves.curved_walls`):
        a rotunda, an apse; such a room's further arcs may be made of runs too short or
        straight to fit a circle alone. The straight walls drawn along such an arc go.
        0: off (as before 2026-11-29). On the ACES map (``map2map slam
        aces-corrected.log.gz``) the rotunda's four arcs are drawn; on 2,240 simulated
        maps (dev build and three fresh builds), the 18 Halmstad maps, FHW and
        BreezySLAM exp2 nothing changes.
    """

    tol: float = 0.12
    min_len: float = 0.35
    bridge: float = 0.2
    thickest: float = 0.35
    max_gap: float = 2.5
    door_min: float = 0.4
    min_room: float = 0.5
    reach: float = 0.35
    other_min: float = 1.0
    snap_px: float = 1.0
    enclosed: float = 0.2
    keep_faces: bool = True
    cut_free: bool = True
    main_min: float = 0.5
    families: int = 3
    cover_run: float = 1.0
    cover_tol: float = 0.15
    jamb_min: float = 0.1
    two_sided: bool = True
    grow_px: float = 1.0
    one_interior: bool = True
    lean_px: float | None = 1.5
    bridge_run: float = 1.0
    bridge_share: float = 0.5
    bridge_beside: float = 2.0
    bridge_same: float = 1.0
    bridge_ends: float = 0.35
    sliver: float = 1.0
    corner_reach: float = 1.0
    curve_min: float = 1.5


@dataclass
class PlanDrawing:
    """What :func:`draw_plan` drew.

    Attributes
    ----------
    segments : (K, 4) float
        ``x0, y0, x1, y1``, continuous pixel coordinates of the map.
    map : (H, W) uint8
        The drawn plan (occupied 0, free 255, unknown 127).
    angle : float
        Dominant wall direction (degrees, image frame: x right, y down), in [-45, 45).
    thickness : float
        Wall thickness drawn (pixels).
    info : dict
        Counts: ``pieces`` (straight pieces found), ``doors`` (gaps kept open), ``joined``
        (gaps closed), ``other`` (segments off the dominant directions), ``cut`` (segments
        more (or fewer) after :func:`_cut_free`), ``two_sided`` (segments drawn thinner,
        between the faces the input saw); ``angles``, the direction families' angles
        (the dominant one first).
    thicknesses : (K,) float, optional
        Each segment's thickness (pixels): ``thickness``, or less for a wall seen from
        both sides (``DrawOptions.two_sided``).
    arcs : (M, 5) float
        The curved walls' centre lines, ``xc, yc, r, a0, span`` (pixels; radians in the
        image frame, :class:`map2map.maps.curves.CurvedWalls`); their chords are among
        ``segments``.
    arc_of : (K,) int
        Per segment, the arc it is a chord of, or -1 (a straight wall).
    """

    segments: np.ndarray
    map: np.ndarray
    angle: float
    thickness: float
    info: dict = field(default_factory=dict)
    thicknesses: np.ndarray | None = None
    arcs: np.ndarray = field(default_factory=lambda: np.zeros((0, 5)))
    arc_of: np.ndarray | None = None

    def __post_init__(self):
        if self.arc_of is None:
            self.arc_of = np.full(len(self.segments), -1)


def wall_points(mask: np.ndarray) -> np.ndarray:
    """Centres ``(x, y)`` (continuous pixel coordinates) of a boolean raster's pixels.

    >>> wall_points(np.eye(2, dtype=bool)).tolist()
    [[0.5, 0.5], [1.5, 1.5]]
    """
    r, c = pixels(np.asarray(mask, bool))
    return np.stack([c + 0.5, r + 0.5], axis=1).astype(float)


def _as_points(evidence, weights) -> tuple[np.ndarray, np.ndarray]:
    """Wall points and weights of a boolean raster or an ``(N, 2)`` array of points."""
    e = np.asarray(evidence)
    if e.dtype == bool:
        if weights is not None:
            raise ValueError("weights go with wall points, not with a raster")
        return wall_points(e), np.ones(int(e.sum()))
    if e.ndim != 2 or e.shape[1] != 2:
        raise ValueError(f"wall evidence must be a boolean raster or (N, 2) points, not "
                         f"{e.dtype} {e.shape}")
    pts = e.astype(float)
    w = np.ones(len(pts)) if weights is None else np.asarray(weights, float).reshape(-1)
    if len(w) != len(pts):
        raise ValueError(f"{len(w)} weights for {len(pts)} wall points")
    keep = np.isfinite(pts).all(axis=1) & (w > 0)
    return pts[keep], w[keep]


def dominant_angle(points: np.ndarray, weights: np.ndarray | None = None,
                   shape: tuple[int, int] | None = None, snap_deg: float = 0.15) -> float:
    """Dominant wall direction (degrees in [-45, 45), image frame) of wall points
    (step 2 of the module doc).

    Examples
    --------
    >>> m = np.zeros((80, 80), bool); m[20:22, 10:70] = True; m[20:60, 10:12] = True
    >>> dominant_angle(wall_points(m))
    0.0
    >>> box = cv2.boxPoints(((60.0, 60.0), (80.0, 50.0), 20.0))    # a room turned by 20
    >>> img = np.zeros((120, 120), np.uint8)
    >>> _ = cv2.polylines(img, [np.round(box).astype(np.int32)], True, 1, 2)
    >>> round(dominant_angle(wall_points(img > 0)))               # corners on pixels
    20
    """
    pts = np.asarray(points, float).reshape(-1, 2)
    w = np.ones(len(pts)) if weights is None else np.asarray(weights, float)
    if len(pts) < 3:
        return 0.0
    lo = np.floor(pts.min(axis=0)) - 2
    if shape is None:
        shape = tuple(int(v) for v in (np.ceil(pts.max(axis=0)) - lo + 3)[::-1])
    img = _splat(pts - lo, w, shape).astype(np.float32)
    # coarse: the structure tensor's orientation (gradient products averaged over a few
    # pixels: a 9 x 9 box), folded modulo 90 degrees, weighted by its coherence; 0.5
    # degree bins
    ang, coh = orientation(img, coherent=1e-3)
    hist = np.bincount(np.minimum((ang * 2).astype(np.int64), 179), coh, 180)
    k = np.array([1.0, 2, 3, 4, 3, 2, 1])
    sm = np.convolve(np.concatenate([hist[-3:], hist, hist[:3]]), k, "valid")
    coarse = (int(np.argmax(sm)) + 0.5) / 2.0
    # refine: the angle whose projections onto both axes are sharpest (linear binning
    # in half pixels, so that the score is smooth in the angle): +-3 degrees in steps of
    # 0.5, then +-0.4 in steps of 0.1
    best = sharp_angle(pts, w, coarse, 3.0)
    a = (best + 45.0) % 90.0 - 45.0
    a = round(a, 1)
    return 0.0 if abs(a) <= snap_deg else float(a)


class _Frame:
    """The frame turned by ``angle``: ``to(p)`` maps image points into a canvas in which
    the dominant family is horizontal, ``back(p)`` maps them back."""

    def __init__(self, angle: float, shape: tuple[int, int]):
        H, W = shape
        self.angle = angle
        t = math.radians(angle)
        self.c, self.s = math.cos(t), math.sin(t)
        if angle == 0.0:
            self.shape, self.shift, self.centre = (H, W), np.zeros(2), np.zeros(2)
            return
        Wr = int(math.ceil(abs(W * self.c) + abs(H * self.s))) + 4
        Hr = int(math.ceil(abs(W * self.s) + abs(H * self.c))) + 4
        self.shape = (Hr, Wr)
        self.centre = np.array([W / 2.0, H / 2.0])
        self.shift = np.array([Wr / 2.0, Hr / 2.0])

    def to(self, p: np.ndarray) -> np.ndarray:
        if self.angle == 0.0:
            return p
        q = p - self.centre
        return np.stack([q[:, 0] * self.c + q[:, 1] * self.s,
                         -q[:, 0] * self.s + q[:, 1] * self.c], axis=1) + self.shift

    def back(self, p: np.ndarray) -> np.ndarray:
        if self.angle == 0.0:
            return p
        q = p - self.shift
        return np.stack([q[:, 0] * self.c - q[:, 1] * self.s,
                         q[:, 0] * self.s + q[:, 1] * self.c], axis=1) + self.centre

    def warp(self, img: np.ndarray, border: int) -> np.ndarray:
        """``img`` (uint8) in the canvas, nearest pixel."""
        if self.angle == 0.0:
            return img
        # continuous p' = R (p - centre) + shift; pixel indices i = p - 0.5
        R = np.array([[self.c, self.s], [-self.s, self.c]])
        t = self.shift - R @ self.centre + R @ np.array([0.5, 0.5]) - 0.5
        M = np.concatenate([R, t[:, None]], axis=1)
        return cv2.warpAffine(img, M, (self.shape[1], self.shape[0]), flags=cv2.INTER_NEAREST,
                              borderMode=cv2.BORDER_CONSTANT, borderValue=border)


def _pieces(E: np.ndarray, u: np.ndarray, v: np.ndarray, w: np.ndarray, L: int,
            min_w: float, bridge: int = 3, main: np.ndarray | None = None) -> np.ndarray:
    """Horizontal pieces of the canvas evidence ``E`` (uint8 0/1): rows ``(c, lo, hi,
    sw, swu, swv, swuu, swuv, npix, nmain)``, ``c`` the weighted mean ``v`` of the points
    in the piece, ``lo``/``hi`` the centres of its first and last pixel along, then the
    sums of the points' weights (``sw``), moments (for a line fit), its pixel count and
    how many of its points are ``main`` (1 or 0 per point; default all); and each
    point's piece (-1: none). Gaps along a run up to ``bridge - 1`` pixels long are
    bridged first (a dotted wall is a wall); a piece whose own evidence covers less than
    half of its length must be at least ``2 L`` long (a few specks in a row are not)."""
    closed = cv2.morphologyEx(E, cv2.MORPH_CLOSE, np.ones((1, bridge), np.uint8))
    closed |= E
    opened = open_runs(closed, L, axis=1).astype(np.uint8)
    # a wall across the family as thick as L holds runs of L along it: its pixels are
    # not this direction's where their run across is at least 2 L and twice their run
    # along, so a thick perpendicular wall is neither a piece nor joined to the wall it
    # meets (a pixel of two walls belongs to the longer)
    across = cv2.morphologyEx(E, cv2.MORPH_CLOSE, np.ones((bridge, 1), np.uint8)) | E
    rr, cc = pixels(opened & open_runs(across, 2 * L, axis=0))
    if len(rr):
        v_run = run_through(np.ascontiguousarray(across.T), cc, rr)
        drop = v_run >= 2 * run_through(closed, rr, cc)
        opened[rr[drop], cc[drop]] = 0
    n, lab, stats, _ = cv2.connectedComponentsWithStats(opened, connectivity=8)
    if n <= 1:
        return np.zeros((0, 10)), np.full(len(u), -1, np.int64)
    H, W = E.shape
    left = stats[1:, cv2.CC_STAT_LEFT].astype(np.int64)
    right = left + stats[1:, cv2.CC_STAT_WIDTH] - 1
    npix = stats[1:, cv2.CC_STAT_AREA].astype(np.int64)
    ci = np.clip(np.floor(u).astype(np.int64), 0, W - 1)
    ri = np.clip(np.floor(v).astype(np.int64), 0, H - 1)
    lp = lab[ri, ci]
    main = np.ones(len(u)) if main is None else main
    st = [np.bincount(lp, x, n)[1:] for x in (w, w * u, w * v, w * u * u, w * u * v)]
    nmain = np.bincount(lp, main, n)[1:]
    # share of each piece's positions along that hold evidence of its own
    er, ec = pixels(E & (lab > 0))
    cols = np.unique(lab[er, ec].astype(np.int64) * W + ec)
    cover = np.bincount(cols // W, minlength=n)[1:] / (right - left + 1.0)
    ok = (st[0] >= min_w) & ((cover >= 0.5) | (right - left + 1 >= 2 * L))
    c = st[2][ok] / st[0][ok]
    index = np.full(n, -1, np.int64)
    index[1:][ok] = np.arange(int(ok.sum()))
    return np.stack([c, left[ok] + 0.5, right[ok] + 0.5] + [x[ok] for x in st]
                    + [npix[ok], nmain[ok]], axis=1), index[lp]


def _lines(p: np.ndarray, tol: float) -> np.ndarray:
    """Line id of each piece: pieces sorted across, a new line where one lies more than
    ``tol`` beyond the first of the current line (lines at most ``tol`` wide)."""
    order = np.argsort(p[:, 0], kind="stable")
    ids = np.empty(len(p), np.int64)
    cur, first = -1, -np.inf
    for i in order:                                # one pass over pieces, not pixels
        if p[i, 0] - first > tol:
            cur, first = cur + 1, p[i, 0]
        ids[i] = cur
    return ids


def _family(p: np.ndarray, free: np.ndarray, room: np.ndarray, tol: float, half: int,
            door_min: int, max_gap: float
            ) -> tuple[np.ndarray, int, int, np.ndarray, np.ndarray]:
    """Join the horizontal pieces ``p`` of each line across gaps without a door; returns
    segments as rows like :func:`_pieces`' (sums added up, ``c`` their weighted mean)
    plus the number of doors kept and gaps joined, each piece's segment and whether
    each segment's ends (low, high) are at a door ((n, 2) bool: a jamb may be short).

    ``free`` is the canvas's free mask; ``room`` marks free pixels of a room-sized
    region (every gap closed)."""
    seg_of = np.full(len(p), -1, np.int64)
    if len(p) == 0:
        return np.zeros((0, 10)), 0, 0, seg_of, np.zeros((0, 2), bool)
    H, W = free.shape
    line = _lines(p, tol)
    out, doors, joined, at_door = [], 0, 0, []
    order = np.lexsort((p[:, 1], line))
    starts = np.flatnonzero(np.r_[True, line[order][1:] != line[order][:-1]])
    for g in np.split(order, starts[1:]):          # one line at a time
        q = p[g]
        c = float(q[:, 5].sum() / q[:, 3].sum())
        r = int(math.floor(c))
        r0, r1 = max(0, r - half), min(H, r + half + 1)
        through = np.zeros(W, bool)
        side = np.zeros(W, bool)
        if r1 > r0:
            through = free[r0:r1].all(axis=0)
            above = room[max(0, r0 - 2):r0].any(axis=0) if r0 > 0 else np.zeros(W, bool)
            below = room[r1:min(H, r1 + 2)].any(axis=0) if r1 < H else np.zeros(W, bool)
            side = above & below
        cur = q[0].copy()
        seg_of[g[0]] = len(out)
        cur_door = False
        for k in range(1, len(q)):
            gap0, gap1 = cur[2], q[k, 1]
            if gap1 - gap0 <= 1.0:                     # overlapping or touching
                cur = _absorb(cur, q[k])
                seg_of[g[k]] = len(out)
                continue
            j0, j1 = int(math.floor(gap0)) + 1, int(math.ceil(gap1))
            j0, j1 = max(0, j0), min(W, j1)
            door = False
            if j1 > j0:
                t = through[j0:j1]
                if t.any():
                    door = _longest_run(t & side[j0:j1]) >= door_min
            if door or gap1 - gap0 > max_gap:
                doors += int(door)
                out.append(cur)
                at_door.append((cur_door, door))
                cur, cur_door = q[k].copy(), door
            else:
                joined += 1
                cur = _absorb(cur, q[k])
            seg_of[g[k]] = len(out)
        out.append(cur)
        at_door.append((cur_door, False))
    return (np.asarray(out, float).reshape(-1, 10), doors, joined, seg_of,
            np.asarray(at_door, bool).reshape(-1, 2))


def _absorb(cur: np.ndarray, piece: np.ndarray) -> np.ndarray:
    out = cur + piece
    out[1], out[2] = min(cur[1], piece[1]), max(cur[2], piece[2])
    out[0] = out[5] / out[3]
    return out


def _longest_run(b: np.ndarray) -> int:
    if not b.any():
        return 0
    d = np.diff(np.r_[0, b.astype(np.int8), 0])
    return int((np.flatnonzero(d == -1) - np.flatnonzero(d == 1)).max())


def _drop_stubs(h: np.ndarray, v: np.ndarray, band: float, min_len: float
                ) -> tuple[np.ndarray, np.ndarray]:
    """Which segments to keep (two boolean masks): not those without a stretch of at least
    ``min_len`` outside the bands (``band`` either side) of the perpendicular segments
    they cross or touch: ticks and blobs on a wall (also a tick across a wall seen as
    two faces, sticking out of both), and pieces that the corner snapping shrank to
    nothing.

    ``h`` rows ``(x0, y, x1, y)``, ``v`` rows ``(x, y0, x, y1)``."""
    def keep(a, b, ax):
        if len(a) == 0:
            return np.zeros(0, bool)
        i0, i1, ic = (0, 2, 1) if ax == 0 else (1, 3, 0)   # a's ends along, a's line
        j0, j1, jc = (1, 3, 0) if ax == 0 else (0, 2, 1)   # b's ends along, b's line
        lo, hi = np.minimum(a[:, i0], a[:, i1]), np.maximum(a[:, i0], a[:, i1])
        length = hi - lo
        if len(b) == 0:
            return length >= min_len
        blo, bhi = np.minimum(b[:, j0], b[:, j1]), np.maximum(b[:, j0], b[:, j1])
        cross = (blo[None] - band <= a[:, ic, None]) & (a[:, ic, None] <= bhi[None] + band)
        # the bands of the crossing segments along a, sorted; the longest stretch of a
        # outside all of them (a tick across a wall seen as two faces sticks out on both
        # sides: its parts add up to more than min_len, but none is that long)
        s0 = np.where(cross, np.clip(b[None, :, jc] - band, lo[:, None], hi[:, None]),
                      hi[:, None])
        s1 = np.where(cross, np.clip(b[None, :, jc] + band, lo[:, None], hi[:, None]),
                      hi[:, None])
        o = np.argsort(s0, axis=1)
        s0, s1 = np.take_along_axis(s0, o, 1), np.take_along_axis(s1, o, 1)
        end = np.maximum.accumulate(s1, axis=1)
        before = np.concatenate([lo[:, None], end[:, :-1]], axis=1)
        longest = np.maximum((s0 - before).max(axis=1), hi - end[:, -1])
        return longest >= min_len
    return keep(h, v, 0), keep(v, h, 1)


def _fill_rects(img: np.ndarray, segs_h: np.ndarray, segs_v: np.ndarray, t: float | tuple,
                value: int = 1) -> None:
    """Draw axis-aligned segments (rows ``c, lo, hi``) ``t`` pixels thick, ends extended by
    ``t / 2``; pixel rows whose centres lie in ``[c - t/2, c + t/2)``. ``t`` is one
    thickness, or a pair of per-row thicknesses ``(t_h, t_v)``."""
    H, W = img.shape
    th, tv = t if isinstance(t, tuple) else (t, t)
    for segs, horiz, ts in ((segs_h, True, th), (segs_v, False, tv)):
        for (c, lo, hi), tw in zip(segs, np.broadcast_to(np.asarray(ts, float), (len(segs),)),
                                   strict=True):
            a0 = math.ceil(c - tw / 2 - 0.5)
            b0 = math.ceil(lo - tw / 2 - 0.5)
            b1 = math.ceil(hi + tw / 2 - 0.5)
            a0, a1 = max(0, a0), min(H if horiz else W, a0 + int(round(tw)))
            b0, b1 = max(0, b0), min(W if horiz else H, b1)
            if horiz:
                img[a0:a1, b0:b1] = value
            else:
                img[b0:b1, a0:a1] = value


def _residual_lines(E: np.ndarray, drawn: np.ndarray, min_len: int, tol_deg: float = 4.0
                    ) -> np.ndarray:
    """Long straight lines of the evidence ``E`` that the family walls (``drawn``, dilated)
    do not explain, more than ``tol_deg`` off both families (canvas coordinates)."""
    res = (E > 0) & ~drawn
    if res.sum() < min_len:
        return np.zeros((0, 4))
    from skimage.morphology import skeletonize

    sk = skeletonize(res).astype(np.uint8) * 255
    # each group of skeleton pixels (within the Hough's gap of each other) on its own:
    # the probabilistic Hough transform draws its points in a random order, so a pixel
    # more or less anywhere would otherwise move the lines it finds everywhere
    n, lab, st, _ = cv2.connectedComponentsWithStats(
        cv2.dilate(sk, np.ones((3, 3), np.uint8)), connectivity=8)
    found = []
    for i in np.flatnonzero(st[1:, cv2.CC_STAT_AREA] >= min_len) + 1:   # a few groups
        x0, y0 = st[i, cv2.CC_STAT_LEFT], st[i, cv2.CC_STAT_TOP]
        box = np.s_[y0:y0 + st[i, cv2.CC_STAT_HEIGHT], x0:x0 + st[i, cv2.CC_STAT_WIDTH]]
        part = np.where(lab[box] == i, sk[box], 0).astype(np.uint8)
        lines = cv2.HoughLinesP(part, 1, np.pi / 180, threshold=max(5, min_len // 2),
                                minLineLength=min_len, maxLineGap=2)
        if lines is not None:
            found.append(np.asarray(lines, float).reshape(-1, 4) + [x0, y0, x0, y0])
    if not found:
        return np.zeros((0, 4))
    s = np.concatenate(found) + 0.5
    ang = np.degrees(np.arctan2(s[:, 3] - s[:, 1], s[:, 2] - s[:, 0])) % 90.0
    s = s[(ang > tol_deg) & (ang < 90 - tol_deg)]
    if len(s) == 0:
        return s
    # one line per direction and position: the longest first, others within 2 px dropped
    s = s[np.argsort(-np.hypot(s[:, 2] - s[:, 0], s[:, 3] - s[:, 1]), kind="stable")]
    keep: list[np.ndarray] = []
    for a in s:                                     # a few lines, not pixels
        mid = (a[:2] + a[2:]) / 2
        if not any(_near_line(b, mid) < 3.0 for b in keep):
            keep.append(a)
    return np.asarray(keep).reshape(-1, 4)


def _near_line(b: np.ndarray, p: np.ndarray) -> float:
    d = b[2:] - b[:2]
    n = float(np.hypot(*d))
    if n == 0:
        return float(np.hypot(*(p - b[:2])))
    tpar = float(np.clip(np.dot(p - b[:2], d) / n**2, 0, 1))
    return float(np.hypot(*(p - b[:2] - tpar * d)))


def draw_plan(evidence: np.ndarray, occupancy: np.ndarray, resolution: float,
              wall_thickness: float | None = None, *, weights: np.ndarray | None = None,
              options: DrawOptions | None = None, cover: np.ndarray | None = None
              ) -> PlanDrawing:
    """Straight walls of a map, drawn like a plan (the module doc's steps 1-7).

    Parameters
    ----------
    evidence : (H, W) bool or (N, 2) float
        Where the walls are: a raster (e.g. the input's occupied pixels) or wall points
        ``(x, y)`` in continuous pixel coordinates (pixel ``(r, c)``'s centre is
        ``(c + 0.5, r + 0.5)``).
    occupancy : (H, W) uint8
        The input map (occupied 0, free 255, unknown 127): its free space decides which
        gaps are doors and is kept in the drawn map.
    resolution : float
        Metres per pixel.
    wall_thickness : float, optional
        Pixels; default :func:`default_wall_thickness`.
    weights : (N,) float, optional
        Weights of wall points (a point of weight 0 is ignored).
    options : DrawOptions, optional
    cover : (H, W) bool, optional
        The input's wall pixels: where they run straight for at least
        ``options.cover_run`` beside a drawn wall, the wall moves (as little as it
        must) so that they lie within its half thickness plus ``options.cover_tol``
        (:mod:`map2map.maps.cover`); a wall the input shows whole is then not left at
        one end. :func:`draw_plan_map` passes the map's occupied pixels.

    Returns
    -------
    PlanDrawing

    Examples
    --------
    A wall with a door (free space through the gap) and one with a hole (none):

    >>> m = np.full((40, 100), 255, np.uint8)
    >>> m[10:12, :] = 0; m[10:12, 40:52] = 255          # door: free through the wall
    >>> m[30:32, :] = 0; m[30:32, 40:52] = 127          # hole: unknown, no passage
    >>> d = draw_plan(m == 0, m, 0.05, 2)
    >>> sorted(round(float(s[1]), 1) for s in d.segments)
    [11.0, 11.0, 31.0]
    >>> d.info["doors"], d.info["joined"]
    (1, 1)
    """
    opt = options or DrawOptions()
    occ = np.asarray(occupancy)
    if occ.ndim != 2:
        raise ValueError(f"occupancy must be 2-D, not {occ.shape}")
    H, W = occ.shape
    res = float(resolution)
    t = float(wall_thickness) if wall_thickness is not None else float(
        default_wall_thickness(res, opt.grow_px))
    if not t > 0:
        raise ValueError(f"wall thickness must be positive, not {wall_thickness}")
    pts, w = _as_points(evidence, weights)
    if cover is not None:
        cover = np.asarray(cover, bool)
        if cover.shape != occ.shape:
            raise ValueError(f"cover must be shaped like the map {occ.shape}, not "
                             f"{cover.shape}")
    tol, reach, L, band = _scales(opt, res)
    snap = math.degrees(math.atan(opt.snap_px / max(H, W)))
    angle = dominant_angle(pts, w, (H, W), snap) if len(pts) >= 3 else 0.0
    votes = None if cover is None else (wall_points(cover), np.ones(int(cover.sum())))
    angles, fam = angle_families(pts, w, (H, W), angle, res, max_families=opt.families,
                                 votes=votes)
    info = {"pieces": 0, "doors": 0, "joined": 0, "other": 0}
    parts = []
    for k, a in enumerate(angles):           # one frame per direction family (a few)
        sel = fam == k
        segs_k, info_k = _draw_family(pts[sel], w[sel], a, occ, pts, w, t, res, opt,
                                      cover)
        parts.append(segs_k)
        info = {key: info[key] + info_k[key] for key in info}
    segs = np.concatenate(parts).reshape(-1, 4)
    free = occ == FREE
    if len(angles) > 1 and len(segs):
        # corners and junctions between the families' walls (within each family they
        # were closed in its own frame), in the map's frame
        segs = np.concatenate(_trim_overshoots(_snap_ends([segs], reach), L + band, reach,
                                               free, t / 2 + 2)).reshape(-1, 4)
    n0 = len(segs)
    if opt.cut_free and len(segs):
        segs = _cut_free(segs, free, _splat(pts, w, (H, W)) > 0, tol + t / 4,
                         max(2, int(round(tol))), L, t, opt.min_room / res**2, reach)
    if opt.corner_reach > 0 and len(segs) > 1:
        segs = _close_corners(segs, free, t / 2 + 1, opt.corner_reach / res, t)
    tk = np.full(len(segs), t)
    if opt.two_sided and len(segs):
        segs, tk = _two_sided(segs, free, t, opt.grow_px, one=opt.one_interior)
    info.update(cut=int(len(segs) - n0), angles=[float(a) for a in angles],
                two_sided=int((tk < t).sum()), bridged=0, curved=0)
    arcs, arc_of = np.zeros((0, 5)), np.full(len(segs), -1)
    if cover is not None and opt.curve_min > 0:
        cw = curved_walls(cover, free, res, t, segs, min_len=opt.curve_min)
        if len(cw.chords):
            segs = np.concatenate([segs[~cw.drop], cw.chords])
            tk = np.concatenate([tk[~cw.drop], np.full(len(cw.chords), t)])
            arcs, arc_of = cw.arcs, np.concatenate([arc_of[~cw.drop], cw.arc_of])
            info["curved"] = int(len(cw.chords))
    wall = wall_raster(segs, tk, occ.shape)
    if cover is not None and opt.bridge_run > 0 and len(segs):
        extra, tx = _bridges(segs, tk, wall > 0, cover, free, angles, res, opt, t)
        if len(extra):
            segs, tk = np.concatenate([segs, extra]), np.concatenate([tk, tx])
            arc_of = np.concatenate([arc_of, np.full(len(extra), -1)])
            wall = wall_raster(segs, tk, occ.shape)
            info["bridged"] = int(len(extra))
    out = _render(wall, occ, res, opt.min_room, opt.enclosed,
                  max(1.5, opt.sliver * t / 2))
    return PlanDrawing(segs, out, angle, t, info, tk, arcs, arc_of)


def _bridges(segs: np.ndarray, tk: np.ndarray, drawn: np.ndarray, cover: np.ndarray,
             free: np.ndarray, angles: list[float], res: float, opt: DrawOptions,
             t: float) -> tuple[np.ndarray, np.ndarray]:
    """Segments (image frame) and thicknesses that close the gaps the drawn walls
    (``drawn``, image frame) leave in the input's straight wall runs (``cover``), in the
    frame of each direction family and in the grid's own, along both their directions
    (:func:`map2map.maps.cover.bridge_gaps`, step 4): a run column is covered where a
    drawn wall lies within ``tol`` across (within ``t / 2 + 1`` in the run's first and
    last ``t / 2 + 1`` columns: a corner whose perpendicular wall ends just short of
    the run); a gap is the columns between two covered ones and, with ``bridge_ends``, a
    run's end beyond its last covered column or a run with none covered; it is closed
    only where along at least ``bridge_share`` of it no drawn wall lies within
    ``bridge_beside`` times the drawing's thickness ``t``, nor within ``bridge_same``
    with (almost) none of the input's ``free`` pixels between. A bridge is drawn as thin
    as the thinner of the walls nearest its ends."""
    tol = _scales(opt, res)[0]
    n = max(2, int(round(opt.bridge_run / res)))
    drawn = drawn.astype(np.uint8)
    found = []
    # and the grid's own frame: a run along the rows or columns of a map whose walls
    # drift turned a few degrees (a jog the turn left straight) is a run there only
    frames = list(angles) + ([] if 0.0 in angles else [0.0])
    for a in frames:                              # a few families
        fr = _Frame(a, drawn.shape)
        C = fr.warp(cover.view(np.uint8), 0) > 0
        D = fr.warp(drawn, 0) > 0
        Fr = fr.warp(free.view(np.uint8), 0) > 0
        for tr in (False, True):
            b = bridge_gaps(C.T if tr else C, D.T if tr else D, n, near=tol,
                            open_=opt.bridge_beside * t, open_share=opt.bridge_share,
                            free=Fr.T if tr else Fr, same=opt.bridge_same / res,
                            end_near=t / 2 + 1,
                            ends=max(2.0, opt.bridge_ends / res) if opt.bridge_ends > 0
                            else 0.0)
            if not len(b):
                continue
            b = b[:, [1, 0, 3, 2]] if tr else b
            b = np.concatenate([fr.back(b[:, :2]), fr.back(b[:, 2:])], axis=1)
            found.append(b)
            for q in b:                           # later frames see these walls
                cv2.line(drawn, tuple(np.round(q[:2] - 0.5).astype(int).tolist()),
                         tuple(np.round(q[2:] - 0.5).astype(int).tolist()), 1,
                         max(1, int(round(t))))
    if not found:
        return np.zeros((0, 4)), np.zeros(0)
    b = np.concatenate(found)
    d0, _ = point_segment_distances(b[:, :2], segs)
    d1, _ = point_segment_distances(b[:, 2:], segs)
    thick = np.minimum(tk[np.argmin(d0, axis=1)], tk[np.argmin(d1, axis=1)])
    return b, thick


def _two_sided(segs: np.ndarray, free: np.ndarray, t: float, grow: float,
               share: float = 0.5, step: float = 0.25, depth: float = 2.0,
               one: bool = True) -> tuple[np.ndarray, np.ndarray]:
    """Walls the input saw from both sides, drawn between the faces it saw.

    Across each segment (``segs``, image frame), one sample a pixel along it: the
    nearest free pixel of the input (``free``) on either side within ``t / 2 + 2``
    pixels of its line, from which the input is free for ``depth`` pixels on (not the
    sliver between the two lines of a wall SLAM saved twice); the face lies half a
    ``step`` before it. A segment with a face on both sides on at least ``share`` of its
    samples is seen from both sides (an interior wall): it is moved across onto the
    median middle of its faces and drawn ``grow`` pixels beyond each of them (the median
    distance between its faces plus ``2 grow``, at least 2 pixels). With ``one`` and at
    least two interior walls thinner than ``t`` so measured, every interior wall is
    drawn at the median of those (a plan draws its interior walls at one thickness; a
    wall SLAM blurred or saved twice measures thicker than it is); else each at its
    own, and one measured at ``t`` or more is left as it is. The others keep ``t``; a
    wall seen from one side keeps the face :func:`_place` gave it.

    Why: a plan's interior walls are thinner than its outer walls (the generated plans'
    0.10-0.15 m against 0.20-0.30 m), and drawn as thick as the outer walls both faces
    of an interior wall stood in the rooms beside it. ``grow`` is the plans' own
    convention: the dataset's plans have their walls grown by a pixel on each side into
    free space (``map2map dataset build``'s ``thicken``, thesis sec. 4.1), the SLAM
    maps not.

    Returns the segments and their thicknesses (pixels).

    >>> free = np.ones((20, 30), bool); free[8:11, :] = False     # a 3 px wall, rows 8-10
    >>> segs, tk = _two_sided(np.array([[2.0, 9.0, 28.0, 9.0]]), free, 6.0, 1.0)
    >>> segs.round(2).tolist(), tk.tolist()                         # rows 7-11 drawn
    ([[2.0, 9.5, 28.0, 9.5]], [5.0])
    """
    n = len(segs)
    H, W = free.shape
    idx, _, p, _ = segment_samples(segs)
    d = segs[idx, 2:] - segs[idx, :2]
    nrm = np.stack([-d[:, 1], d[:, 0]], 1) / np.maximum(np.hypot(d[:, 0], d[:, 1]),
                                                        1e-9)[:, None]
    m = int(math.ceil((t / 2 + 2) / step)) + 1          # where a face may lie
    deep = int(round(depth / step))                     # free beyond it
    ks = (np.arange(m + deep) + 0.5) * step

    def nearest_free(sign: float) -> tuple[np.ndarray, np.ndarray]:
        sk = sign * ks                            # per axis: ten times faster than (n, k, 2)
        r = np.floor(p[:, 1, None] + sk[None, :] * nrm[:, 1, None]).astype(np.int64)
        c = np.floor(p[:, 0, None] + sk[None, :] * nrm[:, 0, None]).astype(np.int64)
        ok = (r >= 0) & (r < H) & (c >= 0) & (c < W)
        # free at each step (outside the map: not), counted along the normal
        cnt = np.zeros((len(p), m + deep), np.int32)
        cnt[:, 1:] = np.cumsum(free[np.where(ok, r, 0), np.where(ok, c, 0)] & ok,
                               axis=1, dtype=np.int32)[:, :-1]
        # free for ``depth`` pixels from there on (``deep`` steps from step j: the window
        # sum is ``deep``): not the sliver between a doubled wall
        run = (cnt[:, deep:m + deep] - cnt[:, :m]) == deep if deep > 0 else \
            np.ones((len(p), m), bool)
        return run.any(axis=1), ks[np.argmax(run, axis=1)] - step / 2

    hp, dp = nearest_free(1.0)
    hm, dm = nearest_free(-1.0)
    both = hp & hm
    tk = np.full(n, float(t))
    out = segs.copy()
    two = np.bincount(idx, both, minlength=n) >= share * np.maximum(
        np.bincount(idx, minlength=n), 1)
    thick, mid = {}, {}
    for i in np.flatnonzero(two):                  # walls, not pixels
        sel = both & (idx == i)
        thick[i] = float(np.median(dp[sel] + dm[sel])) + 2 * grow
        e = segs[i, 2:] - segs[i, :2]
        mid[i] = float(np.median(dp[sel] - dm[sel])) / 2 * np.array([-e[1], e[0]]) / max(
            math.hypot(*e), 1e-9)
    seen = [v for v in thick.values() if v < t]     # the faces the input shows sharply
    typical = max(2.0, float(np.median(seen))) if one and len(seen) >= 2 else None
    for i, v in thick.items():
        if typical is None and v >= t:
            continue                                # as thick as the drawing: left as it is
        tk[i] = typical if typical is not None else max(2.0, v)
        out[i, :2] += mid[i]
        out[i, 2:] += mid[i]
    return out, tk


def _scales(opt: DrawOptions, res: float) -> tuple[float, float, int, float]:
    """Pixel tolerances of :func:`draw_plan`: ``tol``, ``reach``, the shortest piece
    ``L`` and the band about a crossing wall that :func:`_drop_stubs` leaves out."""
    tol = max(1.5, opt.tol / res)
    L = int(max(round(opt.thickest / res) + 2, round(opt.min_len / res), 4))
    return tol, max(2.0, opt.reach / res), L, max(tol, opt.thickest / res / 2)


def _draw_family(pts: np.ndarray, w: np.ndarray, angle: float, occ: np.ndarray,
                 all_pts: np.ndarray, all_w: np.ndarray, t: float, res: float,
                 opt: DrawOptions, cover: np.ndarray | None = None
                 ) -> tuple[np.ndarray, dict]:
    """Steps 3-7 of the module doc for the wall points of one direction family, in the
    frame turned by its ``angle``: segments in the map's frame (before
    :func:`_cut_free`) and counts. Rooms are told from every family's points
    (``all_pts``), so that a room of one family bounded by another's walls is one;
    ``cover``: the input's wall pixels (image frame), whose straight runs the walls keep
    inside (:func:`map2map.maps.cover.keep_runs_inside`)."""
    H, W = occ.shape
    tol, reach, L, band = _scales(opt, res)
    door_min = max(1, int(round(opt.door_min / res)))
    half = int(math.ceil(t / 2)) + 1
    min_room = opt.min_room / res**2
    fr = _Frame(angle, (H, W))
    uv = fr.to(pts) if len(pts) else np.zeros((0, 2))
    Hr, Wr = fr.shape
    E = (_splat(uv, w, (Hr, Wr)) > 0).astype(np.uint8)
    E_all = E if len(all_pts) == len(pts) else (
        _splat(fr.to(all_pts), all_w, (Hr, Wr)) > 0).astype(np.uint8)
    free_c = fr.warp((occ == FREE).astype(np.uint8), 0) > 0
    bridge = 2 * int(math.ceil(opt.bridge / res / 2)) + 1
    main = (w >= 0.5 * float(all_w.max())).astype(float) if len(w) else w
    ph, pt_h = _pieces(E, uv[:, 0], uv[:, 1], w, L, 1.0, bridge, main)
    pv, pt_v = _pieces(np.ascontiguousarray(E.T), uv[:, 1], uv[:, 0], w, L, 1.0, bridge,
                       main)
    # room-sized free regions with every gap closed (pieces joined regardless of doors)
    closed = np.zeros((Hr, Wr), np.uint8)
    hc = _family(ph, np.zeros((Hr, Wr), bool), np.zeros((Hr, Wr), bool), tol, half,
                 door_min, opt.max_gap / res)[0]
    vc = _family(pv, np.zeros((Wr, Hr), bool), np.zeros((Wr, Hr), bool), tol, half,
                 door_min, opt.max_gap / res)[0]
    _fill_rects(closed, hc[:, :3], vc[:, :3], max(t, 2 * half - 1))
    region = free_c & (closed == 0)
    room = _rooms(region, (closed > 0) | (E_all > 0), min_room, opt.enclosed)
    room |= free_c & (closed > 0)                  # the wall band itself counts
    hs, d1, j1, sh, dh = _family(ph, free_c, room, tol, half, door_min, opt.max_gap / res)
    vs, d2, j2, sv, dv = _family(pv, free_c.T, room.T, tol, half, door_min,
                                 opt.max_gap / res)
    hseg = np.stack([hs[:, 1], hs[:, 0], hs[:, 2], hs[:, 0]], 1).reshape(-1, 4)
    vseg = np.stack([vs[:, 0], vs[:, 1], vs[:, 0], vs[:, 2]], 1).reshape(-1, 4)
    h0, v0 = hseg.copy(), vseg.copy()
    hseg, vseg = _join(hseg, vseg, reach)
    # a short segment's end at a door stays where the door begins (a jamb is not
    # pulled onto the wall it stands on)
    for sg, s0, st, d, ends in ((hseg, h0, hs, dh, (0, 2)), (vseg, v0, vs, dv, (1, 3))):
        short = st[:, 2] - st[:, 1] < L
        for k, e in enumerate(ends):
            sel = short & d[:, k]
            sg[sel, e] = s0[sel, e]
    dh, dv = dh.any(axis=1), dv.any(axis=1)
    kh, kv = _drop_stubs(hseg, vseg, band, L)
    # a door's jamb: a segment beside a door, however short beyond the wall it stands
    # on, is kept (and drawn on its wall's line, below)
    jamb = max(2.0, opt.jamb_min / res)
    jh, jv = _drop_stubs(hseg, vseg, band, jamb)
    kh &= hs[:, 9] >= opt.main_min / res
    kv &= vs[:, 9] >= opt.main_min / res
    jh &= dh & ~kh & (hs[:, 8] >= jamb) & (hs[:, 2] - hs[:, 1] < 2 * L)
    jv &= dv & ~kv & (vs[:, 8] >= jamb) & (vs[:, 2] - vs[:, 1] < 2 * L)
    kh |= jh
    kv |= jv
    hs = _refit(hs, _kept(sh, kh, pt_h), uv[:, 0], uv[:, 1], w)[kh]
    vs = _refit(vs, _kept(sv, kv, pt_v), uv[:, 1], uv[:, 0], w)[kv]
    hseg, vseg, jh, jv = hseg[kh], vseg[kv], jh[kh], jv[kv]
    sh = _seen(hs, hseg[:, 0], hseg[:, 2], free_c, opt.other_min / res)
    sv = _seen(vs, vseg[:, 1], vseg[:, 3], free_c.T, opt.other_min / res)
    hs, hseg, vs, vseg, jh, jv = hs[sh], hseg[sh], vs[sv], vseg[sv], jh[sh], jv[sv]
    drawn = np.zeros((Hr, Wr), np.uint8)
    _fill_rects(drawn, np.stack([hseg[:, 1], hseg[:, 0], hseg[:, 2]], 1).reshape(-1, 3),
                np.stack([vseg[:, 0], vseg[:, 1], vseg[:, 3]], 1).reshape(-1, 3), t + 2 * tol)
    other = _residual_lines(E, drawn > 0, int(round(opt.other_min / res)))
    # slant (drifted walls) and one-sided walls' faces, in each family's own frame
    slant = (math.inf if opt.lean_px is None else float(opt.lean_px), opt.other_min / res,
             math.tan(math.radians(6.0)))
    faces = t if opt.keep_faces else 0.0
    # a wall is seen from the side its rooms lie on: laser rays through an outer wall
    # into the unknown outside are free space, but no side it was seen from
    a = _place(hs, hseg[:, 0], hseg[:, 2], room, faces, half, slant)
    b = _place(vs, vseg[:, 1], vseg[:, 3], room.T, faces, half, slant)
    if cover is not None and opt.cover_run > 0:
        # the input's straight runs stay inside the walls drawn for them (maps.cover)
        C = fr.warp(cover.view(np.uint8), 0) > 0
        n = max(2, int(round(opt.cover_run / res)))
        kw = {"band": t / 2 + 2 * tol, "c": t / 2 + opt.cover_tol / res}
        a = keep_runs_inside(hseg[:, 0], hseg[:, 2], a[0], a[1], C, n, **kw)
        b = keep_runs_inside(vseg[:, 1], vseg[:, 3], b[0], b[1], C.T, n, **kw)
    a = _onto_line(hs[:, 0], hseg[:, 0], hseg[:, 2], *a, jh, tol)
    b = _onto_line(vs[:, 0], vseg[:, 1], vseg[:, 3], *b, jv, tol)
    hseg = np.stack([hseg[:, 0], a[0], hseg[:, 2], a[1]], 1)
    vseg = np.stack([b[0], vseg[:, 1], b[1], vseg[:, 3]], 1)
    hseg, vseg, other = _snap_ends([hseg, vseg, other], reach)
    hseg, vseg, other = _trim_overshoots([hseg, vseg, other], L + band, reach, free_c,
                                         t / 2 + 2)
    segs = np.concatenate([_order(hseg), _order(vseg), other]).reshape(-1, 4)
    if len(segs):
        segs = np.concatenate([fr.back(segs[:, :2]), fr.back(segs[:, 2:])], axis=1)
    info = {"pieces": int(len(ph) + len(pv)), "doors": d1 + d2, "joined": j1 + j2,
            "other": int(len(other))}
    return segs, info


def _onto_line(c: np.ndarray, lo: np.ndarray, hi: np.ndarray, a0: np.ndarray,
               a1: np.ndarray, jamb: np.ndarray, tol: float
               ) -> tuple[np.ndarray, np.ndarray]:
    """Across-positions ``a0``, ``a1`` at the ends of a family's segments, with each
    ``jamb`` moved onto the wall it belongs to: the nearest other segment along whose
    line (``c``) lies within ``tol``, at that segment's end nearest the jamb. A jamb's
    few pixels say less about where the wall runs than the wall beside its door.

    >>> c = np.array([10.0, 11.0]); lo, hi = np.array([0.0, 60.0]), np.array([50.0, 66.0])
    >>> _onto_line(c, lo, hi, c.copy(), c.copy(), np.array([False, True]), 2.0)[0]
    array([10., 10.])
    """
    a0, a1 = a0.copy(), a1.copy()
    wall = np.flatnonzero(~jamb)
    for i in np.flatnonzero(jamb):                 # the few jambs, not pixels
        near = wall[np.abs(c[wall] - c[i]) <= tol]
        if len(near) == 0:
            continue
        gap = np.maximum(lo[near] - hi[i], lo[i] - hi[near])
        j = near[np.argmin(gap)]
        a0[i] = a1[i] = a1[j] if hi[j] <= lo[i] else a0[j]
    return a0, a1


def _cut_free(segs: np.ndarray, free: np.ndarray, ev: np.ndarray, r: float, min_run: int,
              min_len: float, t: float, min_area: float, reach: float) -> np.ndarray:
    """Segments (image frame) cut where their centre line runs over the input's free space
    farther than ``r`` pixels from any wall evidence ``ev``, with free space of at least
    ``min_area`` pixels on both sides of the drawn walls (``t`` thick) unless a side
    is not free at all, for ``min_run``
    samples or more (more than ``reach`` at an end of the segment, where corners are
    closed across free space): the input saw through the drawn wall there (a tick's ends
    beyond the wall it crosses, a line joined across a corridor), and not into a speck. Pieces
    of a cut segment shorter than ``min_len`` go; segments not cut are returned as
    they are."""
    segs = np.asarray(segs, float).reshape(-1, 4)
    H, W = free.shape
    dist = cv2.distanceTransform((~ev).astype(np.uint8), cv2.DIST_L2, 3)
    idx, f, p, n = segment_samples(segs)

    def at(q):
        return (np.clip(np.floor(q[:, 1]).astype(np.int64), 0, H - 1),
                np.clip(np.floor(q[:, 0]).astype(np.int64), 0, W - 1))
    bad = free[at(p)] & (dist[at(p)] > r)
    if bad.any():
        open_ = free & ~_near_segments(segs, (H, W), t / 2)
        nl, lab, stats, _ = cv2.connectedComponentsWithStats(open_.astype(np.uint8),
                                                             connectivity=4)
        speck = stats[:, cv2.CC_STAT_AREA] < min_area
        speck[0] = False
        d = segs[idx, 2:] - segs[idx, :2]
        nrm = np.stack([-d[:, 1], d[:, 0]], 1) / np.maximum(
            np.hypot(d[:, 0], d[:, 1]), 1e-9)[:, None] * (t / 2 + 2)
        bad &= ~speck[lab[at(p + nrm)]] & ~speck[lab[at(p - nrm)]]
    same = np.r_[False, idx[1:] == idx[:-1]]            # sample continues a segment
    run = np.cumsum(bad & ~(same & np.r_[False, bad[:-1]])) * bad
    # a run at an end must be longer than ``reach``: corners closed across free space
    end = np.zeros(run.max() + 1, bool)
    end[run[(f == 0) | (f == 1)]] = True
    cut = bad & (np.bincount(run)[run] >= np.where(end[run], reach + 1, min_run))
    if not cut.any():
        return segs
    keep = ~cut
    piece = np.cumsum(keep & ~(same & np.r_[False, keep[:-1]]))[keep] - 1
    k = np.flatnonzero(keep)
    f0 = np.minimum.reduceat(f[k], np.flatnonzero(np.r_[True, np.diff(piece) > 0]))
    f1 = np.maximum.reduceat(f[k], np.flatnonzero(np.r_[True, np.diff(piece) > 0]))
    seg = idx[k][np.r_[True, np.diff(piece) > 0]]
    d = segs[seg, 2:] - segs[seg, :2]
    out = np.concatenate([segs[seg, :2] + f0[:, None] * d, segs[seg, :2] + f1[:, None] * d], 1)
    was_cut = np.bincount(idx, cut, len(segs)) > 0
    ok = ~was_cut[seg] | (np.hypot(*(out[:, 2:] - out[:, :2]).T) >= min_len)
    return out[ok]


def _near_segments(segs: np.ndarray, shape: tuple[int, int], r: float) -> np.ndarray:
    """Pixels within about ``r`` of the segments (image frame)."""
    img = np.zeros(shape, np.uint8)
    th = max(1, int(round(2 * r)))
    for x0, y0, x1, y1 in np.round((np.asarray(segs, float).reshape(-1, 4) - 0.5) * 16
                                   ).astype(np.int64):     # segments, not pixels
        cv2.line(img, (int(x0), int(y0)), (int(x1), int(y1)), 1, th, cv2.LINE_8, 4)
    return img > 0


def _kept(seg_of: np.ndarray, keep: np.ndarray, point_piece: np.ndarray) -> np.ndarray:
    """Each point's segment (index among all of the family's segments; -1: none or a
    segment not kept)."""
    if len(seg_of) == 0:
        return np.full(len(point_piece), -1, np.int64)
    seg = np.where(point_piece >= 0, seg_of[np.maximum(point_piece, 0)], -1)
    return np.where((seg >= 0) & keep[np.maximum(seg, 0)], seg, -1)


def _line(st: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Weighted least-squares line ``v = vb + b (u - ub)`` of each row of sums."""
    sw = np.maximum(st[:, 3], 1e-12)
    ub, vb = st[:, 4] / sw, st[:, 5] / sw
    var = st[:, 6] / sw - ub**2
    cov = st[:, 7] / sw - ub * vb
    return ub, vb, np.where(var > 1e-9, cov / np.maximum(var, 1e-9), 0.0)


def _refit(st: np.ndarray, seg: np.ndarray, u: np.ndarray, v: np.ndarray, w: np.ndarray
           ) -> np.ndarray:
    """The sums of each segment again, from its points within a pixel plus half its seen
    thickness of its first line only: blobs and ray ends beside a wall neither turn nor
    move it."""
    if len(st) == 0:
        return st
    ub, vb, b = _line(st)
    k = np.maximum(seg, 0)
    length = st[:, 2] - st[:, 1]
    band = 1.0 + 0.5 * st[:, 8] / np.maximum(length + 1.0, 1.0)
    inside = (seg >= 0) & (np.abs(v - vb[k] - b[k] * (u - ub[k])) <= band[k])
    wi = np.where(inside, w, 0.0)
    n = len(st)
    new = [np.bincount(k, x, n) for x in (wi, wi * u, wi * v, wi * u * u, wi * u * v)]
    out = st.copy()
    ok = new[0] > 0
    for j, x in enumerate(new):
        out[ok, 3 + j] = x[ok]
    out[ok, 0] = out[ok, 5] / out[ok, 3]
    return out


def _seen(st: np.ndarray, lo: np.ndarray, hi: np.ndarray, free: np.ndarray,
          long: float, share: float = 0.3) -> np.ndarray:
    """Which of a family's segments to keep: those at least ``long`` pixels long, and
    shorter ones with free space within 3 pixels of their seen band, on one side or the
    other, along at least ``share`` of their length (a laser saw them from the free
    side); not the ray ends and blobs beyond the outer walls."""
    keep = (hi - lo) >= long
    H, W = free.shape
    seen = st[:, 8] / np.maximum(hi - lo + 1.0, 1.0)
    for i in np.flatnonzero(~keep):                 # the short ones: a few slices
        j0, j1 = max(0, int(math.floor(lo[i]))), min(W, int(math.ceil(hi[i])) + 1)
        a = int(math.floor(st[i, 0] - seen[i] / 2 - 0.5))
        b = int(math.ceil(st[i, 0] + seen[i] / 2 + 0.5))
        up = free[max(0, a - 3):max(0, a), j0:j1]
        dn = free[min(H, b):min(H, b + 3), j0:j1]
        f = np.zeros(max(j1 - j0, 0), bool)
        if up.size:
            f |= up.any(axis=0)
        if dn.size:
            f |= dn.any(axis=0)
        keep[i] = f.size > 0 and f.mean() >= share
    return keep


def _place(st: np.ndarray, lo: np.ndarray, hi: np.ndarray, free: np.ndarray, t: float,
           half: int, slant: tuple[float, float, float]) -> tuple[np.ndarray, np.ndarray]:
    """Across-positions at the ends ``lo`` and ``hi`` of a family's segments (rows of
    :func:`_family`, family frame: horizontal; ``free``: the free space of its rooms,
    :func:`_rooms`, without the ray fans beyond outer walls).

    A segment at least ``slant[1]`` long whose points' least-squares line leans by at
    least ``slant[0]`` pixels over its length (and less than ``slant[2]``, a tangent)
    follows that line: a wall that SLAM drift turned by a degree or two is drawn where
    it was seen, not across it. A wall seen from one side only (free space along at
    least half of it on one side, along at most a tenth on the other) keeps its seen
    face: its centre moves away from the free side by half the difference between the
    drawn thickness and the seen one (pixels per length), so the drawn wall's face lies
    where the laser hit it."""
    n = len(st)
    if n == 0:
        return np.zeros(0), np.zeros(0)
    H, W = free.shape
    ub, vb, b = _line(st)
    length = hi - lo
    lean = (np.abs(b) * length >= slant[0]) & (length >= slant[1]) & (np.abs(b) < slant[2])
    b = np.where(lean, b, 0.0)
    c = np.where(lean, vb, st[:, 0])
    a0, a1 = c + b * (lo - ub), c + b * (hi - ub)
    seen = st[:, 8] / np.maximum(length + 1.0, 1.0)
    shift = np.clip((t - seen) / 2, 0, t / 2)
    for i in range(n):                      # one slice per segment, not per pixel
        j0, j1 = max(0, int(math.floor(lo[i]))), min(W, int(math.ceil(hi[i])))
        r = int(math.floor((a0[i] + a1[i]) / 2))
        if j1 <= j0 or shift[i] <= 0:
            continue
        up = free[max(0, r - half - 3):max(0, r - half), j0:j1]
        dn = free[min(H, r + half + 1):min(H, r + half + 4), j0:j1]
        fu = up.any(axis=0).mean() if up.size else 0.0
        fd = dn.any(axis=0).mean() if dn.size else 0.0
        if fu >= 0.5 and fd <= 0.1:
            a0[i] += shift[i]
            a1[i] += shift[i]
        elif fd >= 0.5 and fu <= 0.1:
            a0[i] -= shift[i]
            a1[i] -= shift[i]
    return a0, a1


def _stack(groups: list[np.ndarray]):
    """The segments of ``groups`` as one array ``s`` with their starts, unit directions
    and lengths, and the group sizes; None with fewer than two segments."""
    s = np.concatenate([np.asarray(g, float).reshape(-1, 4) for g in groups])
    if len(s) < 2:
        return None
    d = s[:, 2:] - s[:, :2]
    ln = np.maximum(np.hypot(d[:, 0], d[:, 1]), 1e-9)
    return s, s[:, :2], d / ln[:, None], ln, [len(g) for g in groups]


def _crossings(P: np.ndarray, p0: np.ndarray, u: np.ndarray):
    """Where the line through each point ``P[i]`` along ``u[i]`` meets segment ``j``'s
    line (``P_i + t u_i = p0_j + s u_j``): ``(t, s, ok)``, (n, n) each, ``ok`` where the
    two lines are more than 30 degrees apart (never ``i == j``)."""
    cross = u[:, None, 0] * u[None, :, 1] - u[:, None, 1] * u[None, :, 0]
    ok = np.abs(cross) > 0.5
    np.fill_diagonal(ok, False)
    den = np.where(ok, cross, 1.0)
    dx = p0[None, :, :] - P[:, None, :]
    t = (dx[..., 0] * u[None, :, 1] - dx[..., 1] * u[None, :, 0]) / den
    s = (dx[..., 0] * u[:, None, 1] - dx[..., 1] * u[:, None, 0]) / den
    return t, s, ok


def _close_corners(segs: np.ndarray, free: np.ndarray, lo: float, hi: float,
                   t: float, max_free: float = 0.25) -> np.ndarray:
    """Segments (image frame) with the open L-corners closed: two walls more than 30
    degrees apart whose free ends (no other wall within ``t + 1``) both stop short of
    their lines' crossing, by more than ``lo`` and at most ``hi`` pixels each, are
    extended to it where the extensions run over at most ``max_free`` of the input's
    ``free`` pixels: a room's corner the robot never saw (free space meeting unknown
    across the corner), not a door beside it (the robot saw through a door). Gaps of
    both ends within the corner snap's reach are closed before (:func:`_snap_ends`).

    >>> free = np.zeros((50, 50), bool); free[12:40, 12:40] = True
    >>> walls = np.array([[18.0, 10.0, 40.0, 10.0], [10.0, 18.0, 10.0, 40.0]])
    >>> _close_corners(walls, free, 3.0, 20.0, 4.0).tolist()       # an unseen corner
    [[10.0, 10.0, 40.0, 10.0], [10.0, 10.0, 10.0, 40.0]]
    >>> free[8:12, 10:18] = True                                    # seen through: a door
    >>> _close_corners(walls, free, 3.0, 20.0, 4.0).tolist()
    [[18.0, 10.0, 40.0, 10.0], [10.0, 18.0, 10.0, 40.0]]
    """
    st = _stack([segs])
    if st is None:
        return segs
    s, p0, u, ln, _ = st
    n = len(s)
    ends = s.reshape(-1, 2)                              # 2 i: start of i, 2 i + 1: end
    loose = _loose_ends(s, t)
    H, W = free.shape

    def free_share(a: np.ndarray, b: np.ndarray) -> float:
        k = max(2, int(np.ceil(np.hypot(*(b - a)))) + 1)
        q = a[None, :] + np.linspace(0.0, 1.0, k)[:, None] * (b - a)[None, :]
        r = np.clip(np.floor(q[:, 1]).astype(np.int64), 0, H - 1)
        c = np.clip(np.floor(q[:, 0]).astype(np.int64), 0, W - 1)
        return float(free[r, c].mean())

    cand = []
    for e, sign in ((0, -1.0), (1, 1.0)):               # start (outward -u), end (+u)
        P = ends[e::2]
        ti, sj, ok = _crossings(P, p0, u)
        di = sign * ti                                   # outward from this end
        beyond_start, beyond_end = -sj, sj - ln[None, :]
        dj = np.where(sj < 0, beyond_start, beyond_end)
        fj = np.where(sj < 0, 0, 1)                      # which end of j
        ok &= (di > lo) & (di <= hi) & (dj > lo) & (dj <= hi)
        ok &= loose[2 * np.arange(n) + e][:, None]
        ok &= loose[2 * np.arange(n)[None, :] + fj]
        for i, j in zip(*np.nonzero(ok), strict=True):  # a few corners a map
            cand.append((max(di[i, j], dj[i, j]), i, e, j, int(fj[i, j]), ti[i, j]))
    out = s.copy()
    used = set()
    for _, i, e, j, f, tij in sorted(cand):
        if (i, e) in used or (j, f) in used:
            continue
        x = s[i, 2 * e:2 * e + 2] + tij * u[i]
        if max(free_share(s[i, 2 * e:2 * e + 2], x),
               free_share(s[j, 2 * f:2 * f + 2], x)) > max_free:
            continue
        out[i, 2 * e:2 * e + 2] = x
        out[j, 2 * f:2 * f + 2] = x
        used |= {(i, e), (j, f)}
    return out


def _split(out: np.ndarray, sizes: list[int]) -> list[np.ndarray]:
    return np.split(out, np.cumsum(sizes)[:-1])


def _snap_ends(groups: list[np.ndarray], reach: float) -> list[np.ndarray]:
    """Move every segment end onto the intersection with another segment's line (one
    more than 30 degrees off its own) when that point lies within ``reach`` of the end
    and within ``reach`` of the other segment: corners and T-junctions stay closed
    after walls are leaned or moved onto their faces. Where both ends of a segment
    would move onto the same segment's line, only the nearer one does."""
    st = _stack(groups)
    if st is None:
        return [np.asarray(g, float).reshape(-1, 4) for g in groups]
    s, p0, u, ln, sizes = st
    out = s.copy()
    rows = np.arange(len(s))
    hits = []
    for e in (0, 2):                           # each end: all other segments at once
        P = s[:, e:e + 2]
        ti, sj, ok = _crossings(P, p0, u)
        ok &= (np.abs(ti) <= reach) & (sj >= -reach) & (sj <= ln[None, :] + reach)
        dist = np.where(ok, np.abs(ti), np.inf)
        k = np.argmin(dist, axis=1)
        hits.append((k, dist[rows, k], ti[rows, k]))
    # a segment shorter than twice the reach (a door's jamb) whose both ends find the
    # same wall moves only its nearer end onto it
    (k0, d0, t0), (k1, d1, t1) = hits
    same = np.isfinite(d0) & np.isfinite(d1) & (k0 == k1)
    for e, d, t, far in ((0, d0, t0, same & (d0 > d1)), (2, d1, t1, same & (d1 >= d0))):
        hit = np.isfinite(d) & ~far
        out[hit, e:e + 2] = s[hit, e:e + 2] + t[hit, None] * u[hit]
    keep = np.hypot(out[:, 2] - out[:, 0], out[:, 3] - out[:, 1]) > 1e-6
    return [g[k] for g, k in zip(_split(out, sizes), _split(keep, sizes), strict=True)]


def _trim_overshoots(groups: list[np.ndarray], max_len: float, reach: float,
                     free: np.ndarray, side: float) -> list[np.ndarray]:
    """Cut every segment end that runs on past a wall it crosses (one more than 30 degrees
    off its own, the crossing within ``reach`` of that wall's extent) by less than
    ``max_len`` back to the crossing, unless the part beyond borders free space (cells
    ``side`` px either side of it, more than half of them free in ``free``, (rows, cols)
    of the segments' frame): a plan's wall does not poke out of a corner into the
    outside by less than the shortest wall drawn (``_drop_stubs``' rule for whole
    segments: ``max_len`` is its ``min_len`` plus its band), while a door's jamb beside
    a junction, with rooms on both sides, stays. Such ends come from a wall's evidence
    running on along laser hits outside the building, left beyond ``_snap_ends``' reach
    when the crossing wall moved onto its face."""
    st = _stack(groups)
    if st is None:
        return [np.asarray(g, float).reshape(-1, 4) for g in groups]
    s, p0, u, ln, sizes = st
    out = s.copy()
    for e, inward in ((0, 1.0), (2, -1.0)):
        P = s[:, e:e + 2]
        ti, sj, base = _crossings(P, p0, u)
        ti = ti * inward                        # distance from the end, inwards
        # the crossing lies inside this segment, under max_len from its end, on the other
        ok = base & (ti > 1e-6) & (ti < max_len) & (ti < ln[:, None] - max_len) & \
            (sj >= -reach) & (sj <= ln[None, :] + reach)
        dist = np.where(ok, ti, np.inf)
        k = np.argmin(dist, axis=1)
        t_hit = dist[np.arange(len(s)), k]
        for i in np.flatnonzero(np.isfinite(t_hit)):     # a few ends per map
            a = np.arange(0.5, t_hit[i], 1.0)
            along = P[i] + inward * a[:, None] * u[i]
            n = np.array([-u[i, 1], u[i, 0]])
            pts = np.concatenate([along + side * n, along - side * n])
            r = np.clip(np.round(pts[:, 1]).astype(int), 0, free.shape[0] - 1)
            c = np.clip(np.round(pts[:, 0]).astype(int), 0, free.shape[1] - 1)
            if len(pts) and free[r, c].mean() <= 0.5:
                out[i, e:e + 2] = P[i] + inward * t_hit[i] * u[i]
    return _split(out, sizes)


def _order(s: np.ndarray) -> np.ndarray:
    """Segments with ``x0 <= x1`` (``y0 <= y1`` for vertical ones), sorted."""
    s = np.asarray(s, float).reshape(-1, 4)
    swap = (s[:, 0] > s[:, 2]) | ((s[:, 0] == s[:, 2]) & (s[:, 1] > s[:, 3]))
    s[swap] = s[swap][:, [2, 3, 0, 1]]
    return s[np.lexsort((s[:, 2], s[:, 0], s[:, 1]))]


def render_plan(segments: np.ndarray, occupancy: np.ndarray, thickness: float | np.ndarray,
                resolution: float, *, min_room: float = 0.5, enclosed: float = 0.2,
                sliver: float = 1.5) -> np.ndarray:
    """The drawn map (step 8 of the module doc): free and unknown from ``occupancy``
    (its occupied pixels take their nearest non-occupied pixel's value; free regions
    under ``min_room`` m^2, or with less than ``enclosed`` of their outline along a wall,
    become unknown), walls ``thickness`` pixels thick along
    ``segments`` (continuous pixel coordinates; ``thickness`` one for all, or one per
    segment), nothing else occupied; unknown slivers between a wall and a room up to
    ``2 sliver`` pixels across become free (:func:`draw_plan` passes half its
    ``DrawOptions.sliver`` thicknesses).

    Examples
    --------
    >>> m = np.full((20, 30), 255, np.uint8); m[9, :] = 0
    >>> out = render_plan(np.array([[2.0, 10.0, 28.0, 10.0]]), m, 2, 0.05, min_room=0.01)
    >>> int((out == 0).sum(axis=0)[5]), int((out[9] == 0).sum()), int((out[10] == 0).sum())
    (2, 27, 27)
    """
    occ = np.asarray(occupancy)
    return _render(wall_raster(segments, thickness, occ.shape), occ, resolution,
                   min_room, enclosed, sliver)


def wall_raster(segments: np.ndarray, thickness: float | np.ndarray,
                shape: tuple[int, int]) -> np.ndarray:
    """The walls :func:`render_plan` draws, alone: uint8, 1 on a wall (``render_plan``'s
    occupied pixels are exactly these).

    >>> wall_raster(np.array([[2.0, 10.0, 28.0, 10.0]]), 2, (20, 30)).sum(axis=0)[5].item()
    2
    """
    H, W = shape
    segs = np.asarray(segments, float).reshape(-1, 4)
    tk = np.broadcast_to(np.asarray(thickness, float), (len(segs),)).copy()
    segs = _free_ends_in(segs, tk)
    wall = np.zeros((H, W), np.uint8)
    axis = np.abs(segs[:, 1] - segs[:, 3]) < 1e-9
    vert = np.abs(segs[:, 0] - segs[:, 2]) < 1e-9
    h = segs[axis & ~vert]
    v = segs[vert & ~axis]
    _fill_rects(wall, np.stack([h[:, 1], np.minimum(h[:, 0], h[:, 2]),
                                np.maximum(h[:, 0], h[:, 2])], 1).reshape(-1, 3),
                np.stack([v[:, 0], np.minimum(v[:, 1], v[:, 3]),
                          np.maximum(v[:, 1], v[:, 3])], 1).reshape(-1, 3),
                (tk[axis & ~vert], tk[vert & ~axis]))
    rest, tr = segs[~(axis ^ vert)], tk[~(axis ^ vert)]
    if len(rest):
        d = rest[:, 2:] - rest[:, :2]
        ang = np.degrees(np.arctan2(np.abs(d[:, 1]), np.abs(d[:, 0])))
        xm, ym = ang <= _NEAR_AXIS_DEG, ang >= 90 - _NEAR_AXIS_DEG
        _fill_columns(wall, rest[xm], tr[xm])
        _fill_columns(wall.T, rest[ym][:, [1, 0, 3, 2]], tr[ym])
        rest, tr = rest[~xm & ~ym], tr[~xm & ~ym]
    if len(rest):
        d = rest[:, 2:] - rest[:, :2]
        n = np.maximum(np.hypot(d[:, 0], d[:, 1]), 1e-9)[:, None]
        along = d / n * (tr[:, None] / 2)
        # OpenCV fills the pixels the outline touches: a quarter pixel less each side
        # measures ``thickness`` across at any angle (within 0.2 px)
        across = np.stack([-along[:, 1], along[:, 0]], 1) * (1 - 0.5 / tr[:, None])
        a, b = rest[:, :2] - along, rest[:, 2:] + along
        quads = np.stack([a - across, b - across, b + across, a + across], 1) - 0.5
        for q in np.round(quads * 16).astype(np.int32):   # one call per wall: one call
            cv2.fillConvexPoly(wall, q, 1, cv2.LINE_8, shift=4)  # for all XORs overlaps
    return wall


def _render(wall: np.ndarray, occ: np.ndarray, resolution: float, min_room: float,
            enclosed: float, sliver: float = 1.5) -> np.ndarray:
    """:func:`render_plan` given its walls (:func:`wall_raster`); unknown slivers up to
    ``2 sliver`` pixels across become free (:func:`_slivers`)."""
    H, W = occ.shape
    walls = occ == OCCUPIED
    out = occ.copy()
    if walls.any():
        # an occupied pixel takes the value (free or unknown) of its nearest other pixel
        d = [cv2.distanceTransform((occ != v).astype(np.uint8), cv2.DIST_L2, 3)
             if (occ == v).any() else np.full((H, W), np.inf, np.float32)
             for v in (FREE, UNKNOWN)]
        out[walls] = np.where(d[0][walls] <= d[1][walls], FREE, UNKNOWN)
    free = (out == FREE) & (wall == 0)
    keep = _rooms(free, wall > 0, min_room / resolution**2, enclosed)
    out = np.where(free & ~keep, np.uint8(UNKNOWN), out)
    out[wall > 0] = OCCUPIED
    out[_slivers(out, sliver)] = FREE
    return out


def _slivers(out: np.ndarray, width: float = 1.5) -> np.ndarray:
    """Unknown slivers between a drawn wall and a room: unknown regions (8-connected)
    at most ``2 width`` pixels across (no pixel farther than ``width`` from a known
    one) that touch both a wall and free space of ``out`` and not the map's border.
    They are what a wall drawn off the input's wall leaves behind (the input's wall
    pixels and the unknown beyond them, now inside the room); a wider unknown region
    (a room's corner the robot never saw) is left as it is.

    >>> m = np.full((9, 12), 127, np.uint8); m[1:8, 1:11] = 255; m[1, 1:11] = 0
    >>> m[2, 3:9] = 127                       # the unknown beyond a wall drawn lower
    >>> int(_slivers(m).sum())
    6
    >>> m[2:6, 3:9] = 127                     # a pocket 4 px deep is not a sliver
    >>> int(_slivers(m).sum())
    0
    """
    lab, enclosed = enclosed_unknown(out)
    if len(enclosed) <= 1:
        return np.zeros(out.shape, bool)
    U = (out == UNKNOWN).astype(np.uint8)
    d = cv2.distanceTransform(np.pad(U, 1, constant_values=1), cv2.DIST_L2, 3)[1:-1, 1:-1]
    deep = np.zeros(len(enclosed), bool)
    deep[lab[d > width]] = True
    return (enclosed & ~deep)[lab]


def enclosed_unknown(m: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The unknown regions (8-connected) of a three-valued map and which of them lie
    between a wall and free space: they touch both (within a pixel) and not the map's
    border (unknown outside a building touches the border or no wall). Returns the
    regions' labels (0: not unknown) and, per label, whether it is enclosed (label 0:
    False). :func:`_slivers` fills the thin ones; ``evaluate.drawing.unknown_pockets``
    counts them.

    >>> m = np.full((12, 20), 127, np.uint8); m[2:10, 2:18] = 255; m[9:11, 1:19] = 0
    >>> m[1, 1:19] = 0; m[1:11, 1] = 0; m[1:11, 18] = 0; m[7:9, 4:15] = 127
    >>> lab, enclosed = enclosed_unknown(m)
    >>> int(enclosed.sum()), bool(enclosed[lab[7, 4]]), bool(enclosed[lab[0, 0]])
    (1, True, False)
    """
    m = np.asarray(m)
    n, lab, st, _ = cv2.connectedComponentsWithStats((m == UNKNOWN).astype(np.uint8),
                                                     connectivity=8)
    if n <= 1:
        return lab, np.zeros(n, bool)
    H, W = m.shape
    k = np.ones((3, 3), np.uint8)
    touches = [np.bincount(lab[cv2.dilate((m == v).astype(np.uint8), k) > 0],
                           minlength=n) > 0 for v in (OCCUPIED, FREE)]
    x0, y0 = st[:, cv2.CC_STAT_LEFT], st[:, cv2.CC_STAT_TOP]
    border = ((x0 == 0) | (y0 == 0) | (x0 + st[:, cv2.CC_STAT_WIDTH] == W)
              | (y0 + st[:, cv2.CC_STAT_HEIGHT] == H))
    ok = touches[0] & touches[1] & ~border
    ok[0] = False
    return lab, ok


def _loose_ends(segs: np.ndarray, t: float | np.ndarray) -> np.ndarray:
    """Per segment end (start of segment i at ``2 i``, its end at ``2 i + 1``): no other
    segment comes within ``t + 1`` pixels of it (``t`` one for all, or one per
    segment): a door's side or a wall ending in a room, not a corner or junction."""
    n = len(segs)
    t = np.broadcast_to(np.asarray(t, float), (n,))
    dist, _ = point_segment_distances(segs.reshape(-1, 2), segs)   # ends: 2 a segment
    dist[np.arange(2 * n), np.repeat(np.arange(n), 2)] = np.inf      # not its own wall
    return (dist > np.repeat(t, 2)[:, None] + 1.0).all(axis=1)


def _free_ends_in(segs: np.ndarray, t: float) -> np.ndarray:
    """Segments with each free end moved inwards by ``t / 2 - 0.5``, at most to the
    segment's middle: drawn extended by ``t / 2`` as every end is (so that corners
    close), a free end then covers its last evidence pixel and no more, and a door is
    drawn as wide as the input shows it, not ``t`` narrower. An end is free when no
    other segment comes within ``t + 1`` pixels of it (a door's side, a wall ending in
    a room); nearer, its extension reaches that wall, and it keeps it (an end that
    stops short of a corner still closes it).

    >>> segs = np.array([[10.0, 20.0, 40.0, 20.0], [40.0, 20.0, 40.0, 60.0]])
    >>> _free_ends_in(segs, 6.0)      # (10, 20) and (40, 60) are free, (40, 20) a corner
    array([[12.5, 20. , 40. , 20. ],
           [40. , 20. , 40. , 57.5]])
    """
    n = len(segs)
    t = np.broadcast_to(np.asarray(t, float), (n,))
    if n == 0 or (t <= 1).all():
        return segs
    free = _loose_ends(segs, t).reshape(n, 2) & (t > 1)[:, None]
    d = segs[:, 2:] - segs[:, :2]
    length = np.sqrt(np.maximum((d**2).sum(axis=1), 1e-12))
    step = np.minimum(t / 2 - 0.5, length / 2)[:, None] / length[:, None] * d
    out = segs.copy()
    out[:, :2] += np.where(free[:, :1], step, 0.0)
    out[:, 2:] -= np.where(free[:, 1:], step, 0.0)
    return out


#: Segments within this of the grid axes are drawn column by column (:func:`_fill_columns`).
_NEAR_AXIS_DEG = 10.0


def _fill_columns(img: np.ndarray, segs: np.ndarray, t: float | np.ndarray) -> None:
    """Draw segments that run within 45 degrees of the rows, column by column: in every
    column whose centre lies within the segment (extended by ``t / 2`` along), the
    ``round(t / cos)`` pixels whose centres are nearest the segment's line, so a wall
    turned by a fraction of a degree is ``t`` pixels thick everywhere (OpenCV's polygon
    fill makes it ``t + 1`` along half its length). ``t``: one thickness, or one per
    segment. ``img`` may be a transposed view."""
    H, W = img.shape
    segs = np.asarray(segs, float).reshape(-1, 4)
    ts = np.broadcast_to(np.asarray(t, float), (len(segs),))
    for (x0, y0, x1, y1), tw in zip(segs, ts, strict=True):         # walls, not pixels
        if x1 < x0:
            x0, y0, x1, y1 = x1, y1, x0, y0
        dx, dy = x1 - x0, y1 - y0
        length = math.hypot(dx, dy)
        if length == 0:
            continue
        cosa = dx / length
        n = max(1, int(round(tw / cosa)))
        e = tw / 2 * cosa
        c0 = max(0, math.ceil(x0 - e - 0.5))
        c1 = min(W - 1, math.ceil(x1 + e - 0.5) - 1)
        if c1 < c0:
            continue
        cols = np.arange(c0, c1 + 1)
        yc = y0 + (cols + 0.5 - x0) * (dy / dx)
        top = np.ceil(yc - n / 2 - 0.5).astype(np.int64)
        rows = top[:, None] + np.arange(n)[None, :]
        cc = np.broadcast_to(cols[:, None], rows.shape)
        ok = (rows >= 0) & (rows < H)
        img[rows[ok], cc[ok]] = 1


def _rooms(free: np.ndarray, walls: np.ndarray, min_area: float, enclosed: float
           ) -> np.ndarray:
    """Free pixels of regions (4-connected) at least ``min_area`` pixels large whose
    outline runs along ``walls`` (within a pixel) for at least ``enclosed`` of its length:
    rooms, not the fans of laser rays that left the building (bounded by unknown). The
    largest region is a room whatever its outline: on a real map the building's free
    space is bounded by unknown along most of its ragged outline, and a few walls more
    or less must not turn all of it unknown."""
    n, lab = cv2.connectedComponents(free.astype(np.uint8), connectivity=4)
    area = np.bincount(lab.ravel(), minlength=n)
    f8 = free.astype(np.uint8)
    edge = free & (cv2.erode(f8, np.ones((3, 3), np.uint8), borderValue=0) == 0)
    near = cv2.dilate(walls.astype(np.uint8), np.ones((3, 3), np.uint8)) > 0
    le = lab[edge]
    tot = np.bincount(le, minlength=n)
    along = np.bincount(le[near[edge]], minlength=n)
    ok = (area >= min_area) & (along >= enclosed * np.maximum(tot, 1))
    if n > 1:            # the largest region is the building, however ragged its outline
        ok[1 + int(np.argmax(area[1:]))] |= bool(area[1:].max() >= min_area)
    ok[0] = False
    return ok[lab]


def draw_plan_map(m: OccupancyMap, evidence: np.ndarray | None = None,
                  wall_thickness: float | None = None, *, weights: np.ndarray | None = None,
                  options: DrawOptions | None = None) -> tuple[OccupancyMap, np.ndarray]:
    """:func:`draw_plan` on a map: the drawn map (same grid, origin and meta, plus
    ``meta["plan_drawer"]``: pixel segments, angle, thickness, counts) and the segments
    in world metres (``x0, y0, x1, y1``), what :func:`save_plan_dxf` writes.

    ``evidence`` defaults to the map's own occupied pixels (the classical path).

    Examples
    --------
    >>> m = OccupancyMap(np.full((40, 60), 255, np.uint8), resolution=0.05)
    >>> m.data[20:22, 5:55] = 0
    >>> out, world = draw_plan_map(m, wall_thickness=2)
    >>> out.shape == m.shape, world.round(3).tolist()
    (True, [[0.275, 0.95, 2.725, 0.95]])
    """
    ev = m.occupied if evidence is None else evidence
    d = draw_plan(ev, m.data, m.resolution, wall_thickness, weights=weights, options=options,
                  cover=m.occupied)
    out = m.copy(d.map)
    out.meta["plan_drawer"] = {"segments_px": d.segments.tolist(), "angle": d.angle,
                               "thickness_px": d.thickness, **d.info}
    if d.thicknesses is not None:
        out.meta["plan_drawer"]["thicknesses_px"] = d.thicknesses.tolist()
    if len(d.arcs):                       # curved walls: rare, so only when there are
        out.meta["plan_drawer"].update(arcs_px=d.arcs.tolist(), arc_of=d.arc_of.tolist())
    s = d.segments
    x0, y0 = m.pixel_to_world(s[:, 1] - 0.5, s[:, 0] - 0.5)
    x1, y1 = m.pixel_to_world(s[:, 3] - 0.5, s[:, 2] - 0.5)
    return out, np.stack([x0, y0, x1, y1], axis=1).reshape(-1, 4)


def _draw_job(job: tuple) -> tuple[OccupancyMap, np.ndarray]:
    """One :func:`draw_plan_maps` item (a module-level function: it runs in a worker)."""
    m, evidence, thickness, weights, options = job
    return draw_plan_map(m, evidence, thickness, weights=weights, options=options)


def draw_plan_maps(maps: list[OccupancyMap], evidence: list | None = None,
                   wall_thickness: list | float | None = None, *,
                   weights: list | None = None, options: DrawOptions | None = None,
                   workers: int | None = None, min_maps: int = 16
                   ) -> list[tuple[OccupancyMap, np.ndarray]]:
    """:func:`draw_plan_map` for many maps, on the CPU's cores.

    The drawer holds the GIL (threads draw no faster), so from ``min_maps`` maps on it
    runs in ``workers`` processes (:func:`map2map.core.parallel.process_map`; default one
    per core, 1: in this process). The results do not depend on ``workers``.

    Parameters
    ----------
    maps : list of OccupancyMap
        The maps to draw.
    evidence, weights : list, optional
        Per map, as :func:`draw_plan_map`'s (None: each map's own walls, weight 1).
    wall_thickness : float or list, optional
        One thickness in pixels for all maps, or one per map (None: the default).

    Examples
    --------
    >>> m = OccupancyMap(np.full((40, 60), 255, np.uint8), resolution=0.05)
    >>> m.data[20:22, 5:55] = 0
    >>> [w.round(3).tolist() for _, w in draw_plan_maps([m, m], wall_thickness=2)]
    [[[0.275, 0.95, 2.725, 0.95]], [[0.275, 0.95, 2.725, 0.95]]]
    """
    n = len(maps)
    ev = [None] * n if evidence is None else list(evidence)
    w = [None] * n if weights is None else list(weights)
    t = (list(wall_thickness) if isinstance(wall_thickness, (list, tuple, np.ndarray))
         else [wall_thickness] * n)
    if not len(ev) == len(w) == len(t) == n:
        raise ValueError("draw_plan_maps: evidence, weights and wall_thickness need one "
                         "entry per map")
    jobs = [(m, e, tk, wk, options) for m, e, tk, wk in zip(maps, ev, t, w, strict=True)]
    return process_map(_draw_job, jobs, workers=workers, min_items=min_maps)


def save_plan_dxf(drawing: PlanDrawing | np.ndarray, path, resolution: float,
                  origin: tuple[float, float, float] = (0.0, 0.0, 0.0),
                  height: int | None = None, *, width: bool = False) -> np.ndarray:
    """Write a drawing's segments as DXF lines in world metres (through
    :func:`map2map.maps.dxf.save_segments_dxf`; a drawing's curved walls as arcs) and
    return them.

    ``height`` is the map's number of rows (the ROS origin is its lower-left corner);
    ``width=True`` gives each line the drawing's wall thickness as its width. The origin's
    yaw turns the drawing about that corner.

    Examples
    --------
    >>> import tempfile, pathlib, ezdxf
    >>> m = np.full((40, 60), 255, np.uint8); m[20:22, 5:55] = 0
    >>> d = draw_plan(m == 0, m, 0.05, 2)
    >>> p = pathlib.Path(tempfile.mkdtemp()) / "w.dxf"
    >>> save_plan_dxf(d, p, 0.05).round(3).tolist()
    [[0.275, 0.95, 2.725, 0.95]]
    >>> len(ezdxf.readfile(p).modelspace().query("LINE"))
    1
    """
    from .dxf import save_segments_dxf

    segs = drawing.segments if isinstance(drawing, PlanDrawing) else np.asarray(drawing, float)
    segs = np.asarray(segs, float).reshape(-1, 4)
    if height is None:
        if not isinstance(drawing, PlanDrawing):
            raise ValueError("height (the map's rows) is needed with bare segments")
        height = drawing.map.shape[0]
    ox, oy, yaw = (tuple(origin) + (0.0,))[:3]
    c, s = math.cos(yaw), math.sin(yaw)

    def to_world(px, py):
        x, y = px * resolution, (height - py) * resolution
        return ox + c * x - s * y, oy + s * x + c * y

    world = np.empty_like(segs)
    for k in (0, 2):
        world[:, k], world[:, k + 1] = to_world(segs[:, k], segs[:, k + 1])
    drawn = isinstance(drawing, PlanDrawing)
    wd = drawing.thickness * resolution if (width and drawn) else None
    save_segments_dxf(world, path, width=wd,
                      arcs=arcs_to_world(drawing.arcs, to_world) if drawn else None,
                      arc_of=drawing.arc_of if drawn else None)
    return world
