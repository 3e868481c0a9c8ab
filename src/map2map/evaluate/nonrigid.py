"""Nonrigid optimisation of the aligned edge points, eq. 7, and the piecewise-affine warp.

Section 3.2.3 of the appendix paper, after Shahbandi & Magnusson. The plan's
distance map is turned into the Gaussian fitness map ``M_f = exp(-M_d^2 / 2
sigma_f^2)``; the edge points ``X`` of the aligned source move to maximise
``sum_i M_f(x_i + dx_i)`` (eq. 7). The gradient of ``M_f`` at ``x`` is
``M_f(x) (c(x) - x) / sigma_f^2`` where ``c(x)`` is the nearest plan wall cell (the
distance transform's index), so a gradient-ascent step of size ``sigma_f^2`` is
``dx_i = M_f(x_i) (c_i - x_i)``: far points (furniture, unmapped walls) barely move.

Coherence: each motion is replaced by the Gaussian-weighted average of its
neighbours' motions, ``dx'_i = sum_j w_ij dx_j / sum_j w_ij m_j`` with
``w_ij = m_j exp(-|x_i - x_j|^2 / 2 sigma_n^2)`` (``m_j = M_f(x_j)``; the paper's
``1/K`` normalisation is replaced by the weight sum so that isolated points are not
pulled towards zero). Over all pairs this is O(N^2) per iteration — the cause of the
paper's 8-17 hour runs. Here it is a normalised convolution on a grid of cell
``sigma_n / 4``: the motions are splatted on the grid, Gaussian-filtered and
interpolated back, O(N + G) per iteration. ``sigma_f`` and ``sigma_n`` are
annealed from coarse to fine.

Matching respects wall sides: a point on a wall surface facing direction ``n`` is
only attracted by plan surfaces facing the same way (:func:`.features.side_masks`),
so the two faces of a wall are never swapped.

The motions define a piecewise-affine warp over the Delaunay triangulation of
control points (:class:`PiecewiseAffine`); images are warped by rasterising the
triangles and one ``cv2.remap``.

Examples
--------
>>> import numpy as np
>>> plan = np.full((100, 100), 255, np.uint8); plan[:, 50] = 0
>>> fields = SideFields.from_map(plan, theta=0.0)
>>> X = np.column_stack([np.full(40, 54.5), np.linspace(20, 80, 40)])
>>> N = np.tile([-1.0, 0.0], (40, 1))              # faces the free space on the left
>>> X_opt = optimise(X, N, fields, sigma_f=(8.0, 4.0), sigma_n=(40.0, 20.0))
>>> float(np.abs(X_opt[:, 0] - 50.5).max()) < 0.5  # moved onto the plan's wall
True
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import cv2
import numpy as np
from scipy.spatial import Delaunay

from ..core.grid import FREE, OCCUPIED, UNKNOWN
from ..maps.directions import orientation
from .features import side_masks
from .fitness import distance_map

__all__ = [
    "SideFields",
    "optimise",
    "coherent_motion",
    "to_plane",
    "PiecewiseAffine",
    "control_points",
    "warp_image",
]


@dataclass
class SideFields:
    """Distance transforms (with nearest-wall indices) of the plan's wall surfaces.

    ``sides[k]`` holds the surfaces facing ``angles[k]``: ``theta + k pi/2`` (k =
    0..3) for a plan whose walls run along ``theta`` and ``theta + pi/2``; a plan
    with further direction ``families`` (a wing at 45 degrees,
    :func:`~map2map.evaluate.orientation.wall_families`) has four more sides per
    family, and each wall cell belongs to the sides of its own family (the
    structure tensor's orientation around it, :func:`map2map.maps.directions.orientation`).
    ``walls`` holds all occupied cells (for points whose side is unknown). The
    fields may cover only a window of the plan (its known content): ``offset`` (x,
    y) is the window's top-left corner in plan pixels and ``plan_shape`` the whole
    plan's shape.
    """

    theta: float
    sides: list[tuple[np.ndarray, np.ndarray]]
    wall_mask: np.ndarray
    offset: tuple[int, int] = (0, 0)
    plan_shape: tuple[int, int] | None = None
    known: np.ndarray | None = None
    families: tuple[float, ...] = ()
    _walls: tuple[np.ndarray, np.ndarray] | None = None
    _flat: np.ndarray | None = None
    _thickness: float | None = None

    @property
    def walls(self) -> tuple[np.ndarray, np.ndarray]:
        """Distance transform and indices of all wall cells (computed when first needed)."""
        if self._walls is None:
            self._walls = distance_map(self.wall_mask, return_indices=True)
        return self._walls

    @classmethod
    def from_map(
        cls, data: np.ndarray, theta: float, window: tuple[int, int, int, int] | None = None,
        families: Sequence[float] = (),
    ) -> SideFields:
        """Fields of a plan, optionally of its ``window = (row0, row1, col0, col1)`` only.

        ``families``: the plan's direction families beside ``theta`` (radians; a
        list that starts with ``theta``, as
        :func:`~map2map.evaluate.orientation.wall_families` returns it, is taken
        as is)."""
        r0, r1, c0, c1 = window or (0, data.shape[0], 0, data.shape[1])
        sub = data[r0:r1, c0:c1]
        extra = tuple(float(f) for f in families if _apart(f, theta) > 1e-9)
        masks = side_masks(sub, theta) if not extra else _family_masks(sub, (theta, *extra))
        sides = [distance_map(m, return_indices=True) for m in masks]
        walls = sub == OCCUPIED
        # the plan's known cells, grown by 3 px: walls seen at the edge of its known area
        known = cv2.dilate((sub != UNKNOWN).astype(np.uint8), np.ones((7, 7), np.uint8)) > 0
        return cls(float(theta), sides, walls, (int(c0), int(r0)), tuple(data.shape), known,
                   extra)

    @property
    def angles(self) -> np.ndarray:
        """The direction each side's surfaces face (radians): four per family."""
        fams = (self.theta, *self.families)
        return np.array([f + k * np.pi / 2 for f in fams for k in range(4)])

    @property
    def n_sides(self) -> int:
        """Number of sides (4 per family); a point's unknown side is group ``n_sides``."""
        return 4 * (1 + len(self.families))

    def is_known(self, pts: np.ndarray) -> np.ndarray:
        """Whether points fall on (or within 3 px of) known cells of the plan."""
        if self.known is None:
            return np.ones(len(pts), bool)
        ox, oy = self.offset
        h, w = self.known.shape
        c = np.floor(pts[:, 0] - ox).astype(np.int64)
        r = np.floor(pts[:, 1] - oy).astype(np.int64)
        ok = (r >= 0) & (r < h) & (c >= 0) & (c < w)
        out = np.zeros(len(pts), bool)
        out[ok] = self.known[r[ok], c[ok]]
        return out

    @property
    def shape(self) -> tuple[int, int]:
        return self.wall_mask.shape

    def _table(self) -> np.ndarray:
        """(n_sides + 1, H * W) flat index of the nearest wall cell: the sides, then all
        walls."""
        if getattr(self, "_flat", None) is None:
            h, w = self.shape
            rows = []
            for d, idx in [*self.sides, self.walls]:
                if not np.isfinite(d).any():  # a side without surfaces: use all walls
                    d, idx = self.walls
                rows.append((idx[0] * w + idx[1]).ravel())  # int32: windows < 46k px a side
            self._flat = np.stack(rows)
        return self._flat

    @property
    def wall_thickness(self) -> float:
        """Typical thickness of the plan's walls (px): twice the 90th percentile of the
        distance from wall cells to the nearest non-wall cell (1 for empty fields)."""
        if self._thickness is None:
            if not self.wall_mask.any():
                self._thickness = 1.0
            else:
                inner = cv2.distanceTransform(self.wall_mask.astype(np.uint8), cv2.DIST_L1, 3)
                self._thickness = float(2 * np.percentile(inner[self.wall_mask], 90))
        return self._thickness

    def side_groups(self, normals: np.ndarray) -> np.ndarray:
        """Side index (0 to ``n_sides - 1``) whose surfaces each normal faces (the
        nearest side angle), ``n_sides`` where the normal is unknown."""
        n = np.asarray(normals, float).reshape(-1, 2)
        group = np.full(len(n), self.n_sides)
        has = np.hypot(n[:, 0], n[:, 1]) > 0.5
        if not self.families:
            ang = np.arctan2(n[:, 1], n[:, 0]) - self.theta
            group[has] = np.mod(np.round(ang[has] / (np.pi / 2)), 4).astype(int)
            return group
        ang = np.arctan2(n[has, 1], n[has, 0])
        off = np.abs(_wrap_pi(ang[:, None] - self.angles[None, :]))
        group[has] = np.argmin(off, axis=1)
        return group

    def side_normals(self, normals: np.ndarray) -> np.ndarray:
        """Normal ``angles[k]`` of the plan surfaces each point matches (0 if unknown)."""
        group = self.side_groups(normals)
        a = np.append(self.angles, 0.0)[group]
        out = np.column_stack([np.cos(a), np.sin(a)])
        out[group == self.n_sides] = 0.0
        return out

    def corners(self, normals: np.ndarray, band: float) -> np.ndarray:
        """Whether each normal lies near the bisector between the two side angles
        flanking it: a corner, whose side is a toss-up (False where the normal is
        unknown). With one family: within ``band`` (radians) of the diagonal between
        the axes, 45 degrees from each; with more, the band shrinks with the angle
        between the two sides (a wing at 45 degrees: the sides 45 degrees apart, within
        ``band / 2`` of the bisector), so that a wall's normals, noisy by a few
        degrees, stay on their side's side as they do on the axes."""
        n = np.asarray(normals, float).reshape(-1, 2)
        has = np.hypot(n[:, 0], n[:, 1]) > 0.5
        a = np.arctan2(n[:, 1], n[:, 0])
        if not self.families:
            ang = np.mod(a - self.theta, np.pi / 2)
            return has & (np.abs(ang - np.pi / 4) < band)
        d = _wrap_pi(a[:, None] - self.angles[None, :])
        # the sides flanking each normal: the nearest one either way round
        ahead = np.where(d >= 0, d, np.inf).min(axis=1)
        behind = np.where(d < 0, -d, np.inf).min(axis=1)
        gap = ahead + behind
        return has & (np.abs(ahead - behind) < 2 * band * gap / (np.pi / 2))

    def across(self) -> np.ndarray:
        """(n_sides, n_sides) bool: sides that meet side ``g`` at a corner (their
        angles 30-150 degrees apart): with one family, the two perpendicular sides."""
        d = np.abs(_wrap_pi(self.angles[:, None] - self.angles[None, :]))
        return (d > np.radians(30.0)) & (d < np.radians(150.0))

    def nearest(self, pts: np.ndarray, normals: np.ndarray | None = None):
        """Nearest plan wall cell centre (x, y) of each point, its distance, and inside flags.

        With ``normals`` (unit, target frame; zero = unknown side) each point is matched
        to the surfaces facing its way. Points off the fields' window get themselves
        back and ``inside`` False.
        """
        pts = np.asarray(pts, float)
        h, w = self.shape
        ox, oy = self.offset
        c = np.floor(pts[:, 0] - ox).astype(np.int64)
        r = np.floor(pts[:, 1] - oy).astype(np.int64)
        inside = (r >= 0) & (r < h) & (c >= 0) & (c < w)
        # n_sides = all walls (side unknown)
        group = np.full(len(pts), self.n_sides) if normals is None else self.side_groups(normals)
        # one gather in the stacked flat index table of the five fields
        flat = self._table()[group[inside], r[inside] * w + c[inside]]
        near = pts.copy()
        near[inside, 0] = flat % w + 0.5 + ox
        near[inside, 1] = flat // w + 0.5 + oy
        dist = np.hypot(*(near - pts).T)
        return near, dist, inside


