"""The metric against the truth: maps with known errors, evaluated and scored.

The appendix paper validates its error metric (Algorithm 1) on synthetic SLAM maps made
from ground-truth plans by known transformations (its section 5.1 and Table 2: rigid
motion with low and high local shear, and global scale/shear). Here the truth is known
exactly: :mod:`map2map.maps.synthetic` returns the displacement every deformed cell
carries, and :func:`map2map.maps.synthetic.true_errors` turns it into the true local
error of every wall point of the deformed map, measured from the metric's own rigid
alignment. :func:`known_error_case` evaluates a deformed map against its plan and puts
the metric's mean and max beside the true ones, for both chains (each chain over the
points it counts). :func:`table2_cases` builds the appendix Table 2 set.

Used by ``map2map.experiments.metric_accuracy`` and ``map2map reproduce``.

Examples
--------
>>> from map2map.maps.synthetic import draw_walls, office_walls, wall_displacement
>>> walls = office_walls(300, 240, thickness=4)
>>> built = office_walls(300, 240, thickness=4, corridor_shift=(4.0, 0.0))
>>> plan = draw_walls((240, 300), walls)
>>> u = wall_displacement((240, 300), walls, built)
>>> c = known_error_case("corridor 4 px", plan, draw_walls((240, 300), built), u)
>>> c.chosen, round(c.true["rigid"]["max_px"]), round(c.reported["rigid"]["max_px"])
('rigid', 4, 4)
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from ..core.geometry import decompose_similarity
from ..core.grid import OccupancyMap
from ..maps.synthetic import (
    affine_field,
    bump_field,
    deform,
    min_jacobian,
    true_errors,
)
from .pipeline import EvaluateParams, Evaluation, evaluate_maps

__all__ = ["KnownErrorCase", "known_error_case", "Table2Spec", "TABLE2", "table2_cases"]

CHAINS = ("nonrigid", "rigid")


@dataclass
class KnownErrorCase:
    """A map with known errors, evaluated: reported and true mean/max per chain (px).

    ``reported[chain]`` and ``true[chain]`` hold ``mean_px`` and ``max_px`` over the
    points the chain counts (matched wall points, corners left out); ``chosen`` is the
    chain the metric's rule picked; ``rotation_deg`` the rigid alignment's rotation.
    """

    name: str
    chosen: str
    reported: dict[str, dict[str, float]]
    true: dict[str, dict[str, float]]
    rotation_deg: float
    points: int
    evaluation: Evaluation = field(repr=False)

    def relative(self, chain: str | None = None) -> tuple[float, float]:
        """(reported / true - 1) of the mean and of the max, for ``chain`` (default chosen)."""
        c = chain or self.chosen
        r, t = self.reported[c], self.true[c]
        return r["mean_px"] / max(t["mean_px"], 1e-9) - 1, r["max_px"] / max(t["max_px"], 1e-9) - 1


def known_error_case(
    name: str,
    plan: np.ndarray,
    slam: np.ndarray,
    carried: np.ndarray,
    forward: np.ndarray | None = None,
    *,
    resolution: float = 0.05,
    params: EvaluateParams | None = None,
) -> KnownErrorCase:
    """Evaluate ``slam`` against ``plan`` and score the metric against the known truth.

    Parameters
    ----------
    name : str
        Label of the case.
    plan, slam : (H, W) uint8 arrays
        The plan and the map made from it with known errors.
    carried : (H, W, 2) float array
        Displacement each cell of ``slam`` carries
        (:func:`~map2map.maps.synthetic.wall_displacement` or the second output of
        :func:`~map2map.maps.synthetic.deform`).
    forward : (H, W, 2) float array, optional
        The forward field given to :func:`~map2map.maps.synthetic.deform`, if it made
        the map (the truth is then the field's continuous displacement of each face).
    resolution : float
        Metres per pixel of both maps.
    params : EvaluateParams, optional
        Metric settings.

    Returns
    -------
    KnownErrorCase
    """
    ev = evaluate_maps(OccupancyMap(slam, resolution), OccupancyMap(plan, resolution),
                       resolution=resolution, params=params)  # fmt: skip
    reg = ev.registration
    truth = np.abs(true_errors(reg.X, reg.normals, reg.alignment.rigid, plan, carried, forward))
    reported, true = {}, {}
    for chain in CHAINS:
        valid = ev.errors[chain].valid
        rep = ev.report["errors"][chain]
        reported[chain] = {"mean_px": float(rep["mean_px"]), "max_px": float(rep["max_px"])}
        t = truth[valid]
        true[chain] = {
            "mean_px": float(t.mean()) if len(t) else float("nan"),
            "max_px": float(t.max()) if len(t) else float("nan"),
        }
    _, angle, _, _ = decompose_similarity(reg.alignment.rigid)
    return KnownErrorCase(name, ev.chosen, reported, true, math.degrees(angle),
                          int(ev.errors[ev.chosen].valid.sum()), ev)  # fmt: skip


@dataclass(frozen=True)
class Table2Spec:
    """One synthetic map of appendix Table 2: global transform + local shear (pixels).

    ``local`` is the amplitude of the local-shear bumps (low / high local shear).
    """

    name: str
    what: str
    rotation_deg: float
    translation: tuple[float, float]
    scale: tuple[float, float] = (1.0, 1.0)
    shear: float = 0.0
    local: float = 2.0


#: The appendix's three kinds of synthetic map per ground truth (its section 5.1):
#: rotation + translation + low local shear; the same with high local shear; global
#: scale and shear + rotation + translation + low local shear.
TABLE2 = (
    Table2Spec(".1", "rotation, translation, low local shear", 4.0, (9.0, -6.0), local=2.5),
    Table2Spec(".2", "rotation, translation, high local shear", -3.0, (-7.0, 5.0), local=7.0),
    Table2Spec(".3", "scale, shear, rotation, translation, low local shear", 3.0, (6.0, 4.0),
               scale=(1.06, 0.96), shear=0.05, local=2.5),
)


def table2_cases(
    plans: dict[str, np.ndarray],
    seed: int = 0,
    *,
    specs: tuple[Table2Spec, ...] = TABLE2,
    resolution: float = 0.05,
    min_det: float = 0.5,
    progress=None,
) -> list[tuple[Table2Spec, str, np.ndarray, KnownErrorCase]]:
    """Appendix Table 2: every plan deformed by every spec, evaluated against the truth.

    The local shear is :func:`~map2map.maps.synthetic.bump_field` (4 bumps of width a
    sixth of the plan's smaller side, seeded by ``(seed, plan index, spec index)``),
    scaled down if needed so that the field never compresses the map more than
    ``min_det`` (Jacobian determinant), then composed with the global
    :func:`~map2map.maps.synthetic.affine_field` about the plan's centre.

    Parameters
    ----------
    plans : dict
        Name -> plan (uint8, walls occupied, with a margin of unknown around it so that
        the rotated map stays in the image).
    seed : int
        Seed of the local shear.
    specs : tuple of Table2Spec
        The deformations.
    resolution : float
        Metres per pixel.
    min_det : float
        Smallest Jacobian determinant allowed.
    progress : callable, optional
        Called with the case name before each evaluation.

    Returns
    -------
    list of (spec, case name, deformed map, KnownErrorCase)
    """
    out = []
    for i, (pname, plan) in enumerate(plans.items()):
        H, W = plan.shape
        for j, spec in enumerate(specs):
            rng = np.random.default_rng([seed, i, j])
            local = bump_field((H, W), spec.local, min(H, W) / 6, 4, rng)
            glob = affine_field((H, W), rotation_deg=spec.rotation_deg,
                                translation=spec.translation, scale=spec.scale,
                                shear=spec.shear)  # fmt: skip
            k = 1.0
            while k > 0.1 and min_jacobian(glob + k * local) < min_det:
                k -= 0.1
            fwd = glob + k * local
            slam, carried = deform(plan, fwd)
            name = pname + spec.name
            if progress is not None:
                progress(name)
            case = known_error_case(name, plan, slam, carried, fwd, resolution=resolution)
            out.append((spec, name, slam, case))
    return out
