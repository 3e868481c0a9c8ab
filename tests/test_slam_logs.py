"""Log readers for SLAM (CARMEN, simulator runs, BreezySLAM) and the ``map2map slam`` command."""

from __future__ import annotations

import gzip
import math

import numpy as np
import pytest
from _slam_synth import synthetic_run

from map2map.cli.main import main
from map2map.core.errors import InputError
from map2map.maps.ros import load_ros_map
from map2map.robotlog.carmen import write_carmen
from map2map.robotlog.logs import BreezyRobot, detect_format, load_log, read_breezyslam


@pytest.fixture(scope="module")
def run_records():
    wp = [(1.0, 1.0), (4.0, 1.0), (4.0, 4.0), (2.0, 4.0)]
    plan, true, stream = synthetic_run(seed=5, waypoints=wp)
    return [(o, s, tuple(p)) for (o, s), p in zip(stream, true, strict=True)]


def _breezy_line(t_us, left, right, ranges_mm, extra=0):
    fields = [t_us, 0, left, right] + [0] * 20 + list(ranges_mm) + [0] * extra
    return " ".join(str(v) for v in fields)


# ----------------------------------------------------------------------------- parsing


def test_carmen_log_and_simulator_folder(tmp_path, run_records):
    write_carmen(tmp_path / "run.log", run_records[:40])
    write_carmen(tmp_path / "run.log.gz", run_records[:40])
    for path in (tmp_path / "run.log", tmp_path / "run.log.gz", tmp_path):
        log = load_log(path)
        assert len(log) == 40
        assert log.scans[0].n_beams == 360
        assert log.odometry[5] == run_records[5][0]
    assert detect_format(tmp_path / "run.log") == "carmen"
    assert detect_format(tmp_path) == "simrun"


def test_breezyslam_parsing_integrates_ticks(tmp_path):
    rob = BreezyRobot()
    r = np.full(682, 1500)
    r[:10] = 0  # no return
    lines = [
        _breezy_line(5_000_000, 1000, 1000, r),
        _breezy_line(5_100_000, 3000, 3000, r, extra=1),  # one wheel turn forward each
        _breezy_line(5_200_000, 3000, 3000 + 2000, r),  # right wheel one more turn
    ]
    path = tmp_path / "exp.dat"
    path.write_text("\n".join(lines) + "\n")
    assert detect_format(path) == "breezyslam"
    log = read_breezyslam(path)
    assert len(log) == 3
    circ = 2 * math.pi * rob.wheel_radius
    o = log.odometry
    assert [x.t for x in o] == pytest.approx([0.0, 0.1, 0.2])
    assert (o[1].x, o[1].y, o[1].theta) == pytest.approx((circ, 0.0, 0.0))
    assert o[2].theta == pytest.approx(circ / (2 * rob.half_axle))
    s = log.scans[0]
    assert s.n_beams == 682 and s.sensor_offset == (0.145, 0.0, 0.0)
    assert np.isnan(s.ranges[:10]).all() and s.ranges[10] == pytest.approx(1.5)
    assert math.degrees(s.angles[0]) == pytest.approx(-120)
    assert math.degrees(s.angles[-1]) == pytest.approx(120)


def test_real_breezyslam_log(shared_data):
    log = load_log(shared_data / "breezyslam" / "exp2.dat")
    assert len(log) > 600 and log.scans[0].n_beams == 682
    assert np.isfinite(log.scans[100].ranges).sum() > 100


# ----------------------------------------------------------------------------- bad input

RAW = "RAWLASER1 3 0.0 6.265732 0.017453 3.5 0.01 0 {n} {r} 0 {t} host {t}"
ODOM = "ODOM {x} 0.0 0.0 0.0 0.0 0.0 {t} host {t}"


def _raw(t, n=360):
    return RAW.format(n=n, r=" ".join(["1.500"] * n), t=t)


BAD_LOGS = {
    "not_a_message": (["# header", ODOM.format(x=0, t=0), "12.5 1 2 3 0 host 0"], "line 3"),
    "corrupt": ([ODOM.format(x=0, t=0), _raw(0), "ODOM 0.1 zz 0 0 0 0 1 host 1"], "line 3"),
    "truncated": (
        [ODOM.format(x=0, t=0), "RAWLASER1 3 0.0 6.2 0.017 3.5 0.01 0 360 1.0"],
        "line 2",
    ),
    "no_odometry": ([_raw(0), _raw(1)], "no odometry"),
    "no_scans": ([ODOM.format(x=0, t=0), ODOM.format(x=1, t=1)], "no laser scans"),
    "beam_change": ([ODOM.format(x=0, t=0), _raw(0), _raw(1, n=300)], "line 3"),
    "empty": ([], "empty log"),
}


@pytest.mark.parametrize("case", sorted(BAD_LOGS))
def test_bad_carmen_logs_exit_2_and_write_nothing(tmp_path, capsys, case):
    lines, needle = BAD_LOGS[case]
    log = tmp_path / f"{case}.log"
    log.write_text("\n".join(lines) + ("\n" if lines else ""))
    out = tmp_path / "out"
    rc = main(["slam", str(log), "--out", str(out), "--quiet"])
    err = capsys.readouterr().err.strip().splitlines()
    assert rc == 2
    assert len(err) == 1 and err[0].startswith("map2map: error:"), err
    assert log.name in err[0] and needle in err[0], err[0]
    assert not out.exists()


BAD_BREEZY = {
    "not_a_number": (
        lambda r: [_breezy_line(0, 0, 0, r), _breezy_line(1, 0, 0, r).replace(" 1500", " 15o0", 1)],
        "line 2",
    ),
    "short_line": (lambda r: [_breezy_line(0, 0, 0, r), _breezy_line(1, 0, 0, r[:300])], "line 2"),
    "time_backwards": (lambda r: [_breezy_line(9, 0, 0, r), _breezy_line(1, 0, 0, r)], "line 2"),
}


