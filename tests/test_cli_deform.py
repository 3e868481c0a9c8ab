"""``map2map deform`` on the command line: outputs, repeatability and every bad input."""

from __future__ import annotations

import numpy as np
import pytest
import yaml
from _parametric_plans import centre, two_rooms

from map2map.cli.main import main
from map2map.core.grid import OCCUPIED, OccupancyMap
from map2map.maps.ros import load_ros_map, save_ros_map

FILES = {
    "slam_map.yaml",
    "slam_map.pgm",
    "displacement.npz",
    "trajectory.csv",
    "params.yaml",
    "figure.png",
}


@pytest.fixture(scope="module")
def plan_yaml(tmp_path_factory):
    d = tmp_path_factory.mktemp("plan")
    plan = two_rooms()
    plan.origin = (-1.0, 2.0, 0.0)
    save_ros_map(plan, d / "plan.yaml")
    return d / "plan.yaml"


def _pt(plan, r, c):
    x, y = plan.pixel_to_world([r], [c])
    return [f"{float(x[0]):.4f}", f"{float(y[0]):.4f}"]


def test_deform_writes_the_listed_files(plan_yaml, tmp_path):
    out = tmp_path / "out"
    plan = load_ros_map(plan_yaml)
    rc = main(
        [
            "deform",
            str(plan_yaml),
            "--out",
            str(out),
            "--seed",
            "4",
            "--quiet",
            "--start",
            *_pt(plan, 10, 10),
            "--goal",
            *_pt(plan, 70, 100),
        ]
    )
    assert rc == 0
    assert {p.name for p in out.iterdir()} == FILES
    m = load_ros_map(out / "slam_map.yaml")
    assert m.shape == plan.shape
    assert m.resolution == plan.resolution and m.origin == plan.origin
    with np.load(out / "displacement.npz") as z:
        assert z["dx"].dtype == np.float32 and z["dy"].dtype == np.float32
        assert z["dx"].shape == plan.shape and z["dy"].shape == plan.shape
        assert np.abs(z["dx"]).max() > 0
    header = (out / "trajectory.csv").read_text().splitlines()[0]
    assert header == "t,x,y,theta,v,omega"
    doc = yaml.safe_load((out / "params.yaml").read_text())
    assert doc["run"]["seed"] == 4 and doc["run"]["method"] == "additive"
    assert "eta" in doc["parameters"] and "lidar" in doc["drawn"]


def test_repeat_from_params_and_trajectory_gives_identical_bytes(plan_yaml, tmp_path):
    a = tmp_path / "a"
    assert (
        main(
            [
                "deform",
                str(plan_yaml),
                "--out",
                str(a),
                "--samples",
                "2",
                "--seed",
                "10",
                "--method",
                "ekf",
                "--quiet",
            ]
        )
        == 0
    )
    assert sorted(p.name for p in a.iterdir()) == ["sample_000", "sample_001"]
    s1 = a / "sample_001"
    assert {p.name for p in s1.iterdir()} == FILES
    b = tmp_path / "b"
    seed = str(yaml.safe_load((s1 / "params.yaml").read_text())["run"]["seed"])
    assert seed == "11"
    assert (
        main(
            [
                "deform",
                str(plan_yaml),
                "--out",
                str(b),
                "--seed",
                seed,
                "--method",
                "ekf",
                "--params",
                str(s1 / "params.yaml"),
                "--trajectory",
                str(s1 / "trajectory.csv"),
                "--quiet",
            ]
        )
        == 0
    )
    for name in ("slam_map.pgm", "displacement.npz", "trajectory.csv"):
        assert (s1 / name).read_bytes() == (b / name).read_bytes(), name
    # the two samples differ
    assert (a / "sample_000" / "slam_map.pgm").read_bytes() != (s1 / "slam_map.pgm").read_bytes()


