"""Maps with known errors: walls moved by known amounts, smooth known displacement fields.

Ground truth for the error metric (the appendix paper validates its metric on
synthetic deformations, section 5.1): a plan drawn from wall segments can be redrawn
with some walls moved perpendicular to themselves, and any map can be deformed by
a smooth displacement field. Each generator returns the deformed map together with
the true per-pixel displacement, so that the true error of every edge point is
known.

Examples
--------
>>> walls = office_walls(200, 160)
>>> plan = draw_walls((160, 200), walls)
>>> built = office_walls(200, 160, partition_shift=(4.0, 0.0))
>>> u = wall_displacement((160, 200), walls, built)
>>> sorted(set(u[..., 0].round(6).ravel().tolist()))
[0.0, 4.0]

The true local error of a wall point of the built map, aligned by the identity:

>>> X = np.array([[68.5, 30.5]])        # right face of the partition, built 4 px right
>>> true_errors(X, np.array([[1.0, 0.0]]), np.eye(3), plan, u).round(6).tolist()
[4.0]
"""

from __future__ import annotations

from dataclasses import dataclass, replace

import cv2
import numpy as np

from ..core.geometry import apply, invert_displacement
from ..core.grid import FREE, OCCUPIED, UNKNOWN

__all__ = [
    "Wall",
    "cluttered",
    "office_walls",
    "draw_walls",
    "wall_displacement",
    "gaussian_field",
    "affine_field",
    "bump_field",
    "min_jacobian",
    "deform",
    "true_errors",
]


@dataclass(frozen=True)
class Wall:
    """An axis-aligned wall segment from (x0, y0) to (x1, y1), ``thickness`` px, with doors.

    ``doors`` are (start, stop) intervals along the wall (pixels from its start)
    left open. ``outer`` marks the building outline (free space is inside it).
    """

    x0: float
    y0: float
    x1: float
    y1: float
    thickness: int = 3
    doors: tuple[tuple[float, float], ...] = ()
    outer: bool = False

    @property
    def vertical(self) -> bool:
        return abs(self.x1 - self.x0) < abs(self.y1 - self.y0)

    def moved(self, shift: float) -> Wall:
        """The wall moved perpendicular to itself by ``shift`` px (+x or +y).

        Parameters
        ----------
        shift : float
            Pixels.

        Returns
        -------
        Wall
        """
        if self.vertical:
            return replace(self, x0=self.x0 + shift, x1=self.x1 + shift)
        return replace(self, y0=self.y0 + shift, y1=self.y1 + shift)


def office_walls(
    width: int,
    height: int,
    margin: int = 15,
    thickness: int = 3,
    *,
    corridor_shift: tuple[float, float] = (0.0, 0.0),
    partition_shift: tuple[float, float] = (0.0, 0.0),
) -> list[Wall]:
    """An outline, a corridor and six rooms (doors included) in a ``width x height`` image.

    ``corridor_shift`` moves the two corridor walls (y, px) and ``partition_shift``
    the two room partitions (x, px); the walls attached to them follow (they are
    lengthened or shortened), as in a building built with walls out of place.
    Walls are in a fixed order: outline (4), corridor (2), partitions (4).

    Parameters
    ----------
    width, height : int
        Image size in pixels.
    margin : int
        Distance of the outline from the image border, pixels.
    thickness : int
        Wall thickness, pixels.
    corridor_shift : (float, float)
        Moves of the two corridor walls along y, pixels.
    partition_shift : (float, float)
        Moves of the two room partitions along x, pixels.

    Returns
    -------
    list of Wall
        10 walls in the order above.
    """
    x0, y0, x1, y1 = margin, margin, width - margin, height - margin
    # deliberately asymmetric: a symmetric plan has several equally good alignments
    cy = [y0 + f * (y1 - y0) + d for f, d in zip((0.36, 0.53), corridor_shift, strict=True)]
    xs = [x0 + f * (x1 - x0) + d for f, d in zip((0.28, 0.63), partition_shift, strict=True)]
    t = thickness
    walls = [
        Wall(x0, y0, x1, y0, t, outer=True),
        Wall(x0, y1, x1, y1, t, outer=True),
        Wall(x0, y0, x0, y1, t, outer=True),
        Wall(x1, y0, x1, y1, t, outer=True),
    ]
    door = 0.12 * (x1 - x0) / 3
    for yc in cy:
        doors = tuple(
            (xd - x0 - door / 2, xd - x0 + door / 2)
            for xd in ((x0 + xs[0]) / 2, (xs[0] + xs[1]) / 2, (xs[1] + x1) / 2)
        )
        walls.append(Wall(x0, yc, x1, yc, t, doors=doors))
    for xc in xs:
        walls.append(Wall(xc, y0, xc, cy[0], t))
        walls.append(Wall(xc, cy[1], xc, y1, t))
    return walls