@pytest.mark.parametrize("case", sorted(BAD_BREEZY))
def test_bad_breezyslam_logs_exit_2(tmp_path, capsys, case):
    make, needle = BAD_BREEZY[case]
    log = tmp_path / f"{case}.dat"
    log.write_text("\n".join(make(np.full(682, 1500))) + "\n")
    out = tmp_path / "out"
    rc = main(["slam", str(log), "--out", str(out), "--quiet"])
    err = capsys.readouterr().err.strip().splitlines()
    assert rc == 2 and len(err) == 1 and needle in err[0] and log.name in err[0], err
    assert not out.exists()


def test_missing_log_and_bad_arguments(tmp_path, capsys):
    out = tmp_path / "out"
    assert main(["slam", str(tmp_path / "nope.log"), "--out", str(out)]) == 2
    assert "not found" in capsys.readouterr().err
    log = tmp_path / "a.log"
    log.write_text(ODOM.format(x=0, t=0) + "\n" + _raw(0) + "\n")
    assert main(["slam", str(log), "--out", str(out), "--particles", "0"]) == 2
    assert "--particles" in capsys.readouterr().err
    assert main(["slam", str(log), "--out", str(out), "--resolution", "-1"]) == 2
    assert not out.exists()
    with pytest.raises(InputError):
        load_log(log, "nonsense")


# ----------------------------------------------------------------------------- command


@pytest.mark.parametrize("backend", ["graph", "rbpf"])
def test_slam_command_writes_map_trajectory_figure(tmp_path, run_records, backend, capsys):
    write_carmen(tmp_path / "run.log", run_records)
    out = tmp_path / "out"
    rc = main(
        [
            "slam",
            str(tmp_path / "run.log"),
            "--out",
            str(out),
            "--backend",
            backend,
            "--particles",
            "4",
            "--quiet",
        ]
    )
    assert rc == 0, capsys.readouterr().err
    m = load_ros_map(out / "map.yaml")
    assert m.occupied.sum() > 100 and m.free.sum() > 1000
    traj = np.loadtxt(out / "trajectory.csv", delimiter=",", skiprows=1)
    assert traj.shape[1] == 4 and len(traj) > 5
    assert np.all(np.diff(traj[:, 0]) > 0)
    assert (out / "figure.png").stat().st_size > 10_000
    assert not list(out.glob(".*.tmp*"))


def test_gzip_breezyslam(tmp_path):
    r = np.full(682, 2000)
    text = "\n".join(_breezy_line(k * 100_000, 10 * k, 10 * k, r) for k in range(3)) + "\n"
    with gzip.open(tmp_path / "x.dat.gz", "wt") as f:
        f.write(text)
    assert len(load_log(tmp_path / "x.dat.gz")) == 3


def test_simulate_defaults_to_rbpf_and_its_run_replays(tmp_path, capsys):
    import json

    from map2map.core.grid import OccupancyMap
    from map2map.maps.formats import save_map

    data = np.full((52, 72), 127, np.uint8)
    data[1:-1, 1:-1] = 255
    data[[1, -2], 1:-1] = 0
    data[1:-1, [1, -2]] = 0
    save_map(OccupancyMap(data, 0.05), tmp_path / "plan.yaml")
    out = tmp_path / "run"
    rc = main(
        ["simulate", str(tmp_path / "plan.yaml"), "--out", str(out), "--duration", "15", "--quiet"]
    )
    assert rc == 0, capsys.readouterr().err
    assert json.loads((out / "report.json").read_text())["mapper"] == "rbpf"
    # the simulator's run folder is a valid input of map2map slam
    rc = main(["slam", str(out), "--out", str(tmp_path / "slam"), "--backend", "graph", "--quiet"])
    assert rc == 0, capsys.readouterr().err
    assert (tmp_path / "slam" / "map.yaml").is_file()


def test_demo_stage_maps_a_simulated_run(tmp_path):
    from _slam_synth import room_plan

    from map2map.demo import DemoContext, stage_slam

    ctx = DemoContext(out=tmp_path, seed=0, plan=room_plan())
    stage_slam(ctx)
    written = {p.relative_to(tmp_path).as_posix() for _, p in ctx.written}
    for backend in ("rbpf", "graph"):
        assert {f"slam/{backend}/map.yaml", f"slam/{backend}/figure.png"} <= written
        m = load_ros_map(tmp_path / "slam" / backend / "map.yaml")
        assert m.occupied.sum() > 100
    assert set(ctx.slam) == {"rbpf", "graph"}


def test_slam_command_skips_unused_messages_with_one_note(tmp_path, run_records, capsys):
    """Radish logs carry NEFF, SYNC, GPS... lines: skipped, counted, said once."""
    write_carmen(tmp_path / "run.log", run_records[:40])
    lines = (tmp_path / "run.log").read_text().splitlines()
    extra = []
    for line in lines:
        extra.append(line)
        if line.startswith("RAWLASER1"):
            extra += ["NEFF 29.5", "SYNC tag 0 host 0"]
    (tmp_path / "radish.log").write_text("\n".join(extra) + "\n")
    out = tmp_path / "out"
    rc = main(
        ["slam", str(tmp_path / "radish.log"), "--out", str(out), "--quiet", "--backend", "graph"]
    )
    err = capsys.readouterr().err.strip().splitlines()
    assert rc == 0 and (out / "map.yaml").is_file()
    notes = [e for e in err if "skipped" in e]
    assert len(notes) == 1 and "40 NEFF" in notes[0] and "40 SYNC" in notes[0], err
