"""Issue 11, item 4: a map too large for a command's memory budget is refused up front.

The inputs only *claim* to be huge (a PGM/PNG header, a HouseExpo plan or a CARMEN log
at a tiny resolution): nothing of their size is ever allocated. Each refusal is one
line naming the file, its size and the way out, exit status 2, no output written, and
the decoder is never called.
"""

from __future__ import annotations

import json
import struct

import numpy as np
import pytest

from map2map.cli.main import main
from map2map.core import limits

#: 32000 x 32000 px: over every command's budget, under the readers' hard cap.
SIDE = 32000

COMMANDS = {
    "convert": ["{map}", "{out}/x.png"],
    "prep": ["{map}", "{out}/x.png", "--size", "64"],
    "show": ["{map}", "--out", "{out}/x.png"],
    "simulate": ["{map}", "--out", "{out}/run"],
    "deform": ["{map}", "--out", "{out}/d"],
    "align": ["{map}", "{map}", "--out", "{out}/a"],
    "evaluate": ["{map}", "{map}", "--out", "{out}/e"],
}


@pytest.fixture
def no_decoding(monkeypatch):
    """Fail the test if anything decodes an image (the refusal must come first)."""
    import map2map.maps.raster as raster

    def refuse(*a, **k):
        raise AssertionError("decoded an image that should have been refused up front")

    monkeypatch.setattr(raster.cv2, "imdecode", refuse)


def huge_pgm(tmp_path):
    pgm = tmp_path / "huge.pgm"
    pgm.write_bytes(b"P5\n# claims to be huge\n%d %d\n255\n" % (SIDE, SIDE) + bytes(64))
    yaml = tmp_path / "huge.yaml"
    yaml.write_text(
        "image: huge.pgm\nresolution: 0.05\norigin: [0.0, 0.0, 0.0]\n"
        "negate: 0\noccupied_thresh: 0.65\nfree_thresh: 0.196\n"
    )
    return yaml


def huge_png(tmp_path):
    png = tmp_path / "huge.png"
    ihdr = struct.pack(">II", SIDE, SIDE) + bytes([8, 0, 0, 0, 0])
    png.write_bytes(b"\x89PNG\r\n\x1a\n" + struct.pack(">I", 13) + b"IHDR" + ihdr + bytes(8))
    return png


def check_refused(rc, capsys, out, *needles):
    err = capsys.readouterr().err.strip().splitlines()
    assert rc == 2, err
    assert len(err) == 1 and err[0].startswith("map2map: error:"), err
    for n in needles:
        assert n in err[0], err[0]
    assert not out.exists() or not any(out.iterdir()), list(out.rglob("*"))


def test_every_budget_lies_between_real_maps_and_the_test_size():
    """The sizes the tests use are refused, the real maps of the project are not."""
    for command in limits.MODELS:
        assert limits.max_pixels(command) < SIDE * SIDE < limits.READ_MAX_PIXELS, command
        if command != "slam":  # Halmstad maps (1585 px), HouseExpo renders at 1 cm
            assert limits.max_pixels(command) >= 3746 * 3268, command
    # slam: a 150 m square floor at the default 0.05 m
    assert limits.max_pixels("slam") >= 3000 * 3000


@pytest.mark.parametrize("command", sorted(COMMANDS))
@pytest.mark.parametrize("kind", ["ros", "png"])
def test_a_huge_map_is_refused_in_one_line_before_decoding(
    command, kind, tmp_path, capsys, no_decoding
):
    src = huge_pgm(tmp_path) if kind == "ros" else huge_png(tmp_path)
    out = tmp_path / "out"
    out.mkdir()
    argv = [a.format(map=src, out=out) for a in COMMANDS[command]]
    rc = main([command, *argv])
    name = "huge.pgm" if kind == "ros" else "huge.png"
    check_refused(rc, capsys, out, name, f"{SIDE} x {SIDE} px", "--max-pixels", "prep")


