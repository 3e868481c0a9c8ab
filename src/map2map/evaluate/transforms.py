"""Planar transforms as 3x3 homogeneous matrices, and their least-squares fits.

They live in :mod:`map2map.core.geometry` (one implementation for the whole package);
this module re-exports them under the names :mod:`map2map.evaluate` has always used.

Examples
--------
>>> import numpy as np
>>> T = similarity_matrix(scale=2.0, angle=np.pi / 2, tx=10.0, ty=0.0)
>>> apply(T, np.array([[1.0, 0.0]])).round(6).tolist()
[[10.0, 2.0]]
"""

from __future__ import annotations

from ..core.geometry import (
    affine_distortion,
    apply,
    decompose_similarity,
    fit_affine,
    fit_rigid,
    fit_similarity,
    similarity_matrix,
    transform_normals,
)

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