def _wrap_pi(a):
    """Radians folded into [-pi, pi)."""
    return np.mod(np.asarray(a) + np.pi, 2 * np.pi) - np.pi


def _apart(a: float, b: float) -> float:
    """How far two wall directions lie apart, modulo pi/2 (radians)."""
    d = abs(float(a) - float(b)) % (np.pi / 2)
    return min(d, np.pi / 2 - d)


def _family_masks(data: np.ndarray, families: Sequence[float]) -> list[np.ndarray]:
    """The wall surfaces facing each side ``family + k pi/2`` of each family (four per
    family), for a plan with more than one direction family.

    A surface cell is an occupied cell beside free space. It belongs to its own
    family's sides only: the family nearest its local orientation (the structure
    tensor over 9 x 9 pixels, :func:`map2map.maps.directions.orientation`); a wall at
    45 or 30 degrees is a staircase of cells that face the axes too, and would
    otherwise be matched by its steps. Which of the four sides it faces is the
    direction of the free space around it (the gradient of the free cells blurred over
    a pixel) within 45 degrees; a cell with free space on both sides (a wall one pixel
    thick) faces each side within 45 degrees of one of its free neighbours.
    (:func:`~map2map.evaluate.features.side_masks`'s one-neighbour rule serves a
    plan of one family: rounded to the eight neighbours, a side at 60 degrees would
    look below, as the side at 90 does.)"""
    occ = data == OCCUPIED
    free = data == FREE
    near = cv2.dilate(free.astype(np.uint8), np.ones((3, 3), np.uint8)) > 0
    r, c = np.nonzero(occ & near)
    out = [np.zeros_like(occ) for _ in range(4 * len(families))]
    if not len(r):
        return out
    ang, _ = orientation(occ.astype(np.float32), at=(r, c))
    fam = np.degrees(np.asarray(families, float))
    label = np.argmin(np.abs((ang[:, None] - fam[None, :] + 45.0) % 90.0 - 45.0), axis=1)
    blur = cv2.GaussianBlur(free.astype(np.float32), (0, 0), 1.0)
    gx = cv2.Sobel(blur, cv2.CV_32F, 1, 0, ksize=3)[r, c]
    gy = cv2.Sobel(blur, cv2.CV_32F, 0, 1, ksize=3)[r, c]
    one = np.hypot(gx, gy) > 0.5                     # free space on one side
    towards = np.arctan2(gy, gx)
    H, W = data.shape
    steps = [(dx, dy) for dy in (-1, 0, 1) for dx in (-1, 0, 1) if dx or dy]
    for i, f in enumerate(families):
        own = label == i
        for k in range(4):
            a = f + k * np.pi / 2
            m = own & one & (np.abs(_wrap_pi(towards - a)) < np.pi / 4)
            for dx, dy in steps:                     # eight neighbours, not pixels
                if abs(_wrap_pi(np.arctan2(dy, dx) - a)) >= np.pi / 4:
                    continue
                rr, cc = r + dy, c + dx
                ok = (rr >= 0) & (rr < H) & (cc >= 0) & (cc < W)
                hit = np.zeros(len(r), bool)
                hit[ok] = free[rr[ok], cc[ok]]
                m |= own & ~one & hit
            out[4 * i + k][r[m], c[m]] = True
    return out


