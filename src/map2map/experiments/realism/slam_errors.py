"""Statistics of what the thesis calls SLAM errors, per map (issue #33): a wall saved
twice, a room rotated against the plan, free space that ends in the open, and laser
streaks. Each is a number per square map (``N x N`` px; the pixel settings below are
for the datasets' 256 px squares) that :mod:`map2map.experiments.realism.measure` adds to
its statistics, so that its Wasserstein ratios compare generated and simulated maps on
them too (``bend``, the bend of straight walls, is there already).

Maps and plans are ternary ``uint8`` (occupied 0, unknown 127, free 255); outside the
square counts as unknown. "Occupied" below is ``== 0``, "free" ``== 255``.

* ``doubled``: share of the plan's observed straight wall centre-line pixels at which the
  map shows the wall twice. The centre line is the skeleton of the plan's walls; a
  centre-line pixel is *straight* when the skeleton pixels within :data:`LINE_RADIUS` px
  (at least :data:`LINE_MIN_PX` of them) lie on a line: the square root of their scatter
  matrix's smaller eigenvalue is below :data:`STRAIGHT_PX` (the rule of ``bend``); the
  wall's direction is the larger eigenvector. Along the wall's normal, within
  +-:data:`PROFILE_PX` px, map and plan are sampled every 0.5 px (nearest pixel). The
  window is cut where it would reach another plan wall, halfway across the gap (so two
  plan walls close together, a corridor, are not a doubled wall). The pixel is
  *observed* when the map has an occupied sample in the window, and *doubled* when,
  after gaps shorter than :data:`GAP_PX` px are closed, the map's occupied samples form
  two or more separate runs (a gap of >= 2 px free or unknown between them).
  ``doubled`` = doubled / observed (NaN if no straight wall pixel is observed). A wall
  saved twice, two copies 3-6 px apart, scores 1 along its length; a single wall, however
  thick, scores 0. On simulated maps the doubled pixels lie where two rooms mapped at
  different times (and turned differently) each left their own copy of the wall between
  them.
* ``room_rot``: rotation of the map against the plan per room, in degrees. The plan's
  rooms are :func:`map2map.learn.ab.room_drift.segment_rooms` (the watershed that the
  room-wise drift and ``realism.room_offsets`` use); every pixel within
  :data:`ROOM_REACH_PX` px of the plan's free space belongs to the room whose free pixel
  is nearest (a wall between two rooms is split along its middle, each room keeps the
  face it sees). Orientation: at every occupied pixel, the direction ``theta`` of the
  line fitted to the occupied pixels around it (larger eigenvector of their scatter,
  weighted by a Gaussian of sigma :data:`ORIENT_SIGMA` px) and its coherence ``c = (l1 -
  l2) / (l1 + l2)`` (1 on a straight wall, 0 at a corner or a lone speck); the room's
  dominant wall orientation is the angle of ``sum c^2 exp(4 i theta)`` over its pixels,
  divided by 4 (the doubled-angle average with a 90 degree period, so that walls at right
  angles agree). For the plan, its wall pixels within :data:`SEEN_PX` px of a map
  occupied cell (the walls the map saw). The room's angle is map minus plan, wrapped to
  [-45, 45) degrees; a room counts when it holds at least :data:`ROOM_MIN_CELLS`
  occupied map cells. ``room_rot`` = the mean ``|angle|`` over those rooms weighted by
  their occupied cells (NaN if no room counts). A map equal to its plan scores 0
  exactly. Measured on a square room of 2 px walls drawn turned (skimage polygons): 4.9
  deg for a 5 deg turn, 10.0 for 10 (120 px room); below about 3 deg the rasterised walls
  themselves are not turned by the angle they were drawn at (a 52 px room drawn at 0.5
  and 1 deg gives the same pixels), so small angles read coarsely. Gradient directions
  (Gaussian derivatives, sigma 1 px) were tried first and read 5 deg as 4.1.
  On the first 25 simulated maps of a dataset build (rooms of >= 40 cells), the angles
  agree with ``realism.room_offsets``' brute-force rigid fit of each room (correlation
  0.88 with the fit's angle, which turns the map back, so of opposite sign; mean
  ``|angle|`` 3.2 deg against the fit's 3.0): the simulated maps' rooms really are turned.
* ``frontier_open``: of the map's free border pixels (free pixels with a 4-neighbour
  that is not free), the share that lie farther than :data:`OPEN_PX` px (Euclidean) from
  every occupied cell: free space ending in unknown, not at a wall (NaN with no free
  border).
* ``frontier_rough``: the open frontier's length (its pixel count) over the length of
  the same frontier after a binary closing of the free mask with a disc of radius
  :data:`ROUGH_RADIUS` px (open border pixels of the closed mask by the same rule, same
  occupied cells). 1 for a straight or gently curved edge; larger for a ragged or cloudy
  one: the closing fills notches, bays and holes of unknown narrower than about 5 px.
  NaN with no open frontier, or none left after the closing (a frontier of small holes
  only). Measured: 1.00 for a straight cut, 1.25 / 1.83 / 2.09 for an edge whose every
  row ends at a random column within +-1 / 2 / 3 px (one random draw each).
* ``streaks``: laser streaks: free pixels that a binary opening of the free mask with a
  disc of radius :data:`STREAK_RADIUS` px removes (thin free protrusions, at most 4 px
  wide), grouped into 8-connected components; a component counts when it has at least
  :data:`STREAK_MIN_PX` pixels, touches unknown (8-neighbourhood) and is elongated: the
  ratio of its major to minor axis, ``sqrt((l1 + 1/12) / (l2 + 1/12))`` with ``l1 >= l2``
  the eigenvalues of its pixels' scatter (the ``1/12`` is a pixel's own extent, so that a
  1 px wide line of length L scores about L), is at least :data:`STREAK_ELONGATION`.
  ``streaks`` = counted components per 10,000 free pixels (NaN with no free pixel).

What lidar SLAM frontiers look like, and why ``frontier_rough`` closes rather than
smooths: a lidar sees along straight rays, so where free space ends in the open it ends
at ray ends: on the range circle, in fans of rays of different lengths, and in single
rays that slipped through a gap in a wall. On the first 80 simulated maps of a
``map2map dataset build`` (``rbpf``, 256 px) the rooms are closed and the open frontier
is almost all such rays outside the walls (``frontier_open`` median 0.10). A network's
maps rather end free space in soft, cloudy blobs: rounded lobes, notches and specks of
unknown. A Gaussian smoothing (sigma 2 px, thresholded at 0.5, the first version) deletes
every ray, so on those simulated maps the smoothed frontier was often a few pixels and
the ratio ran to 40 at the 90th percentile (209 at most); the closing keeps rays (and
any protrusion) and removes notches and holes, so the same maps read 0.92 / 1.03 / 1.30
(10th / 50th / 90th percentile, at most 2.1). The two statistics then split the
difference: ``frontier_rough`` counts notches, bays between the rays of a fan and
holes (clouds), ``streaks`` the thin straight protrusions (rays).

Cost (2-core machine under load, 256 px simulated squares, CPU time): all five together
about 0.08 s a map (:func:`slam_error_stats`), 0.05 s of it the room segmentation of
the plan (pass ``rooms=`` to reuse it).

Examples
--------
>>> import numpy as np
>>> plan = np.full((64, 64), 127, np.uint8)
>>> plan[8:56, 8:56] = 0; plan[10:54, 10:54] = 255          # one room, 2 px walls
>>> s = slam_error_stats(plan, plan)
>>> s["doubled"], s["room_rot"], s["frontier_open"], s["streaks"]
(0.0, 0.0, 0.0, 0.0)
>>> bool(np.isnan(s["frontier_rough"]))                       # no open frontier
True
"""

