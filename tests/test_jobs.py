"""The jobs layer: typed results, folders written whole, outputs checked before any work,
and the HouseExpo frame of ``deform``'s routes."""

from __future__ import annotations

import json

import numpy as np
import pytest

from map2map.cli.main import main
from map2map.core._io import atomic_dir
from map2map.core.grid import OccupancyMap
from map2map.jobs import deform as jdeform
from map2map.jobs import evaluate as jeval
from map2map.jobs import simulate as jsim
from map2map.jobs import slam as jslam
from map2map.maps.formats import load_map, save_map
from map2map.trajectory.timing import read_trajectory


class Interrupted(Exception):
    pass


def _boom(*args, **kwargs):
    raise Interrupted("interrupted while writing")


def _must_not_run(*args, **kwargs):
    raise AssertionError("the heavy work ran although the output path cannot be written")


def _box(h=60, w=100) -> OccupancyMap:
    data = np.full((h, w), 255, np.uint8)
    data[[0, -1], :] = 0
    data[:, [0, -1]] = 0
    return OccupancyMap(data, 0.05)


@pytest.fixture(scope="module")
def files(tmp_path_factory):
    """A small ROS plan and a short simulated run (its CARMEN log feeds ``slam``)."""
    d = tmp_path_factory.mktemp("inputs")
    save_map(_box(), d / "plan.yaml")
    run = jsim.simulate(
        jsim.SimulateSpec(d / "plan.yaml", d / "run", duration=6, mapper="oracle",
                          figures=False, progress=False)
    )  # fmt: skip
    return {"plan": d / "plan.yaml", "run": d / "run", "sim": run}


def _left(folder) -> list[str]:
    """Everything in ``folder`` (hidden temporaries included)."""
    return sorted(p.name for p in folder.iterdir())


def _specs(files, out):
    plan = files["plan"]
    return {
        "simulate": (
            jsim.simulate,
            jsim.SimulateSpec(plan, out, duration=4, mapper="oracle", progress=False),
        ),  # fmt: skip
        "deform": (
            jdeform.deform,
            jdeform.DeformSpec(plan, out, start=(0.5, 0.5), goal=(4.0, 2.0), progress=False),
        ),  # fmt: skip
        "slam": (jslam.slam, jslam.SlamSpec(files["run"], out, backend="graph", progress=False)),
        "align": (jeval.align, jeval.AlignSpec(plan, plan, out)),
        "evaluate": (jeval.evaluate, jeval.EvaluateSpec(plan, plan, out)),
    }


# where each job is interrupted (the last file it writes) and its heavy work
LAST_WRITE = {
    "simulate": (jsim, "save_figure_png"),
    "deform": (jdeform, "deform_figure"),
    "slam": (jslam, "_figure"),
    "align": (jeval, "overlay_figure"),
    "evaluate": (jeval, "error_map_figure"),
}
HEAVY = {
    "simulate": (jsim, "run_simulation"),
    "deform": (jdeform, "run_model"),
    "slam": (jslam, "run_slam"),
    "align": (jeval, "register"),
    "evaluate": (jeval, "evaluate_maps"),
}
JOBS = sorted(LAST_WRITE)


def test_typed_results_keep_the_in_memory_result(files, tmp_path):
    d = jdeform.deform(jdeform.DeformSpec(files["plan"], tmp_path / "d", samples=2,
                                          start=(0.5, 0.5), goal=(4.0, 2.0),
                                          figures=False, progress=False))  # fmt: skip
    assert len(d.results) == 2 and d.results[0].map.shape == (60, 100)
    assert "sample_001/displacement" in d.written and "sample_000/figure" not in d.written
    assert all(p.is_file() for p in d.written.values())
    a = jeval.align(jeval.AlignSpec(files["plan"], files["plan"], tmp_path / "a", figures=False))
    doc = json.loads(a.written["alignment"].read_text())
    assert doc["scale"] == pytest.approx(a.report["scale"])
    assert np.allclose(doc["similarity"], a.alignment.similarity)
    assert set(a.written) == {"alignment"}
    e = jeval.evaluate(jeval.EvaluateSpec(files["plan"], files["plan"], tmp_path / "e"))
    assert e.evaluation is not None and set(e.written) >= {"report", "overlay", "error_map"}
    report = json.loads(e.written["report"].read_text())
    assert report == json.loads(json.dumps(e.evaluation.report))


