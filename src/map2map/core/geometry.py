"""Planar geometry used across map2map, each piece written once.

* angles: :func:`wrap_angle`;
* robot poses ``(x, y, theta)``: :func:`compose_pose` (``a (+) b``), :func:`relative_pose`
  (``a^-1 (+) b``) and :func:`invert_pose` -- GMapping's ``absoluteSum`` and
  ``absoluteDifference``, used by the simulator, both SLAM backends and the log readers;
* 3x3 homogeneous transforms of pixel coordinates ``(x, y, 1)`` (x = column, y = row,
  origin top-left), ``p' = T @ p``: :func:`apply`, :func:`similarity_matrix`,
  :func:`decompose_similarity`, and the weighted least-squares fits
  :func:`fit_similarity` (Umeyama 1991, 2-D closed form), :func:`fit_rigid` (the
  Euclidean ``ET`` of paper eqs. 2 and 5) and :func:`fit_affine`, with
  :func:`affine_distortion` and :func:`transform_normals` -- the building blocks of the
  alignment chains of the appendix paper (paper sec. 3.2) and of the trajectory error
  (ATE) of :mod:`map2map.slam.quality`;
* points against line segments: :func:`point_segment_distances` (the wall inspection's
  nearest wall, the plan drawer's free wall ends) and :func:`segment_samples` (a sample a
  pixel along each segment: the plan drawer's cuts, its curved walls' replaced chords);
* displacement fields (thesis sec. 3.2, "(d_x, d_y) used to deform the map"):
  :func:`invert_displacement` finds, for every output pixel ``q``, the source ``p`` with
  ``p + d(p) = q``; the parametric model (:mod:`map2map.parametric.field`) and the
  synthetic test maps (:mod:`map2map.maps.synthetic`) both warp with it.

Examples
--------
>>> import numpy as np
>>> round(wrap_angle(3 * np.pi / 2), 12)
-1.570796326795
>>> a = (1.0, 2.0, np.pi / 2)
>>> [round(v, 12) + 0.0 for v in compose_pose(a, (1.0, 0.0, 0.0))]
[1.0, 3.0, 1.570796326795]
>>> [round(v, 12) + 0.0 for v in relative_pose(a, compose_pose(a, (0.5, 0.2, 0.1)))]
[0.5, 0.2, 0.1]
>>> T = similarity_matrix(scale=2.0, angle=np.pi / 2, tx=10.0, ty=0.0)
>>> apply(T, np.array([[1.0, 0.0]])).round(6).tolist()
[[10.0, 2.0]]
>>> P = np.array([[0.0, 0.0], [10.0, 0.0], [0.0, 5.0]])
>>> np.allclose(fit_similarity(P, apply(T, P)), T)
True
"""

from __future__ import annotations

import math

import numpy as np

__all__ = [
    "wrap_angle",
    "compose_pose",
    "relative_pose",
    "invert_pose",
    "apply",
    "similarity_matrix",
    "decompose_similarity",
    "fit_similarity",
    "fit_rigid",
    "fit_affine",
    "affine_distortion",
    "transform_normals",
    "point_segment_distances",
    "segment_samples",
    "invert_displacement",
]

_TWO_PI = 2 * math.pi


# ------------------------------------------------------------------------ angles
def wrap_angle(a, *, keep_in_range: bool = False):
    """Angle(s) wrapped into ``[-pi, pi)``.

    Parameters
    ----------
    a : float or array_like
        Angle(s) in radians.
    keep_in_range : bool
        Return values already in ``[-pi, pi)`` unchanged, bit for bit (``(a + pi) % 2 pi
        - pi`` may change their last bits). Trajectories and the parametric model use it.

    Returns
    -------
    float or ndarray
        A Python float for a Python scalar (computed with plain float arithmetic, so it
        is usable in hot scalar loops), else an array of the input's shape.

    Examples
    --------
    >>> wrap_angle(math.pi)
    -3.141592653589793
    >>> wrap_angle(np.array([0.5, 7.0]), keep_in_range=True).round(6).tolist()
    [0.5, 0.716815]
    """
    if keep_in_range:
        a = np.asarray(a, float)
        return np.where((a >= -np.pi) & (a < np.pi), a, (a + np.pi) % (2 * np.pi) - np.pi)
    if isinstance(a, float | int):
        return (a + math.pi) % _TWO_PI - math.pi
    return (np.asarray(a) + np.pi) % (2 * np.pi) - np.pi