from __future__ import annotations

import numpy as np
from scipy import ndimage

from ...core.grid import FREE, OCCUPIED

__all__ = ["SLAM_ERROR_STATS", "SLAM_ERROR_INFO", "slam_error_stats", "doubled_walls",
           "straight_centre_line", "room_rotations", "room_rotation", "frontier",
           "streak_components", "streaks"]

#: The names :func:`slam_error_stats` returns, in order.
SLAM_ERROR_STATS = ("doubled", "room_rot", "frontier_open", "frontier_rough", "streaks")
#: What each statistic is (units).
SLAM_ERROR_INFO = {
    "doubled": "share of observed straight plan walls the map shows twice (>= 2 runs "
               "across the wall)",
    "room_rot": "per-room rotation against the plan (deg), mean |angle| weighted by walls",
    "frontier_open": "share of the free border ending in unknown, > 2 px from walls",
    "frontier_rough": "open frontier length over its smoothed length (1: smooth)",
    "streaks": "thin elongated free protrusions into unknown per 10,000 free px",
}

#: Radius (px) of the disc over which the plan's wall centre line is fitted by a line.
LINE_RADIUS = 5
#: Fewest centre-line pixels in that disc for a straight wall pixel.
LINE_MIN_PX = 6
#: Largest RMS distance (px) of those pixels to their line for a straight wall pixel.
STRAIGHT_PX = 0.25
#: Half-length (px) of the profile across a wall.
PROFILE_PX = 8.0
#: Profile sampling step (px).
PROFILE_STEP = 0.5
#: Gaps shorter than this (px) across a wall do not separate two runs.
GAP_PX = 2.0
#: Pixels this close (px) to a room's free space are the room's.
ROOM_REACH_PX = 6.0
#: Sigma (px) of the Gaussian window of the local line fits that give wall orientations.
ORIENT_SIGMA = 3.0
#: Plan pixels this close (px) to a map occupied cell count for a room's plan orientation.
SEEN_PX = 4.0
#: Fewest occupied map cells in a room for its angle to count.
ROOM_MIN_CELLS = 40
#: A free border pixel farther than this (px) from every occupied cell is open.
OPEN_PX = 2.0
#: Radius (px) of the disc of the closing that ``frontier_rough`` compares with.
ROUGH_RADIUS = 2
#: Radius (px) of the disc of the opening that leaves streaks behind.
STREAK_RADIUS = 2
#: Fewest pixels of a streak.
STREAK_MIN_PX = 6
#: Smallest major / minor axis ratio of a streak.
STREAK_ELONGATION = 3.0

