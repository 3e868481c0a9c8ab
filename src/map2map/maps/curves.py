"""Curved walls of a map: the input's wall runs that bend along a circle, drawn as arcs.

The plan drawer (:mod:`map2map.maps.vectorize`) draws straight walls at a map's dominant
directions; a rotunda's wall fits none of them, and the drawer left it out or drew a few
short straight pieces across it, so a round room the input shows closed came out open to
the unknown. This step (:func:`curved_walls`):

1. cuts the skeleton of the input's wall pixels (dotted walls closed over a pixel) at
   its corners and junctions (:func:`cv2.cornerHarris`), so a curved wall that runs on
   into a straight one is a run of its own, and drops the straight runs;
2. fits each run a circle (scikit-image's :class:`skimage.measure.CircleModel`; radius
   ``min_radius``-``max_radius``, RMS residual at most ``max_rms``), joins the runs on
   one circle (a dotted arc) and fits them again; an arc is a stretch of them with no
   gap over ``max_gap`` (a door keeps it open), at least ``min_len`` long, bending by at
   least ``min_sagitta``;
3. keeps the arcs around one room that turn by ``min_turn`` together (a third of a
   circle: a rotunda, an apse) unless a long straight wall is drawn along one (a wall
   that SLAM drift bent): a real map's walls wobble, and one wobble is no round room.
   Such a room's further arcs may be made of runs no circle fits alone (short, nearly
   straight, cut at a dent's corners: a stretch SLAM bent out of round) where, chained
   along the room's circle, they fit one as any arc must;
4. draws each arc as a chain of chords within ``sag_tol`` of its circle, keeping the
   face the input saw (the thickness grows away from the free side, as for straight
   walls), and says which straight walls drawn along it go.

The chords are segments like any other wall (the raster is drawn from them); each arc is
also returned as its circle (:class:`CurvedWalls`), so the DXF holds it as one ``ARC``
(:func:`map2map.maps.dxf.save_segments_dxf`), within ``sag_tol`` of the raster's chords.

Examples
--------
A round room of radius 40 px whose wall no straight wall explains:

>>> import numpy as np
>>> m = np.full((120, 120), 127, np.uint8)
>>> yy, xx = np.mgrid[0:120, 0:120] + 0.5
>>> r = np.hypot(xx - 60, yy - 60)
>>> m[r < 40] = 255; m[(r >= 40) & (r < 42)] = 0
>>> cw = curved_walls(m == 0, m == 255, 0.05, 4)
>>> len(cw.chords) > 20, len(cw.arcs)               # one closed chain of chords
(True, 1)
>>> d = np.hypot(cw.chords[:, 0] - 60, cw.chords[:, 1] - 60)
>>> bool(np.all(np.abs(d - 42) < 1.0))              # the face at 40, grown outwards
True
>>> xc, yc, r, a0, span = cw.arcs[0]
>>> round(float(r)), round(float(span), 2)           # its circle: closed
(42, 6.28)
"""

from __future__ import annotations

import math
import warnings
from collections.abc import Callable
from typing import NamedTuple

import cv2
import numpy as np

from ..core.geometry import point_segment_distances, segment_samples

__all__ = ["curved_walls", "arc_chords", "CurvedWalls", "arcs_to_world", "circle_arcs"]


class CurvedWalls(NamedTuple):
    """What :func:`curved_walls` found.

    Attributes
    ----------
    chords : (K, 4) float
        The chords of every arc, in order along each arc (``x0, y0, x1, y1``,
        continuous pixel coordinates, image frame).
    drop : (N,) bool
        The straight segments an arc replaces.
    arcs : (M, 5) float
        Each arc's drawn centre line: ``xc, yc, r, a0, span`` (pixels; angles in
        radians in the image frame, x right and y down, ``span`` >= 0 from ``a0``;
        ``span`` 2 pi: a closed circle).
    arc_of : (K,) int
        The arc each chord belongs to (an index of ``arcs``).
    """

    chords: np.ndarray
    drop: np.ndarray
    arcs: np.ndarray
    arc_of: np.ndarray


