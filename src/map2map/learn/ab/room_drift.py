"""Room-wise rigid drift on synthesized SLAM maps (issue #15: the simulated maps' wall error).

The simulated (``rbpf``) SLAM maps of the datasets place their walls 1.5-1.6 px from the
plan's on average, with a heavy tail: whole rooms, or every room mapped after some moment
of the run, are rotated or shifted against the plan by a pose error the particle filter
kept (docs/synthesize.md, "Room-wise drift"). The parametric field of
:mod:`map2map.learn.ab.drift` is a per-pixel field; scaled up to that size it tears the
network's walls into dots. This module draws the error the way the simulated maps show
it, as one small rigid transform per room, chained along the order in which a robot
starting in one room would reach the others, and blends the rooms' transforms over a few
pixels across the walls between them so that the warped walls stay continuous:

1. **rooms** (:func:`segment_rooms`): the plan's free space cut by a watershed of its
   distance transform (markers: the h-maxima, ``h_px`` deep, of the smoothed distance;
   doors are the saddles), every other pixel (walls, outside) given to its nearest room;
2. **visiting order**: from a random start room, a random depth-first walk over the
   rooms' door adjacency (rooms whose free pixels touch); rooms of other connected parts
   hang off the nearest room already visited;
3. **error growth** (the form of the parametric model's odometry error, thesis eqs.
   3.81-3.82: a linear error proportional to the distance travelled, ``E_lin = 0.09 dl +
   sigma``, and an angular one per turn, ``E_ang = 0.095 dtheta + alpha``): the step from
   a room to the next adds a rotation about the door between them, ``N(0, rot_deg^2)``
   degrees, and a shift ``N(0, (lin * dl)^2)`` per axis, ``dl`` the distance (px) between
   the two rooms' centroids; each room's transform is its parent's composed with its
   step's, so errors accumulate along the order (rooms reached late are off the most);
   one amplitude ``exp(spread * z)`` (``z`` standard normal) per map multiplies every
   step: most runs drift little, a few a lot (the heavy tail);
4. **field**: the displacement ``A_r p + b_r - p`` of room ``r``'s transform, blended
   between rooms by Gaussian-smoothed room memberships (standard deviation
   ``blend_px``, widened where two neighbouring rooms moved so far apart that the
   field's slope across their wall would exceed :data:`MAX_SLOPE`; they sum to one), so
   the field is smooth, does not fold, and is nearly rigid inside each room.
   :func:`map2map.parametric.field.warp_map` then moves the map along it (field
   inversion, wall pixels splatted).

The magnitudes are fitted to the per-room offsets measured on the simulated maps of
``gen900``'s val plans (``map2map.experiments.realism.room_offsets``), not eqs.
3.81-3.82's coefficients (raw odometry, not what the particle filter leaves of it).

The rooms' field moves free space and walls without making or erasing them (gen900 val:
-0.5 % free, +0.4 % wall pixels a map). The parametric field that
:class:`RoomDriftParams` adds by default does not: the additive method pushes whatever a
pose sees away from it (thesis eq. 3.83's range error is positive), so summed over the
poses it grows the rooms (+12 % free pixels) and squeezes walls (-15 %).
``conserve=True`` adds only its divergence-free part (:func:`solenoidal`), which keeps
both (-0.5 % free, +1 % walls); not the default: the retuned setting lost on test
(docs/synthesize.md, "Drift that keeps walls and free space", session 12).

Examples
--------
>>> from map2map.maps.floorplan import generate_floorplan
>>> plan = generate_floorplan(3, size=(10, 8))
>>> rooms = segment_rooms(plan.data, h_px=2.0)
>>> bool(rooms.max() >= 2)
True
>>> rd = room_drift_field(plan.data, np.random.default_rng(0), RoomDriftParams())
>>> rd.field.shape == plan.shape, rd.transforms.shape[1:]
(True, (2, 3))
>>> out = apply_room_drift(plan.data, rd)
>>> out.shape == plan.shape, set(np.unique(out).tolist()) <= {0, 127, 255}
(True, True)
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from scipy import ndimage

from ...core.errors import InputError
from ...core.grid import FREE
from ...parametric.field import DisplacementField, warp_map
from .wall_collapse import MAX_WALL_PX, MIN_SHARED_PX, collapse_shift, shared_walls

__all__ = ["RoomDriftParams", "RoomDrift", "segment_rooms", "room_adjacency",
           "room_drift_field", "apply_room_drift", "solenoidal"]

#: The square size the pixel settings refer to (the datasets' 256 px squares).
REF_SIZE = 256
#: Largest slope of the blended field across a wall between two rooms (px per px): the
#: blend widens beyond ``blend_px`` where neighbouring rooms moved far apart.
MAX_SLOPE = 0.4


@dataclass(frozen=True)
class RoomDriftParams:
    """How a room-wise drift is drawn (module doc).

    Parameters
    ----------
    rot_deg : float
        Standard deviation [deg] of the rotation each step to a new room adds (about the
        door between the two rooms).
    lin : float
        Standard deviation of the shift each step adds, per axis, as a fraction of the
        step's length (distance between the two rooms' centroids).
    across : float
        Factor on the part of each step's shift across the wall of the door between the
        two rooms (1: the shift is isotropic; 0: the new room only slides along that wall,
        as a scan matcher that sees the wall from both sides keeps it whole).
    collapse : float
        Probability that a step also lays the new room's faces of the walls it shares with
        the rooms mapped before it onto theirs, as a scan matcher does
        (:mod:`map2map.learn.ab.wall_collapse`; drawn only when > 0).
    jump_share, jump_deg : float
        Probability that a step is a *jump* instead, and its rotation's standard
        deviation [deg] (its shift as any step's): a particle filter keeps most rooms
        nearly right and now and then a wrong match that turns every room reached after
        it (0: no jumps, every step alike; drawn only when > 0).
    spread : float
        Log-normal spread of the per-map amplitude that multiplies every step.
    blend_px : float
        Standard deviation [px of a 256 px square] of the Gaussian that blends the rooms'
        transforms across the walls between them.
    h_px : float
        Depth [px of a 256 px square] of the distance-transform maxima that seed rooms.
    scale : float
        Final factor on the drawn rotations and shifts, and on the added parametric field
        (0: no drift). Session 12's val choice with ``conserve=True``: 0.7 (not the
        default: worse on test, docs/synthesize.md).
    parametric : bool
        Also add the default parametric field of :mod:`map2map.learn.ab.drift` (drawn first,
        from the same generator; :func:`map2map.learn.ab.drift.drift_field`).
    method : {"additive", "ekf"}
        That parametric field's odometry-to-map conversion.
    smooth_m : float
        That parametric field's Gaussian smoothing [m] (``DriftParams.smooth_m``; 0:
        none, the default drift's rough field).
    conserve : bool
        Keep only the divergence-free part of that parametric field (:func:`solenoidal`),
        so that it bends walls without growing or shrinking the map: the additive
        method's range error (thesis eq. 3.83, ``z eta + E_lin``, positive) pushes every
        pixel a pose sees away from that pose, and summed over the poses (thesis eqs.
        3.89-3.90) the field expands the rooms (about +12 % free pixels a map on gen900
        val) and, smoothed across the edge of what the model's LIDAR saw, squeezes walls
        (about -15 % wall pixels; docs/synthesize.md, "Drift that keeps walls and free
        space", session 12). ``False`` (the default): the field as drawn, which the
        session 11 traces were tuned with; with ``True`` use ``scale=0.7`` and
        ``TraceParams(floor_px=0.85)`` (session 12's val choice; not the default since
        it was worse on test).
    """

    rot_deg: float = 1.5
    lin: float = 0.02
    across: float = 1.0
    collapse: float = 0.0
    jump_share: float = 0.0
    jump_deg: float = 0.0
    spread: float = 0.8
    blend_px: float = 4.0
    h_px: float = 4.0
    scale: float = 1.0
    parametric: bool = True
    method: str = "additive"
    smooth_m: float = 0.2
    conserve: bool = False

    def __post_init__(self):
        bad = [n for n in ("rot_deg", "lin", "across", "spread", "scale", "h_px", "smooth_m",
                           "jump_deg")
               if not (math.isfinite(getattr(self, n)) and getattr(self, n) >= 0)]
        bad += [n for n in ("jump_share", "collapse") if not 0.0 <= getattr(self, n) <= 1.0]
        if not (math.isfinite(self.blend_px) and self.blend_px > 0):
            bad.append("blend_px")
        if self.method not in ("additive", "ekf"):
            raise InputError("drift_method",
                             f"must be one of additive, ekf, got {self.method!r}")
        if bad:
            raise InputError(bad[0], f"out of range: {getattr(self, bad[0])!r}")

    def describe(self) -> str:
        """One line naming every setting.

        Examples
        --------
        >>> RoomDriftParams().describe()[:58]
        'rooms: 1.5 deg + 0.02 dl per step, spread 0.8, blend 4 px,'
        """
        return (f"rooms: {self.rot_deg:g} deg + {self.lin:g} dl per step, "
                + (f"x{self.across:g} across the door, " if self.across != 1.0 else "")
                + (f"walls collapsed {self.collapse:g}, " if self.collapse > 0 else "")
                + (f"jumps {self.jump_share:g} x {self.jump_deg:g} deg, "
                   if self.jump_share > 0 else "") + "spread "
                f"{self.spread:g}, blend {self.blend_px:g} px, h {self.h_px:g} px, "
                f"x{self.scale:g}" + (f" + parametric {self.method} smoothed "
                                      f"{self.smooth_m:g} m"
                                      + (", divergence-free" if self.conserve else "")
                                      if self.parametric else ""))


@dataclass
class RoomDrift:
    """A room-wise drift of one plan (module doc).

    Attributes
    ----------
    field : DisplacementField
        Displacement [px] of every pixel.
    rooms : (H, W) int32
        Room label of every pixel (1..n; walls and outside given to the nearest room).
    transforms : (n, 2, 3) float
        Room ``r``'s transform ``[A | b]`` (``q = A p + b``, ``p = (x, y)`` = (column,
        row)) at index ``r - 1``.
    order : (n,) int
        Rooms in visiting order (labels).
    amplitude : float
        The map's drawn amplitude (times ``scale``).
    params : RoomDriftParams
    extra : DisplacementField or None
        A field added before the warp (the parametric one, ``params.parametric``).
    """

    field: DisplacementField
    rooms: np.ndarray
    transforms: np.ndarray
    order: np.ndarray
    amplitude: float
    params: RoomDriftParams
    extra: DisplacementField | None = None

    def stats(self) -> dict:
        """Mean and maximum ``|d|`` [px] over the map, and the largest room rotation [deg]."""
        mag = self.field.magnitude
        rot = np.degrees(np.arctan2(self.transforms[:, 1, 0], self.transforms[:, 0, 0]))
        return {"mean": float(mag.mean()), "max": float(mag.max()),
                "max_rot_deg": float(np.abs(rot).max()) if rot.size else 0.0}


def _size_factor(plan: np.ndarray) -> float:
    """Pixels of ``plan``'s content per pixel of a :data:`REF_SIZE` square."""
    known = np.asarray(plan) != 127
    if not known.any():
        return 1.0
    rows, cols = np.flatnonzero(known.any(1)), np.flatnonzero(known.any(0))
    return max(rows[-1] - rows[0] + 1, cols[-1] - cols[0] + 1) / REF_SIZE


