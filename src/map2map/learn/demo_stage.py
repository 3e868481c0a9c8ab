"""Demo stage: auto-correct the demo's simulated SLAM map with the shipped Model_BA.

Writes ``autocorrect/cad.yaml`` (+ ``.pgm``), ``autocorrect/walls.dxf`` and
``autocorrect/before_after.png``; leaves the corrected map in
``ctx.results["autocorrected"]``. Skipped, with a note, when PyTorch is not installed
(``pip install 'map2map[learn]'``) or no SLAM map was made.
"""

from __future__ import annotations

import warnings

from ..maps.grid import OccupancyMap

__all__ = ["stage_autocorrect"]


def stage_autocorrect(ctx) -> None:
    """Auto-correct the simulated SLAM map (or the parametric model's) into a plan."""
    sim = ctx.results.get("sim")
    slam = getattr(sim, "slam_map", None)
    if not isinstance(slam, OccupancyMap):
        slam = getattr(ctx.results.get("parametric"), "map", None)
    if not isinstance(slam, OccupancyMap):
        print("autocorrect: no SLAM map in this demo run; skipped")
        return
    try:
        from .autocorrect import autocorrect_many, save_segments_dxf
        from .figures import save_before_after
    except ImportError:
        print("autocorrect: PyTorch not installed (pip install 'map2map[learn]'); skipped")
        return
    from ..maps.formats import save_map

    out = ctx.out / "autocorrect"
    out.mkdir(parents=True, exist_ok=True)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        (res,) = autocorrect_many([slam])
    save_map(res.map, out / "cad.yaml")
    ctx.wrote("auto-corrected plan (Model_BA, ROS map)", out / "cad.yaml")
    save_segments_dxf(res.segments, out / "walls.dxf")
    ctx.wrote("auto-corrected walls (DXF line segments)", out / "walls.dxf")
    save_before_after(slam, res.map, out / "before_after.png",
                      res.map.meta["autocorrect"]["segments_px"],
                      title="Model_BA (provisional weights): SLAM map -> CAD-like plan")
    ctx.wrote("auto-correct before/after figure", out / "before_after.png")
    for w in res.warnings:
        print(f"autocorrect: warning: {w}")
    ctx.results["autocorrected"] = res.map
