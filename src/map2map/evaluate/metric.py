"""The local error metric, Algorithm 1, and the global IoU.

Section 3.2.4 of the appendix paper. The plan's distance transform comes with a
*label* array: every cell carries the index of its nearest occupied cell. The
paper turns it into a table ``Matches`` of (cell, nearest wall cell) rows and
looks the optimised points ``X_optimised`` up in it (lines 1-13); the distance
transform's index array *is* that table, addressed directly, so the look-up is
O(1) per point (``scipy.ndimage.distance_transform_edt(return_indices=True)``).
The correspondence ``X_corr`` of each point is the plan wall cell nearest to its
optimised position (on the wall side it faces, see :mod:`.nonrigid`); points
optimised off the plan correspond to themselves (line 11). The local error of a
point is the distance between its rigidly aligned position ``X_rigid`` and
``X_corr``; the mean and the max of those errors (lines 14-15), times the
resolution, are the reported errors.

Two chains (Fig. 1): the *nonrigid* chain optimises the affinely aligned points
(``X_optimised -> X_corr``), the *rigid* chain the rigidly aligned ones
(``X_optimised,rigid -> X_corr,rigid``); both measure from ``X_rigid``. The paper's
rule picks the nonrigid chain when the map is globally scaled or sheared, the rigid
one otherwise (:func:`choose_chain`).

Examples
--------
>>> import numpy as np
>>> from map2map.evaluate.nonrigid import SideFields
>>> plan = np.full((50, 50), 255, np.uint8); plan[:, 20] = 0
>>> fields = SideFields.from_map(plan, 0.0)
>>> X_rigid = np.array([[26.5, 10.5], [26.5, 30.5]])    # a wall mapped 6 px right
>>> X_opt = X_rigid - [6.0, 0.0]                       # optimisation moved it back
>>> err = local_errors(X_rigid, X_opt, fields)
>>> err.distances.tolist(), err.summary(0.05)["mean_m"]
([6.0, 6.0], 0.3)
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .nonrigid import SideFields, to_plane
from .transforms import affine_distortion, decompose_similarity

__all__ = ["ChainErrors", "local_errors", "choose_chain", "iou"]


@dataclass
class ChainErrors:
    """Per-point errors of one chain (target pixels) and the points behind them."""

    X_rigid: np.ndarray
    X_optimised: np.ndarray
    X_corr: np.ndarray
    distances: np.ndarray
    corner: np.ndarray | None = None

    @property
    def valid(self) -> np.ndarray:
        """Points counted in the statistics (all but corners)."""
        if self.corner is None:
            return np.ones(len(self.distances), bool)
        return ~self.corner

    def summary(self, resolution: float | None) -> dict[str, float | str | None]:
        """Mean and max error in pixels, and in metres when ``resolution`` is known.

        Corner points (see :func:`local_errors`: corners, wall ends and junctions,
        whose nearest-wall correspondence is ambiguous) are left out of every
        statistic and counted; ``max_all_px`` is the max over all points, corners
        included, for reference, and ``excluded`` says in words what was left out.
        """
        d = self.distances[self.valid]
        mean_px = float(d.mean()) if d.size else float("nan")
        max_px = float(d.max()) if d.size else float("nan")
        out: dict[str, float | str | None] = {
            "mean_px": mean_px,
            "max_px": max_px,
            "median_px": float(np.median(d)) if d.size else float("nan"),
            "p95_px": float(np.percentile(d, 95)) if d.size else float("nan"),
            "max_all_px": float(self.distances.max()) if self.distances.size else float("nan"),
            "points": int(d.size),
            "corner_points_excluded": int(len(self.distances) - d.size),
            "excluded": "points whose wall normal is more than 18 deg off the plan's wall "
            "axes (corners, wall ends, junctions: ambiguous correspondence) are left out "
            "of mean, max, median and p95; max_all_px includes them",
        }
        out["mean_m"] = None if resolution is None else round(mean_px * resolution, 12)
        out["max_m"] = None if resolution is None else round(max_px * resolution, 12)
        return out


def local_errors(
    X_rigid: np.ndarray,
    X_optimised: np.ndarray,
    fields: SideFields,
    normals: np.ndarray | None = None,
    *,
    corner_band: float = np.radians(27.0),
) -> ChainErrors:
    """Algorithm 1: ``Dist_i = |X_rigid,i - X_corr,i|`` with ``X_corr`` from the DT labels.

    With ``normals`` (unit, plan frame, zero where unknown) the optimised motion of
    each point is first projected on its wall normal: a nearest-wall correspondence
    cannot observe motion *along* a wall, and the coherence of eq. 7 drags wall
    points sideways near junctions with moved walls (the "shifted correspondences"
    of the paper's Fig. 9); the projection removes that spurious part. Likewise
    ``X_corr`` is taken on the line through ``X_rigid`` along the normal of the plan
    surface it was matched to (point-to-plane distance to the plan's wall), so that
    neither the pixel rounding along the wall nor a tilt of the map's wall (a wall
    bent by drift) shortens or lengthens the error. Points whose
    normal points diagonally between the plan's wall axes (within
    ``corner_band`` radians of 45 degrees, i.e. more than 18 degrees off both
    axes by default) are corners, wall ends and wall junctions, where the edge
    normal mixes two walls and the nearest-wall correspondence is ambiguous; they
    are flagged in ``corner`` and left out of the statistics, the max included
    (they are the outliers of the paper's Fig. 9). With a 20 degree band a
    junction point tilted 24 degrees set the max of a wall moved by 4 px to
    4.46 px (+12%); with 27 degrees the max of all ten known-error cases of
    ``benchmarks/metric_accuracy.py`` is within 5% of the truth.
    """
    X_rigid = np.asarray(X_rigid, float)
    X_optimised = np.asarray(X_optimised, float)
    if normals is not None:
        n = np.asarray(normals, float)
        has = np.hypot(n[:, 0], n[:, 1]) > 0.5
        d = X_optimised - X_rigid
        along = (d * n).sum(1, keepdims=True) * n
        X_optimised = np.where(has[:, None], X_rigid + along, X_optimised)
    near, d_side, inside = fields.nearest(X_optimised, normals)
    if normals is not None:
        # a point optimised onto a plan wall belongs to that wall: when the surface of
        # its side is farther than the wall's thickness beyond the nearest wall cell,
        # its normal is a pixel step of the map's wall (a wall shifted by a pixel has
        # short faces across it), not a face of its own; it takes the nearest wall
        # cell, the paper's plain label (with a 4 px plan wall one such step once set
        # the max to 49 px on a wall its truth has at 0.3 px)
        near_any, d_any, _ = fields.nearest(X_optimised)
        step = (d_any <= 1.5) & (d_side > d_any + fields.wall_thickness + 1.0)
        near = np.where(step[:, None], near_any, near)
    X_corr = np.where(inside[:, None], near, X_optimised)  # line 11: no match -> itself
    if normals is not None:
        # distance across the plan's wall (point to plane, the plane of the plan surface
        # the point was matched to): X_corr is a pixel centre, its rounding along the
        # wall (up to half a pixel) is no error, and neither is a tilt of the map's wall
        m = fields.side_normals(n)
        X_corr = to_plane(X_rigid, X_corr, np.where(has[:, None], m, n))
    dist = np.hypot(*(X_rigid - X_corr).T)
    corner = None
    if normals is not None:
        ang = np.mod(np.arctan2(n[:, 1], n[:, 0]) - fields.theta, np.pi / 2)
        corner = has & (np.abs(ang - np.pi / 4) < corner_band)
    return ChainErrors(X_rigid, X_optimised, X_corr, dist, corner)


def choose_chain(
    similarity: np.ndarray,
    affine: np.ndarray,
    rigid_scale: float = 1.0,
    *,
    tolerance: float = 0.02,
) -> tuple[str, str]:
    """The paper's rule: ``"nonrigid"`` if global scale or shear is present, else ``"rigid"``.

    Scale is present when the similarity's scale differs from ``rigid_scale`` by more
    than ``tolerance`` (relative); shear when the affine refinement's anisotropy or
    shear exceeds it. Returns the chain and the reason in words.
    """
    s = decompose_similarity(similarity)[0]
    _, aniso, shear = affine_distortion(affine)
    reasons = []
    if abs(s / rigid_scale - 1.0) > tolerance:
        reasons.append(f"global scale {s / rigid_scale:.3f}")
    if max(aniso, shear) > tolerance:
        reasons.append(f"global shear (anisotropy {aniso:.3f}, shear {shear:.3f})")
    if reasons:
        return "nonrigid", " and ".join(reasons) + " present"
    return "rigid", "no global scale or shear"


def iou(a: np.ndarray, b: np.ndarray) -> float:
    """Intersection over union of two boolean masks (nan when both are empty)."""
    a = np.asarray(a, bool)
    b = np.asarray(b, bool)
    union = np.logical_or(a, b).sum()
    return float(np.logical_and(a, b).sum() / union) if union else float("nan")
