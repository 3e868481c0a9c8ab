"""The parametric demo stage on a small plan."""

from __future__ import annotations

from _parametric_plans import two_rooms

from map2map.demo import STAGES, DemoContext, stage_parametric
from map2map.maps.preprocess import reduce_plan
from map2map.maps.ros import load_ros_map


def test_demo_stage_writes_map_field_and_figures(tmp_path):
    assert [name for name, _ in STAGES].index("parametric") > [n for n, _ in STAGES].index("plan")
    ctx = DemoContext(out=tmp_path, seed=3)
    ctx.plan = two_rooms()
    stage_parametric(ctx)
    names = {p.name for _, p in ctx.written}
    assert {"roadmap.png", "slam_map.yaml", "displacement.npz", "figure.png"} <= names
    assert "figure_ekf.png" in names
    for _, p in ctx.written:
        assert p.exists() and p.stat().st_size > 0
    m = load_ros_map(tmp_path / "parametric" / "slam_map.yaml")
    assert m.shape == ctx.plan.shape
    assert ctx.parametric.observed.sum() > 0.5 * ctx.plan.free.sum()


def test_reduce_plan_keeps_walls_and_frame():
    plan = two_rooms(res=0.01)
    small = reduce_plan(plan, max_side=60)
    assert max(small.shape) <= 60
    assert small.resolution == 0.03
    # the lower-left corner keeps its world position
    assert small.origin == plan.origin
    # the 2 px wall between the rooms (columns 60-61) survives in reduced column 20,
    # closed above the door (rows 4-19) and open at the door (rows 20-35)
    assert small.shape == (28, 42)
    assert small.occupied[2:6, 20].all()
    assert small.free[7:12, 20].all()
