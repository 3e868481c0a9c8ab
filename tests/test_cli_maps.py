"""``map2map convert`` and ``map2map show``: every format, and every bad input of issue 2."""

import json
import os

import cv2
import ezdxf
import numpy as np
import pytest
import yaml

from map2map.cli.main import main
from map2map.core.grid import OccupancyMap
from map2map.maps.formats import load_map, save_map


@pytest.fixture
def inputs(tmp_path):
    """One small valid file of every format in tmp_path/in."""
    d = tmp_path / "in"
    d.mkdir()
    rng = np.random.default_rng(0)
    m = OccupancyMap(
        rng.choice(np.array([0, 127, 255], np.uint8), size=(30, 40)), 0.05, (1.0, -2.0, 0.3)
    )
    save_map(m, d / "ros.yaml")
    px = np.full((20, 30), 255, np.uint8)
    px[0] = px[-1] = 0
    cv2.imwrite(str(d / "pic.png"), px)
    plan = {
        "id": "t",
        "verts": [[0, 0], [2, 0], [2, 1.5], [2.01, 1.5], [2.01, 0], [4, 0], [4, 3], [0, 3]],
        "bbox": {"min": [0, 0], "max": [4, 3]},
        "room_category": {"Kitchen": [[0, 0, 2, 3]], "Bedroom": [[2, 0, 4, 3]]},
    }
    (d / "plan.json").write_text(json.dumps(plan))
    doc = ezdxf.new(units=4)
    doc.layers.add("WALLS")
    doc.layers.add("NOTES")
    msp = doc.modelspace()
    msp.add_lwpolyline(
        [(0, 0), (5000, 0), (5000, 4000), (0, 4000)], close=True, dxfattribs={"layer": "WALLS"}
    )
    msp.add_text("Hall", dxfattribs={"layer": "NOTES"})
    doc.saveas(d / "plan.dxf")
    return {"dir": d, "map": m}


def listing(folder):
    return sorted(str(p.relative_to(folder)) for p in folder.rglob("*"))


def cli(capsys, *args):
    rc = main([str(a) for a in args])
    out, err = capsys.readouterr()
    return rc, out, err


# ------------------------------------------------------------------ working conversions
@pytest.mark.parametrize("name", ["ros.yaml", "pic.png", "plan.json", "plan.dxf"])
@pytest.mark.parametrize("suffix", [".yaml", ".png", ".pgm"])
def test_convert_every_format(inputs, tmp_path, capsys, name, suffix):
    out = tmp_path / "out" / f"converted{suffix}"
    rc, stdout, err = cli(capsys, "convert", inputs["dir"] / name, out)
    assert rc == 0, err
    # a picture without a stored resolution keeps no metric scale through a conversion
    assert "wrote" in stdout and (" m, " in stdout or (name == "pic.png"
                                                        and "no metric scale" in stdout))
    back = load_map(out)
    src = load_map(inputs["dir"] / name)
    assert np.array_equal(back.data, src.data) and back.resolution == src.resolution
    assert np.allclose(back.origin, src.origin)
    if suffix == ".yaml":
        assert (out.parent / "converted.pgm").exists()


def test_convert_to_dxf_and_back(inputs, tmp_path, capsys):
    """HouseExpo plan -> ROS map -> DXF drawing -> ROS map: the walls survive cell for cell."""
    assert cli(capsys, "convert", inputs["dir"] / "plan.json", tmp_path / "a.yaml")[0] == 0
    rc, out, err = cli(capsys, "convert", tmp_path / "a.yaml", tmp_path / "a.dxf")
    assert rc == 0, err
    assert cli(capsys, "convert", tmp_path / "a.dxf", tmp_path / "b.yaml")[0] == 0
    a, b = load_map(tmp_path / "a.yaml"), load_map(tmp_path / "b.yaml")
    r, c = (int(v) for v in b.world_to_pixel(*a.pixel_to_world(0, 0)))
    window = b.data[r : r + a.height, c : c + a.width]
    assert np.array_equal(window == 0, a.occupied) and np.array_equal(window == 255, a.free)


def test_convert_ros_round_trip_is_exact(inputs, tmp_path, capsys):
    rc, _, _ = cli(capsys, "convert", inputs["dir"] / "ros.yaml", tmp_path / "a.yaml")
    assert rc == 0
    assert load_map(tmp_path / "a.yaml") == inputs["map"]


