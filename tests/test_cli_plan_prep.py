"""`map2map plan` and `map2map prep`: outputs, determinism, bad input (exit 2, nothing written)."""

from __future__ import annotations

import json

import numpy as np
import pytest

from map2map.cli.main import main
from map2map.maps.floorplan import generate_floorplan
from map2map.maps.formats import load_map, save_map


def run_cli(argv, capsys):
    rc = main([str(a) for a in argv])
    out, err = capsys.readouterr()
    return rc, out, err


def test_plan_writes_map_figure_and_layout(tmp_path, capsys):
    out = tmp_path / "plan.yaml"
    rc, stdout, _ = run_cli(
        ["plan", "--seed", 3, "--out", out, "--size", 10, 8, "--kind", "office",
         "--figure", tmp_path / "plan.png", "--meta", tmp_path / "plan.json"],
        capsys,
    )  # fmt: skip
    assert rc == 0, stdout
    m = load_map(out)
    ref = generate_floorplan(3, kind="office", size=(10, 8))
    assert np.array_equal(m.data, ref.data)
    assert m.resolution == ref.resolution and m.origin == ref.origin
    assert (tmp_path / "plan.png").read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    layout = json.loads((tmp_path / "plan.json").read_text())
    assert layout["rooms"] == ref.meta["rooms"] and layout["seed"] == 3
    assert "office" in stdout and str(out) in stdout


def test_plan_is_deterministic_and_honours_options(tmp_path, capsys):
    for name in ("a", "b"):
        argv = ["plan", "--seed", 9, "--out", tmp_path / f"{name}.yaml", "--resolution", 0.1]
        assert run_cli([*argv, "--furniture"], capsys)[0] == 0
    assert (tmp_path / "a.pgm").read_bytes() == (tmp_path / "b.pgm").read_bytes()
    m = load_map(tmp_path / "a.yaml")
    assert m.resolution == 0.1


@pytest.mark.parametrize(
    ("extra", "message"),
    [
        (["--size", "3", "10"], "at least 4"),
        (["--size", "10", "2.5"], "at least 4"),
        (["--resolution", "0"], "resolution must be positive"),
        (["--resolution", "-0.05"], "resolution must be positive"),
    ],
)
def test_plan_bad_input(tmp_path, capsys, extra, message):
    out = tmp_path / "plan.yaml"
    rc, _, err = run_cli(["plan", "--out", out, "--figure", tmp_path / "f.png", *extra], capsys)
    assert rc == 2
    assert err.startswith("map2map: error: ") and message in err and len(err.splitlines()) == 1
    assert list(tmp_path.iterdir()) == []


def test_plan_unwritable_output(tmp_path, capsys):
    blocker = tmp_path / "file"
    blocker.write_text("not a folder")
    rc, _, err = run_cli(["plan", "--out", blocker / "plan.yaml"], capsys)
    assert rc == 2 and "map2map: error:" in err
    # the figure destination is checked before the map is written
    rc, _, err = run_cli(
        ["plan", "--out", tmp_path / "p.yaml", "--figure", blocker / "f.png"], capsys
    )
    assert rc == 2 and not (tmp_path / "p.yaml").exists() and not (tmp_path / "p.pgm").exists()


@pytest.fixture
def plan_yaml(tmp_path):
    path = tmp_path / "in.yaml"
    save_map(generate_floorplan(4, size=(12, 6)), path)
    return path


def test_prep_squares_resizes_and_thickens(tmp_path, capsys, plan_yaml):
    out = tmp_path / "out.yaml"
    rc, stdout, _ = run_cli(
        ["prep", plan_yaml, out, "--size", 64, "--thicken", 1, "--crop", "--margin", 2], capsys
    )
    assert rc == 0, stdout
    m = load_map(out)
    src = load_map(plan_yaml)
    assert m.shape == (64, 64)
    assert set(np.unique(m.data).tolist()) == {0, 127, 255}
    # the building (12 m wide + 2 px margin each side) spans the output width
    assert m.resolution == pytest.approx((src.content_bbox()[3] - src.content_bbox()[2] + 4)
                                         * src.resolution / 64)  # fmt: skip
    default = tmp_path / "d.yaml"
    assert run_cli(["prep", plan_yaml, default], capsys)[0] == 0
    assert load_map(default).shape == (256, 256)


@pytest.mark.parametrize(
    ("extra", "message"),
    [
        (["--size", "0"], "--size"),
        (["--size", "-5"], "--size"),
        (["--thicken", "-1"], "--thicken"),
        (["--margin", "-2"], "--margin"),
    ],
)
def test_prep_bad_options(tmp_path, capsys, plan_yaml, extra, message):
    out = tmp_path / "out.yaml"
    rc, _, err = run_cli(["prep", plan_yaml, out, *extra], capsys)
    assert rc == 2 and err.startswith("map2map: error: ") and message in err
    assert not out.exists() and not (tmp_path / "out.pgm").exists()


def test_prep_missing_input(tmp_path, capsys):
    out = tmp_path / "out.yaml"
    rc, _, err = run_cli(["prep", tmp_path / "nope.yaml", out], capsys)
    assert rc == 2 and "nope.yaml" in err and len(err.splitlines()) == 1
    assert list(tmp_path.iterdir()) == []


def test_plan_bad_output_suffixes(tmp_path, capsys):
    for extra in (["--out", tmp_path / "p.txt"],
                  ["--out", tmp_path / "p.yaml", "--figure", tmp_path / "f.gif"],
                  ["--out", tmp_path / "p.yaml", "--meta", tmp_path / "m.yaml"]):  # fmt: skip
        rc, _, err = run_cli(["plan", *extra], capsys)
        assert rc == 2 and err.startswith("map2map: error: ")
    assert list(tmp_path.iterdir()) == []


def test_prep_real_houseexpo_plan(tmp_path, capsys, shared_data):
    src = shared_data / "houseexpo" / "json" / "0a1b29dba355df2ab02630133187bfab.json"
    out = tmp_path / "he.png"
    rc, stdout, err = run_cli(["prep", src, out, "--crop", "--thicken", "1"], capsys)
    assert rc == 0, err
    m = load_map(out)
    full = load_map(src)
    assert m.shape == (256, 256)
    # the plan's longer side fills the square (minus the crop margin), aspect kept
    r0, r1, c0, c1 = full.content_bbox()
    side = max(r1 - r0, c1 - c0) + 2 * 4
    assert m.resolution == pytest.approx(full.resolution * side / 256)
    q0, q1, p0, p1 = m.content_bbox()
    assert (q1 - q0) / (p1 - p0) == pytest.approx((r1 - r0) / (c1 - c0), rel=0.05)


def test_prep_figure(tmp_path, capsys, plan_yaml):
    fig = tmp_path / "prep.png"
    rc, _, err = run_cli(["prep", plan_yaml, tmp_path / "o.png", "--figure", fig], capsys)
    assert rc == 0, err
    assert fig.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    rc, _, err = run_cli(
        ["prep", plan_yaml, tmp_path / "p.png", "--figure", tmp_path / "x.gif"], capsys
    )
    assert rc == 2 and not (tmp_path / "p.png").exists()


def test_demo_prep_stage(tmp_path):
    from map2map.demo import DemoContext, stage_prep

    ctx = DemoContext(out=tmp_path, seed=0)
    ctx.plan = generate_floorplan(0, size=(9, 7))
    stage_prep(ctx)
    assert ctx.prep.shape == (256, 256)
    assert load_map(tmp_path / "plan_256.png").shape == (256, 256)
    assert [p.name for _, p in ctx.written] == ["plan_256.png", "prep.png"]
