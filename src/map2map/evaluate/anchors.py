"""Anchoring, eqs. 1-6, and automatic anchors (the appendix paper's future work).

Section 3.2.2: two anchor points ``P_s1, P_s2`` of the source (SLAM) map and their
counterparts ``P_d1, P_d2`` in the plan are given. The source anchors are mapped by
the preliminary alignment (eq. 1, eq. 4 for its rigid variant); the Euclidean
transform ``ET`` that best maps them onto the plan anchors in the least-squares
sense (eqs. 2 and 5) is composed after the alignment (eqs. 3 and 6)::

    tform_align,anch       = tform_anch       . tform_align          (3)
    tform_align,anch,rigid = tform_anch,rigid . tform_align,rigid    (6)

Automatic anchoring replaces the manual choice: distinctive corners of the source
(Shi-Tomasi "good features to track") are mapped by the alignment, each is matched
locally in the plan by normalised cross-correlation of a patch, and the two
well-matched corners farthest apart become the anchors.

Examples
--------
>>> import numpy as np
>>> T_align = np.eye(3); T_align[0, 2] = 5.0            # alignment off by 5 px in x
>>> Ps = np.array([[0.0, 0.0], [100.0, 0.0]])
>>> Pd = np.array([[0.0, 0.0], [100.0, 0.0]])
>>> anchor(T_align, Ps, Pd).round(6).tolist()         # eq. 3 removes the offset
[[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]]
"""

from __future__ import annotations

import csv
import os

import cv2
import numpy as np

from ..core.errors import InputError
from ..core.geometry import apply, fit_rigid
from ..core.grid import OCCUPIED

__all__ = ["Anchors", "anchor", "read_anchors", "validate_anchors", "auto_anchors"]

#: header of an anchors CSV file
ANCHOR_COLUMNS = ("x_source", "y_source", "x_target", "y_target")


class Anchors(tuple):
    """``(P_s (2, 2), P_d (2, 2))``: source and target anchor points, x/y in pixels."""

    __slots__ = ()

    def __new__(cls, source: np.ndarray, target: np.ndarray):
        return super().__new__(cls, (np.asarray(source, float), np.asarray(target, float)))

    @property
    def source(self) -> np.ndarray:
        return self[0]

    @property
    def target(self) -> np.ndarray:
        return self[1]


def anchor(T_align: np.ndarray, P_s: np.ndarray, P_d: np.ndarray) -> np.ndarray:
    """Eqs. 1-3 (or 4-6 with a rigid ``T_align``): ``ET(T_align(P_s), P_d) . T_align``."""
    P_sa = apply(T_align, P_s)  # eq. 1 / eq. 4
    T_anch = fit_rigid(P_sa, np.asarray(P_d, float))  # eq. 2 / eq. 5
    return T_anch @ T_align  # eq. 3 / eq. 6


def read_anchors(path: str | os.PathLike) -> Anchors:
    """Read an anchors CSV (header ``x_source,y_source,x_target,y_target``, >= 2 rows)."""
    try:
        with open(path, newline="") as fh:
            rows = list(csv.reader(fh))
    except OSError as exc:
        raise InputError(path, f"cannot read anchors file ({exc.strerror})") from None
    except UnicodeDecodeError:
        raise InputError(path, "anchors file is not a text CSV file") from None
    rows = [r for r in rows if any(cell.strip() for cell in r)]
    if not rows or tuple(c.strip() for c in rows[0]) != ANCHOR_COLUMNS:
        raise InputError(
            path, "anchors file must start with the header " + ",".join(ANCHOR_COLUMNS)
        )
    values = []
    for i, r in enumerate(rows[1:], start=2):
        if len(r) != 4:
            raise InputError(path, f"line {i}: expected 4 values, got {len(r)}")
        try:
            v = [float(c) for c in r]
        except ValueError:
            raise InputError(path, f"line {i}: values must be numbers") from None
        if not np.all(np.isfinite(v)):
            raise InputError(path, f"line {i}: values must be finite")
        values.append(v)
    if len(values) < 2:
        raise InputError(path, f"need at least two anchor pairs, got {len(values)}")
    a = np.array(values)
    return Anchors(a[:, :2], a[:, 2:])