def test_max_pixels_override_lowers_and_lifts_the_limit(tmp_path, capsys, no_decoding):
    src = huge_pgm(tmp_path)
    out = tmp_path / "out"
    out.mkdir()
    rc = main(["convert", str(src), str(out / "x.png"), "--max-pixels", "1000"])
    check_refused(rc, capsys, out, "--max-pixels 1000 given")
    with pytest.raises(AssertionError, match="decoded"):  # lifted: it goes on to decode
        main(["convert", str(src), str(out / "x.png"), "--max-pixels", "0"])


def test_a_houseexpo_plan_at_a_tiny_resolution_is_refused_before_rasterising(
    tmp_path, capsys, monkeypatch
):
    import map2map.maps.houseexpo as hx

    def refuse(*a, **k):
        raise AssertionError("rasterised a plan that should have been refused")

    monkeypatch.setattr(hx, "fill_exact", refuse)
    plan = tmp_path / "house.json"
    verts = [[0, 0], [15, 0], [15, 15], [0, 15]]
    plan.write_text(json.dumps({"verts": verts, "bbox": {"min": [0, 0], "max": [15, 15]}}))
    out = tmp_path / "out"
    out.mkdir()
    rc = main(["convert", str(plan), str(out / "x.png"), "--resolution", "0.0005"])
    check_refused(rc, capsys, out, "house.json", "convert would need about")


def test_slam_refuses_a_map_too_large_for_its_resolution(tmp_path, capsys, monkeypatch):
    import map2map.robotlog.mappers as mappers

    def refuse(*a, **k):
        raise AssertionError("built a mapper for a map that should have been refused")

    monkeypatch.setattr(mappers, "make_mapper", refuse)
    ranges = " ".join(["2.0"] * 180)
    lines = [
        f"FLASER 180 {ranges} {x} 0.0 0.0 {x} 0.0 0.0 {t} host {t}"
        for t, x in enumerate([0.0, 0.1, 0.2, 300.0])
    ]
    log = tmp_path / "far.log"
    log.write_text("\n".join(lines) + "\n")
    out = tmp_path / "out"
    rc = main(["slam", str(log), "--out", str(out), "--resolution", "0.001", "--quiet"])
    check_refused(rc, capsys, out, "far.log", "would need about", "coarser --resolution")


def test_coherent_motion_takes_more_points_than_cv2_remap_rows():
    """Large maps have > 32766 edge points: cv2.remap refused a column that long."""
    from map2map.evaluate.nonrigid import coherent_motion

    rng = np.random.default_rng(0)
    n = 40000
    pts = rng.uniform(0, 2000, (n, 2))
    motion = np.column_stack([np.sin(pts[:, 0] / 300), np.cos(pts[:, 1] / 300)])
    out = coherent_motion(pts, motion, np.ones(n), 20.0)
    assert out.shape == (n, 2) and np.isfinite(out).all()
    # a smooth field stays itself: values sampled back in the wrong order would not
    assert np.abs(out - motion).mean() < 0.05


def test_slam_budget_counts_the_readings_not_the_sensor_maximum():
    """A 50 m scanner whose readings reach 8 m: the map is estimated from the 8 m."""
    from map2map.robotlog.base import LaserScan, OdometryReading
    from map2map.robotlog.carmen import CarmenLog
    from map2map.slam.offline import farthest_reading, map_tiles_estimate, memory_estimate

    scans = [LaserScan(float(t), np.full(180, 8.0), -np.pi / 2, np.pi / 180, 0.1, 50.0)
             for t in range(3)]  # fmt: skip
    log = CarmenLog([OdometryReading(float(t), 20.0 * t, 0.0, 0.0) for t in range(3)], scans)
    assert farthest_reading(log) == 8.0
    # the tiles the beams cross: the readings, not the 50 m
    assert map_tiles_estimate(log, 0.05, 8.1) == map_tiles_estimate(log, 0.05, 50.0)
    full = memory_estimate(log, "graph", max_range=50.0)
    assert full == memory_estimate(log, "graph", max_range=8.0)