_CROSS = ndimage.generate_binary_structure(2, 1)
_SQUARE = np.ones((3, 3), bool)


def _disc(radius: int) -> np.ndarray:
    yy, xx = np.mgrid[-radius:radius + 1, -radius:radius + 1]
    return xx**2 + yy**2 <= radius**2


def _check(m, plan=None):
    m = np.asarray(m)
    if m.ndim != 2:
        raise ValueError(f"a map is 2-D, got shape {m.shape}")
    if plan is None:
        return m
    plan = np.asarray(plan)
    if m.shape != plan.shape:
        raise ValueError(f"map {m.shape} and plan {plan.shape} differ in shape")
    return m, plan


def straight_centre_line(walls: np.ndarray):
    """The straight pixels of a wall mask's centre line and the walls' direction there.

    Parameters
    ----------
    walls : (H, W) bool
        Wall pixels (a plan's occupied cells).

    Returns
    -------
    rows, cols : (K,) int
        Centre-line (skeleton) pixels where the wall is straight (module doc,
        ``doubled``).
    theta : (K,) float
        The wall's direction there (radians, of the ``(x, y) = (col, row)`` vector).

    Examples
    --------
    >>> w = np.zeros((30, 30), bool); w[14:16, 3:27] = True          # a 2 px wall
    >>> r, c, th = straight_centre_line(w)
    >>> len(r) > 10, bool(np.allclose(np.sin(th), 0.0))
    (True, True)
    """
    from skimage.morphology import skeletonize

    walls = np.asarray(walls, bool)
    if not walls.any():
        e = np.zeros(0, int)
        return e, e, np.zeros(0)
    skel = skeletonize(walls)
    rows, cols = np.nonzero(skel)
    # the skeleton pixels in the disc around each skeleton pixel: gathered, not convolved
    dy, dx = (d[_disc(LINE_RADIUS)].astype(float) for d in np.mgrid[
        -LINE_RADIUS:LINE_RADIUS + 1, -LINE_RADIUS:LINE_RADIUS + 1])
    pad = np.pad(skel, LINE_RADIUS)
    w = pad[rows[:, None] + LINE_RADIUS + dy.astype(int)[None],
            cols[:, None] + LINE_RADIUS + dx.astype(int)[None]].astype(float)
    n = w.sum(1)
    dev, theta = line_scatter(n, w @ dx, w @ dy, w @ (dx * dx), w @ (dy * dy), w @ (dx * dy))
    keep = (n >= LINE_MIN_PX) & (dev < STRAIGHT_PX)
    return rows[keep], cols[keep], theta[keep]