def _wall_mask(shape: tuple[int, int], w: Wall) -> np.ndarray:
    m = np.zeros(shape, np.uint8)
    h = (w.thickness - 1) / 2.0
    if w.vertical:
        ys, ye = sorted((w.y0, w.y1))
        r0, r1 = int(round(ys - h)), int(round(ye + h)) + 1
        c0 = int(round(w.x0 - h))
        m[max(r0, 0) : r1, max(c0, 0) : c0 + w.thickness] = 1
        for a, b in w.doors:
            m[int(round(ys + a)) : int(round(ys + b)), :] = 0
    else:
        xs, xe = sorted((w.x0, w.x1))
        c0, c1 = int(round(xs - h)), int(round(xe + h)) + 1
        r0 = int(round(w.y0 - h))
        m[max(r0, 0) : r0 + w.thickness, max(c0, 0) : c1] = 1
        for a, b in w.doors:
            m[:, int(round(xs + a)) : int(round(xs + b))] = 0
    return m.astype(bool)


def draw_walls(shape: tuple[int, int], walls: list[Wall]) -> np.ndarray:
    """Occupancy map (0/127/255) of walls: free inside the outline, unknown outside.

    Parameters
    ----------
    shape : (H, W)
        Image size.
    walls : list of Wall
        From :func:`office_walls` (outline walls marked ``outer``).

    Returns
    -------
    (H, W) uint8 array
    """
    outer = [w for w in walls if w.outer]
    data = np.full(shape, UNKNOWN, np.uint8)
    if outer:
        xs = [v for w in outer for v in (w.x0, w.x1)]
        ys = [v for w in outer for v in (w.y0, w.y1)]
        data[int(round(min(ys))) : int(round(max(ys))) + 1,
             int(round(min(xs))) : int(round(max(xs))) + 1] = FREE  # fmt: skip
    for w in walls:
        data[_wall_mask(shape, w)] = OCCUPIED
    return data


def wall_displacement(shape: tuple[int, int], planned: list[Wall], built: list[Wall]) -> np.ndarray:
    """(H, W, 2) true displacement (x, y) of every wall cell of the ``built`` map.

    Wall ``i`` of ``built`` is wall ``i`` of ``planned`` moved perpendicular to
    itself; its cells carry that move (lengthening along the wall is not an
    error). Where walls cross, the least-moved one wins.

    Parameters
    ----------
    shape : (H, W)
        Image size.
    planned, built : list of Wall
        The same walls (same order) as planned and as built.

    Returns
    -------
    (H, W, 2) float array
        Zero off the walls.

    Examples
    --------
    >>> u = wall_displacement((240, 300), office_walls(300, 240),
    ...                       office_walls(300, 240, corridor_shift=(4, 0)))
    >>> float(np.abs(u[..., 1]).max())
    4.0
    """
    u = np.zeros((*shape, 2))
    best = np.full(shape, np.inf)
    for wp, wb in zip(planned, built, strict=True):
        d = (wb.x0 - wp.x0, 0.0) if wb.vertical else (0.0, wb.y0 - wp.y0)
        m = _wall_mask(shape, wb) & (best > abs(d[0]) + abs(d[1]))
        u[m] = d
        best[m] = abs(d[0]) + abs(d[1])
    return u


def gaussian_field(
    shape: tuple[int, int],
    centre: tuple[float, float],
    amplitude: tuple[float, float],
    sigma: float,
) -> np.ndarray:
    """(H, W, 2) smooth field ``amplitude * exp(-|p - centre|^2 / 2 sigma^2)`` at cell centres.

    Parameters
    ----------
    shape : (H, W)
        Image size.
    centre : (x, y)
        Centre of the bump, pixels.
    amplitude : (ax, ay)
        Displacement at the centre, pixels.
    sigma : float
        Width, pixels.

    Returns
    -------
    (H, W, 2) float array

    Examples
    --------
    >>> f = gaussian_field((50, 60), (30.5, 25.5), (2.0, -1.0), 8.0)  # cell (25, 30) centre
    >>> f[25, 30].tolist()
    [2.0, -1.0]
    """
    H, W = shape
    yy, xx = np.mgrid[0:H, 0:W] + 0.5
    g = np.exp(-((xx - centre[0]) ** 2 + (yy - centre[1]) ** 2) / (2 * sigma**2))
    return np.stack([amplitude[0] * g, amplitude[1] * g], axis=-1)