def test_waypoints_and_fov(plan_yaml, tmp_path):
    plan = load_ros_map(plan_yaml)
    wp = tmp_path / "w.txt"
    wp.write_text("\n".join(" ".join(_pt(plan, r, c)) for r, c in [(10, 10), (30, 90), (70, 60)]))
    out = tmp_path / "o"
    rc = main(
        [
            "deform",
            str(plan_yaml),
            "--out",
            str(out),
            "--waypoints",
            str(wp),
            "--fov",
            "180",
            "--quiet",
        ]
    )
    assert rc == 0
    assert yaml.safe_load((out / "params.yaml").read_text())["parameters"]["fov_deg"] == 180


def _bad(args, tmp_path, capsys, expect):
    out = tmp_path / "never"
    rc = main([*args, "--out", str(out), "--quiet"])
    err = capsys.readouterr().err.strip().splitlines()
    assert rc == 2
    assert len(err) == 1 and err[0].startswith("map2map: error: "), err
    assert expect in err[0], err[0]
    assert not out.exists()
    return err[0]


def test_bad_plan_without_free_space(tmp_path, capsys):
    solid = OccupancyMap(np.full((20, 20), OCCUPIED, np.uint8), 0.05)
    save_ros_map(solid, tmp_path / "solid.yaml")
    _bad(["deform", str(tmp_path / "solid.yaml")], tmp_path, capsys, "no free space")


def test_bad_start_in_wall_or_outside(plan_yaml, tmp_path, capsys):
    plan = load_ros_map(plan_yaml)
    goal = _pt(plan, 10, 10)
    _bad(
        ["deform", str(plan_yaml), "--start", *_pt(plan, 3, 30), "--goal", *goal],
        tmp_path,
        capsys,
        "in a wall",
    )
    _bad(
        ["deform", str(plan_yaml), "--start", "100", "100", "--goal", *goal],
        tmp_path,
        capsys,
        "outside the map",
    )
    _bad(
        ["deform", str(plan_yaml), "--start", *goal, "--goal", "-50", "3"],
        tmp_path,
        capsys,
        "goal (-50, 3) m is outside the map",
    )


def test_bad_start_goal_not_connected(tmp_path, capsys):
    closed = two_rooms(door=False)
    save_ros_map(closed, tmp_path / "closed.yaml")
    s, g = centre(closed, 30, 30), centre(closed, 30, 90)
    line = _bad(
        [
            "deform",
            str(tmp_path / "closed.yaml"),
            "--start",
            str(s[0]),
            str(s[1]),
            "--goal",
            str(g[0]),
            str(g[1]),
        ],
        tmp_path,
        capsys,
        "are not connected",
    )
    assert f"start ({s[0]:g}, {s[1]:g}) m" in line and f"goal ({g[0]:g}, {g[1]:g}) m" in line


def test_bad_waypoints_file(plan_yaml, tmp_path, capsys):
    wp = tmp_path / "w.txt"
    wp.write_text("1 2\n3 four\n")
    _bad(["deform", str(plan_yaml), "--waypoints", str(wp)], tmp_path, capsys, "w.txt: line 2")
    wp.write_text("1 2 3\n")
    _bad(["deform", str(plan_yaml), "--waypoints", str(wp)], tmp_path, capsys, "2 columns")


def test_bad_params_file(plan_yaml, tmp_path, capsys):
    pf = tmp_path / "p.yaml"
    pf.write_text("eta: 0.01\nwheel_size: 3\n")
    _bad(["deform", str(plan_yaml), "--params", str(pf)], tmp_path, capsys, "unknown parameter")
    pf.write_text("eta: .nan\n")
    _bad(["deform", str(plan_yaml), "--params", str(pf)], tmp_path, capsys, "finite")


def test_bad_samples_zero(plan_yaml, tmp_path, capsys):
    _bad(["deform", str(plan_yaml), "--samples", "0"], tmp_path, capsys, "--samples")


def test_bad_trajectory_outside_map(plan_yaml, tmp_path, capsys):
    tf = tmp_path / "t.csv"
    tf.write_text("x,y,theta\n0,3,0\n500,3,0\n")
    _bad(["deform", str(plan_yaml), "--trajectory", str(tf)], tmp_path, capsys, "outside the map")
