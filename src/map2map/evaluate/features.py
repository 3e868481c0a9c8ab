"""Point features of an occupancy map: occupied points, Canny edge points and their sides.

The alignment works on the occupied cells of the source (``X_GFT`` of the appendix
paper, section 3.2.1); the optimisation and the error metric work on its edge
points ``X`` (Canny, section 3.2.2). Every edge point also gets the direction of
the free space it faces (its *side*), so that the two faces of a wall are never
confused with each other when points are matched to the plan.

Examples
--------
>>> import numpy as np
>>> from map2map.core.grid import OccupancyMap
>>> data = np.full((20, 20), 255, np.uint8); data[:, 10:12] = 0
>>> pts, normals = edge_points(data)
>>> sorted(set(pts[:, 0].tolist()))        # both faces of the wall, columns 10 and 11
[10.5, 11.5]
>>> bool(normals[pts[:, 0] == 10.5, 0].max() < 0)  # column 10 faces the free space on the left
True
"""

from __future__ import annotations

import cv2
import numpy as np

from ..core.grid import FREE, OCCUPIED, UNKNOWN

__all__ = [
    "occupied_points",
    "surface_mask",
    "surface_points",
    "edge_points",
    "downsample",
    "side_masks",
    "subsample",
]


def occupied_points(data: np.ndarray) -> np.ndarray:
    """(N, 2) (x, y) continuous pixel coordinates of the occupied cells' centres, row-major."""
    r, c = np.nonzero(data == OCCUPIED)
    return np.column_stack([c + 0.5, r + 0.5])


def surface_mask(data: np.ndarray) -> np.ndarray:
    """Occupied cells with a free cell among their 8 neighbours: the walls' surfaces.

    What a range sensor sees of a wall is its surface; the inside of a solid block
    (a HouseExpo plan draws everything outside the rooms occupied, up to the bounding
    box) is no evidence of where a wall is, and scoring it lets one block lie on
    another at any scale. A map whose occupied cells touch no free cell (no free
    space at all) keeps all its occupied cells.
    """
    occ = data == OCCUPIED
    near_free = cv2.dilate((data == FREE).astype(np.uint8), np.ones((3, 3), np.uint8)) > 0
    surf = occ & near_free
    return surf if surf.any() else occ


def surface_points(data: np.ndarray) -> np.ndarray:
    """(N, 2) (x, y) pixel centres of the cells of :func:`surface_mask`, row-major."""
    r, c = np.nonzero(surface_mask(data))
    return np.column_stack([c + 0.5, r + 0.5])


def subsample(pts: np.ndarray, n: int, rng: np.random.Generator | int = 0) -> np.ndarray:
    """At most ``n`` rows of ``pts``, drawn without replacement (deterministic for a seed)."""
    if len(pts) <= n:
        return pts
    rng = np.random.default_rng(rng)
    return pts[np.sort(rng.choice(len(pts), n, replace=False))]


def _normal_field(free: np.ndarray, radius: int = 2) -> tuple[np.ndarray, np.ndarray]:
    """Mean unit vector from each pixel towards the free pixels around it (``radius`` px)."""
    k = 2 * radius + 1
    yy, xx = np.mgrid[-radius : radius + 1, -radius : radius + 1].astype(np.float32)
    rr = np.hypot(xx, yy)
    rr[radius, radius] = 1.0
    kx = np.where(rr <= radius + 0.5, xx / rr, 0).astype(np.float32)
    ky = np.where(rr <= radius + 0.5, yy / rr, 0).astype(np.float32)
    kx[radius, radius] = ky[radius, radius] = 0
    f = free.astype(np.float32)
    # filter2D correlates: sum_k f(p + k) * kx(k) = free-weighted mean offset
    nx = cv2.filter2D(f, -1, kx, borderType=cv2.BORDER_CONSTANT)
    ny = cv2.filter2D(f, -1, ky, borderType=cv2.BORDER_CONSTANT)
    assert kx.shape == (k, k)
    return nx, ny