def affine_field(
    shape: tuple[int, int],
    *,
    rotation_deg: float = 0.0,
    translation: tuple[float, float] = (0.0, 0.0),
    scale: tuple[float, float] = (1.0, 1.0),
    shear: float = 0.0,
    centre: tuple[float, float] | None = None,
) -> np.ndarray:
    """(H, W, 2) displacement of a global affine map about ``centre`` (appendix Table 2).

    The map ``p -> c + R S H (p - c) + t`` with ``S = diag(scale)``, ``H`` the shear
    ``[[1, shear], [0, 1]]`` and ``R`` the rotation, as a displacement ``u(p)`` at the
    cell centres: the rigid (rotation + translation) and the global scale/shear errors
    of the appendix paper's synthetic maps (its section 5.1).

    Parameters
    ----------
    shape : (H, W)
        Image size.
    rotation_deg : float
        Rotation, degrees (counter-clockwise in x right, y down pixels: clockwise on screen).
    translation : (tx, ty)
        Pixels.
    scale : (sx, sy)
        Global scale along x and y.
    shear : float
        Global shear of x by y.
    centre : (x, y), optional
        Fixed point of the linear part (default the image centre).

    Returns
    -------
    (H, W, 2) float array

    Examples
    --------
    >>> u = affine_field((40, 60), translation=(2.0, -1.0))
    >>> u[0, 0].tolist(), u[39, 59].tolist()
    ([2.0, -1.0], [2.0, -1.0])
    >>> u = affine_field((40, 60), scale=(1.1, 1.1), centre=(0.5, 0.5))
    >>> [round(v, 6) for v in u[0, 10].tolist()]      # 10 px right of the centre
    [1.0, 0.0]
    """
    H, W = shape
    cx, cy = centre if centre is not None else (W / 2, H / 2)
    a = np.deg2rad(rotation_deg)
    R = np.array([[np.cos(a), -np.sin(a)], [np.sin(a), np.cos(a)]])
    A = R @ np.diag(scale) @ np.array([[1.0, shear], [0.0, 1.0]])
    yy, xx = np.mgrid[0:H, 0:W] + 0.5
    px, py = xx - cx, yy - cy
    ux = A[0, 0] * px + A[0, 1] * py - px + translation[0]
    uy = A[1, 0] * px + A[1, 1] * py - py + translation[1]
    return np.stack([ux, uy], axis=-1)


def bump_field(
    shape: tuple[int, int],
    amplitude: float,
    sigma: float,
    count: int,
    rng: np.random.Generator,
    margin: float = 0.15,
) -> np.ndarray:
    """(H, W, 2) local shear: ``count`` seeded Gaussian bumps of random direction.

    Each bump is :func:`gaussian_field` with its centre uniform in the image (``margin``
    of each side left out), its displacement of length ``amplitude`` px in a uniform
    random direction and width ``sigma`` px; the bumps add up. Low and high local shear
    of the appendix paper's synthetic maps (Table 2) are two amplitudes.

    Parameters
    ----------
    shape : (H, W)
        Image size.
    amplitude : float
        Displacement at each bump's centre, pixels.
    sigma : float
        Bump width, pixels.
    count : int
        Number of bumps.
    rng : numpy.random.Generator
        Source of the centres and directions.
    margin : float
        Share of the width/height on each side where no centre falls.

    Returns
    -------
    (H, W, 2) float array

    Examples
    --------
    >>> f = bump_field((50, 60), 3.0, 10.0, 2, np.random.default_rng(0))
    >>> f.shape, bool(np.abs(f).max() <= 6.0)
    ((50, 60, 2), True)
    """
    H, W = shape
    out = np.zeros((H, W, 2))
    for _ in range(count):
        cx = rng.uniform(margin, 1 - margin) * W
        cy = rng.uniform(margin, 1 - margin) * H
        ang = rng.uniform(0, 2 * np.pi)
        out += gaussian_field(shape, (cx, cy), (amplitude * np.cos(ang), amplitude * np.sin(ang)),
                              sigma)  # fmt: skip
    return out