def line_scatter(n, sx, sy, sxx, syy, sxy):
    """The best-fitting line of weighted points, from their sums: the RMS distance of the
    points to it (sqrt of the smaller eigenvalue of their scatter) and its direction.

    Parameters
    ----------
    n, sx, sy, sxx, syy, sxy : array_like
        Sums of the weights and of ``w x``, ``w y``, ``w x^2``, ``w y^2``, ``w x y`` (any
        shape, all alike; a zero ``n`` is taken as 1).

    Returns
    -------
    dev, theta : ndarray
        RMS distance to the line, and the line's direction (radians, of ``(x, y)``).

    Examples
    --------
    >>> x = np.arange(5.0); y = 2.0 + 0 * x                       # points on y = 2
    >>> dev, th = line_scatter(5.0, x.sum(), y.sum(), (x * x).sum(), (y * y).sum(),
    ...                        (x * y).sum())
    >>> round(float(dev), 6), round(float(th), 6)
    (0.0, 0.0)
    """
    safe = np.maximum(n, 1.0)
    mx, my = sx / safe, sy / safe
    cxx = sxx / safe - mx**2
    cyy = syy / safe - my**2
    cxy = sxy / safe - mx * my
    lam = 0.5 * (cxx + cyy) - np.sqrt(np.maximum(0.25 * (cxx - cyy) ** 2 + cxy**2, 0.0))
    return np.sqrt(np.maximum(lam, 0.0)), 0.5 * np.arctan2(2 * cxy, cxx - cyy)


def _runs(a: np.ndarray) -> np.ndarray:
    """Runs of True per row of a 2-D bool array."""
    p = np.pad(a, ((0, 0), (1, 0)))
    return np.count_nonzero(p[:, 1:] & ~p[:, :-1], axis=1)


def _within_gap(side: np.ndarray) -> np.ndarray:
    """Per half-profile (centre first, outwards): the samples before the middle of the
    gap between the centre's wall run and the next plan wall (all when there is none)."""
    run = np.logical_and.accumulate(side, axis=1)
    other = side & ~run
    first = np.where(other.any(1), other.argmax(1), 2 * side.shape[1])
    return np.arange(side.shape[1])[None] < 0.5 * (run.sum(1) + first)[:, None]


def doubled_walls(m: np.ndarray, plan: np.ndarray, *, profiles: bool = False):
    """``doubled`` of the module doc: the share of observed straight plan wall pixels at
    which map ``m`` shows two or more separate wall runs across the wall.

    Parameters
    ----------
    m, plan : (N, N) uint8
        Ternary map and its plan.
    profiles : bool
        Also return the per-pixel detail.

    Returns
    -------
    float or (float, dict)
        The share (NaN if no straight wall pixel is observed); with ``profiles``, also
        ``{"rows", "cols", "observed", "runs"}`` per straight centre-line pixel.

    Examples
    --------
    >>> plan = np.full((40, 40), 255, np.uint8); plan[19:21, 2:38] = 0
    >>> doubled_walls(plan, plan)
    0.0
    >>> m = plan.copy(); m[24:26, 2:38] = 0                 # saved again 5 px below
    >>> doubled_walls(m, plan)
    1.0
    """
    m, plan = _check(m, plan)
    rows, cols, theta = straight_centre_line(plan == OCCUPIED)
    t = np.arange(-PROFILE_PX, PROFILE_PX + 1e-9, PROFILE_STEP)
    c = len(t) // 2
    ny, nx = np.cos(theta), -np.sin(theta)            # the normal of (cos, sin) in (x, y)
    R = rows[:, None] + t[None] * ny[:, None]
    C = cols[:, None] + t[None] * nx[:, None]
    coords = [R.ravel(), C.ravel()]
    occ = (m == OCCUPIED).astype(np.uint8)
    wall = (plan == OCCUPIED).astype(np.uint8)
    M = ndimage.map_coordinates(occ, coords, order=0, mode="constant").reshape(R.shape) > 0
    P = ndimage.map_coordinates(wall, coords, order=0, mode="constant").reshape(R.shape) > 0
    # cut each side of the window halfway across the gap to the next plan wall
    valid = np.zeros_like(M)
    valid[:, c:] = _within_gap(P[:, c:])
    valid[:, c::-1] |= _within_gap(P[:, c::-1])
    M &= valid
    observed = M.any(1)
    k = int(round(GAP_PX / PROFILE_STEP))             # gaps of < k samples are closed
    pad = np.pad(M, ((0, 0), (k, k)))
    closed = ndimage.binary_closing(pad, np.ones((1, k), bool))[:, k:-k] if k > 1 else M
    runs = _runs(closed)
    share = float(np.mean(runs[observed] >= 2)) if observed.any() else float("nan")
    if profiles:
        return share, {"rows": rows, "cols": cols, "observed": observed, "runs": runs}
    return share


