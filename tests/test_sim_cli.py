"""``map2map simulate`` end to end and its bad inputs (exit 2, one line, nothing written)."""

import json

import numpy as np
import pytest

from map2map.cli.main import main
from map2map.core.grid import OccupancyMap
from map2map.maps.formats import save_map


def room_plan(tmp_path, h=50, w=70, name="plan.yaml"):
    data = np.full((h + 2, w + 2), 127, np.uint8)
    data[1:-1, 1:-1] = 255
    data[[1, -2], 1:-1] = 0
    data[1:-1, [1, -2]] = 0
    path = tmp_path / name
    save_map(OccupancyMap(data, 0.05, (0.0, 0.0, 0.0)), path)
    return path


def test_simulate_writes_every_output(tmp_path, capsys):
    plan = room_plan(tmp_path)
    out = tmp_path / "run"
    # the oracle mapper: its map must lie on the plan's walls (the default rbpf only nearly)
    rc = main(
        ["simulate", str(plan), "--out", str(out), "--duration", "20", "--quiet", "--gif"]
        + ["--mapper", "oracle"]
    )
    assert rc == 0, capsys.readouterr().err
    names = {p.name for p in out.iterdir()}
    assert {
        "slam_map.yaml",
        "slam_map.pgm",
        "trajectory_true.csv",
        "trajectory_estimated.csv",
        "run.log",
        "report.json",
        "figure.png",
        "exploration.gif",
    } <= names
    rep = json.loads((out / "report.json").read_text())
    for key in ("coverage", "path_length_m", "collisions", "simulated_seconds", "wall_seconds"):
        assert key in rep
    assert rep["coverage"] > 0.8 and rep["collisions"] == 0
    from map2map.maps.formats import load_map

    slam = load_map(out / "slam_map.yaml")
    src = load_map(plan)
    assert slam.shape == src.shape and slam.resolution == src.resolution
    assert np.allclose(slam.origin, src.origin)
    # mapped walls lie on plan walls, within a cell (the map is in the plan's frame)
    from scipy.ndimage import binary_dilation

    near_wall = binary_dilation(src.occupied, np.ones((3, 3), bool))
    assert near_wall[slam.occupied].mean() > 0.97


def test_simulate_says_its_lidar_field_of_view(tmp_path, capsys):
    """simulate's 360 degree default differs from dataset build's 180 (the thesis's):
    its --help says why, and its summary line and report.json say which it used."""
    with pytest.raises(SystemExit):
        main(["simulate", "--help"])
    helptext = " ".join(capsys.readouterr().out.split())
    assert "(default: 360, the LDS-01's full circle; the thesis cut it to 180" in helptext
    plan = room_plan(tmp_path)
    for fov in ("360", "180"):
        out = tmp_path / f"run{fov}"
        rc = main(["simulate", str(plan), "--out", str(out), "--duration", "4", "--quiet",
                   "--mapper", "oracle"] + (["--fov", fov] if fov == "180" else []))
        assert rc == 0
        assert f"s (time budget, {fov} deg lidar) in " in capsys.readouterr().out.splitlines()[0]
        assert json.loads((out / "report.json").read_text())["fov_deg"] == float(fov)


def test_simulate_route_files(tmp_path, capsys):
    plan = room_plan(tmp_path)
    wp = tmp_path / "wp.txt"
    wp.write_text("# x y\n0.6 0.6\n2.8 0.6\n2.8 1.9\n")
    out = tmp_path / "r1"
    rc = main(["simulate", str(plan), "--out", str(out), "--waypoints", str(wp), "--quiet"])
    assert rc == 0, capsys.readouterr().err
    assert json.loads((out / "report.json").read_text())["stop_reason"] == "route done"
    traj = tmp_path / "traj.csv"
    traj.write_text("t,x,y,theta\n0,0.6,1.2,0\n5,1.6,1.2,0\n10,2.6,1.2,0\n")
    out = tmp_path / "r2"
    rc = main(["simulate", str(plan), "--out", str(out), "--trajectory", str(traj), "--quiet"])
    assert rc == 0, capsys.readouterr().err


def _bad(tmp_path, capsys, args, message):
    out = tmp_path / "out"
    rc = main(["simulate", *args, "--out", str(out), "--quiet"])
    err = capsys.readouterr().err
    assert rc == 2
    lines = [line for line in err.splitlines() if line.strip()]
    assert len(lines) == 1 and lines[0].startswith("map2map: error:"), err
    assert message in lines[0], lines[0]
    assert not out.exists()


def test_bad_plan_without_free_space(tmp_path, capsys):
    path = tmp_path / "walls.yaml"
    save_map(OccupancyMap(np.zeros((30, 30), np.uint8), 0.05), path)
    _bad(tmp_path, capsys, [str(path)], "no free space")


def test_bad_plan_too_small_for_robot(tmp_path, capsys):
    data = np.zeros((12, 12), np.uint8)
    data[3:9, 3:9] = 255  # 0.3 m wide: the 0.2 m-radius robot does not fit
    path = tmp_path / "tiny.yaml"
    save_map(OccupancyMap(data, 0.05), path)
    _bad(tmp_path, capsys, [str(path)], "too small for the robot")


@pytest.mark.parametrize(
    ("start", "message"),
    [(["0.06", "1.0", "0"], "in or too close to a wall"), (["9", "9", "0"], "outside the plan")],
)
def test_bad_start_pose(tmp_path, capsys, start, message):
    plan = room_plan(tmp_path)
    _bad(tmp_path, capsys, [str(plan), "--start", *start], message)


def test_bad_duration(tmp_path, capsys):
    plan = room_plan(tmp_path)
    _bad(tmp_path, capsys, [str(plan), "--duration", "0"], "duration must be > 0")
    _bad(tmp_path, capsys, [str(plan), "--duration", "-5"], "duration must be > 0")


def test_bad_route_files(tmp_path, capsys):
    plan = room_plan(tmp_path)
    bad = tmp_path / "bad.txt"
    bad.write_text("0.6 0.6\n1.0 abc\n")
    _bad(tmp_path, capsys, [str(plan), "--waypoints", str(bad)], "line 2: not numbers")
    cols = tmp_path / "cols.csv"
    cols.write_text("1,2,3,4,5\n1,2,3,4,5\n")
    _bad(tmp_path, capsys, [str(plan), "--trajectory", str(cols)], "columns")
    wall = tmp_path / "wall.txt"
    wall.write_text("0.6 0.6\n5.0 0.6\n")  # leaves the room through the east wall
    _bad(tmp_path, capsys, [str(plan), "--waypoints", str(wall)], "wall.txt")
    _bad(tmp_path, capsys, [str(plan), "--waypoints", str(tmp_path / "nope.txt")], "cannot read")


def test_bad_mapper_and_missing_plan(tmp_path, capsys):
    plan = room_plan(tmp_path)
    _bad(tmp_path, capsys, [str(plan), "--mapper", "nosuch"], "unknown mapper 'nosuch'")
    _bad(tmp_path, capsys, [str(tmp_path / "missing.yaml")], "not found")