def min_jacobian(field: np.ndarray) -> float:
    """Smallest determinant of the Jacobian of ``p -> p + field(p)`` (> 0: no folding).

    A field that folds (determinant <= 0) has no true error; one that squeezes walls
    (determinant well below 1) leaves walls too thin to have two faces.

    Parameters
    ----------
    field : (H, W, 2) float array
        Displacement (x, y), pixels.

    Returns
    -------
    float

    Examples
    --------
    >>> round(min_jacobian(affine_field((20, 20), scale=(0.5, 1.0))), 6)
    0.5
    """
    dxx, dxy = np.gradient(field[..., 0], axis=1), np.gradient(field[..., 0], axis=0)
    dyx, dyy = np.gradient(field[..., 1], axis=1), np.gradient(field[..., 1], axis=0)
    return float(((1 + dxx) * (1 + dyy) - dxy * dyx).min())


def deform(
    data: np.ndarray, field: np.ndarray, iterations: int = 8
) -> tuple[np.ndarray, np.ndarray]:
    """Move every cell ``p`` of a map to ``p + u(p)`` (nearest-neighbour resampling).

    ``field`` is the (H, W, 2) forward displacement ``u`` at the cell centres of
    ``data``. The inverse mapping is found by fixed-point iteration. Returns the
    deformed map and the displacement each deformed cell actually carries: from the
    centre of the cell of ``data`` it was copied from to its own centre (whole
    pixels, as nearest-neighbour resampling realises the field) — the true error of
    every cell of the deformed map.

    Parameters
    ----------
    data : (H, W) uint8 array
        The map values.
    field : (H, W, 2) float array
        Forward displacement ``u`` (x, y) in pixels.
    iterations : int
        Fixed-point iterations of the inverse mapping.

    Returns
    -------
    deformed : (H, W) uint8 array
    carried : (H, W, 2) float array
        Displacement (x, y) each deformed cell carries, whole pixels.
    """
    H, W = data.shape
    yy, xx = np.mgrid[0:H, 0:W].astype(np.float32) + 0.5
    ux = field[..., 0].astype(np.float32)
    uy = field[..., 1].astype(np.float32)
    # p = q - u(p): the inverse as the parametric model finds it, every step taken
    px, py = invert_displacement(
        ux, uy, max(iterations - 1, 0), 0.0, 1.0, origin=0.5, planar=True
    )
    # nearest-neighbour resampling, explicitly, so that the copied cell is known
    ci = np.floor(px).astype(np.int64)
    ri = np.floor(py).astype(np.int64)
    ok = (ri >= 0) & (ri < H) & (ci >= 0) & (ci < W)
    out = np.full((H, W), UNKNOWN, np.uint8)
    out[ok] = data[ri[ok], ci[ok]]
    return out, np.stack([xx - (ci + 0.5), yy - (ri + 0.5)], axis=-1)


def _plan_surface(
    P: np.ndarray, normals: np.ndarray, plan: np.ndarray, max_steps: int
) -> tuple[np.ndarray, np.ndarray]:
    """The plan wall face over each source cell ``P``, and the axis step towards its free side.

    From the (occupied) plan cell ``P`` walk along the dominant axis of the normal,
    towards the free side, while the next cell is occupied (at most ``max_steps``
    cells: a wall end seen edge-on would otherwise be walked along its length).
    Returns the face point (the edge between the last occupied cell and the free
    one, continuous pixel coordinates) and the unit axis step.
    """
    H, W = plan.shape
    n = np.asarray(normals, float)
    ax = (np.abs(n[:, 1]) > np.abs(n[:, 0])).astype(int)
    step = np.zeros_like(n)
    step[np.arange(len(n)), ax] = np.sign(n[np.arange(len(n)), ax])
    B = P.copy()
    walking = np.ones(len(P), bool)
    for _ in range(max_steps):
        nxt = B + step
        r = np.clip(np.floor(nxt[:, 1]).astype(int), 0, H - 1)
        c = np.clip(np.floor(nxt[:, 0]).astype(int), 0, W - 1)
        walking &= plan[r, c] == OCCUPIED
        B = np.where(walking[:, None], nxt, B)
    # a walk that never left the wall is a wall end seen along its length: the cell
    # itself is the best guess of its face
    B = np.where(walking[:, None], P, B)
    return B + 0.5 * step, step