@pytest.mark.parametrize("job", JOBS)
def test_an_interrupted_job_leaves_no_folder(job, files, tmp_path, monkeypatch):
    """An exception raised while the outputs are written: no folder, no temporaries."""
    module, name = LAST_WRITE[job]
    monkeypatch.setattr(module, name, _boom)
    func, spec = _specs(files, tmp_path / "out")[job]
    with pytest.raises(Interrupted):
        func(spec)
    assert _left(tmp_path) == []


def test_an_interrupted_job_keeps_the_old_folder_and_a_finished_one_replaces_it(
    files, tmp_path, monkeypatch
):
    out = tmp_path / "out"
    out.mkdir()
    (out / "stale.txt").write_text("from an earlier run")
    func, spec = _specs(files, out)["deform"]
    with monkeypatch.context() as mp:
        mp.setattr(jdeform, "deform_figure", _boom)
        with pytest.raises(Interrupted):
            func(spec)
    assert _left(tmp_path) == ["out"] and _left(out) == ["stale.txt"]
    run = func(spec)
    assert _left(tmp_path) == ["out"] and "stale.txt" not in _left(out)
    assert sorted(p.name for p in run.written.values()) == _left(out)


def test_ctrl_c_leaves_no_folder(tmp_path):
    with pytest.raises(KeyboardInterrupt):
        with atomic_dir(tmp_path / "run") as tmp:
            (tmp / "half.csv").write_text("t,x\n")
            raise KeyboardInterrupt
    assert _left(tmp_path) == []


@pytest.mark.parametrize("job", JOBS)
@pytest.mark.parametrize("where", ["under a file", "a file"])
def test_an_unwritable_output_is_refused_before_any_work(job, where, files, tmp_path, monkeypatch):
    module, name = HEAVY[job]
    monkeypatch.setattr(module, name, _must_not_run)
    (tmp_path / "f").write_text("x")
    out = tmp_path / "f" / "out" if where == "under a file" else tmp_path / "f"
    func, spec = _specs(files, out)[job]
    with pytest.raises(jdeform.InputError, match="not a directory"):
        func(spec)
    assert _left(tmp_path) == ["f"]


def test_cli_refuses_an_unwritable_output_in_one_line(files, tmp_path, monkeypatch, capsys):
    monkeypatch.setattr(jsim, "run_simulation", _must_not_run)
    (tmp_path / "f").write_text("x")
    rc = main(["simulate", str(files["plan"]), "--out", str(tmp_path / "f" / "o"), "--quiet"])
    err = capsys.readouterr().err.strip().splitlines()
    assert rc == 2 and len(err) == 1 and "not a directory" in err[0]


def test_output_folder_holding_an_input_is_refused(files, tmp_path):
    with pytest.raises(jdeform.InputError, match="holds the input"):
        jslam.slam(jslam.SlamSpec(files["run"] / "run.log", files["run"], progress=False))


def test_cli_errors_name_flags_from_the_jobs_parameters(files, tmp_path, capsys):
    plan = str(files["plan"])
    cases = [
        (["deform", plan, "--out", str(tmp_path / "d"), "--start", "1", "1"], "--goal:"),
        (["deform", plan, "--out", str(tmp_path / "d"), "--samples", "0"], "--samples:"),
        (["deform", plan, "--out", str(tmp_path / "d"), "--seed", "-1"], "--seed:"),
        (["simulate", plan, "--out", str(tmp_path / "s"), "--seed", "-1"], "--seed:"),
        (["slam", str(files["run"]), "--out", str(tmp_path / "l"), "--seed", "-1"], "--seed:"),
        (["align", plan, plan, "--out", str(tmp_path / "a"), "--resolution", "0"],
         "--resolution:"),
        (["evaluate", plan, plan, "--out", str(tmp_path / "e"), "--source-resolution", "-2"],
         "--source-resolution:"),
        (["evaluate", plan, "--pairs", plan, "--out", str(tmp_path / "e")], "--pairs:"),
    ]  # fmt: skip
    for argv, flag in cases:
        assert main(argv) == 2, argv
        err = capsys.readouterr().err.strip().splitlines()
        assert len(err) == 1 and err[0].startswith(f"map2map: error: {flag}"), (argv, err)
    assert _left(tmp_path) == []


