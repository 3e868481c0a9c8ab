"""Particle count of ``map2map slam``: more for a recorded log than for a simulator run
(issue #35, item 3), ``--particles`` overriding; no full SLAM run."""

from __future__ import annotations

import numpy as np
import pytest

from map2map.cli.main import main
from map2map.robotlog.base import LaserScan, OdometryReading
from map2map.robotlog.carmen import CarmenLog
from map2map.slam.offline import (
    RECORDED_LOG_PARTICLES,
    backend_options,
    default_particles,
    run_slam,
)
from map2map.slam.rbpf import GMappingParams

SIM_START = {"map2map_start_x": "1.0", "map2map_start_y": "2.0", "map2map_start_theta": "0.5"}


def _log(params=None, n=3, beams=180, range_max=50.0) -> CarmenLog:
    ang = np.pi / (beams - 1)
    scans = [
        LaserScan(float(k), np.full(beams, 2.0, np.float32), -np.pi / 2, ang, 0.1, range_max)
        for k in range(n)
    ]
    odo = [OdometryReading(float(k), 0.1 * k, 0.0, 0.0) for k in range(n)]
    return CarmenLog(odometry=odo, scans=scans, params=params or {})


def test_recorded_log_gets_more_particles_than_a_simulator_run():
    assert RECORDED_LOG_PARTICLES > GMappingParams().particles == 5
    assert default_particles(_log()) == RECORDED_LOG_PARTICLES
    assert default_particles(_log(SIM_START)) == 5  # simulate / datasets: unchanged
    assert default_particles(_log(), "graph") is None
    assert backend_options(_log())["particles"] == RECORDED_LOG_PARTICLES
    assert backend_options(_log(SIM_START))["particles"] == 5
    assert "particles" not in backend_options(_log(), "graph")


@pytest.mark.parametrize("params", [None, SIM_START])
def test_particles_argument_overrides_the_default(params):
    assert backend_options(_log(params), particles=2)["particles"] == 2
    res = run_slam(_log(params), "rbpf", particles=2)
    assert res.mapper.params.particles == 2
    assert len(res.mapper.grids) == 2


def test_run_slam_uses_the_default_for_the_log():
    assert run_slam(_log()).mapper.params.particles == RECORDED_LOG_PARTICLES
    assert run_slam(_log(SIM_START)).mapper.params.particles == 5


def test_slam_help_states_the_default(capsys):
    with pytest.raises(SystemExit):
        main(["slam", "--help"])
    text = " ".join(capsys.readouterr().out.split())
    assert f"default {RECORDED_LOG_PARTICLES} for a recorded log" in text
    assert "5 for a 'map2map simulate' run" in text