def arc_chords(centre: tuple[float, float], radius: float, a0: float, span: float,
               sag_tol: float = 0.25) -> np.ndarray:
    """(K, 4) segments ``x0, y0, x1, y1`` along the arc from angle ``a0`` (radians, image
    frame) over ``span``, each chord within ``sag_tol`` pixels of the circle.

    >>> s = arc_chords((0.0, 0.0), 10.0, 0.0, math.pi / 2, 0.25)
    >>> s[0, :2].round(3).tolist(), s[-1, 2:].round(3).tolist()
    ([10.0, 0.0], [0.0, 10.0])
    """
    step = 2 * math.acos(max(-1.0, 1 - sag_tol / max(radius, 1e-9)))
    n = max(1, math.ceil(abs(span) / max(step, 1e-6)))
    a = a0 + np.linspace(0.0, span, n + 1)
    x = centre[0] + radius * np.cos(a)
    y = centre[1] + radius * np.sin(a)
    return np.stack([x[:-1], y[:-1], x[1:], y[1:]], 1)


def arcs_to_world(arcs: np.ndarray, to_world) -> np.ndarray:
    """Arcs ``xc, yc, r, a0, span`` in pixels (image frame, :class:`CurvedWalls`) as
    ``xc, yc, r, start, sweep`` in world units, the angles in degrees counter-clockwise
    (a DXF ``ARC`` from ``start`` to ``start + sweep``; ``sweep`` 360: a circle).

    ``to_world(x, y)`` maps continuous pixel coordinates to the world (any rotation,
    scale and reflection: a map's rows run down, its world's y up).

    >>> a = np.array([[10.0, 10.0, 4.0, 0.0, math.pi / 2]])   # x right, y down
    >>> arcs_to_world(a, lambda x, y: (x * 0.05, (20 - y) * 0.05)).round(3).tolist()
    [[0.5, 0.5, 0.2, 270.0, 90.0]]
    """
    arcs = np.asarray(arcs, float).reshape(-1, 5)
    out = np.zeros((len(arcs), 5))
    for i, (xc, yc, r, a0, span) in enumerate(arcs):
        a = a0 + np.array([0.0, span / 2, span])
        x, y = to_world(xc + r * np.cos(a), yc + r * np.sin(a))
        cx, cy = to_world(np.array([xc]), np.array([yc]))
        cx, cy = float(cx[0]), float(cy[0])
        ang = np.degrees(np.arctan2(np.asarray(y) - cy, np.asarray(x) - cx))
        rw = float(np.hypot(x[0] - cx, y[0] - cy))
        sweep = math.degrees(span)
        # counter-clockwise from the start (the map's rows down reverse the turn)
        ccw = (x[0] - cx) * (y[1] - cy) - (y[0] - cy) * (x[1] - cx) > 0
        start = ang[0] if ccw or sweep >= 360 - 1e-9 else ang[2]
        out[i] = cx, cy, rw, float(np.mod(start, 360.0)), min(sweep, 360.0)
    return out


def _arcs_of(ang: np.ndarray, max_gap: float) -> list[tuple[float, float]]:
    """(start, span) of the runs of sorted angles ``ang`` with no gap over ``max_gap``
    (radians): the largest gap is the arc's outside; a full circle is one run."""
    a = np.sort(np.mod(ang, 2 * math.pi))
    gaps = np.diff(np.concatenate([a, a[:1] + 2 * math.pi]))
    k = int(np.argmax(gaps))
    if gaps[k] <= max_gap:                       # a closed circle
        return [(float(a[0]), 2 * math.pi)]
    a = np.roll(a, -(k + 1))
    a = np.where(a < a[0], a + 2 * math.pi, a)
    cut = np.flatnonzero(np.diff(a) > max_gap)
    starts = np.concatenate([[0], cut + 1])
    ends = np.concatenate([cut, [len(a) - 1]])
    return [(float(a[s]), float(a[e] - a[s])) for s, e in zip(starts, ends, strict=True)]


def _circle(p: np.ndarray) -> tuple[float, float, float] | None:
    """(xc, yc, r) of the least-squares circle through ``p``, or None (scikit-image's
    :class:`~skimage.measure.CircleModel`: ``from_estimate`` from 0.26 on, ``estimate``
    before)."""
    from skimage.measure import CircleModel

    if hasattr(CircleModel, "from_estimate"):
        fit = CircleModel.from_estimate(p)
        if not fit:
            return None
        (xc, yc), r = fit.center, fit.radius
    else:  # pragma: no cover - scikit-image < 0.26
        fit = CircleModel()
        if not fit.estimate(p):
            return None
        xc, yc, r = fit.params
    return float(xc), float(yc), float(r)