def to_plane(pts: np.ndarray, near: np.ndarray, normals: np.ndarray | None) -> np.ndarray:
    """Correspondences moved onto the normal through each point (point-to-plane residuals).

    ``pts + ((near - pts) . n) n`` where a point has a normal, ``near`` elsewhere:
    only the distance across the wall counts, not the pixel rounding along it.
    """
    if normals is None:
        return near
    n = np.asarray(normals, float)
    has = np.hypot(n[:, 0], n[:, 1]) > 0.5
    along = ((near - pts) * n).sum(1, keepdims=True) * n
    return np.where(has[:, None], pts + along, near)


def coherent_motion(
    pts: np.ndarray, motion: np.ndarray, weight: np.ndarray, sigma_n: float
) -> np.ndarray:
    """Neighbourhood coherence ``dx'_i`` by normalised convolution on a grid (O(N + G)).

    Equivalent, up to the grid's ``sigma_n / 4`` quantisation, to
    ``sum_j w_j g(x_i - x_j) dx_j / sum_j w_j g(x_i - x_j)`` with a Gaussian ``g``
    of standard deviation ``sigma_n``.
    """
    if len(pts) == 0:
        return motion.copy()
    h = max(1.0, sigma_n / 4.0)
    lo = pts.min(0) - 3 * sigma_n
    ij = np.floor((pts - lo) / h).astype(np.int64)
    W, H = ij.max(0) + int(np.ceil(3 * sigma_n / h)) + 2
    acc = np.zeros((3, H, W), np.float64)
    flat = ij[:, 1] * W + ij[:, 0]
    for k, v in enumerate((weight * motion[:, 0], weight * motion[:, 1], weight)):
        acc[k].ravel()[:] = np.bincount(flat, weights=v, minlength=H * W)
    s = sigma_n / h
    blurred = [cv2.GaussianBlur(a.astype(np.float32), (0, 0), s) for a in acc]
    # sample back with bilinear interpolation at the points' continuous grid coordinates
    g = (pts - lo) / h - 0.5
    n = len(g)
    # cv2.remap takes maps of under 32767 rows and columns: a column of n points up
    # to 32766 (as before), else rows of 4096 (more points than that: large maps)
    cols = 1 if n < 32767 else 4096
    pad = -n % cols
    mx = np.pad(g[:, 0].astype(np.float32), (0, pad)).reshape(-1, cols)
    my = np.pad(g[:, 1].astype(np.float32), (0, pad)).reshape(-1, cols)
    vals = [
        cv2.remap(b, mx, my, cv2.INTER_LINEAR, borderMode=cv2.BORDER_REPLICATE).ravel()[:n]
        for b in blurred
    ]
    den = np.maximum(vals[2].astype(np.float64), 1e-12)
    out = np.column_stack([vals[0] / den, vals[1] / den])
    out[vals[2] < 1e-9] = 0.0
    return out