# ------------------------------------------------------------------------- poses
def _scalar_pose(p) -> bool:
    return not isinstance(p, np.ndarray)


def compose_pose(a, b):
    """Pose composition ``a (+) b``: ``b`` given in the frame of ``a``, expressed in ``a``'s parent.

    Parameters
    ----------
    a, b : (x, y, theta) tuples, or arrays of shape (..., 3)
        Poses in metres and radians. Arrays compose row-wise with broadcasting
        (GMapping ``absoluteSum``).

    Returns
    -------
    tuple of float or ndarray
        A tuple when both inputs are tuples/lists (plain float arithmetic), else an
        array of shape (..., 3). Headings are wrapped into ``[-pi, pi)``.

    Examples
    --------
    >>> compose_pose((1.0, 0.0, 0.0), (2.0, 1.0, 0.5))
    (3.0, 1.0, 0.5)
    >>> compose_pose(np.zeros((2, 3)), np.array([1.0, 0.0, 0.0])).tolist()
    [[1.0, 0.0, 0.0], [1.0, 0.0, 0.0]]
    """
    if _scalar_pose(a) and _scalar_pose(b):
        ca, sa = math.cos(a[2]), math.sin(a[2])
        return (
            a[0] + ca * b[0] - sa * b[1],
            a[1] + sa * b[0] + ca * b[1],
            wrap_angle(a[2] + b[2]),
        )
    p = np.asarray(a, float)
    d = np.asarray(b, float)
    c, s = np.cos(p[..., 2]), np.sin(p[..., 2])
    return np.stack(
        [
            p[..., 0] + c * d[..., 0] - s * d[..., 1],
            p[..., 1] + s * d[..., 0] + c * d[..., 1],
            wrap_angle(p[..., 2] + d[..., 2]),
        ],
        axis=-1,
    )


def relative_pose(a, b):
    """Pose ``b`` expressed in the frame of pose ``a``: ``a^-1 (+) b``.

    Parameters
    ----------
    a, b : (x, y, theta) tuples, or arrays of shape (..., 3)
        Arrays are taken row-wise (GMapping ``absoluteDifference(b, a)``).

    Returns
    -------
    tuple of float or ndarray
        A tuple for tuple inputs, else an array of shape (..., 3) (with ``-0.0``
        turned into ``0.0``).

    Examples
    --------
    >>> relative_pose((0.0, 1.0, math.pi / 2), (1.0, 1.0, math.pi / 2))[1]
    -1.0
    >>> relative_pose(np.array([0.0, 1.0, np.pi / 2]), np.array([1.0, 1.0, np.pi / 2])).round(9)
    array([ 0., -1.,  0.])
    """
    if _scalar_pose(a) and _scalar_pose(b):
        dx, dy = b[0] - a[0], b[1] - a[1]
        ca, sa = math.cos(a[2]), math.sin(a[2])
        return (ca * dx + sa * dy, -sa * dx + ca * dy, wrap_angle(b[2] - a[2]))
    p1 = np.asarray(b, float)
    p2 = np.asarray(a, float)
    dx = p1[..., 0] - p2[..., 0]
    dy = p1[..., 1] - p2[..., 1]
    c, s = np.cos(p2[..., 2]), np.sin(p2[..., 2])
    out = np.stack([c * dx + s * dy, -s * dx + c * dy, wrap_angle(p1[..., 2] - p2[..., 2])], -1)
    return out + 0.0