def curved_walls(cover: np.ndarray, free: np.ndarray, resolution: float, thickness: float,
                 segments: np.ndarray | None = None, *, min_len: float = 1.5,
                 min_radius: float = 1.0, max_radius: float = 10.0, max_rms: float = 0.75,
                 min_sagitta: float = 3.0, max_gap: float = 0.4, sag_tol: float = 0.25,
                 min_turn: float = 2 * math.pi / 3) -> CurvedWalls:
    """Segments (continuous pixel coordinates, image frame) of the input's curved walls,
    their circles, and which of the straight ``segments`` drawn so far lie along them.

    Parameters
    ----------
    cover : (H, W) bool
        The input's wall pixels.
    free : (H, W) bool
        The input's free space: the side an arc was seen from.
    resolution : float
        Metres per pixel.
    thickness : float
        Pixels: the drawn walls' thickness (the arc is drawn at it).
    segments : (N, 4) float, optional
        The straight walls drawn so far. Those lying along an arc (60 % of their length
        within half a thickness and 2 pixels of it) are its chords at the wrong angle
        and go. Where straight walls at least half an arc's length lie that close to 60
        % of the arc, the run is a straight wall SLAM drift bent, and no arc is drawn
        (on the dev build's 320 maps, whose plans have no curved wall, five such walls
        bend by 2.8-3.5 px over 23-46 degrees, as much as a rotunda's arcs).
    min_len, min_radius, max_radius, max_gap : float
        Metres: an arc's shortest length, its radius range, and the widest gap between
        its pixels along it (a wider one is a door: the arc is cut there).
    max_rms, min_sagitta, sag_tol : float
        Pixels: the fit's largest RMS residual, an arc's least bend over its length (a
        straight run within the fit's residual bends by about 2), and the chords'
        largest distance from the circle.
    min_turn : float
        Radians: the least angle the arcs around one room (:func:`_round_rooms`) turn
        by together (a third of a circle: a rotunda, an apse). A real map's walls
        wobble: on the 18 Halmstad sensor maps, whose buildings have no curved wall,
        58 runs fit a circle of 1-10 m within 0.75 px over 1.5-3.7 m bending by 3-9 px,
        none with others around one room, each turning by at most 88 degrees; the ACES
        rotunda's three arcs turn by 159.

    Returns
    -------
    CurvedWalls
        The chords (what the raster draws), the ``segments`` they replace, and the arcs
        (what the DXF holds).
    """
    res = float(resolution)
    t = float(thickness)
    cover = np.asarray(cover, bool)
    free = np.asarray(free, bool)
    segs = np.zeros((0, 4)) if segments is None else np.asarray(segments, float).reshape(-1, 4)
    drop = np.zeros(len(segs), bool)
    n_min = min_len / res
    pieces, rest_of = _smooth_pieces(cover, n_min / 2)
    fits, rest = [], []
    for p in pieces:                                # a few dozen runs
        f = _fit(p, min_radius / res, max_radius / res, max_rms)
        if f is not None:
            fits.append((f, p))
        else:
            rest.append(p)
    if not fits:
        return _found([], [], drop)
    r_range = (min_radius / res, max_radius / res)
    cand = []                                      # (centre, radius, a0, span, points)
    for p in _same_circles(fits):
        f = _fit(p, min_radius / res, max_radius / res, max_rms)
        if f is None:
            continue
        xc, yc, r = f
        ang = np.arctan2(p[:, 1] - yc, p[:, 0] - xc)
        cand += [((xc, yc), r, a0, span, p) for a0, span in _arcs_of(ang, max_gap / res / r)
                 if span * r >= n_min
                 and r * (1 - math.cos(min(span, math.pi) / 2)) >= min_sagitta]
    out, circles = [], []
    depth = samples = seg_len = None
    for g in _round_rooms([(c, r) for c, r, *_ in cand]):
        if sum(cand[k][3] for k in g) < min_turn:
            continue                                # a wobble, not a round room
        if depth is None:                           # a round room: rare
            from scipy import ndimage as ndi

            rest += rest_of()
            depth = ndi.distance_transform_edt(~free)      # px to the free space
            samples = segment_samples(segs)
            seg_len = np.hypot(segs[:, 2] - segs[:, 0], segs[:, 3] - segs[:, 1])
        kept = []
        for k in g:
            (xc, yc), r, a0, span, p = cand[k]
            ang = np.arctan2(p[:, 1] - yc, p[:, 0] - xc)
            rc = r + _face_shift(p, (xc, yc), r, ang, free, depth, t)
            ch = arc_chords((xc, yc), rc, a0, span, sag_tol)
            if not _straight_along(ch, segs[seg_len >= span * r / 2], t / 2 + 2):
                kept.append((k, ch, rc))    # else a straight wall drawn along it: drift
        if sum(cand[k][3] for k, *_ in kept) < min_turn:
            continue
        arcs = [cand[k][:4] for k, *_ in kept]
        # the room's other arcs: runs too short or too straight alone to be an arc,
        # which on the room's circle make one together (a stretch SLAM bent out of
        # round, a dent cutting it at a corner)
        for (xc, yc), r, a0, span, p in _completed(arcs, rest, cover, r_range, max_rms,
                                                   n_min, min_sagitta, max_gap / res):
            ang = np.arctan2(p[:, 1] - yc, p[:, 0] - xc)
            rc = r + _face_shift(p, (xc, yc), r, ang, free, depth, t)
            ch = arc_chords((xc, yc), rc, a0, span, sag_tol)
            if not _straight_along(ch, segs[seg_len >= span * r / 2], t / 2 + 2):
                kept.append((None, ch, rc))
                arcs.append(((xc, yc), r, a0, span))
        for (_, ch, rc), ((xc, yc), r, a0, span) in zip(kept, arcs, strict=True):
            out.append(ch)
            circles.append((xc, yc, rc, a0, span))
            drop |= _along(samples, (xc, yc), r, a0, span, t / 2 + 2)
    return _found(out, circles, drop)