def optimise(
    X: np.ndarray,
    normals: np.ndarray | None,
    fields: SideFields,
    *,
    sigma_f: tuple[float, ...] = (16.0, 8.0, 4.0, 2.0),
    sigma_n: tuple[float, ...] = (160.0, 80.0, 40.0, 20.0),
    iterations: int = 6,
) -> np.ndarray:
    """Maximise eq. 7: move points ``X`` (plan pixels) onto the plan's walls, coherently.

    ``sigma_f`` (fitness neighbourhood) and ``sigma_n`` (coherence) are pixel
    schedules annealed together; ``iterations`` steps per stage. Returns
    ``X_optimised`` in the same order as ``X``.
    """
    X = np.asarray(X, float)
    Y = X.copy()
    for sf, sn in zip(sigma_f, sigma_n, strict=True):
        for _ in range(iterations):
            near, d, inside = fields.nearest(Y, normals)
            near = to_plane(Y, near, normals)
            # points over the plan's unknown space have nothing to match: they only follow
            m = np.where(inside & fields.is_known(Y), np.exp(-(d**2) / (2 * sf**2)), 0.0)
            dx = coherent_motion(Y, (near - Y), m, sn)
            Y = Y + dx
            if np.abs(dx).max() < 0.05:
                break
    return Y