def invert_pose(a):
    """The inverse pose ``a^-1`` (so that ``compose_pose(a, invert_pose(a))`` is the identity).

    Parameters
    ----------
    a : (x, y, theta) tuple, or array of shape (..., 3)
        Pose(s), angle in radians.

    Returns
    -------
    tuple of float or ndarray
        The inverse pose(s), shaped like ``a`` (see :func:`relative_pose`).

    Examples
    --------
    >>> [round(v, 12) + 0.0 for v in invert_pose((1.0, 0.0, math.pi / 2))]
    [0.0, 1.0, -1.570796326795]
    """
    zero = (0.0, 0.0, 0.0) if _scalar_pose(a) else np.zeros_like(np.asarray(a, float))
    return relative_pose(a, zero)


# -------------------------------------------------------------------- transforms
def apply(T: np.ndarray, pts: np.ndarray) -> np.ndarray:
    """Apply a 3x3 transform to (N, 2) points ``(x, y)``; returns (N, 2) floats.

    Parameters
    ----------
    T : (3, 3) array-like
        Homogeneous 2-D transform (similarity, rigid or affine).
    pts : (N, 2) array-like
        Points ``(x, y)``.

    Returns
    -------
    (N, 2) ndarray of float
        ``T`` applied to every point.

    Examples
    --------
    >>> apply(np.eye(3), [[1, 2]]).tolist()
    [[1.0, 2.0]]
    """
    pts = np.asarray(pts, float).reshape(-1, 2)
    return pts @ T[:2, :2].T + T[:2, 2]


def similarity_matrix(scale: float, angle: float, tx: float, ty: float) -> np.ndarray:
    """``[[s cos, -s sin, tx], [s sin, s cos, ty], [0, 0, 1]]`` (angle in radians).

    Parameters
    ----------
    scale : float
        Isotropic scale ``s``.
    angle : float
        Rotation in radians.
    tx, ty : float
        Translation.

    Returns
    -------
    (3, 3) ndarray

    Examples
    --------
    >>> similarity_matrix(1.0, 0.0, 2.0, 3.0)[:2, 2].tolist()
    [2.0, 3.0]
    """
    c, s = scale * math.cos(angle), scale * math.sin(angle)
    return np.array([[c, -s, tx], [s, c, ty], [0.0, 0.0, 1.0]])


def decompose_similarity(T: np.ndarray) -> tuple[float, float, float, float]:
    """(scale, angle, tx, ty) of the similarity closest to ``T`` (its linear part's mean).

    Parameters
    ----------
    T : (3, 3) array-like
        A similarity, or a transform close to one.

    Returns
    -------
    scale, angle, tx, ty : float
        Angle in radians.

    Examples
    --------
    >>> [round(v, 9) for v in decompose_similarity(similarity_matrix(2.0, 0.5, 1.0, 0.0))]
    [2.0, 0.5, 1.0, 0.0]
    """
    a = 0.5 * (T[0, 0] + T[1, 1])
    b = 0.5 * (T[1, 0] - T[0, 1])
    return math.hypot(a, b), math.atan2(b, a), float(T[0, 2]), float(T[1, 2])


def _weights(w, n: int) -> np.ndarray:
    w = np.ones(n) if w is None else np.asarray(w, float).reshape(-1)
    if w.shape[0] != n:
        raise ValueError("weights must have one entry per point")
    return w