def circle_arcs(walls: np.ndarray, resolution: float, segments: np.ndarray | None = None,
                *, min_len: float = 1.0, min_radius: float = 0.5, max_radius: float = 50.0,
                max_rms: float = 0.75, min_sagitta: float = 3.0, max_gap: float = 0.4,
                band: float = 2.5, seed: int = 0) -> tuple[np.ndarray, np.ndarray]:
    """The circular arcs of a drawn plan's walls: ``(arcs, drop)``.

    A plan's walls are exact, so unlike :func:`curved_walls` (a SLAM map's wobbling
    walls, judged around one room) any arc is taken, wherever it is: a curved facade,
    an apse, a rotunda. Its wall may run on tangentially into a straight one (no corner
    to cut at), so the arcs are found in each run of the walls' skeleton by RANSAC
    (:func:`skimage.measure.ransac` with :class:`~skimage.measure.CircleModel`, seeded:
    the same plan gives the same arcs): the circle of radius ``min_radius`` -
    ``max_radius`` metres that most of its pixels lie on within ``max_rms``, refitted to
    them; its stretches with no gap over ``max_gap`` metres, at least ``min_len`` long
    and bending by at least ``min_sagitta`` pixels, are arcs; the rest of the run is
    searched again.

    ``segments`` (N, 4): the straight walls found in the same plan (continuous pixels).
    Those lying along an arc (60 % of their length within ``band`` pixels of it, inside
    its angles: the short chords a line detector cuts a curve into) are in ``drop``; the
    arcs end where a remaining straight wall takes over (their pixels within a pixel of
    one are not the arc's: a straight wall leaving an arc tangentially hugs it).

    Returns
    -------
    arcs : (M, 5) float
        ``xc, yc, r, a0, span``: the walls' centre lines (pixels, image frame; radians,
        ``span`` >= 0 from ``a0``), as :class:`CurvedWalls` gives them.
    drop : (N,) bool

    Examples
    --------
    >>> m = np.zeros((140, 200), bool)
    >>> yy, xx = np.mgrid[0:140, 0:200] + 0.5
    >>> m[(np.abs(np.hypot(xx - 100, yy - 70) - 50) < 1) & (xx >= 100)] = True   # an apse
    >>> m[19:21, 20:100] = True; m[119:121, 20:100] = True                        # its walls
    >>> arcs, _ = circle_arcs(m, 0.05)        # the walls leave it tangentially: ...
    >>> np.round(arcs[:, :3]).tolist(), round(float(np.degrees(arcs[0, 4])))
    ([[100.0, 70.0, 50.0]], 200)
    >>> straight = np.array([[20.0, 20.0, 100.0, 20.0], [20.0, 120.0, 100.0, 120.0]])
    >>> arcs, drop = circle_arcs(m, 0.05, straight)     # ... the straight walls end it
    >>> round(float(np.degrees(arcs[0, 4]))), drop.tolist()
    (176, [False, False])
    """
    from skimage.measure import ransac

    res = float(resolution)
    walls = np.asarray(walls, bool)
    segs = np.zeros((0, 4)) if segments is None else np.asarray(segments, float).reshape(-1, 4)
    n_min = min_len / res
    r_lo, r_hi = min_radius / res, max_radius / res
    rng = np.random.default_rng(seed)

    def ok(model, *data) -> bool:
        return bool(r_lo <= float(model.radius) <= r_hi)

    def stretches(p, f):
        xc, yc, r = f
        ang = np.arctan2(p[:, 1] - yc, p[:, 0] - xc)
        return [(a0, span) for a0, span in _arcs_of(ang, max_gap / res / r)
                if span * r >= n_min and r * (1 - math.cos(min(span, math.pi) / 2))
                >= min_sagitta]

    found = []                                      # (circle, points)
    # the runs that bend (a straight run, within about a pixel of its line, holds no
    # arc bending by min_sagitta > 2 max_rms): the arcs, and the walls they run on into
    for p in _smooth_pieces(walls, 3)[0]:
        while len(p) >= n_min:
            with warnings.catch_warnings():         # "no inliers": a straight run
                warnings.simplefilter("ignore", UserWarning)
                model, inl = ransac(p, _CircleModel, 3, max_rms, is_model_valid=ok,
                                    max_trials=300, rng=rng)
            if model is None or inl is None or inl.sum() < n_min:
                break
            f = _fit(p[inl], r_lo, r_hi, max_rms)
            if f is None or not stretches(p[inl], f):
                break
            found.append((f, p[inl]))
            p = p[~inl]
    drop = np.zeros(len(segs), bool)
    if not found:
        return np.zeros((0, 5)), drop
    samples = segment_samples(segs)
    for (xc, yc, r), p in found:
        for a0, span in stretches(p, (xc, yc, r)):
            drop |= _along(samples, (xc, yc), r, a0, span, band)
    kept = segs[~drop]
    arcs = []
    for (xc, yc, r), p in found:
        if len(kept):                               # where a straight wall takes over
            d, _ = point_segment_distances(p, kept)
            p = p[d.min(axis=1) > 1.0]
        arcs += [(xc, yc, r, a0, span) for a0, span in stretches(p, (xc, yc, r))]
    return np.array(arcs, float).reshape(-1, 5), drop