def test_convert_options_reach_the_readers(inputs, tmp_path, capsys):
    rc, _, err = cli(
        capsys, "convert", inputs["dir"] / "plan.dxf", tmp_path / "d.yaml",
        "--layers", "walls", "--wall-thickness", "0.2", "--resolution", "0.1",
    )  # fmt: skip
    assert rc == 0, err
    m = load_map(tmp_path / "d.yaml")
    assert m.resolution == 0.1 and m.width == round((5 + 0.2 + 1.0) / 0.1)
    rc, _, err = cli(capsys, "convert", inputs["dir"] / "pic.png", tmp_path / "p.yaml")
    assert rc == 0 and "assuming 0.05 m/px" in err
    rc, _, _ = cli(
        capsys, "convert", inputs["dir"] / "pic.png", tmp_path / "n.png", "--negate",
        "--resolution", "0.02",
    )  # fmt: skip
    n = load_map(tmp_path / "n.png")
    assert n.resolution == 0.02 and n.occupied[5, 5] and n.free[0, 0]


@pytest.mark.parametrize("name", ["ros.yaml", "pic.png", "plan.json", "plan.dxf"])
def test_show_draws_every_format(inputs, tmp_path, capsys, name):
    out = tmp_path / "fig" / "show.png"
    rc, stdout, err = cli(capsys, "show", inputs["dir"] / name, "--out", out, "--title", "T")
    assert rc == 0, err
    img = cv2.imread(str(out))
    assert img is not None and img.shape[0] > 200 and img.shape[1] > 200
    assert len(np.unique(img.reshape(-1, 3), axis=0)) > 4  # a real picture, not blank


def test_help_of_both_commands(capsys):
    for command in ("convert", "show"):
        with pytest.raises(SystemExit) as exc:
            main([command, "--help"])
        assert exc.value.code == 0
        assert "HouseExpo" in capsys.readouterr().out


# ------------------------------------------------------------------ bad input
def assert_bad(rc, err, *needles):
    lines = err.strip().splitlines()
    assert rc == 2, err
    assert len(lines) == 1, err
    assert lines[0].startswith("map2map: error: ")
    assert "Traceback" not in err
    for needle in needles:
        assert needle in lines[0], (needle, lines[0])


def write_yaml(folder, name="bad.yaml", **keys):
    doc = {"image": "img.pgm", "resolution": 0.05, "origin": [0, 0, 0], "negate": 0}
    doc.update({"occupied_thresh": 0.65, "free_thresh": 0.196})
    doc.update(keys)
    doc = {k: v for k, v in doc.items() if v is not None}
    cv2.imwrite(str(folder / "img.pgm"), np.full((4, 4), 254, np.uint8))
    (folder / name).write_text(yaml.safe_dump(doc))
    return folder / name


def bad_cases(d):
    """(input file, extra arguments, expected words) for every bad input of issue 2."""
    (d / "text.png").write_text("this is not an image")
    ok, buf = cv2.imencode(".png", np.zeros((64, 64), np.uint8))
    (d / "cut.png").write_bytes(buf.tobytes()[:60])
    (d / "noverts.json").write_text('{"bbox": {"min": [0, 0], "max": [1, 1]}}')
    (d / "twoverts.json").write_text('{"verts": [[0, 0], [1, 1]]}')
    doc = ezdxf.new()
    doc.layers.add("NOTES")
    doc.modelspace().add_text("only text", dxfattribs={"layer": "NOTES"})
    doc.saveas(d / "text.dxf")
    y = {}
    y["noimage"] = write_yaml(d, "noimage.yaml", image=None)
    y["nores"] = write_yaml(d, "nores.yaml", resolution=None)
    y["zero"] = write_yaml(d, "zero.yaml", resolution=0)
    y["neg"] = write_yaml(d, "neg.yaml", resolution=-0.05)
    y["noimg"] = write_yaml(d, "noimg.yaml", image="missing.pgm")
    y["corrupt"] = write_yaml(d, "corrupt.yaml", image="cut.png")
    y["occ"] = write_yaml(d, "occ.yaml", occupied_thresh=1.5)
    y["order"] = write_yaml(d, "order.yaml", free_thresh=0.7)
    return {
        "missing file": (d / "absent.yaml", [], ["absent.yaml", "file not found"]),
        "missing picture": (d / "absent.png", [], ["absent.png", "not found"]),
        "yaml without image": (y["noimage"], [], ["noimage.yaml", "no 'image'"]),
        "yaml without resolution": (y["nores"], [], ["nores.yaml", "no 'resolution'"]),
        "zero resolution": (y["zero"], [], ["zero.yaml", "resolution must be > 0"]),
        "negative resolution": (y["neg"], [], ["neg.yaml", "resolution must be > 0"]),
        "negative --resolution": (d / "text.png", ["--resolution", "-1"], ["must be > 0"]),
        "zero --resolution json": (d / "noverts.json", ["--resolution", "0"], ["resolution"]),
        "image not found": (y["noimg"], [], ["missing.pgm", "not found", "noimg.yaml"]),
        "corrupt image via yaml": (y["corrupt"], [], ["cut.png", "not a readable image"]),
        "corrupt image": (d / "cut.png", [], ["cut.png", "not a readable image"]),
        "non-image file": (d / "text.png", [], ["text.png", "not a readable image"]),
        "threshold above 1 in yaml": (y["occ"], [], ["occ.yaml", "occupied_thresh must lie in"]),
        "free >= occupied in yaml": (y["order"], [], ["order.yaml", "must be smaller than"]),
        "threshold below 0": (d / "cut.png", ["--free-thresh", "-0.1"], ["free_thresh must lie"]),
        "free >= occupied": (d / "cut.png", ["--free-thresh", "0.8"], ["must be smaller than"]),
        "json without verts": (d / "noverts.json", [], ["noverts.json", "no 'verts'"]),
        "json with 2 vertices": (d / "twoverts.json", [], ["twoverts.json", "at least 3"]),
        "dxf without entities": (d / "text.dxf", ["--layers", "NOTES"], ["text.dxf", "drawable"]),
        "option for another format": (d / "cut.png", ["--layers", "WALLS"], ["does not apply"]),
        "unknown input format": (d / "thing.xyz", [], ["thing.xyz", "unknown map format"]),
    }  # fmt: skip


