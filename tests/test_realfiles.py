"""Real files load: every command reads maps the same way (grey walls), the project reads its
own outputs, degenerate inputs are flagged, and bad arguments answer one line + exit 2."""

from __future__ import annotations

import json

import cv2
import numpy as np
import pytest

from map2map.cli.main import build_parser, main
from map2map.maps.floorplan import generate_floorplan
from map2map.maps.formats import MapReadOptions, load_map, save_map

#: Commands that read a map, with the arguments they need besides the map.
MAP_READERS = {
    "convert": ["{map}", "{out}/x.png"],
    "prep": ["{map}", "{out}/x.png"],
    "show": ["{map}", "--out", "{out}/x.png"],
    "simulate": ["{map}", "--out", "{out}"],
    "deform": ["{map}", "--out", "{out}"],
    "align": ["{map}", "{map}", "--out", "{out}"],
    "evaluate": ["{map}", "{map}", "--out", "{out}"],
}
READ_FLAGS = [
    "--occupied-thresh",
    "0.3",
    "--free-thresh",
    "0.1",
    "--negate",
    "--mode",
    "trinary",
    "--layers",
    "A,B",
    "--wall-thickness",
    "0.2",
    "--dxf-units",
    "mm",
]


@pytest.fixture(scope="module")
def small_plan():
    return generate_floorplan(3, size=(6, 5))


def grey_walls(m):
    """The map as real ones are saved: walls grey (170), unknown map_saver's 205."""
    grey = m.data.copy()
    grey[m.data == 0] = 170
    grey[m.data == 127] = 205
    return grey


def err_lines(capsys):
    return capsys.readouterr().err.strip().splitlines()


def assert_one_line_exit_2(rc, capsys, *needles):
    err = err_lines(capsys)
    assert rc == 2, err
    assert len(err) == 1 and err[0].startswith("map2map: error:"), err
    for n in needles:
        assert n in err[0], err[0]


# ------------------------------------------------------------------ reading options


@pytest.mark.parametrize("command", sorted(MAP_READERS))
def test_every_map_reading_command_takes_the_same_reading_options(command):
    args = [a.format(map="m.png", out="o") for a in MAP_READERS[command]]
    ns = build_parser().parse_args([command, *args, *READ_FLAGS])
    from map2map.cli._mapargs import read_options_from_args

    o = read_options_from_args(ns)
    assert (o.occupied_thresh, o.free_thresh, o.negate, o.mode) == (0.3, 0.1, True, "trinary")
    assert (o.layers, o.wall_thickness, o.units) == (("A", "B"), 0.2, "mm")


def test_grey_walls_align_and_deform_with_threshold(tmp_path, small_plan, capsys):
    """A real map whose walls are grey (170) reads them as unknown by default; the reading
    options that convert has make align, evaluate and deform see them."""
    save_map(small_plan, tmp_path / "plan.png")
    grey = grey_walls(small_plan)
    cv2.imwrite(str(tmp_path / "grey.png"), grey)
    g, p = str(tmp_path / "grey.png"), str(tmp_path / "plan.png")
    rc = main(["align", g, p, "--out", str(tmp_path / "a0"), "--resolution", "0.05"])
    assert_one_line_exit_2(rc, capsys, "no occupied pixels", "--occupied-thresh")
    rc = main(
        ["align", g, p, "--out", str(tmp_path / "a1"), "--resolution", "0.05",
         "--occupied-thresh", "0.3"]
    )  # fmt: skip
    assert rc == 0, err_lines(capsys)
    doc = json.loads((tmp_path / "a1" / "alignment.json").read_text())
    assert doc["fitness"] > 0.9 and abs(doc["scale"] - 1) < 0.02
    # an option that applies to none of the inputs is refused
    rc = main(["align", g, p, "--out", str(tmp_path / "a2"), "--layers", "WALLS"])
    assert_one_line_exit_2(rc, capsys, "--layers", "does not apply")
    # deform reads the grey walls too, and its repeat line carries the option
    rc = main(
        ["deform", g, "--out", str(tmp_path / "d"), "--resolution", "0.05", "--quiet",
         "--occupied-thresh", "0.3"]
    )  # fmt: skip
    assert rc == 0, err_lines(capsys)
    params = (tmp_path / "d" / "params.yaml").read_text()
    assert "--occupied-thresh 0.3" in params