def _quad(mask: np.ndarray) -> np.ndarray:
    """At every pixel of ``mask``: ``c^2 exp(4 i theta)``, ``theta`` the direction of the
    local line fit to the mask's pixels (the larger eigenvector of their scatter, weighted
    by a Gaussian of sigma :data:`ORIENT_SIGMA` px) and ``c = (l1 - l2) / (l1 + l2)`` its
    coherence (0 at a corner or a speck, 1 on a straight wall); 0 off the mask."""
    # moments about each pixel by separable correlations (float32, small numbers):
    # 3 passes along the rows (weights g, y g, y^2 g), 6 along the columns
    m = mask.astype(np.float32)
    r = int(np.ceil(3 * ORIENT_SIGMA))
    x = np.arange(-r, r + 1, dtype=np.float32)
    g = np.exp(-x**2 / np.float32(2 * ORIENT_SIGMA**2))

    def c1(a, w, axis):
        return ndimage.correlate1d(a, w, axis=axis, mode="constant")

    r0, r1, r2 = c1(m, g, 0), c1(m, x * g, 0), c1(m, x * x * g, 0)
    n = np.maximum(c1(r0, g, 1), 1e-6)
    mx, my = c1(r0, x * g, 1) / n, c1(r1, g, 1) / n
    cxx = c1(r0, x * x * g, 1) / n - mx**2
    cyy = c1(r2, g, 1) / n - my**2
    cxy = c1(r1, x * g, 1) / n - mx * my
    z = (cxx - cyy) + 2j * cxy                        # (l1 - l2) exp(2 i theta)
    mag = np.abs(z)
    coh = mag / np.maximum(cxx + cyy, 1e-12)
    q = (z / np.maximum(mag, 1e-12)) ** 2 * coh**2
    return np.where(mask & (mag > 1e-6), q, 0.0)


def room_rotations(m: np.ndarray, plan: np.ndarray, rooms: np.ndarray | None = None):
    """Per room of ``plan``: map ``m``'s rotation against the plan (module doc,
    ``room_rot``).

    Parameters
    ----------
    m, plan : (N, N) uint8
        Ternary map and its plan.
    rooms : (N, N) int, optional
        The plan's rooms (labels ``1..n`` on its free space, 0 elsewhere); default
        :func:`map2map.learn.ab.room_drift.segment_rooms` ``(plan, fill=False)``.

    Returns
    -------
    labels : (K,) int
        The rooms with at least :data:`ROOM_MIN_CELLS` occupied map cells.
    angles : (K,) float
        Their rotation (degrees, map minus plan, in [-45, 45); positive turns ``+x``
        towards ``+y``, i.e. clockwise on the image).
    cells : (K,) int
        Their occupied map cells (the weights of :func:`room_rotation`).

    Examples
    --------
    >>> from skimage.draw import polygon
    >>> def room(deg):                               # a 2 px square outline, turned
    ...     a = np.radians(deg); out = np.full((150, 150), 127, np.uint8)
    ...     for h, v in ((60, 0), (58, 255)):
    ...         x, y = np.array([-h, h, h, -h]), np.array([-h, -h, h, h])
    ...         rr, cc = polygon(75 + np.sin(a) * x + np.cos(a) * y,
    ...                          75 + np.cos(a) * x - np.sin(a) * y, (150, 150))
    ...         out[rr, cc] = v
    ...     return out
    >>> labels, angles, cells = room_rotations(room(10), room(0))
    >>> labels.tolist(), round(float(angles[0]))
    ([1], 10)
    """
    m, plan = _check(m, plan)
    free = plan == FREE
    occ = m == OCCUPIED
    if rooms is None:
        from ...learn.ab.room_drift import segment_rooms

        rooms = segment_rooms(plan, fill=False)
    rooms = np.where(free, np.asarray(rooms), 0)
    if not occ.any() or rooms.max() == 0:
        return np.zeros(0, int), np.zeros(0), np.zeros(0, int)
    # every pixel near the plan's free space: the room of its nearest free pixel
    dist, idx = ndimage.distance_transform_edt(rooms == 0, return_indices=True)
    part = np.where(dist <= ROOM_REACH_PX, rooms[idx[0], idx[1]], 0).ravel()
    n = int(rooms.max()) + 1
    cells = np.bincount(part, weights=occ.ravel(), minlength=n).astype(int)
    seen = ndimage.distance_transform_edt(~occ) <= SEEN_PX
    zm = _quad(occ).ravel()
    zp = _quad(plan == OCCUPIED).ravel() * seen.ravel()

    def csum(z):
        return np.bincount(part, z.real, n) + 1j * np.bincount(part, z.imag, n)

    sm, sp = csum(zm), csum(zp)
    labels = np.flatnonzero(cells >= ROOM_MIN_CELLS)
    labels = labels[(labels > 0) & (np.abs(sm[labels]) > 0) & (np.abs(sp[labels]) > 0)]
    diff = np.degrees(np.angle(sm[labels]) - np.angle(sp[labels])) / 4.0
    diff = (diff + 45.0) % 90.0 - 45.0                               # in [-45, 45)
    return labels, diff, cells[labels]