CASES = [
    "missing file", "missing picture", "yaml without image", "yaml without resolution",
    "zero resolution", "negative resolution", "negative --resolution", "zero --resolution json",
    "image not found", "corrupt image via yaml", "corrupt image", "non-image file",
    "threshold above 1 in yaml", "free >= occupied in yaml", "threshold below 0",
    "free >= occupied", "json without verts", "json with 2 vertices", "dxf without entities",
    "option for another format", "unknown input format",
]  # fmt: skip


@pytest.mark.parametrize("command", ["convert", "show"])
@pytest.mark.parametrize("case", CASES)
def test_bad_input_is_one_line_exit_2_nothing_written(tmp_path, capsys, case, command):
    d = tmp_path / "in"
    d.mkdir()
    (d / "thing.xyz").write_text("?")
    path, extra, needles = bad_cases(d)[case]
    before = listing(tmp_path)
    out = tmp_path / "out" / ("map.yaml" if command == "convert" else "fig.png")
    argv = ["convert", path, out] if command == "convert" else ["show", path, "--out", out]
    rc, stdout, err = cli(capsys, *argv, *extra)
    assert_bad(rc, err, *needles)
    assert listing(tmp_path) == before  # nothing written, not even the output folder


@pytest.mark.parametrize("command", ["convert", "show"])
def test_output_directory_not_writable(inputs, tmp_path, capsys, command):
    blocker = tmp_path / "a_file"
    blocker.write_text("I am a file, not a folder")
    out = blocker / "sub" / ("map.yaml" if command == "convert" else "fig.png")
    before = listing(tmp_path)
    argv = ["convert", inputs["dir"] / "pic.png", out]
    if command == "show":
        argv = ["show", inputs["dir"] / "pic.png", "--out", out]
    rc, _, err = cli(capsys, *argv)
    assert_bad(rc, err, "a_file", "output directory")
    assert listing(tmp_path) == before


@pytest.mark.skipif(
    hasattr(os, "geteuid") and os.geteuid() == 0, reason="root ignores directory permissions"
)
def test_output_directory_read_only(inputs, tmp_path, capsys):
    ro = tmp_path / "ro"
    ro.mkdir()
    ro.chmod(0o555)
    try:
        rc, _, err = cli(capsys, "convert", inputs["dir"] / "pic.png", ro / "map.yaml")
        assert_bad(rc, err, "ro", "not writable")
        assert list(ro.iterdir()) == []
    finally:
        ro.chmod(0o755)


def test_bad_output_suffix(inputs, tmp_path, capsys):
    rc, _, err = cli(capsys, "convert", inputs["dir"] / "pic.png", tmp_path / "map.gif")
    assert_bad(rc, err, "map.gif", "cannot write")
    rc, _, err = cli(capsys, "show", inputs["dir"] / "pic.png", "--out", tmp_path / "fig.yaml")
    assert_bad(rc, err, "fig.yaml", "cannot write")
    assert listing(tmp_path) == listing(tmp_path)  # and nothing appeared
    assert not (tmp_path / "map.gif").exists() and not (tmp_path / "fig.yaml").exists()


def test_no_scale_bar_on_a_map_without_a_metric_scale():
    """draw_map draws the metric scale bar only on a map whose resolution is its own."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from matplotlib.offsetbox import AnchoredOffsetbox

    from map2map.core.grid import OccupancyMap
    from map2map.core.viz import draw_map

    data = np.full((40, 60), 255, np.uint8)
    for meta, bars in (({}, 1), ({"resolution_assumed": True}, 0)):
        fig, ax = plt.subplots()
        draw_map(ax, OccupancyMap(data, 0.05, meta=meta))
        assert sum(isinstance(a, AnchoredOffsetbox) for a in ax.artists) == bars
        plt.close(fig)