class _CircleModel:
    """:class:`skimage.measure.CircleModel` for :func:`skimage.measure.ransac`, through
    :func:`_circle` (scikit-image's estimation API changed in 0.26)."""

    def __init__(self):
        self.centre, self.radius = (0.0, 0.0), 0.0

    @classmethod
    def from_estimate(cls, p: np.ndarray) -> _CircleModel | None:
        m = cls()
        return m if m.estimate(p) else None

    def estimate(self, p: np.ndarray) -> bool:
        f = _circle(p)
        if f is None or not all(math.isfinite(v) for v in f):
            return False
        self.centre, self.radius = f[:2], f[2]
        return True

    def residuals(self, p: np.ndarray) -> np.ndarray:
        return np.abs(np.hypot(p[:, 0] - self.centre[0], p[:, 1] - self.centre[1])
                      - self.radius)


def _completed(arcs: list, rest: list[np.ndarray], cover: np.ndarray,
               r_range: tuple[float, float], max_rms: float, n_min: float,
               min_sagitta: float, max_gap: float) -> list:
    """Further arcs of a round room (``arcs``: its ``(centre, r, a0, span)``), each
    ``(centre, r, a0, span, points)``, made of the wall runs ``rest`` (runs no circle
    fitted alone) that lie along the room's circle outside its arcs: runs within a
    quarter of the radius of the room's circle, running along it, chained in angle
    (:func:`_chains`), fitted one circle per chain as any arc is (and of the same room
    by :func:`_round_rooms`'s rule)."""
    w = np.array([span * r for _, r, _, span in arcs])
    c = np.array([[x, y, r] for (x, y), r, _, _ in arcs])
    xc, yc, R = (c * w[:, None]).sum(0) / w.sum()
    taken = []                                      # the room's arcs, about its centre
    for (x, y), r, a0, span in arcs:
        a = a0 + np.linspace(0.0, span, 16)
        taken.append(np.arctan2(y + r * np.sin(a) - yc, x + r * np.cos(a) - xc))
    taken = np.concatenate(taken)
    runs = []
    for p in rest:
        d = np.hypot(p[:, 0] - xc, p[:, 1] - yc)
        a = np.arctan2(p[:, 1] - yc, p[:, 0] - xc)
        along = R * _spread(a)
        if (len(p) < 3 or np.mean(np.abs(d - R) <= R / 4) < 0.9
                or np.ptp(d) > along / 2):          # off the circle, or across it
            continue
        if _within(a, taken, max_gap / R / 2).mean() > 0.1:
            continue                                # on an arc already drawn
        runs.append((float(np.arctan2(np.sin(a).mean(), np.cos(a).mean())), p))
    if not runs:
        return []
    runs.sort(key=lambda q: q[0])
    out = []
    for grp in _chains([q[1] for q in runs], cover, max_gap):
        p = np.concatenate(grp)
        f = _fit(p, *r_range, max_rms)
        if f is None or not (np.hypot(f[0] - xc, f[1] - yc) <= (f[2] + R) / 4
                             and abs(f[2] - R) <= (f[2] + R) / 8):
            continue                                # not this room's circle
        a = np.arctan2(p[:, 1] - f[1], p[:, 0] - f[0])
        for a0, span in _arcs_of(a, 3 * max_gap / f[2]):   # the chain's joins
            if (span * f[2] >= n_min
                    and f[2] * (1 - math.cos(min(span, math.pi) / 2)) >= min_sagitta):
                out.append(((f[0], f[1]), f[2], a0, span, p))
    return out