def room_rotation(m: np.ndarray, plan: np.ndarray, rooms: np.ndarray | None = None
                  ) -> float:
    """``room_rot`` of the module doc: the mean ``|angle|`` of :func:`room_rotations`,
    weighted by the rooms' occupied map cells (NaN if no room counts).

    Parameters
    ----------
    m, plan, rooms
        As for :func:`room_rotations`.

    Returns
    -------
    float
        Degrees, in [0, 45).

    Examples
    --------
    >>> plan = np.full((60, 60), 127, np.uint8)
    >>> plan[5:55, 5:55] = 0; plan[7:53, 7:53] = 255
    >>> room_rotation(plan, plan)
    0.0
    """
    _, angles, cells = room_rotations(m, plan, rooms)
    if not len(angles):
        return float("nan")
    return float(np.average(np.abs(angles), weights=cells))


def _open_border(free: np.ndarray, far: np.ndarray) -> np.ndarray:
    """Free pixels with a non-free 4-neighbour (outside: unknown), far from walls."""
    border = free & ~ndimage.binary_erosion(free, _CROSS, border_value=0)
    return border, border & far


def frontier(m: np.ndarray) -> tuple[float, float]:
    """``(frontier_open, frontier_rough)`` of the module doc for map ``m``.

    Parameters
    ----------
    m : (N, N) uint8
        Ternary map (outside the square counts as unknown).

    Returns
    -------
    (float, float)
        The open share of the free border (NaN with no free border) and the open
        frontier's roughness (NaN with no open frontier, or none after the closing).

    Examples
    --------
    >>> m = np.full((40, 40), 127, np.uint8)
    >>> m[5:35, 5:35] = 0; m[7:33, 7:33] = 255              # a closed room
    >>> op, rough = frontier(m)
    >>> op, bool(np.isnan(rough))
    (0.0, True)
    >>> m[7:33, 25:35] = 127                                # cut by unknown at column 25
    >>> op, rough = frontier(m)
    >>> round(op * 84), round(rough, 2)     # of 84 border px: column 24, rows 9..30
    (22, 1.0)
    """
    m = _check(m)
    free = m == FREE
    occ = m == OCCUPIED
    if occ.any():
        far = ndimage.distance_transform_edt(~occ) > OPEN_PX
    else:
        far = np.ones(m.shape, bool)
    border, open_ = _open_border(free, far)
    nb = int(np.count_nonzero(border))
    if nb == 0:
        return float("nan"), float("nan")
    length = int(np.count_nonzero(open_))
    if length == 0:
        return 0.0, float("nan")
    p = 2 * ROUGH_RADIUS                              # outside the square is not free
    closed = ndimage.binary_closing(np.pad(free, p), _disc(ROUGH_RADIUS))[p:-p, p:-p]
    closed_len = int(np.count_nonzero(_open_border(closed, far)[1]))
    return length / nb, length / closed_len if closed_len else float("nan")


