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

from ..core.geometry import affine_distortion, decompose_similarity
from .nonrigid import SideFields, to_plane

__all__ = ["ChainErrors", "EXCLUDED_RULE", "local_errors", "summary_lines", "choose_chain", "iou"]


#: in words, what the wall statistics leave out (report.json ``excluded``)
EXCLUDED_RULE = (
    "wall statistics (mean, max, median, p95) count only points matched to a plan wall: "
    "a point is unmatched (clutter: furniture, unplanned structure, stray points) when, "
    "after the optimisation of eq. 7, no plan surface facing its way lies within "
    "match_px of it (3 sigma_f of the last stage, 0.3 m by default) over the plan's known "
    "space; corner points (normal within 10 deg of the diagonal between the plan's wall "
    "axes, of each direction family the plan has, or matched within 1.5 px of a plan "
    "surface across the matched one: ambiguous correspondence) are left out too; the "
    "*_all_px figures count every point"
)


@dataclass
class ChainErrors:
    """Per-point errors of one chain (target pixels) and the points behind them.

    ``corner`` flags points whose correspondence is ambiguous (corners, wall ends,
    junctions), ``unmatched`` points that match no plan wall (clutter or unplanned
    structure); neither counts in the wall statistics.
    """

    X_rigid: np.ndarray
    X_optimised: np.ndarray
    X_corr: np.ndarray
    distances: np.ndarray
    corner: np.ndarray | None = None
    unmatched: np.ndarray | None = None

    @property
    def valid(self) -> np.ndarray:
        """Points counted in the wall statistics (matched, not corners)."""
        ok = np.ones(len(self.distances), bool)
        if self.corner is not None:
            ok &= ~self.corner
        if self.unmatched is not None:
            ok &= ~self.unmatched
        return ok

    def classes(self) -> np.ndarray:
        """Per point ``"wall"``, ``"corner"`` or ``"unmatched"`` (unmatched wins)."""
        out = np.full(len(self.distances), "wall", dtype=object)
        if self.corner is not None:
            out[self.corner] = "corner"
        if self.unmatched is not None:
            out[self.unmatched] = "unmatched"
        return out

    def summary(self, resolution: float | None) -> dict[str, float | str | None]:
        """Wall statistics in pixels (and metres when ``resolution`` is known), and counts.

        ``mean_px``, ``max_px``, ``median_px``, ``p95_px`` describe the points matched
        to a plan wall (:data:`EXCLUDED_RULE`); ``mean_all_px``, ``max_all_px``,
        ``p95_all_px`` every point, unmatched and corners included. ``points`` is the
        number of wall points, ``unmatched_points`` and ``corner_points_excluded`` the
        others, ``unmatched_share`` the unmatched share of all points.
        """
        d = self.distances[self.valid]
        a = self.distances
        nan = float("nan")

        def st(x, f):
            return float(f(x)) if x.size else nan

        n_unm = 0 if self.unmatched is None else int(self.unmatched.sum())
        n_corner = int(len(a) - d.size - n_unm)
        out: dict[str, float | str | None] = {
            "mean_px": st(d, np.mean),
            "max_px": st(d, np.max),
            "median_px": st(d, np.median),
            "p95_px": st(d, lambda x: np.percentile(x, 95)),
            "mean_all_px": st(a, np.mean),
            "max_all_px": st(a, np.max),
            "p95_all_px": st(a, lambda x: np.percentile(x, 95)),
            "points": int(d.size),
            "points_all": int(a.size),
            "unmatched_points": n_unm,
            "unmatched_share": n_unm / a.size if a.size else 0.0,
            "corner_points_excluded": n_corner,
            "excluded": EXCLUDED_RULE,
        }
        for k in ("mean", "max", "median", "p95", "mean_all", "max_all", "p95_all"):
            v = out[f"{k}_px"]
            out[f"{k}_m"] = None if resolution is None else round(v * resolution, 12)
        return out