def control_points(pts: np.ndarray, spacing: float) -> np.ndarray:
    """Indices of one point per ``spacing``-px cell (the first in each), for triangulation."""
    cells = np.floor(pts / spacing).astype(np.int64)
    _, first = np.unique(cells, axis=0, return_index=True)
    return np.sort(first)


class PiecewiseAffine:
    """Piecewise-affine map over the Delaunay triangulation of control points.

    Inside the convex hull of ``src``, a point is mapped by the affine transform of
    its triangle (which sends the triangle's ``src`` vertices to their ``dst``
    vertices); outside, it is left where it is.

    Examples
    --------
    >>> src = np.array([[0.0, 0.0], [10, 0], [0, 10], [10, 10]])
    >>> pw = PiecewiseAffine(src, src + [2.0, 0.0])
    >>> pw.forward(np.array([[5.0, 5.0], [50.0, 50.0]])).tolist()
    [[7.0, 5.0], [50.0, 50.0]]
    """

    def __init__(self, src: np.ndarray, dst: np.ndarray):
        self.src = np.asarray(src, float)
        self.dst = np.asarray(dst, float)
        self.tri = Delaunay(self.src)
        self.simplices = self.tri.simplices
        self.fwd = self._affines(self.src, self.dst)
        self.inv = self._affines(self.dst, self.src)

    def _affines(self, a: np.ndarray, b: np.ndarray) -> np.ndarray:
        """(M, 2, 3) affine of every triangle mapping its ``a`` vertices to its ``b`` ones."""
        A = a[self.simplices]  # (M, 3, 2)
        B = b[self.simplices]
        Ah = np.concatenate([A, np.ones((*A.shape[:2], 1))], axis=2)  # (M, 3, 3)
        det = np.linalg.det(Ah)
        ok = np.abs(det) > 1e-9
        out = np.zeros((len(A), 2, 3))
        out[:, 0, 0] = out[:, 1, 1] = 1.0  # degenerate triangles: identity
        sol = np.linalg.solve(Ah[ok], B[ok])  # (k, 3, 2): Ah @ sol = B
        out[ok] = np.transpose(sol, (0, 2, 1))
        return out

    def forward(self, pts: np.ndarray) -> np.ndarray:
        """Map points (x, y); points outside the hull are returned unchanged."""
        pts = np.asarray(pts, float).reshape(-1, 2)
        s = self.tri.find_simplex(pts)
        out = pts.copy()
        ok = s >= 0
        M = self.fwd[s[ok]]
        out[ok] = np.einsum("kij,kj->ki", M[:, :, :2], pts[ok]) + M[:, :, 2]
        return out

    def inverse_maps(self, shape: tuple[int, int]) -> tuple[np.ndarray, np.ndarray]:
        """For every cell centre of a (H, W) image, its preimage (x, y) under the warp.

        The ``dst`` triangles are rasterised (``cv2.fillConvexPoly``) into a label
        image and each cell applies its triangle's inverse affine; cells outside
        every triangle map to themselves. Returns float32 ``(map_x, map_y)`` of
        continuous coordinates.
        """
        H, W = shape
        label = np.full((H, W), -1, np.int32)
        tris = self.dst[self.simplices] - 0.5  # continuous -> pixel-index coordinates
        for i, t in enumerate(np.round(tris * 16).astype(np.int32)):
            cv2.fillConvexPoly(label, t, i, lineType=cv2.LINE_8, shift=4)
        yy, xx = np.mgrid[0:H, 0:W].astype(np.float32)
        xx += 0.5
        yy += 0.5
        map_x, map_y = xx.copy(), yy.copy()
        sel = label >= 0
        M = self.inv[label[sel]].astype(np.float32)
        px, py = xx[sel], yy[sel]
        map_x[sel] = M[:, 0, 0] * px + M[:, 0, 1] * py + M[:, 0, 2]
        map_y[sel] = M[:, 1, 0] * px + M[:, 1, 1] * py + M[:, 1, 2]
        return map_x, map_y


def warp_image(
    image: np.ndarray,
    T: np.ndarray,
    shape: tuple[int, int],
    pw: PiecewiseAffine | None = None,
    *,
    border: int = 127,
) -> np.ndarray:
    """Warp a source image into a (H, W) target frame by ``T`` then the optional warp ``pw``.

    Nearest-neighbour sampling (occupancy values stay 0/127/255).
    """
    H, W = shape
    if pw is None:
        yy, xx = np.mgrid[0:H, 0:W].astype(np.float32)
        ax, ay = xx + 0.5, yy + 0.5
    else:
        ax, ay = pw.inverse_maps(shape)
    Ti = np.linalg.inv(T).astype(np.float32)
    sx = Ti[0, 0] * ax + Ti[0, 1] * ay + Ti[0, 2] - 0.5
    sy = Ti[1, 0] * ax + Ti[1, 1] * ay + Ti[1, 2] - 0.5
    return cv2.remap(
        image, sx, sy, cv2.INTER_NEAREST, borderMode=cv2.BORDER_CONSTANT, borderValue=border
    )