def true_errors(
    X: np.ndarray,
    normals: np.ndarray,
    T: np.ndarray,
    plan: np.ndarray,
    u: np.ndarray,
    field: np.ndarray | None = None,
    *,
    max_steps: int = 6,
) -> np.ndarray:
    """Signed true local error of wall points of a deformed map, across their wall (px).

    ``X`` are wall points (cell centres) of the deformed map, ``normals`` their unit
    normals towards free space, ``T`` the 3x3 transform that aligns the deformed map
    to the ``plan`` (the metric's rigid alignment; errors are measured from
    ``T(X)``), ``u`` the displacement every deformed cell carries (from
    :func:`wall_displacement` or :func:`deform`) and ``field`` the forward field
    given to :func:`deform`, if that made the map.

    The truth is the displacement of the wall *face*, not of the cell: ``X`` lies
    on the face of a wall of the deformed map, and that face is the image of the
    plan face ``S`` found from the cell ``X - u`` it was copied from
    (:func:`_plan_surface`). Without a field the whole wall moved by ``u``; with one
    the face moved to ``S + field(S)`` (bilinear). Without one the face is where the
    deformed map draws it, the edge of ``X`` towards free space. The error is the
    distance of the aligned face from the plan's wall, ``(T(face) - S) . a``, with
    ``a`` the plan wall's normal (the axis of ``normals``, as the synthetic plans'
    walls are axis-aligned). Points without a normal (zero rows: a one-pixel wall
    seen from both sides) get the distance of ``T(X)`` from the cell ``X - u``. The cell
    ``X - u`` itself is not the truth: nearest-neighbour resampling of a field that
    varies across a wall thins or thickens the wall, and the face cell of the
    deformed map can be copied from inside the plan's wall, one pixel from its face.

    Parameters
    ----------
    X : (N, 2) float array
        Wall points (cell centres) of the deformed map, pixels.
    normals : (N, 2) float array
        Their unit normals towards free space (zero rows: none).
    T : (3, 3) array
        Transform aligning the deformed map to the plan.
    plan : (H, W) uint8 array
        The plan's values.
    u : (H, W, 2) float array
        Displacement every deformed cell carries.
    field : (H, W, 2) float array, optional
        The forward field given to :func:`deform`.
    max_steps : int
        Cells searched across the wall for the plan face.

    Returns
    -------
    (N,) float array
        Signed errors in pixels.
    """
    X = np.asarray(X, float)
    n = np.asarray(normals, float)
    H, W = plan.shape
    r = np.clip(np.floor(X[:, 1]).astype(int), 0, H - 1)
    c = np.clip(np.floor(X[:, 0]).astype(int), 0, W - 1)
    S, step = _plan_surface(X - u[r, c], n, plan, max_steps)
    if field is None:
        moved = X + 0.5 * step  # the face as drawn on the deformed map
    else:
        mx = (S[:, 0] - 0.5).astype(np.float32)[None]
        my = (S[:, 1] - 0.5).astype(np.float32)[None]
        f = [
            cv2.remap(field[..., k].astype(np.float32), mx, my, cv2.INTER_LINEAR,
                      borderMode=cv2.BORDER_REPLICATE)[0]
            for k in (0, 1)
        ]  # fmt: skip
        moved = S + np.column_stack(f)
    err = ((apply(T, moved) - S) * step).sum(1)
    # a point without a normal (a one-pixel wall with free space on both sides) has no
    # face: its error is the distance of the cell from the one it was copied from
    none = ~step.any(1)
    err[none] = np.hypot(*(apply(T, X[none]) - (X[none] - u[r[none], c[none]])).T)
    return err


def cluttered(plan: np.ndarray, seed: int = 0, n: int = 80) -> np.ndarray:
    """The plan as a robot maps it: ``n`` furniture blocks (3-8 px) on free cells, 1 % of
    free cells occupied (clutter), and walls grown into noisy clouds (half the cells
    beside a wall occupied). Seeded: the same plan and seed give the same map.

    Examples
    --------
    >>> plan = draw_walls((60, 80), office_walls(80, 60))
    >>> m = cluttered(plan, seed=1)
    >>> bool((m == 0).sum() > (plan == 0).sum()), bool(np.array_equal(m, cluttered(plan, 1)))
    (True, True)
    """
    from ..core.grid import FREE, OCCUPIED

    rng = np.random.default_rng(seed)
    m = plan.copy()
    free = np.argwhere(m == FREE)
    for _ in range(n):
        r, c = free[rng.integers(len(free))]
        h, w = rng.integers(3, 9, 2)
        m[r : r + h, c : c + w] = OCCUPIED
    m[(m == FREE) & (rng.random(m.shape) < 0.01)] = OCCUPIED
    thick = cv2.dilate((m == OCCUPIED).astype(np.uint8), np.ones((3, 3), np.uint8)) > 0
    m[thick & (rng.random(m.shape) < 0.5)] = OCCUPIED
    return m