def validate_anchors(
    anchors: Anchors,
    source_shape: tuple[int, int],
    target_shape: tuple[int, int],
    source_name: str | os.PathLike = "anchors",
    *,
    min_separation: float = 1.0,
) -> None:
    """Raise :class:`InputError` for anchors outside the maps or coincident anchor points."""
    for pts, (h, w), which in (
        (anchors.source, source_shape, "source"),
        (anchors.target, target_shape, "target"),
    ):
        bad = (pts[:, 0] < 0) | (pts[:, 0] > w) | (pts[:, 1] < 0) | (pts[:, 1] > h)
        if bad.any():
            i = int(np.flatnonzero(bad)[0])
            raise InputError(
                source_name,
                f"anchor {i + 1}: {which} point ({pts[i, 0]:g}, {pts[i, 1]:g}) lies outside the "
                f"{which} map ({w} x {h} px)",
            )
        d = np.hypot(*(pts[:, None, :] - pts[None, :, :]).transpose(2, 0, 1))
        d[np.diag_indices(len(pts))] = np.inf
        if d.min() < min_separation:
            i, j = np.unravel_index(int(np.argmin(d)), d.shape)
            raise InputError(
                source_name,
                f"anchors {i + 1} and {j + 1} have identical {which} points; "
                "choose two distant corners",
            )


def auto_anchors(
    source: np.ndarray,
    target: np.ndarray,
    T: np.ndarray,
    *,
    patch: int = 24,
    search: int = 12,
    min_score: float = 0.6,
    max_corners: int = 60,
) -> Anchors | None:
    """Two anchor pairs found automatically, or None when no reliable pair exists.

    Corners of the source walls (``cv2.goodFeaturesToTrack``) are mapped by ``T``;
    around each, a ``2 patch + 1`` px patch of the source, warped by ``T``, is
    matched against the plan within ``+-search`` px (``cv2.matchTemplate``,
    normalised correlation coefficient of blurred wall masks). Of the matches
    scoring at least ``min_score``, the two farthest apart are returned.
    """
    occ_s = (source == OCCUPIED).astype(np.float32)
    occ_t = cv2.GaussianBlur((target == OCCUPIED).astype(np.float32), (0, 0), 1.0)
    corners = cv2.goodFeaturesToTrack(
        cv2.GaussianBlur(occ_s, (0, 0), 1.0), max_corners, 0.05, 2 * patch, blockSize=7
    )
    if corners is None or len(corners) < 2:
        return None
    ps = corners.reshape(-1, 2).astype(float) + 0.5
    qs = apply(T, ps)
    h, w = target.shape
    good_s, good_d = [], []
    size = 2 * patch + 1
    for p, q in zip(ps, qs, strict=True):
        x0, y0 = int(round(q[0])) - patch, int(round(q[1])) - patch
        if x0 - search < 0 or y0 - search < 0 or x0 + size + search > w or y0 + size + search > h:
            continue
        # warp the source into a patch of the target frame whose corner is (x0, y0)
        shift = np.array([[1.0, 0, -x0], [0, 1.0, -y0], [0, 0, 1.0]]) @ T
        tpl = cv2.warpAffine(occ_s, shift[:2], (size, size), flags=cv2.INTER_LINEAR)
        tpl = cv2.GaussianBlur(tpl, (0, 0), 1.0)
        if tpl.std() < 1e-3:
            continue
        region = occ_t[y0 - search : y0 + size + search, x0 - search : x0 + size + search]
        res = cv2.matchTemplate(region, tpl, cv2.TM_CCOEFF_NORMED)
        _, score, _, loc = cv2.minMaxLoc(res)
        if score < min_score:
            continue
        dx, dy = loc[0] - search, loc[1] - search
        good_s.append(p)
        good_d.append(q + (dx, dy))
    if len(good_s) < 2:
        return None
    S, D = np.array(good_s), np.array(good_d)
    dist = np.hypot(*(S[:, None, :] - S[None, :, :]).transpose(2, 0, 1))
    i, j = np.unravel_index(int(np.argmax(dist)), dist.shape)
    if dist[i, j] < 4 * patch:
        return None
    return Anchors(S[[i, j]], D[[i, j]])