def test_read_options_value_drives_load_map(tmp_path, small_plan):
    grey = grey_walls(small_plan)
    cv2.imwrite(str(tmp_path / "grey.png"), grey)
    assert not load_map(tmp_path / "grey.png").occupied.any()
    m = load_map(tmp_path / "grey.png", MapReadOptions(occupied_thresh=0.3))
    assert np.array_equal(m.occupied, small_plan.occupied)


# -------------------------------------------------------- the project's own files


def test_plan_meta_json_converts_back_to_the_plan(tmp_path, capsys):
    yaml_, meta = tmp_path / "apt.yaml", tmp_path / "apt.json"
    assert main(["plan", "--seed", "2", "--out", str(yaml_), "--meta", str(meta),
                 "--resolution", "0.1"]) == 0  # fmt: skip
    assert main(["convert", str(meta), str(tmp_path / "back.yaml")]) == 0, err_lines(capsys)
    assert load_map(tmp_path / "back.yaml") == load_map(yaml_)  # same bytes, same resolution
    # any resolution: the layout is rebuilt, not resampled
    assert main(["convert", str(meta), str(tmp_path / "fine.png"), "--resolution", "0.05"]) == 0
    assert load_map(tmp_path / "fine.png").shape[0] == 2 * load_map(yaml_).shape[0]
    # a layout whose digest no longer matches (another generator version) is refused
    doc = json.loads(meta.read_text())
    doc["map_sha256"] = "0" * 64
    meta.write_text(json.dumps(doc))
    rc = main(["convert", str(meta), str(tmp_path / "x.yaml")])
    assert_one_line_exit_2(rc, capsys, "apt.json", "convert the map file saved with it")


def _square_dxf(path, size_m=10.0):
    import ezdxf

    doc = ezdxf.new()
    doc.header["$INSUNITS"] = 6  # metres
    msp = doc.modelspace()
    c = [(0, 0), (size_m, 0), (size_m, 0.8 * size_m), (0, 0.8 * size_m), (0, 0)]
    for a, b in zip(c[:-1], c[1:], strict=True):
        msp.add_line(a, b)
    doc.saveas(path)


def test_dxf_read_with_wrong_units_warns_and_empty_map_is_refused(tmp_path, capsys):
    _square_dxf(tmp_path / "m.dxf")
    assert main(["convert", str(tmp_path / "m.dxf"), str(tmp_path / "ok.yaml")]) == 0
    assert not [e for e in err_lines(capsys) if "warning" in e]
    rc = main(["convert", str(tmp_path / "m.dxf"), str(tmp_path / "mm.yaml"), "--units", "mm"])
    err = [e for e in err_lines(capsys) if "warning" in e]
    assert rc == 0 and len(err) == 1, err
    assert "m.dxf" in err[0] and "no free space" in err[0] and "implausible" in err[0]
    # an all-unknown picture reads as nothing at all: refused
    cv2.imwrite(str(tmp_path / "blank.png"), np.full((40, 40), 127, np.uint8))
    rc = main(["convert", str(tmp_path / "blank.png"), str(tmp_path / "b.yaml")])
    assert_one_line_exit_2(rc, capsys, "blank.png", "empty")
    assert not (tmp_path / "b.yaml").exists()


# ------------------------------------------------------------ one line, exit 2


@pytest.fixture(scope="module")
def maps_dir(tmp_path_factory, small_plan):
    d = tmp_path_factory.mktemp("maps")
    save_map(small_plan, d / "plan.yaml")
    full = np.zeros_like(small_plan.data)
    cv2.imwrite(str(d / "walls.png"), full)  # an all-occupied map
    return d


SEED_COMMANDS = {
    "simulate": ["{plan}", "--out", "{out}", "--duration", "5"],
    "deform": ["{plan}", "--out", "{out}"],
    "slam": ["{run}", "--out", "{out}"],
    "align": ["{plan}", "{plan}", "--out", "{out}"],
    "evaluate": ["{plan}", "{plan}", "--out", "{out}"],
}


@pytest.mark.parametrize("command", sorted(SEED_COMMANDS))
def test_negative_seed_is_one_line(command, maps_dir, tmp_path, capsys):
    run = tmp_path / "run.log"
    run.write_text("ODOM 0 0 0 0 0 0 1 h 1\nRAWLASER1 3 0 1 1 3.5 0.01 0 2 1.0 1.0 0 1 h 1\n")
    args = [
        a.format(plan=maps_dir / "plan.yaml", out=tmp_path / "o", run=run)
        for a in SEED_COMMANDS[command]
    ]
    rc = main([command, *args, "--seed", "-1"])
    assert_one_line_exit_2(rc, capsys, "--seed", "non-negative")
    assert not (tmp_path / "o").exists()