def segment_rooms(plan: np.ndarray, h_px: float = 4.0, smooth_px: float = 1.0,
                  fill: bool = True) -> np.ndarray:
    """Rooms of a plan: watershed of its free space's distance transform (module doc,
    step 1).

    Parameters
    ----------
    plan : (H, W) uint8
        Ternary plan (free 255).
    h_px : float
        Depth of the smoothed distance's maxima that seed a room (px).
    smooth_px : float
        Gaussian smoothing of the distance transform (px).
    fill : bool
        Give every non-free pixel the label of its nearest room (``False``: 0 there).

    Returns
    -------
    (H, W) int32
        Labels ``1..n`` (all 0 when the plan has no free pixel).

    Examples
    --------
    >>> p = np.full((20, 41), 255, np.uint8); p[:, 20] = 0; p[8:12, 20] = 255
    >>> lab = segment_rooms(p, h_px=1.0)
    >>> int(lab.max()), int(lab[10, 5]) != int(lab[10, 35])
    (2, True)
    """
    from skimage.morphology import h_maxima
    from skimage.segmentation import watershed

    free = np.asarray(plan) == FREE
    if not free.any():
        return np.zeros(free.shape, np.int32)
    dist = ndimage.distance_transform_edt(free)
    sm = ndimage.gaussian_filter(dist, smooth_px) if smooth_px > 0 else dist
    peaks = h_maxima(sm, h_px).astype(bool) & free if h_px > 0 else free
    markers, n = ndimage.label(peaks, structure=np.ones((3, 3)))
    if n == 0:
        markers, n = ndimage.label(free, structure=np.ones((3, 3)))
    lab = watershed(-sm, markers, mask=free).astype(np.int32)
    # free parts no marker reached (none in practice) become rooms of their own
    rest, k = ndimage.label(free & (lab == 0))
    if k:
        lab[rest > 0] = rest[rest > 0] + lab.max()
    lab = _relabel(lab)
    if fill and (lab == 0).any():
        idx = ndimage.distance_transform_edt(lab == 0, return_distances=False,
                                             return_indices=True)
        lab = lab[idx[0], idx[1]]
    return lab