def local_errors(
    X_rigid: np.ndarray,
    X_optimised: np.ndarray,
    fields: SideFields,
    normals: np.ndarray | None = None,
    *,
    corner_band: float = np.radians(10.0),
    corner_px: float = 1.5,
    match_px: float | None = 6.0,
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
    bent by drift) shortens or lengthens the error.

    Correspondence respects the side a point faces: it is matched only to plan
    surfaces facing its way (:meth:`.SideFields.nearest`). A point that, at its
    optimised position, has no such surface within ``match_px`` pixels (over the
    plan's known space) matches no plan wall: it is *unmatched* (furniture, clutter,
    unplanned structure, a stray point outside the building, or a point whose
    normal disagrees with the wall beside it) and flagged in ``unmatched``, left
    out of the wall statistics (``None`` disables the rule). In the parametric
    demo a point 3.6 px beside a vertical wall, whose normal faced down, was
    matched to a horizontal wall 27 px away and set the max to 145 cm (the field's
    max was 36 cm).

    Corners, wall ends and junctions, where the correspondence is ambiguous, are
    flagged in ``corner``: points whose normal lies within ``corner_band`` of the
    diagonal between the plan's wall axes (the side is a toss-up; with a second
    direction family, of the bisector between the two nearest directions the plan's
    surfaces face, :meth:`.SideFields.corners`), and points whose correspondence
    lies within ``corner_px`` of a plan surface across the one matched (30-150
    degrees off it: perpendicular, with one family; they sit at a plan corner). The
    earlier rule (normal more than 18 degrees off the axes) dropped 2,410 of 7,347
    points of a real office map, whose ragged walls have noisy normals.
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
    step = np.zeros(len(X_rigid), bool)
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
    unmatched = None
    if match_px is not None:
        matched = inside & fields.is_known(X_optimised) & ((d_side <= match_px) | step)
        unmatched = ~matched
    corner = None
    if normals is not None:
        corner = fields.corners(n, corner_band)
        if corner_px > 0:
            # at a plan corner: a surface across the matched one is right there (with
            # one family, the two perpendicular sides)
            g = fields.side_groups(n)
            ox, oy = fields.offset
            h, w = fields.shape
            c = np.floor(X_corr[:, 0] - ox).astype(np.int64)
            r = np.floor(X_corr[:, 1] - oy).astype(np.int64)
            ok = has & ~step & (g < fields.n_sides) & (r >= 0) & (r < h) & (c >= 0) & (c < w)
            meets = fields.across()
            for k in range(fields.n_sides):
                sel = ok & meets[np.minimum(g, fields.n_sides - 1), k]
                d_perp = np.full(len(g), np.inf)
                d_perp[sel] = fields.sides[k][0][r[sel], c[sel]]
                corner |= d_perp <= corner_px
    return ChainErrors(X_rigid, X_optimised, X_corr, dist, corner, unmatched)


def summary_lines(report: dict) -> list[str]:
    """The printed summary of ``map2map evaluate``: every number with its unit.

    One line per chain (the chosen one starred) with the wall statistics, then one
    line with the points that match no plan wall and the figures over all points.
    """
    lines = []
    for chain in ("rigid", "nonrigid"):
        e = report["errors"][chain]
        mark = "*" if chain == report["chosen_chain"] else " "
        line = f"{mark} {chain:<8s} walls: mean {_len(e, 'mean')}, max {_len(e, 'max')}, "
        line += f"p95 {_len(e, 'p95')} ({e['points']} points)"
        lines.append(line)
    e = report["errors"][report["chosen_chain"]]
    lines.append(
        f"  not in the wall statistics: {e['unmatched_points']} unmatched points "
        f"({100 * e['unmatched_share']:.1f}%, clutter or unplanned structure), "
        f"{e['corner_points_excluded']} corner points; all {e['points_all']} points: "
        f"mean {_len(e, 'mean_all')}, max {_len(e, 'max_all')}"
    )
    lines.append(f"chosen: {report['chosen_chain']} ({report['chosen_reason']})")
    return lines


def _len(e: dict, key: str) -> str:
    """``1.23 px (0.062 m)``, or pixels alone without a resolution."""
    px = e[f"{key}_px"]
    m = e.get(f"{key}_m")
    return f"{px:.2f} px" + ("" if m is None else f" ({m:.3f} m)")


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
