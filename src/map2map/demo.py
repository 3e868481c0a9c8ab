"""The main job on the embedded default: every stage of map2map on a generated plan.

Each stage is a function ``stage(ctx: DemoContext) -> None`` that writes its
outputs under ``ctx.out``, records them with :meth:`DemoContext.wrote`, and may
leave results in ``ctx.results`` for later stages. Stages run in the order of
:data:`STAGES`; a later issue adds its stage to that list.
"""

from __future__ import annotations

import time
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from tqdm.auto import tqdm

from ._io import ensure_output_dir
from .evaluate.demo_stage import stage_evaluate
from .learn.demo_stage import stage_autocorrect
from .maps.prep_demo import stage_prep
from .parametric.demo_stage import stage_parametric
from .sim.demo_stage import stage_simulate
from .slam import demo_stage as _slam_stage

__all__ = ["DemoContext", "STAGES", "run_demo"]


@dataclass
class DemoContext:
    """State handed from stage to stage."""

    out: Path
    seed: int
    results: dict[str, Any] = field(default_factory=dict)
    written: list[tuple[str, Path]] = field(default_factory=list)
    timings: dict[str, float] = field(default_factory=dict)

    def wrote(self, what: str, path: Path) -> None:
        self.written.append((what, Path(path)))


def _stage_plan(ctx: DemoContext) -> None:
    """Generate the embedded default floor plan and draw it."""
    from .maps.floorplan import generate_floorplan
    from .maps.formats import save_map
    from .maps.render import save_map_figure

    plan = generate_floorplan(ctx.seed, kind="apartment")
    ctx.results["plan"] = plan
    path = ctx.out / "plan.yaml"
    save_map(plan, path)
    ctx.wrote("floor plan (ROS map)", path)
    fig_path = ctx.out / "plan.png"
    save_map_figure(plan, fig_path, title=f"Generated apartment, seed {ctx.seed}")
    ctx.wrote("floor plan figure", fig_path)


#: (name, function) of every demo stage, in order.
STAGES: list[tuple[str, Callable[[DemoContext], None]]] = [
    ("plan", _stage_plan),
    ("prep", stage_prep),
    ("parametric", stage_parametric),
    ("simulate", stage_simulate),
    ("slam", _slam_stage.stage_slam),
    ("autocorrect", stage_autocorrect),
    ("evaluate", stage_evaluate),  # keep last: it evaluates the maps the stages above made
]


def run_demo(out: str | Path = "demo_out", seed: int = 0, progress: bool = True) -> DemoContext:
    """Run every stage on a generated plan; return the context listing what was written."""
    out_dir = ensure_output_dir(out)
    ctx = DemoContext(out=out_dir, seed=int(seed))
    bar = tqdm(STAGES, desc="map2map demo", unit="stage", disable=not progress)
    for name, stage in bar:
        bar.set_postfix_str(name)
        t0 = time.perf_counter()
        stage(ctx)
        ctx.timings[name] = time.perf_counter() - t0
    bar.close()
    return ctx