def streak_components(m: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The laser streaks of map ``m`` (module doc, ``streaks``).

    Parameters
    ----------
    m : (N, N) uint8
        Ternary map.

    Returns
    -------
    labels : (N, N) int32
        The free pixels the opening removes, 8-connected components labelled ``1..k``.
    streak : (k,) bool
        Which components are streaks.

    Examples
    --------
    >>> m = np.full((40, 40), 127, np.uint8); m[5:35, 5:20] = 255
    >>> m[10, 20:32] = m[25, 20:30] = 255                   # two 1 px rays
    >>> lab, streak = streak_components(m)
    >>> int(streak.sum())
    2
    """
    m = _check(m)
    free = m == FREE
    removed = free & ~ndimage.binary_opening(free, _disc(STREAK_RADIUS), border_value=0)
    lab, k = ndimage.label(removed, structure=_SQUARE)
    if k == 0:
        return lab, np.zeros(0, bool)
    unknown = ~free & (m != OCCUPIED)
    near_unknown = ndimage.binary_dilation(np.pad(unknown, 1, constant_values=True),
                                           _SQUARE)[1:-1, 1:-1]
    idx = np.arange(1, k + 1)
    flat = lab.ravel()
    count = np.bincount(flat, minlength=k + 1)[1:].astype(float)
    Y, X = np.indices(m.shape, dtype=float)

    def mean(a):
        return np.bincount(flat, a.ravel(), k + 1)[1:] / count

    mx, my = mean(X), mean(Y)
    cxx, cyy, cxy = mean(X * X) - mx**2, mean(Y * Y) - my**2, mean(X * Y) - mx * my
    root = np.sqrt(np.maximum(0.25 * (cxx - cyy) ** 2 + cxy**2, 0.0))
    l1 = np.maximum(0.5 * (cxx + cyy) + root, 0.0)
    l2 = np.maximum(0.5 * (cxx + cyy) - root, 0.0)
    elong = np.sqrt((l1 + 1 / 12) / (l2 + 1 / 12))
    touches = np.asarray(ndimage.maximum(near_unknown, lab, idx), bool)
    streak = (count >= STREAK_MIN_PX) & touches & (elong >= STREAK_ELONGATION)
    return lab, streak


def streaks(m: np.ndarray) -> float:
    """``streaks`` of the module doc: laser streaks per 10,000 free pixels of map ``m``.

    Parameters
    ----------
    m : (N, N) uint8
        Ternary map.

    Returns
    -------
    float
        NaN for a map without free pixels.

    Examples
    --------
    >>> m = np.full((40, 40), 127, np.uint8); m[:, :20] = 255
    >>> streaks(m)
    0.0
    >>> m[10, 20:32] = 255                                  # one ray into the unknown
    >>> round(streaks(m) * int((m == 255).sum()) / 1e4, 6)
    1.0
    """
    m = _check(m)
    nfree = int(np.count_nonzero(m == FREE))
    if nfree == 0:
        return float("nan")
    return float(np.count_nonzero(streak_components(m)[1])) * 1e4 / nfree


def slam_error_stats(m: np.ndarray, plan: np.ndarray, rooms: np.ndarray | None = None
                     ) -> dict[str, float]:
    """The five statistics of the module doc for SLAM map ``m`` of ``plan`` (same square).

    Parameters
    ----------
    m, plan : (N, N) uint8
        Ternary maps (occupied 0, unknown 127, free 255).
    rooms : (N, N) int, optional
        The plan's rooms (:func:`room_rotations`), if already segmented.

    Returns
    -------
    dict
        One float per name of :data:`SLAM_ERROR_STATS`.

    Examples
    --------
    >>> plan = np.full((48, 48), 127, np.uint8)
    >>> plan[4:44, 4:44] = 0; plan[6:42, 6:42] = 255
    >>> sorted(slam_error_stats(plan, plan)) == sorted(SLAM_ERROR_STATS)
    True
    """
    m, plan = _check(m, plan)
    fo, fr = frontier(m)
    return {"doubled": doubled_walls(m, plan), "room_rot": room_rotation(m, plan, rooms),
            "frontier_open": fo, "frontier_rough": fr, "streaks": streaks(m)}