def _spread(a: np.ndarray) -> float:
    """The angle (radians) a set of directions ``a`` spans, around the circle."""
    s = np.sort(np.mod(a, 2 * math.pi))
    gaps = np.diff(np.concatenate([s, s[:1] + 2 * math.pi]))
    return float(2 * math.pi - gaps.max())


def _within(a: np.ndarray, ref: np.ndarray, tol: float) -> np.ndarray:
    """Which angles ``a`` lie within ``tol`` (radians, around the circle) of one of
    ``ref``."""
    d = np.abs(np.mod(a[:, None] - ref[None, :] + math.pi, 2 * math.pi) - math.pi)
    return d.min(axis=1) <= tol


def _chains(pts: list[np.ndarray], cover: np.ndarray, max_gap: float
            ) -> list[list[np.ndarray]]:
    """Runs (sorted by angle about a room's centre) joined where neighbours' nearest
    points lie at most ``max_gap`` pixels apart, or where the input's wall pixels
    (``cover``, within a pixel) fill the gap between them (the runs of one wall cut at a
    dent's corner)."""
    groups = [[pts[0]]]
    for k in range(1, len(pts)):
        if _joins(groups[-1][-1], pts[k], cover, max_gap):
            groups[-1].append(pts[k])
        else:
            groups.append([pts[k]])
    if len(groups) > 1 and _joins(groups[-1][-1], groups[0][0], cover, max_gap):
        groups[0] = groups.pop() + groups[0]        # around the circle: last to first
    return groups