def fit_similarity(
    src: np.ndarray,
    dst: np.ndarray,
    weights: np.ndarray | None = None,
    *,
    scale: float | None = None,
) -> np.ndarray:
    """Weighted least-squares similarity ``dst ~ s R src + t`` (Umeyama 1991, no reflection).

    Parameters
    ----------
    src, dst : (N, 2) array_like
        Matched points, N >= 2.
    weights : (N,) array_like, optional
        Non-negative weights (default: all 1).
    scale : float, optional
        Hold the scale fixed: the fit is then Euclidean (rotation and translation only),
        ``ET`` of paper eqs. 2 and 5 when ``scale=1``.

    Returns
    -------
    (3, 3) ndarray
        The transform ``T`` with ``dst ~ apply(T, src)``.

    Raises
    ------
    ValueError
        Fewer than two points with positive weight, or weights of the wrong length.

    Examples
    --------
    >>> P = np.array([[0.0, 0.0], [2.0, 0.0]])
    >>> fit_similarity(P, P * 3).round(9)[:2].tolist()
    [[3.0, -0.0, 0.0], [0.0, 3.0, 0.0]]
    """
    src = np.asarray(src, float).reshape(-1, 2)
    dst = np.asarray(dst, float).reshape(-1, 2)
    w = _weights(weights, len(src))
    sw = w.sum()
    if len(src) < 2 or sw <= 0:
        raise ValueError("need at least two weighted point pairs")
    mu_s = (w[:, None] * src).sum(0) / sw
    mu_d = (w[:, None] * dst).sum(0) / sw
    a = src - mu_s
    b = dst - mu_d
    # cross terms of sum w (b . R a): rotation angle in closed form (2-D Umeyama)
    sxx = (w * (a[:, 0] * b[:, 0] + a[:, 1] * b[:, 1])).sum()
    sxy = (w * (a[:, 0] * b[:, 1] - a[:, 1] * b[:, 0])).sum()
    angle = math.atan2(sxy, sxx)
    if scale is None:
        var = (w * (a**2).sum(1)).sum()
        scale = math.hypot(sxx, sxy) / var if var > 0 else 1.0
    T = similarity_matrix(scale, angle, 0.0, 0.0)
    T[:2, 2] = mu_d - T[:2, :2] @ mu_s
    return T


def fit_rigid(src: np.ndarray, dst: np.ndarray, weights: np.ndarray | None = None) -> np.ndarray:
    """Weighted least-squares Euclidean transform (rotation + translation), ``ET`` of paper eq. 2.

    Parameters
    ----------
    src, dst : (N, 2) array-like
        Corresponding points, ``dst ~ R src + t``.
    weights : (N,) array-like, optional
        Non-negative weights; default equal.

    Returns
    -------
    (3, 3) ndarray
        The rigid transform (scale fixed to 1) minimising the weighted squared residuals.

    Examples
    --------
    >>> P = np.array([[0.0, 0.0], [1.0, 0.0], [0.0, 1.0]])
    >>> fit_rigid(P, P + 5).round(9)[:2, 2].tolist()
    [5.0, 5.0]
    """
    return fit_similarity(src, dst, weights, scale=1.0)


def fit_affine(src: np.ndarray, dst: np.ndarray, weights: np.ndarray | None = None) -> np.ndarray:
    """Weighted least-squares affine ``dst ~ A src + t`` (needs 3 non-collinear points).

    Parameters
    ----------
    src, dst : (N, 2) array-like
        Corresponding points, N >= 3 and not collinear.
    weights : (N,) array-like, optional
        Non-negative weights; default equal.

    Returns
    -------
    (3, 3) ndarray
        The affine transform minimising the weighted squared residuals.

    Examples
    --------
    >>> P = np.array([[0.0, 0.0], [1.0, 0.0], [0.0, 1.0]])
    >>> (fit_affine(P, P * [2, 1]).round(9)[:2, :2] + 0.0).tolist()
    [[2.0, 0.0], [0.0, 1.0]]
    """
    src = np.asarray(src, float).reshape(-1, 2)
    dst = np.asarray(dst, float).reshape(-1, 2)
    w = np.sqrt(_weights(weights, len(src)))
    X = np.column_stack([src, np.ones(len(src))]) * w[:, None]
    sol, *_ = np.linalg.lstsq(X, dst * w[:, None], rcond=None)
    T = np.eye(3)
    T[:2, :] = sol.T
    return T