@pytest.mark.parametrize(
    ("command", "order"),
    [("align", "walls_first"), ("evaluate", "walls_first"), ("evaluate", "plan_first"),
     ("align", "plan_first")],
)  # fmt: skip
def test_all_occupied_map_is_one_line(command, order, maps_dir, tmp_path, capsys):
    plan, walls = str(maps_dir / "plan.yaml"), str(maps_dir / "walls.png")
    pair = [walls, plan] if order == "walls_first" else [plan, walls]
    rc = main([command, *pair, "--out", str(tmp_path / "o"), "--resolution", "0.05"])
    assert_one_line_exit_2(rc, capsys, "walls.png", "no free pixels")


# ------------------------------------------------ every text output parses


def _parse_text_outputs(folder):
    """Parse every .csv/.json/.yaml under ``folder`` with the standard modules."""
    import csv

    import yaml

    #: CSV columns that hold words, not numbers (points.csv's point class, pairs.csv's warnings).
    TEXT_COLUMNS = {"class", "warnings", "slam", "plan", "anchors", "chain"}
    seen = []
    for p in sorted(folder.rglob("*")):
        if p.name.startswith(".") or not p.is_file():
            continue
        if p.suffix == ".csv":
            with open(p, newline="") as fh:
                rows = list(csv.reader(fh))
            header, body = rows[0], rows[1:]
            assert body, p
            for row in body:
                assert len(row) == len(header), (p, row)
                for name, cell in zip(header, row, strict=True):
                    if name in TEXT_COLUMNS:
                        assert "np." not in cell, (p, name, cell)
                        continue
                    float(cell)  # every numeric cell: a plain number (no "np.float64(...)")
        elif p.suffix == ".json":
            json.loads(p.read_text())
        elif p.suffix in (".yaml", ".yml"):
            assert yaml.safe_load(p.read_text()) is not None, p
        else:
            continue
        seen.append(p.relative_to(folder).as_posix())
    return seen


def test_every_command_writes_text_the_standard_modules_read(tmp_path, capsys):
    """plan, convert, prep, deform, simulate, slam, align, evaluate: every CSV, JSON and
    YAML they write parses with csv/json/yaml, and the commands read each other's files
    (deform --trajectory takes the simulator's trajectory_true.csv)."""
    t = tmp_path
    steps = [
        ["plan", "--seed", "3", "--size", "6", "5", "--out", f"{t}/plan/plan.yaml",
         "--meta", f"{t}/plan/plan.json"],
        ["convert", f"{t}/plan/plan.json", f"{t}/convert/plan.yaml"],
        ["prep", f"{t}/plan/plan.yaml", f"{t}/prep/plan_64.yaml", "--size", "64"],
        ["simulate", f"{t}/plan/plan.yaml", "--out", f"{t}/sim", "--duration", "20",
         "--quiet"],
        ["deform", f"{t}/plan/plan.yaml", "--out", f"{t}/deform", "--quiet",
         "--trajectory", f"{t}/sim/trajectory_true.csv"],
        ["slam", f"{t}/sim", "--out", f"{t}/slam", "--quiet"],
        ["align", f"{t}/deform/slam_map.yaml", f"{t}/plan/plan.yaml", "--out", f"{t}/align",
         "--points", f"{t}/points.csv"],
        ["evaluate", f"{t}/deform/slam_map.yaml", f"{t}/plan/plan.yaml", "--out",
         f"{t}/evaluate", "--quiet"],
    ]  # fmt: skip
    (t / "points.csv").write_text("x,y\n10,12\n30.5,40\n")
    for args in steps:
        assert main(args) == 0, (args[0], err_lines(capsys))
    seen = _parse_text_outputs(t)
    for must in [
        "plan/plan.json", "plan/plan.yaml", "convert/plan.yaml", "prep/plan_64.yaml",
        "sim/trajectory_true.csv", "sim/trajectory_estimated.csv", "sim/report.json",
        "sim/slam_map.yaml", "deform/trajectory.csv", "deform/params.yaml",
        "deform/slam_map.yaml", "slam/trajectory.csv", "slam/map.yaml",
        "align/alignment.json", "align/points_aligned.csv", "evaluate/report.json",
    ]:  # fmt: skip
        assert must in seen, (must, seen)