def _joins(p: np.ndarray, q: np.ndarray, cover: np.ndarray, max_gap: float) -> bool:
    """Whether runs ``p`` and ``q`` continue each other (:func:`_chains`)."""
    d = np.hypot(p[:, None, 0] - q[None, :, 0], p[:, None, 1] - q[None, :, 1])
    i, j = np.unravel_index(int(np.argmin(d)), d.shape)
    if d[i, j] <= max_gap:
        return True
    if d[i, j] > 3 * max_gap:
        return False
    n = int(math.ceil(d[i, j])) + 1
    x = np.linspace(p[i, 0], q[j, 0], n).astype(int)
    y = np.linspace(p[i, 1], q[j, 1], n).astype(int)
    H, W = cover.shape
    near = np.zeros(n, bool)
    for dy in (-1, 0, 1):
        for dx in (-1, 0, 1):
            near |= cover[np.clip(y + dy, 0, H - 1), np.clip(x + dx, 0, W - 1)]
    return bool(near.all())


def _found(chords: list, circles: list, drop: np.ndarray) -> CurvedWalls:
    """The :class:`CurvedWalls` of each arc's chords and circle."""
    if not chords:
        return CurvedWalls(np.zeros((0, 4)), drop, np.zeros((0, 5)), np.zeros(0, int))
    return CurvedWalls(np.concatenate(chords), drop, np.array(circles, float).reshape(-1, 5),
                       np.repeat(np.arange(len(chords)), [len(c) for c in chords]))


def _smooth_pieces(cover: np.ndarray, min_px: float
                   ) -> tuple[list[np.ndarray], Callable[[], list[np.ndarray]]]:
    """Pixel centres (x, y) of the input's wall runs cut at corners and junctions: the
    skeleton of the wall pixels (dotted walls closed over a pixel) less every pixel
    within 2 of a Harris corner (:func:`cv2.cornerHarris`, 5 x 5, over 0.008: a drawn
    corner or T-junction answers about 0.06, the rounded corners of a real map's walls
    0.011-0.029, an arc of radius 25 px 0.0066 and of 80 px 0.001). The runs of at
    least ``min_px`` pixels that bend, and a function giving the rest (straight, or
    short) of at least 3 (wanted only around a round room: rare)."""
    from skimage.morphology import skeletonize

    if cover.sum() < min_px:
        return [], list
    joined = cv2.morphologyEx(cover.view(np.uint8), cv2.MORPH_CLOSE, np.ones((3, 3), np.uint8))
    sk = skeletonize(joined > 0)
    corner = cv2.cornerHarris(sk.astype(np.float32), 5, 3, 0.04) > 0.008
    sk &= cv2.dilate(corner.view(np.uint8), np.ones((5, 5), np.uint8)) == 0
    n, lab, st, _ = cv2.connectedComponentsWithStats(sk.view(np.uint8), connectivity=8)
    ys, xs = np.nonzero(lab)
    k = lab[ys, xs]
    # a straight run (every point within about a pixel of its principal line) is no
    # arc: the smaller eigenvalue of each run's covariance, all runs at once
    m = np.maximum(np.bincount(k, minlength=n), 1)
    mx, my = np.bincount(k, xs, n) / m, np.bincount(k, ys, n) / m
    cxx = np.bincount(k, xs * xs.astype(float), n) / m - mx * mx
    cyy = np.bincount(k, ys * ys.astype(float), n) / m - my * my
    cxy = np.bincount(k, xs * ys.astype(float), n) / m - mx * my
    small = (cxx + cyy) / 2 - np.sqrt(((cxx - cyy) / 2) ** 2 + cxy ** 2)
    area = st[:, cv2.CC_STAT_AREA]
    keep = (area >= min_px) & (small > 0.25)
    keep[0] = False
    rest = (area >= 3) & ~keep
    rest[0] = False
    return _split(xs, ys, k, keep), lambda: _split(xs, ys, k, rest)


def _split(xs: np.ndarray, ys: np.ndarray, k: np.ndarray, keep: np.ndarray
           ) -> list[np.ndarray]:
    """Pixel centres of the labels ``k`` that ``keep`` (by label) holds, one array per
    label."""
    sel = keep[k]
    xs, ys, k = xs[sel], ys[sel], k[sel]
    order = np.argsort(k, kind="stable")
    pts = np.column_stack([xs[order] + 0.5, ys[order] + 0.5])
    return np.split(pts, np.flatnonzero(np.diff(k[order])) + 1) if len(pts) else []