def affine_distortion(T: np.ndarray) -> tuple[float, float, float]:
    """(scale, anisotropy, shear) of the linear part of ``T``.

    ``scale`` is sqrt(|det|); ``anisotropy`` is the ratio of the singular values
    minus one; ``shear`` is |cos| of the angle between the transformed axes. A
    similarity gives ``(s, 0, 0)``.

    Parameters
    ----------
    T : (3, 3) array-like
        A 2-D affine transform.

    Returns
    -------
    scale, anisotropy, shear : float

    Examples
    --------
    >>> [round(v, 9) for v in affine_distortion(similarity_matrix(2.0, 0.3, 0, 0))]
    [2.0, 0.0, 0.0]
    """
    A = T[:2, :2]
    sv = np.linalg.svd(A, compute_uv=False)
    scale = float(math.sqrt(abs(np.linalg.det(A))))
    aniso = float(sv[0] / max(sv[1], 1e-12) - 1.0)
    c0, c1 = A[:, 0], A[:, 1]
    shear = float(abs(c0 @ c1) / max(np.linalg.norm(c0) * np.linalg.norm(c1), 1e-12))
    return scale, aniso, shear


def transform_normals(T: np.ndarray, normals: np.ndarray) -> np.ndarray:
    """Unit normals (N, 2) carried by ``T`` (inverse transpose); zero rows stay zero.

    Parameters
    ----------
    T : (3, 3) array-like
        The transform that carries the points.
    normals : (N, 2) array-like
        Normals at those points; zero rows mean "no normal".

    Returns
    -------
    (N, 2) ndarray
        Unit normals after ``T``.

    Examples
    --------
    >>> transform_normals(similarity_matrix(3.0, 0.0, 0, 0), [[1.0, 0.0], [0, 0]]).tolist()
    [[1.0, 0.0], [0.0, 0.0]]
    """
    n = np.asarray(normals, float).reshape(-1, 2)
    m = n @ np.linalg.inv(T[:2, :2])
    norm = np.hypot(m[:, 0], m[:, 1])
    out = np.zeros_like(m)
    ok = (norm > 0) & (np.hypot(n[:, 0], n[:, 1]) > 0)
    out[ok] = m[ok] / norm[ok, None]
    return out


def point_segment_distances(points: np.ndarray, segs: np.ndarray
                            ) -> tuple[np.ndarray, np.ndarray]:
    """Distance from every point to every segment, and where along it the nearest point
    lies (0 at the segment's start, 1 at its end).

    Parameters
    ----------
    points : (N, 2) array-like
    segs : (K, 4) array-like
        ``x0, y0, x1, y1``; a segment of zero length is its start point.

    Returns
    -------
    dist, t : (N, K) ndarray

    Examples
    --------
    >>> d, t = point_segment_distances([[5.0, 3.0], [-4.0, 0.0]], [[0.0, 0.0, 10.0, 0.0]])
    >>> d.ravel().tolist(), t.ravel().tolist()
    ([3.0, 4.0], [0.5, 0.0])
    """
    p = np.asarray(points, float).reshape(-1, 1, 2)
    s = np.asarray(segs, float).reshape(-1, 4)
    a, d = s[:, :2], s[:, 2:] - s[:, :2]
    ll = np.maximum((d**2).sum(1), 1e-12)
    t = np.clip(((p - a) * d).sum(2) / ll, 0.0, 1.0)
    q = a + t[..., None] * d
    return np.hypot(*(p - q).transpose(2, 0, 1)), t