def _relabel(lab: np.ndarray) -> np.ndarray:
    """Labels made consecutive (1..n), 0 kept."""
    u = np.unique(lab)
    u = u[u > 0]
    lut = np.zeros(int(lab.max()) + 1, np.int32)
    lut[u] = np.arange(1, len(u) + 1, dtype=np.int32)
    return lut[lab]


def room_adjacency(rooms: np.ndarray, free: np.ndarray, axes: bool = False):
    """Door adjacency of the rooms: pairs whose free pixels touch (4-neighbours), and a
    door point (x, y) per pair (the mean of the touching pixels).

    With ``axes``, also the door's direction per pair: the unit vector (x, y) along which
    the touching pixels lie (their scatter's larger eigenvector; across a door, the
    direction of the wall it is cut in).

    Returns
    -------
    dict or (dict, dict)
        ``{(a, b): (x, y)}`` with ``a < b``; with ``axes``, also ``{(a, b): (ux, uy)}``.

    Examples
    --------
    >>> lab = np.zeros((6, 9), int); lab[:, :4] = 1; lab[:, 4:] = 2
    >>> doors, ax = room_adjacency(lab, np.ones((6, 9), bool), axes=True)
    >>> doors, [round(abs(v), 6) for v in ax[(1, 2)]]
    ({(1, 2): (3.0, 2.5)}, [0.0, 1.0])
    """
    out: dict = {}
    cov: dict = {}
    lab = np.where(free, rooms, 0)
    for a, b in ((lab[:, :-1], lab[:, 1:]), (lab[:-1, :], lab[1:, :])):
        touch = (a > 0) & (b > 0) & (a != b)
        if not touch.any():
            continue
        r, c = np.nonzero(touch)
        lo, hi = np.minimum(a[touch], b[touch]), np.maximum(a[touch], b[touch])
        key = lo.astype(np.int64) * (int(rooms.max()) + 1) + hi
        for k in np.unique(key):
            sel = key == k
            pair = (int(k // (int(rooms.max()) + 1)), int(k % (int(rooms.max()) + 1)))
            pts = np.stack([c[sel], r[sel]], 1).astype(float)
            if pair in out:
                n0, s0 = out[pair]
                out[pair] = (n0 + len(pts), s0 + pts.sum(0))
                cov[pair] = cov[pair] + pts.T @ pts
            else:
                out[pair] = (len(pts), pts.sum(0))
                cov[pair] = pts.T @ pts
    doors = {k: tuple((s / n).tolist()) for k, (n, s) in out.items()}
    if not axes:
        return doors
    dirs = {}
    for k, (n, s) in out.items():
        m = s / n
        w, v = np.linalg.eigh(cov[k] / n - np.outer(m, m))
        dirs[k] = tuple(v[:, 1].tolist())
    return doors, dirs


def _largest_step(rooms: np.ndarray, T: np.ndarray) -> float:
    """Largest difference (px) between two neighbouring rooms' displacements, over the
    pixels where the (filled) room labels change."""
    best = 0.0
    for a, b in ((rooms[:, :-1], rooms[:, 1:]), (rooms[:-1, :], rooms[1:, :])):
        edge = a != b
        if not edge.any():
            continue
        yy, xx = np.nonzero(edge)
        p = np.stack([xx, yy, np.ones_like(xx)]).astype(float)
        ra, rb = a[edge], b[edge]
        qa = np.einsum("nij,jn->in", T[ra, :2], p)
        qb = np.einsum("nij,jn->in", T[rb, :2], p)
        best = max(best, float(np.hypot(*(qa - qb)).max()))
    return best


def _rigid(theta: float, pivot, shift) -> np.ndarray:
    """3x3 homogeneous rotation by ``theta`` about ``pivot`` followed by ``shift``."""
    c, s = math.cos(theta), math.sin(theta)
    px, py = pivot
    return np.array([[c, -s, px - c * px + s * py + shift[0]],
                     [s, c, py - s * px - c * py + shift[1]],
                     [0.0, 0.0, 1.0]])


def _path_rooms(rooms: np.ndarray, path) -> list[int]:
    """The rooms ``path`` (rows, cols; time order) passes through, in order, consecutive
    repeats merged (pixels outside the map or in no room skipped)."""
    rows, cols = (np.rint(np.asarray(v, float)).astype(int) for v in path)
    H, W = rooms.shape
    inside = (rows >= 0) & (rows < H) & (cols >= 0) & (cols < W)
    lab = rooms[rows[inside], cols[inside]]
    lab = lab[lab > 0]
    if lab.size == 0:
        return []
    keep = np.concatenate([[True], lab[1:] != lab[:-1]])
    return [int(v) for v in lab[keep]]


def room_drift_field(plan: np.ndarray, rng: np.random.Generator,
                     params: RoomDriftParams | None = None, path=None) -> RoomDrift:
    """A room-wise drift of ``plan`` (module doc, steps 1-4).

    Parameters
    ----------
    plan : (H, W) uint8
        Ternary plan (the rooms are cut from its free space), in the frame of the map to
        warp.
    rng : numpy.random.Generator
        Every random draw (start room, order, steps, amplitude), in a fixed sequence.
    params : RoomDriftParams, optional
    path : (rows, cols) arrays, optional
        Pixels a robot passed through, in time order. The drift then follows the robot
        instead of a random walk: its first room is the start (identity), and each room
        steps from the room the robot came from when it first entered it, as a SLAM run's
        pose error grows along the route and a room mapped once keeps its place (rooms the
        path never enters hang off the visited ones as before).

    Returns
    -------
    RoomDrift
    """
    rp = params or RoomDriftParams()
    plan = np.asarray(plan, np.uint8)
    H, W = plan.shape
    f = _size_factor(plan)
    free = plan == FREE
    rooms = segment_rooms(plan, rp.h_px * f)
    n = int(rooms.max())
    amp = rp.scale * math.exp(rp.spread * float(rng.standard_normal()))
    if n == 0:
        z = DisplacementField.zeros((H, W))
        return RoomDrift(z, rooms, np.zeros((0, 2, 3)), np.zeros(0, int), amp, rp)
    idx = np.arange(1, n + 1)
    own = np.where(free, rooms, 0)
    area = ndimage.sum(free, own, idx)
    cy, cx = (np.asarray(v) for v in zip(*ndimage.center_of_mass(free, own, idx),
                                         strict=True))
    doors, axes = room_adjacency(rooms, free, axes=True)
    walls = shared_walls(plan, rooms, MAX_WALL_PX * f, MIN_SHARED_PX * f) if rp.collapse else None
    nbrs: dict[int, list[int]] = {r: [] for r in idx.tolist()}
    for a, b in sorted(doors):
        nbrs[a].append(b)
        nbrs[b].append(a)
    T = np.zeros((n + 1, 3, 3))
    seen = np.zeros(n + 1, bool)
    order: list[int] = []
    start = int(rng.choice(idx, p=area / area.sum())) if area.sum() > 0 else 1

    def step(parent: int, child: int, door) -> None:
        dl = math.hypot(cx[child - 1] - cx[parent - 1], cy[child - 1] - cy[parent - 1])
        deg = rp.rot_deg
        if rp.jump_share > 0 and rng.random() < rp.jump_share:
            deg = rp.jump_deg
        th = math.radians(deg) * amp * float(rng.standard_normal())
        sh = rp.lin * dl * amp * rng.standard_normal(2)
        u = axes.get((min(parent, child), max(parent, child)))
        if rp.across != 1.0 and u is not None:
            # the shift across the door's wall scaled by ``across``, along it kept
            along = float(sh @ u) * np.asarray(u)
            sh = along + rp.across * (sh - along)
        if walls is not None and rng.random() < rp.collapse:
            sh = sh + collapse_shift(walls, child, np.flatnonzero(seen))
        T[child] = T[parent] @ _rigid(th, door, sh)

    seq = _path_rooms(rooms, path) if path is not None else []
    if seq:
        start = seq[0]
    T[start] = np.eye(3)
    seen[start] = True
    order.append(start)
    for r, b in zip(seq[:-1], seq[1:], strict=True):
        if not seen[b]:
            mid = (0.5 * (cx[r - 1] + cx[b - 1]), 0.5 * (cy[r - 1] + cy[b - 1]))
            step(r, b, doors.get((min(r, b), max(r, b)), mid))
            seen[b] = True
            order.append(b)
    stack = list(order)
    while True:
        # depth-first walk in random order from the visited rooms
        while stack:
            r = stack[-1]
            cand = [b for b in nbrs[r] if not seen[b]]
            if not cand:
                stack.pop()
                continue
            b = int(cand[int(rng.integers(len(cand)))])
            step(r, b, doors[(min(r, b), max(r, b))])
            seen[b] = True
            order.append(b)
            stack.append(b)
        left = np.flatnonzero(~seen[1:]) + 1
        if left.size == 0:
            break
        # another connected part: hangs off the nearest visited room (nearest centroids)
        vis = np.asarray(order)
        d2 = (cx[left - 1, None] - cx[vis - 1]) ** 2 + (cy[left - 1, None] - cy[vis - 1]) ** 2
        i, j = np.unravel_index(int(np.argmin(d2)), d2.shape)
        start, parent = int(left[i]), int(vis[j])
        mid = (0.5 * (cx[start - 1] + cx[parent - 1]), 0.5 * (cy[start - 1] + cy[parent - 1]))
        step(parent, start, mid)
        stack = [start]
        seen[start] = True
        order.append(start)
    # blend the rooms' affine coefficients by smoothed memberships (they sum to one), over
    # at least blend_px, and wide enough that the field's slope across a wall stays below
    # MAX_SLOPE (a Gaussian step of height D has slope D / (sigma sqrt(2 pi))): no fold
    sig = max(rp.blend_px * f, _largest_step(rooms, T) / (MAX_SLOPE * math.sqrt(2 * math.pi)))
    coef = np.zeros((6, H, W))
    for r in idx.tolist():
        w = ndimage.gaussian_filter((rooms == r).astype(float), sig, mode="nearest")
        coef += w[None] * T[r, :2].reshape(6, 1, 1)
    yy, xx = np.mgrid[:H, :W].astype(float)
    dx = coef[0] * xx + coef[1] * yy + coef[2] - xx
    dy = coef[3] * xx + coef[4] * yy + coef[5] - yy
    return RoomDrift(DisplacementField(dx, dy), rooms, T[1:, :2].copy(), np.asarray(order),
                     amp, rp)


def solenoidal(field: DisplacementField) -> DisplacementField:
    """The divergence-free part of ``field``: ``d - grad(phi)`` with ``lap(phi) =
    div(d)`` (Helmholtz projection), so the warp along it moves pixels without growing or
    shrinking areas (``det J = 1`` to first order; :class:`RoomDriftParams` ``conserve``).

    Discretization: ``d`` averaged onto the faces between pixels, its divergence per pixel,
    ``phi`` from the 5-point Laplacian with no flow across the square's border (Neumann),
    solved exactly in the DCT-II basis (no loop); ``grad(phi)`` on the faces averaged back
    to the pixels and subtracted. The faces' divergence of the result is zero to rounding;
    at the pixels, up to that averaging. Nothing may flow across the square's border, so
    a motion that carries content across it is removed too, rigid or not: a constant
    shift, a turn of the whole square (the room drift draws the rooms' rigid motion; what
    is kept is the field's local turning and shearing, which bends walls).

    Parameters
    ----------
    field : DisplacementField

    Returns
    -------
    DisplacementField

    Examples
    --------
    A local source (a pure growth, ``d = grad g``) is removed; a local turn of the same
    size (``d = (dg/dy, -dg/dx)``, what bends a wall through it) is kept:

    >>> yy, xx = np.mgrid[:48, :48] - 23.5
    >>> gy, gx = np.gradient(40 * np.exp(-(xx**2 + yy**2) / 72.0))     # |d| up to 4 px
    >>> float(solenoidal(DisplacementField(gx, gy)).magnitude.max()) < 0.1
    True
    >>> turn = DisplacementField(gy, -gx)
    >>> float(np.abs(solenoidal(turn).dx - turn.dx).max()) < 0.01
    True
    """
    from scipy import fft

    dx = field.dx.astype(float)
    dy = field.dy.astype(float)
    H, W = dx.shape
    ux = 0.5 * (dx[:, 1:] + dx[:, :-1])          # x faces between columns j, j+1
    uy = 0.5 * (dy[1:] + dy[:-1])                # y faces between rows i, i+1
    div = np.zeros((H, W))
    div[:, :-1] += ux
    div[:, 1:] -= ux
    div[:-1] += uy
    div[1:] -= uy
    lam = ((2 * np.cos(np.pi * np.arange(H) / H) - 2)[:, None]
           + (2 * np.cos(np.pi * np.arange(W) / W) - 2)[None])
    lam[0, 0] = 1.0
    c = fft.dctn(div, type=2, norm="ortho") / lam
    c[0, 0] = 0.0                                # the mean of phi is free
    phi = fft.idctn(c, type=2, norm="ortho")
    # grad(phi) on the faces (zero flow across the border's faces); a border pixel takes
    # its one inner face's value, so the field has no step at the square's edge
    gx = np.zeros((H, W + 1))
    gx[:, 1:-1] = phi[:, 1:] - phi[:, :-1]
    gx[:, 0], gx[:, -1] = gx[:, 1], gx[:, -2]
    gy = np.zeros((H + 1, W))
    gy[1:-1] = phi[1:] - phi[:-1]
    gy[0], gy[-1] = gy[1], gy[-2]
    return DisplacementField(dx - 0.5 * (gx[:, 1:] + gx[:, :-1]),
                             dy - 0.5 * (gy[1:] + gy[:-1]))


def apply_room_drift(m: np.ndarray, drift: RoomDrift, extra: DisplacementField | None = None
                     ) -> np.ndarray:
    """Map ``m`` (same frame as the drift's plan) moved along the room-wise field (plus
    ``extra``, e.g. a parametric field), :func:`map2map.parametric.field.warp_map`; ``m``'s
    unknown cells stay unknown.

    Parameters
    ----------
    m : (H, W) uint8
    drift : RoomDrift
    extra : DisplacementField, optional
        Added to the room-wise field before the warp.

    Returns
    -------
    (H, W) uint8
    """
    m = np.asarray(m, np.uint8)
    if m.shape != drift.field.shape:
        raise ValueError(f"map {m.shape} and drift field {drift.field.shape} differ in shape")
    f = drift.field if extra is None else drift.field + extra
    return warp_map(m, f, np.ones(m.shape, bool))
