"""Alignment hypotheses between two maps, and the rejection of non-similarity ones.

Section 3.2.1 of the appendix paper, after Shahbandi & Magnusson: every pair of
faces (one from each map) proposes the transform that maps the source face's
oriented minimum bounding box onto the target face's, for each of the four ways
the boxes can be laid on each other. A transform whose two axis scales differ (not
a similarity) or whose scale lies outside ``scale_range`` is rejected — in the
paper this removes ~90% of the hypotheses. The rotation is taken from the maps'
dominant orientations (more precise than the box of a partially seen room).

Partially explored rooms make box sizes unreliable, so a second, dense generator
complements the faces: for each candidate rotation (dominant-orientation
difference + k 90 degrees) and each scale on a geometric grid, the translation
maximising the fitness of eq. 8 is found for *all* translations at once by FFT
cross-correlation of the source's occupied cells with the target's fitness map.
Both sets are scored with the same fitness and the best survive.

Examples
--------
>>> from map2map.evaluate.decomposition import Face
>>> fs = [Face(1, 100.0, (10.0, 10.0), (20.0, 10.0), 90.0)]
>>> ft = [Face(1, 400.0, (50.0, 40.0), (40.0, 20.0), 90.0)]
>>> hyps, stats = face_hypotheses(fs, 0.0, ft, 0.0)
>>> stats
{'face_pairs': 1, 'proposed': 4, 'rejected': 2}
>>> from map2map.core.geometry import apply
>>> apply(hyps[0].T, [[10.0, 10.0]]).round(6).tolist()   # centre onto centre, scale 2
[[50.0, 40.0]]
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from scipy import fft as sfft

from ..core.geometry import apply, decompose_similarity, similarity_matrix, wrap_angle
from .decomposition import Face

__all__ = ["Hypothesis", "face_hypotheses", "dense_hypotheses", "suppress_duplicates"]


@dataclass
class Hypothesis:
    """A candidate transform (3x3, source -> target pixels), where it came from, its fitness."""

    T: np.ndarray
    origin: str
    score: float = 0.0


def face_hypotheses(
    faces_s: list[Face],
    theta_s: float,
    faces_t: list[Face],
    theta_t: float,
    *,
    scale_range: tuple[float, float] = (0.5, 2.0),
    max_anisotropy: float = 0.25,
) -> tuple[list[Hypothesis], dict[str, int]]:
    """Similarity hypotheses from every pair of faces (OMBB onto OMBB).

    For the rotation ``theta_t - theta_s + k pi/2`` (k = 0..3) the source box's
    extents along its map's wall axes are laid onto the target box's (swapped for
    odd k); the two axis scales must agree within ``max_anisotropy`` (relative)
    and their geometric mean lie in ``scale_range``. Returns the hypotheses and
    counts ``{'face_pairs', 'proposed', 'rejected'}``.
    """
    out: list[Hypothesis] = []
    proposed = rejected = 0
    lo, hi = scale_range
    ext_s = [f.extents(theta_s) for f in faces_s]
    ext_t = [f.extents(theta_t) for f in faces_t]
    for k in range(4):
        angle = theta_t - theta_s + k * np.pi / 2
        for fs, (us, vs) in zip(faces_s, ext_s, strict=True):
            if k % 2:
                us, vs = vs, us
            for ft, (ut, vt) in zip(faces_t, ext_t, strict=True):
                proposed += 1
                su, sv = ut / max(us, 1e-9), vt / max(vs, 1e-9)
                scale = math.sqrt(su * sv)
                if abs(su / sv - 1.0) > max_anisotropy or not lo <= scale <= hi:
                    rejected += 1
                    continue
                T = similarity_matrix(scale, angle, 0.0, 0.0)
                T[:2, 2] = np.asarray(ft.centre) - apply(T, [fs.centre])[0]
                out.append(Hypothesis(T, "face"))
    stats = {"face_pairs": len(faces_s) * len(faces_t), "proposed": proposed, "rejected": rejected}
    return out, stats


def _rasterise(pts: np.ndarray) -> tuple[np.ndarray, float, float]:
    """Count image of points (x, y) and the (x0, y0) of its cell (0, 0)."""
    x0, y0 = np.floor(pts.min(0))
    c = np.floor(pts[:, 0] - x0).astype(np.int64)
    r = np.floor(pts[:, 1] - y0).astype(np.int64)
    img = np.zeros((r.max() + 1, c.max() + 1), np.float64)
    np.add.at(img, (r, c), 1.0)
    return img, float(x0), float(y0)


def dense_hypotheses(
    src_pts: np.ndarray,
    Mf: np.ndarray,
    rotations: np.ndarray,
    scales: np.ndarray,
    *,
    peaks_per_pose: int = 2,
) -> list[Hypothesis]:
    """Best translations for every (rotation, scale) by FFT correlation with ``M_f``.

    ``score`` is the fitness of eq. 8 of the hypothesis, evaluated exactly for all
    integer translations at once: ``sum_p M_f(R s p + t) / N``.
    """
    n = len(src_pts)
    H, W = Mf.shape
    out: list[Hypothesis] = []
    if n == 0:
        return out
    centre = src_pts.mean(0)
    radius = float(np.hypot(*(src_pts - centre).T).max())
    side = int(np.ceil(2 * radius * float(np.max(scales)))) + 3
    # one FFT of the fitness map serves every pose (common padded shape)
    shape = (sfft.next_fast_len(H + side - 1), sfft.next_fast_len(W + side - 1))
    F = sfft.rfft2(Mf, shape)
    for angle in rotations:
        for s in scales:
            T = similarity_matrix(float(s), float(angle), 0.0, 0.0)
            T[:2, 2] = -T[:2, :2] @ centre
            img, x0, y0 = _rasterise(apply(T, src_pts))
            h, w = img.shape
            # correlation: corr[k, l] = sum_ij Mf[i + k - (h-1), j + l - (w-1)] img[i, j]
            G = sfft.rfft2(img[::-1, ::-1], shape)
            corr = sfft.irfft2(F * G, shape)[: H + h - 1, : W + w - 1]
            flat = corr.ravel()
            k = min(peaks_per_pose * 8, flat.size)
            best = np.argpartition(flat, -k)[-k:]
            best = best[np.argsort(flat[best])[::-1]]
            taken: list[tuple[int, int]] = []
            for b in best:
                r, c = divmod(int(b), corr.shape[1])
                if any(abs(r - r2) <= 2 and abs(c - c2) <= 2 for r2, c2 in taken):
                    continue
                taken.append((r, c))
                dy, dx = r - (h - 1), c - (w - 1)
                Th = T.copy()
                Th[:2, 2] += (dx - x0, dy - y0)
                out.append(Hypothesis(Th, "dense", float(flat[b]) / n))
                if len(taken) >= peaks_per_pose:
                    break
    return out


def suppress_duplicates(
    hyps: list[Hypothesis], *, translation: float = 4.0, angle: float = 0.05, scale: float = 0.04
) -> list[Hypothesis]:
    """Keep the best-scoring of hypotheses that are near-identical (sorted by score)."""
    kept: list[Hypothesis] = []
    params: list[tuple[float, float, float, float]] = []
    for h in sorted(hyps, key=lambda h: -h.score):
        s, a, tx, ty = decompose_similarity(h.T)
        dup = False
        for s2, a2, tx2, ty2 in params:
            da = abs(wrap_angle(a - a2))
            if (
                da < angle
                and abs(math.log(s / s2)) < scale
                and math.hypot(tx - tx2, ty - ty2) < translation
            ):
                dup = True
                break
        if not dup:
            kept.append(h)
            params.append((s, a, tx, ty))
    return kept