def edge_points(data: np.ndarray, *, min_normal: float = 0.5) -> tuple[np.ndarray, np.ndarray]:
    """Canny edge points of the walls, on the wall surface, with the free side they face.

    Canny (``cv2.Canny`` on the occupied mask) finds the wall boundaries; each edge
    pixel is snapped to the occupied side (the wall surface itself), and only
    surfaces that touch free space are kept (a wall facing unknown space was not
    seen as a surface). Returns ``(points, normals)``, both (N, 2): the pixel
    centres (x, y) and the unit direction towards the free space, or ``(0, 0)``
    where free space lies on both sides (a one-pixel wall seen from both rooms).
    """
    known = data != UNKNOWN
    rows = np.flatnonzero(known.any(1))
    if rows.size == 0:
        return np.zeros((0, 2)), np.zeros((0, 2))
    cols = np.flatnonzero(known.any(0))
    # work on the known content only (+ a margin wider than the normal kernel)
    r0, c0 = max(0, rows[0] - 6), max(0, cols[0] - 6)
    data = data[r0 : rows[-1] + 7, c0 : cols[-1] + 7]
    occ = (data == OCCUPIED).astype(np.uint8)
    free = data == FREE
    edges = cv2.Canny(occ * 255, 50, 150, L2gradient=True) > 0
    # Canny marks one side of each step (and, by non-maximum suppression, sometimes only
    # one face of a thin wall): grow by two pixels and keep the occupied surface
    band = cv2.dilate(edges.astype(np.uint8), np.ones((5, 5), np.uint8)) > 0
    near_free = cv2.dilate(free.astype(np.uint8), np.ones((3, 3), np.uint8)) > 0
    surface = band & (occ > 0) & near_free
    r, c = np.nonzero(surface)
    nx, ny = _normal_field(free, radius=4)
    n = np.column_stack([nx[r, c], ny[r, c]]).astype(float)
    norm = np.hypot(n[:, 0], n[:, 1])
    # the kernel sums up to ~ 2*radius unit vectors on a straight face; below that, two-sided
    strong = norm >= min_normal
    n[strong] /= norm[strong, None]
    n[~strong] = 0.0
    return np.column_stack([c + c0 + 0.5, r + r0 + 0.5]), n


def side_masks(data: np.ndarray, theta: float) -> list[np.ndarray]:
    """Wall-surface masks of the four sides ``theta + k pi/2`` (k = 0..3).

    Side ``k`` holds the occupied pixels whose neighbour in direction
    ``(cos(theta + k pi/2), sin(theta + k pi/2))`` (rounded to the 8-neighbourhood)
    is free: the one-pixel-thick surfaces that face that way. A thin wall is in two
    opposite sides, a corner in two adjacent ones.
    """
    occ = data == OCCUPIED
    free = data == FREE
    out = []
    for k in range(4):
        a = theta + k * np.pi / 2
        dx, dy = np.cos(a), np.sin(a)
        sx, sy = int(round(dx)), int(round(dy))
        hit = np.zeros_like(free)
        h, w = free.shape
        ys0, ys1 = max(0, -sy), min(h, h - sy)
        xs0, xs1 = max(0, -sx), min(w, w - sx)
        # hit[y, x] = free[y + sy, x + sx]
        hit[ys0:ys1, xs0:xs1] = free[ys0 + sy : ys1 + sy, xs0 + sx : xs1 + sx]
        out.append(occ & hit)
    return out


def downsample(data: np.ndarray, factor: int) -> np.ndarray:
    """Occupancy at ``1/factor`` resolution: occupied if any cell of the block is.

    Free if at least half the block is free and none occupied, unknown otherwise:
    thin walls survive, as the alignment needs them.
    """
    if factor <= 1:
        return data.copy()
    h, w = data.shape
    H, W = -(-h // factor), -(-w // factor)
    pad = np.full((H * factor, W * factor), UNKNOWN, np.uint8)
    pad[:h, :w] = data
    blocks = pad.reshape(H, factor, W, factor)
    occ = (blocks == OCCUPIED).any(axis=(1, 3))
    free = (blocks == FREE).mean(axis=(1, 3)) >= 0.5
    out = np.full((H, W), UNKNOWN, np.uint8)
    out[free] = FREE
    out[occ] = OCCUPIED
    return out