def _fit(p: np.ndarray, r_min: float, r_max: float, max_rms: float
         ) -> tuple[float, float, float] | None:
    """(xc, yc, r) of ``p``'s circle when its radius is in range and it fits."""
    f = _circle(p)
    if f is None or not (r_min <= f[2] <= r_max):
        return None
    xc, yc, r = f
    if float(np.sqrt(np.mean((np.hypot(p[:, 0] - xc, p[:, 1] - yc) - r) ** 2))) > max_rms:
        return None
    return f


def _round_rooms(circles: list) -> list[list[int]]:
    """Indices of the arcs around one room: circles whose centres lie within half their
    radius of each other and whose radii differ by at most a quarter (a rotunda SLAM
    made a little oval fits each arc with its own circle: ACES's three arcs, radii 60,
    73 and 74 px, centres 22 px apart)."""
    from scipy.sparse.csgraph import connected_components

    if not circles:
        return []
    c = np.array([[x, y, r] for (x, y), r in circles], float).reshape(-1, 3)
    rm = (c[:, None, 2] + c[None, :, 2]) / 2
    near = ((np.hypot(c[:, None, 0] - c[None, :, 0], c[:, None, 1] - c[None, :, 1]) <= rm / 2)
            & (np.abs(c[:, None, 2] - c[None, :, 2]) <= rm / 4))
    _, lab = connected_components(near, directed=False)
    return [np.flatnonzero(lab == g).tolist() for g in range(int(lab.max()) + 1)]


def _same_circles(fits: list) -> list[np.ndarray]:
    """The pieces' points grouped by circle: centres within 5 % of the radius and 2 px,
    radii within 2 px (the pieces of a dotted arc; the arcs around one room, each on
    its own circle, are grouped by :func:`_round_rooms`)."""
    groups: list[list] = []
    for f, p in fits:
        for g in groups:
            (xc, yc, r), _ = g[0]
            if (math.hypot(f[0] - xc, f[1] - yc) <= 2 + 0.05 * r
                    and abs(f[2] - r) <= 2):
                g.append((f, p))
                break
        else:
            groups.append([(f, p)])
    return [np.concatenate([p for _, p in g]) for g in groups]


def _face_shift(p, centre, r, ang, free, depth, t) -> float:
    """How far the drawn centre line lies from the fitted input line (px, outwards
    positive): the face the input saw kept, the thickness grown away from the free side;
    seen from both sides (or neither), on the input's line."""
    xc, yc = centre
    side = []
    for dr in (-2.0, 2.0):
        qx = np.clip((xc + (r + dr) * np.cos(ang)).astype(int), 0, free.shape[1] - 1)
        qy = np.clip((yc + (r + dr) * np.sin(ang)).astype(int), 0, free.shape[0] - 1)
        side.append(float(free[qy, qx].mean()))
    inside, outside = side
    qx = np.clip(p[:, 0].astype(int), 0, free.shape[1] - 1)
    qy = np.clip(p[:, 1].astype(int), 0, free.shape[0] - 1)
    d = float(np.median(depth[qy, qx]))                 # the input's line to its face
    if inside > 2 * outside:
        return t / 2 - (d - 0.5)
    if outside > 2 * inside:
        return -(t / 2 - (d - 0.5))
    return 0.0


def _straight_along(chords: np.ndarray, long_segs: np.ndarray, band: float,
                    share: float = 0.6) -> bool:
    """Whether ``share`` of an arc's chord ends lie within ``band`` of the long straight
    walls ``long_segs``."""
    if not len(long_segs):
        return False
    p = np.concatenate([chords[:, :2], chords[-1:, 2:]])
    d, _ = point_segment_distances(p, long_segs)
    return bool((d.min(axis=1) <= band).mean() >= share)


def _along(samples: tuple, centre, r: float, a0: float, span: float, band: float,
           share: float = 0.6) -> np.ndarray:
    """Which segments lie along the arc: ``share`` of their samples
    (:func:`map2map.core.geometry.segment_samples`) within ``band`` of the circle, inside
    the arc's angles."""
    idx, _, q, n = samples
    xc, yc = centre
    d = np.abs(np.hypot(q[:, 0] - xc, q[:, 1] - yc) - r)
    a = np.mod(np.arctan2(q[:, 1] - yc, q[:, 0] - xc) - a0, 2 * math.pi)
    on = (d <= band) & (a <= span + band / r)
    return np.bincount(idx, on, len(n)) / np.maximum(n, 1) >= share