# --------------------------------------------------------------- HouseExpo frame
HOUSE = {
    "id": "flip",
    "room_num": 2,
    "bbox": {"min": [0.0, 0.0], "max": [6.0, 4.0]},
    "verts": [
        [0.0, 0.0], [3.0, 0.0], [3.0, 1.5], [3.04, 1.5], [3.04, 0.0], [6.0, 0.0],
        [6.0, 4.0], [3.04, 4.0], [3.04, 2.4], [3.0, 2.4], [3.0, 4.0], [0.0, 4.0],
    ],
}  # fmt: skip


@pytest.fixture
def house(tmp_path):
    p = tmp_path / "house.json"
    p.write_text(json.dumps(HOUSE))
    return p


def test_deform_takes_houseexpo_coordinates_like_simulate(house, tmp_path):
    """Start and goal in HouseExpo's frame (y down): the path starts at (x, -y) in the map."""
    start, goal = (1.0, 0.8), (5.0, 3.2)  # both rooms; (x, +y) lies outside the map
    run = jdeform.deform(jdeform.DeformSpec(house, tmp_path / "m", start=start, goal=goal,
                                            figures=False, progress=False))  # fmt: skip
    traj = run.results[0].trajectory
    assert (traj.x[0], traj.y[0]) == pytest.approx((1.0, -0.8), abs=1e-9)
    assert (traj.x[-1], traj.y[-1]) == pytest.approx((5.0, -3.2), abs=1e-9)
    with pytest.raises(jdeform.InputError):  # the same numbers read in the map's frame
        jdeform.deform(jdeform.DeformSpec(house, tmp_path / "w", start=start, goal=goal,
                                          route_frame="world", progress=False))  # fmt: skip
    wp = tmp_path / "wp.txt"
    wp.write_text("1.0 0.8\n1.5 3.0\n5.0 3.2\n")
    run = jdeform.deform(jdeform.DeformSpec(house, tmp_path / "wp", waypoints=wp,
                                            figures=False, progress=False))  # fmt: skip
    traj = run.results[0].trajectory
    assert (traj.x[0], traj.y[0], traj.y[-1]) == pytest.approx((1.0, -0.8, -3.2), abs=1e-9)


def test_deform_houseexpo_trajectory_is_flipped_and_its_repeat_line_repeats(house, tmp_path):
    csv = tmp_path / "t.csv"
    csv.write_text("x,y,theta\n1.0,0.8,0.3\n1.5,1.0,0.6\n2.0,1.3,0.6\n")
    run = jdeform.deform(jdeform.DeformSpec(house, tmp_path / "a", trajectory=csv, seed=5,
                                            figures=False, progress=False))  # fmt: skip
    out = tmp_path / "a"
    t = read_trajectory(out / "trajectory.csv")
    assert t.y.tolist() == pytest.approx([-0.8, -1.0, -1.3])
    assert t.theta[0] == pytest.approx(-0.3)
    assert "--route-frame world" in (out / "params.yaml").read_text()
    again = jdeform.deform(jdeform.DeformSpec(house, tmp_path / "b", seed=5, route_frame="world",
                                              trajectory=out / "trajectory.csv",
                                              params=out / "params.yaml",
                                              figures=False, progress=False))  # fmt: skip
    assert np.array_equal(again.results[0].map.data, run.results[0].map.data)
    assert (tmp_path / "b" / "slam_map.pgm").read_bytes() == (out / "slam_map.pgm").read_bytes()


def test_plan_job_writes_meta_that_reads_back(tmp_path):
    from map2map.jobs.maps import PlanSpec, plan

    run = plan(PlanSpec(tmp_path / "p.png", seed=2, size=(8.0, 6.0), meta=tmp_path / "p.json"))
    assert set(run.written) == {"map", "meta"}
    assert load_map(tmp_path / "p.json").shape == run.plan.shape
