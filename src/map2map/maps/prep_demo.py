"""Demo stage ``prep``: the thesis 4.1 preprocessing of the demo's floor plan."""

from __future__ import annotations

__all__ = ["stage_prep"]


def stage_prep(ctx) -> None:
    """Square, resize to 256 and thicken the generated plan; save the result and a figure.

    Reads ``ctx.results["plan"]``, leaves the 256 x 256 map in ``ctx.results["prep"]``.
    """
    from .formats import save_map
    from .preprocess import preprocess, save_preprocess_figure

    plan = ctx.results["plan"]
    out = preprocess(plan, size=256, thicken=1, crop=True, margin=4)
    ctx.results["prep"] = out
    path = ctx.out / "plan_256.png"
    save_map(out, path)
    ctx.wrote("plan preprocessed to 256x256 (thesis 4.1)", path)
    fig_path = ctx.out / "prep.png"
    save_preprocess_figure(plan, out, fig_path, title="crop, square, resize to 256, thicken 1 px")
    ctx.wrote("preprocessing figure", fig_path)
