"""Planar transforms as 3x3 homogeneous matrices, and their least-squares fits.

Every transform in :mod:`map2map.evaluate` is a 3x3 matrix ``T`` acting on pixel
coordinates ``(x, y, 1)`` (x = column, y = row, origin top-left): ``p' = T @ p``.
The fits below are the building blocks of the alignment chains of the appendix
paper (section 3.2): the similarity of the preliminary alignment, its affine
refinement, and the Euclidean (rigid) transform ``ET`` of the anchoring, eqs. 2
and 5.

Examples
--------
>>> import numpy as np
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
    "apply",
    "similarity_matrix",
    "decompose_similarity",
    "fit_similarity",
    "fit_rigid",
    "fit_affine",
    "affine_distortion",
    "transform_normals",
]


def apply(T: np.ndarray, pts: np.ndarray) -> np.ndarray:
    """Apply a 3x3 transform to (N, 2) points (x, y); returns (N, 2) floats."""
    pts = np.asarray(pts, float).reshape(-1, 2)
    return pts @ T[:2, :2].T + T[:2, 2]


def similarity_matrix(scale: float, angle: float, tx: float, ty: float) -> np.ndarray:
    """``[[s cos, -s sin, tx], [s sin, s cos, ty], [0, 0, 1]]`` (angle in radians)."""
    c, s = scale * math.cos(angle), scale * math.sin(angle)
    return np.array([[c, -s, tx], [s, c, ty], [0.0, 0.0, 1.0]])


def decompose_similarity(T: np.ndarray) -> tuple[float, float, float, float]:
    """(scale, angle, tx, ty) of the similarity closest to ``T`` (its linear part's mean)."""
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

    With ``scale`` given the scale is held fixed and the fit is Euclidean (rotation
    and translation only): this is ``ET`` of eqs. 2 and 5 when ``scale=1``.
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
    """Weighted least-squares Euclidean transform (rotation + translation), ``ET`` of eq. 2."""
    return fit_similarity(src, dst, weights, scale=1.0)


def fit_affine(src: np.ndarray, dst: np.ndarray, weights: np.ndarray | None = None) -> np.ndarray:
    """Weighted least-squares affine ``dst ~ A src + t`` (needs 3 non-collinear points)."""
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
    """
    A = T[:2, :2]
    sv = np.linalg.svd(A, compute_uv=False)
    scale = float(math.sqrt(abs(np.linalg.det(A))))
    aniso = float(sv[0] / max(sv[1], 1e-12) - 1.0)
    c0, c1 = A[:, 0], A[:, 1]
    shear = float(abs(c0 @ c1) / max(np.linalg.norm(c0) * np.linalg.norm(c1), 1e-12))
    return scale, aniso, shear


def transform_normals(T: np.ndarray, normals: np.ndarray) -> np.ndarray:
    """Unit normals (N, 2) carried by ``T`` (inverse transpose); zero rows stay zero."""
    n = np.asarray(normals, float).reshape(-1, 2)
    m = n @ np.linalg.inv(T[:2, :2])
    norm = np.hypot(m[:, 0], m[:, 1])
    out = np.zeros_like(m)
    ok = (norm > 0) & (np.hypot(n[:, 0], n[:, 1]) > 0)
    out[ok] = m[ok] / norm[ok, None]
    return out