# ------------------------------------------------------------ displacement fields
def segment_samples(segs: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """One sample a pixel along each segment ``x0, y0, x1, y1`` (both ends included):
    the samples' segment, their fraction of the way from the segment's start, their
    points, and the samples per segment.

    >>> idx, f, p, n = segment_samples(np.array([[0.0, 0.0, 2.0, 0.0], [0.0, 0.0, 0.0, 1.0]]))
    >>> idx.tolist(), f.tolist(), n.tolist()
    ([0, 0, 0, 1, 1], [0.0, 0.5, 1.0, 0.0, 1.0], [3, 2])
    >>> p[1].tolist()
    [1.0, 0.0]
    """
    segs = np.asarray(segs, float).reshape(-1, 4)
    d = segs[:, 2:] - segs[:, :2]
    n = np.ceil(np.hypot(d[:, 0], d[:, 1])).astype(np.int64) + 1
    idx = np.repeat(np.arange(len(segs)), n)
    start = np.repeat(np.cumsum(n) - n, n)
    f = (np.arange(len(idx)) - start) / np.maximum(n[idx] - 1, 1)
    return idx, f, segs[idx, :2] + f[:, None] * d[idx], n


def invert_displacement(
    dx: np.ndarray,
    dy: np.ndarray,
    iterations: int = 8,
    tol: float = 0.01,
    settled: float = 0.999,
    *,
    origin: float = 0.0,
    planar: bool = False,
) -> tuple[np.ndarray, np.ndarray]:
    """Source coordinates ``(px, py)`` with ``p + d(p) = q`` for every pixel ``q`` of a field.

    Fixed-point iteration ``p <- q - d(p)`` (``d`` sampled bilinearly with
    :func:`cv2.remap`, border replicated) started at ``p = q - d(q)``; it converges where
    the field is a contraction (``|grad d| < 1``, true of smooth SLAM-like deformations).
    It stops after ``iterations`` steps or when a fraction ``settled`` of the pixels
    moved less than ``tol`` pixels in the last step (where the field jumps or folds
    there is no exact inverse and the iteration keeps oscillating there).

    Parameters
    ----------
    dx, dy : (H, W) float32
        Displacement in pixels of every pixel: ``x`` = columns (right), ``y`` = rows (down).
    iterations : int
        Most steps after the start.
    tol, settled : float
        Early stop: fraction ``settled`` of the pixels moved less than ``tol`` px
        (``tol=0, settled=1``: every step is taken unless nothing moves).
    origin : float
        Coordinates of pixel ``(0, 0)``: 0 for pixel indices, 0.5 for cell centres.
    planar : bool
        Sample with two float coordinate maps (one per axis) instead of one packed
        two-channel map; OpenCV quantises the two differently, so results differ in
        the last bits. The parametric model uses packed maps, the synthetic test maps
        planar ones; each keeps its outputs bit for bit.

    Returns
    -------
    px, py : (H, W) float32
        Source column and row of every output pixel, in the coordinates of ``origin``.

    Examples
    --------
    >>> px, py = invert_displacement(np.full((3, 4), 1.5, np.float32), np.zeros((3, 4), np.float32))
    >>> px[0].tolist()
    [-1.5, -0.5, 0.5, 1.5]
    """
    import cv2

    h, w = dx.shape
    q = np.dstack(np.mgrid[0:h, 0:w][::-1]).astype(np.float32)  # (h, w, 2): x, y
    if origin:
        q = q + np.float32(origin)
    d = np.dstack([dx, dy]).astype(np.float32, copy=False)
    p = q - d
    limit = (1.0 - settled) * h * w
    for _ in range(iterations):
        at = p - np.float32(origin) if origin else p  # pixel indices, as remap samples
        if planar:
            ax, ay = at[..., 0], at[..., 1]
            dp = np.dstack(
                [cv2.remap(c, ax, ay, cv2.INTER_LINEAR, borderMode=cv2.BORDER_REPLICATE)
                 for c in (d[..., 0], d[..., 1])]
            )  # fmt: skip
        else:
            dp = cv2.remap(d, at, None, cv2.INTER_LINEAR, borderMode=cv2.BORDER_REPLICATE)
        new = q - dp
        moving = np.count_nonzero(np.abs(new - p) > tol)  # components: >= moving pixels
        p = new
        if moving <= limit:
            break
    return np.ascontiguousarray(p[..., 0]), np.ascontiguousarray(p[..., 1])
