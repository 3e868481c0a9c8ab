"""ROS map_server / Nav2 maps: hand-computed map_server semantics and exact round trips."""

import math

import cv2
import numpy as np
import pytest
import yaml

from map2map.core.errors import InputError
from map2map.core.grid import FREE, OCCUPIED, UNKNOWN, OccupancyMap
from map2map.maps.ros import load_ros_map, map_server_values, save_ros_map

F, O, U = FREE, OCCUPIED, UNKNOWN


def write_map(tmp_path, pixels, name="m", suffix=".pgm", **keys):
    """A yaml + picture pair; ``pixels`` is (H, W) grey or (H, W, 3|4) RGB(A)."""
    px = np.asarray(pixels)
    if px.ndim == 3:  # OpenCV writes BGR(A)
        px = px[:, :, [2, 1, 0, 3][: px.shape[2]]]
    assert cv2.imwrite(str(tmp_path / f"{name}{suffix}"), px)
    doc = {
        "image": f"{name}{suffix}",
        "resolution": 0.05,
        "origin": [0.0, 0.0, 0.0],
        "negate": 0,
        "occupied_thresh": 0.65,
        "free_thresh": 0.196,
    }
    doc.update(keys)
    doc = {k: v for k, v in doc.items() if v is not None}
    path = tmp_path / f"{name}.yaml"
    path.write_text(yaml.safe_dump(doc))
    return path


# ----------------------------------------------------------------- trinary
def test_trinary_grey_thresholds_by_hand(tmp_path):
    # p = (255 - v) / 255:  0 -> 1.0, 89 -> 0.651 (> 0.65), 90 -> 0.647, 205 -> 0.19608
    # (not < 0.196), 206 -> 0.19216, 254 -> 0.0039, 255 -> 0
    px = np.array([[0, 89, 90, 205, 206, 254, 255]], np.uint8)
    m = load_ros_map(write_map(tmp_path, px))
    assert m.data.tolist() == [[O, O, U, U, F, F, F]]
    assert "ros_values" not in m.meta
    assert m.meta["ros"]["mode"] == "trinary"


def test_trinary_negate_by_hand(tmp_path):
    # negate: p = v / 255:  49 -> 0.192 free, 50 -> 0.196078 unknown, 165 -> 0.647 unknown,
    # 166 -> 0.651 occupied
    px = np.array([[0, 49, 50, 165, 166, 255]], np.uint8)
    m = load_ros_map(write_map(tmp_path, px, negate=1))
    assert m.data.tolist() == [[F, F, U, U, O, O]]
    # the override wins over the yaml
    m2 = load_ros_map(write_map(tmp_path, px, name="n", negate=0), negate=True)
    assert np.array_equal(m.data, m2.data)


def test_trinary_colour_and_alpha_are_averaged(tmp_path):
    rgb = np.array([[[255, 0, 0], [255, 255, 0], [254, 254, 254]]], np.uint8)
    # means 85 (p 0.667 occupied), 170 (p 0.333 unknown), 254 (free)
    m = load_ros_map(write_map(tmp_path, rgb, name="rgb", suffix=".png"))
    assert m.data.tolist() == [[O, U, F]]
    rgba = np.array([[[255, 255, 255, 0], [0, 0, 0, 0], [255, 255, 255, 255]]], np.uint8)
    # trinary averages alpha in: (765 + 0) / 4 = 191.25 -> p 0.25 unknown; black -> occupied
    m = load_ros_map(write_map(tmp_path, rgba, name="rgba", suffix=".png"))
    assert m.data.tolist() == [[U, O, F]]
    m = load_ros_map(write_map(tmp_path, rgba, name="rgba2", suffix=".png", free_thresh=0.3))
    assert m.data.tolist() == [[F, O, F]]


def test_sixteen_bit_picture_uses_its_full_range(tmp_path):
    px = (np.array([[0, 89, 90, 205, 206, 255]], np.uint16) * 257).astype(np.uint16)
    m = load_ros_map(write_map(tmp_path, px, suffix=".png"))
    assert m.data.tolist() == [[O, O, U, U, F, F]]


def test_pgm_with_its_own_maximum_value(tmp_path):
    """A PGM may declare maxval 100: 100 is white, as map_server's image readers scale it."""
    path = write_map(tmp_path, np.zeros((1, 3), np.uint8))
    (tmp_path / "m.pgm").write_bytes(b"P5\n3 1\n100\n\x00\x32\x64")
    assert load_ros_map(path).data.tolist() == [[O, U, F]]
    assert load_ros_map(path, flavor="ros1").data.tolist() == [[O, U, F]]


# ----------------------------------------------------------------- scale
def test_scale_mode_nav2_and_ros1_by_hand(tmp_path):
    # occ 0.6, free 0.2: v=153 -> p 0.4 -> ratio 0.5; v=110 -> p 0.5686 -> ratio 0.9216;
    # v=200 -> p 0.2157 -> ratio 0.0392; v=0 occupied; v=255 free
    px = np.array([[153, 110, 200, 0, 255]], np.uint8)
    path = write_map(tmp_path, px, mode="scale", occupied_thresh=0.6, free_thresh=0.2)
    m = load_ros_map(path)
    assert m.meta["ros_values"].tolist() == [[50, 92, 4, 100, 0]]  # Nav2: rint(100 ratio)
    assert m.data.tolist() == [[U, U, U, O, F]]
    prob = m.meta["occupancy_probability"]
    assert prob.dtype == np.float32
    assert np.allclose(prob, [[0.5, 0.92, 0.04, 1.0, 0.0]])
    r1 = load_ros_map(path, flavor="ros1")
    assert r1.meta["ros_values"].tolist() == [[49, 91, 3, 100, 0]]  # ROS 1: trunc(99 ratio)


def test_scale_mode_negate(tmp_path):
    # negate: p = v / 255: v=102 -> p 0.4 -> ratio 0.5; v=255 -> occupied; v=0 -> free
    px = np.array([[102, 255, 0]], np.uint8)
    m = load_ros_map(
        write_map(tmp_path, px, mode="scale", negate=1, occupied_thresh=0.6, free_thresh=0.2)
    )
    assert m.meta["ros_values"].tolist() == [[50, 100, 0]]
    assert m.data.tolist() == [[U, O, F]]


def test_scale_mode_transparency_is_unknown(tmp_path):
    rgba = np.array(
        [[[0, 0, 0, 0], [0, 0, 0, 128], [153, 153, 153, 255], [153, 153, 153, 0]]], np.uint8
    )
    path = write_map(
        tmp_path, rgba, suffix=".png", mode="scale", occupied_thresh=0.6, free_thresh=0.2
    )
    nav2 = load_ros_map(path)
    # Nav2: any transparency -> unknown; colour channels only (alpha not averaged in)
    assert nav2.meta["ros_values"].tolist() == [[-1, -1, 50, -1]]
    assert np.isnan(nav2.meta["occupancy_probability"][0, [0, 1, 3]]).all()
    # ROS 1: thresholds first, then unknown only for alpha == 0 between them
    ros1 = load_ros_map(path, flavor="ros1")
    assert ros1.meta["ros_values"].tolist() == [[100, 100, 49, -1]]


# ----------------------------------------------------------------- raw
def test_raw_mode_by_hand(tmp_path):
    px = np.array([[0, 50, 100, 101, 255]], np.uint8)
    path = write_map(tmp_path, px, mode="raw")
    m = load_ros_map(path)
    assert m.meta["ros_values"].tolist() == [[0, 50, 100, -1, -1]]
    assert m.data.tolist() == [[F, U, O, U, U]]
    # Nav2 ignores negate in raw mode
    assert load_ros_map(path, negate=True).meta["ros_values"].tolist() == [[0, 50, 100, -1, -1]]
    # ROS 1 applies negate to the mean and stores it as a signed byte
    r1 = load_ros_map(path, negate=True, flavor="ros1").meta["ros_values"]
    assert r1.tolist() == [[-1, -51, 155 - 256, 154 - 256, 0]]
    assert load_ros_map(path, flavor="ros1").meta["ros_values"].tolist() == [[0, 50, 100, 101, -1]]


def test_map_server_values_rejects_unknown_mode():
    from map2map.maps.raster import RasterImage

    img = RasterImage(np.zeros((1, 1, 1), np.uint8), None, 255)
    with pytest.raises(ValueError):
        map_server_values(img, mode="fancy")


# ----------------------------------------------------------------- origin and frame
def test_origin_with_yaw_matches_map_server_cell_positions(tmp_path):
    h, w, res = 6, 9, 0.1
    px = np.full((h, w), 254, np.uint8)
    px[1, 7] = 0  # one occupied pixel, image row 1 (near the top), column 7
    ox, oy, yaw = 1.5, -2.0, math.pi / 4
    m = load_ros_map(write_map(tmp_path, px, resolution=res, origin=[ox, oy, yaw]))
    assert m.origin == (ox, oy, yaw) and m.resolution == res
    # map_server stores image row y at OccupancyGrid row (H - 1 - y); cell (i, j) centre is
    # origin + R(yaw) ((i + 0.5) res, (j + 0.5) res)
    i, j = 7, h - 1 - 1
    lx, ly = (i + 0.5) * res, (j + 0.5) * res
    expect = (
        ox + math.cos(yaw) * lx - math.sin(yaw) * ly,
        oy + math.sin(yaw) * lx + math.cos(yaw) * ly,
    )
    rows, cols = np.nonzero(m.occupied)
    assert (rows.tolist(), cols.tolist()) == ([1], [7])
    assert np.allclose(m.pixel_to_world(rows[0], cols[0]), expect)
    # the lower-left pixel centre sits half a cell from the origin along the rotated axes
    x0, y0 = m.pixel_to_world(h - 1, 0)
    d = 0.5 * res
    assert np.allclose(
        (x0, y0),
        (ox + math.cos(yaw) * d - math.sin(yaw) * d, oy + math.sin(yaw) * d + math.cos(yaw) * d),
    )


# ----------------------------------------------------------------- writing
def random_map(seed=0, shape=(37, 53), res=0.05, origin=(-3.25, 11.5, 0.3)):
    rng = np.random.default_rng(seed)
    data = rng.choice(np.array([O, U, F], np.uint8), size=shape)
    return OccupancyMap(data, res, origin)


def test_save_writes_what_map_saver_writes(tmp_path):
    m = random_map()
    pgm = save_ros_map(m, tmp_path / "out" / "map.yaml")
    assert pgm == tmp_path / "out" / "map.pgm"
    raw = pgm.read_bytes()
    assert raw.startswith(b"P5\n")
    img = cv2.imread(str(pgm), cv2.IMREAD_UNCHANGED)
    assert img.dtype == np.uint8 and img.shape == m.shape
    assert set(np.unique(img).tolist()) == {0, 205, 254}
    assert np.array_equal(img == 254, m.free) and np.array_equal(img == 0, m.occupied)
    doc = yaml.safe_load((tmp_path / "out" / "map.yaml").read_text())
    assert doc["image"] == "map.pgm"
    assert doc["negate"] == 0 and doc["mode"] == "trinary"
    assert doc["occupied_thresh"] == 0.65 and doc["free_thresh"] == 0.196
    assert doc["origin"] == [-3.25, 11.5, 0.3] and doc["resolution"] == 0.05
    assert sorted(p.name for p in (tmp_path / "out").iterdir()) == ["map.pgm", "map.yaml"]


@pytest.mark.parametrize(
    "res, origin", [(0.05, (0.0, 0.0, 0.0)), (0.0123456789, (-1 / 3, 2e-7, -2.5))]
)
def test_round_trip_is_exact(tmp_path, res, origin):
    m = random_map(res=res, origin=origin)
    save_ros_map(m, tmp_path / "a.yaml")
    a = load_ros_map(tmp_path / "a.yaml")
    assert a == m and a.origin == m.origin and a.resolution == m.resolution
    save_ros_map(a, tmp_path / "b.yaml")
    b = load_ros_map(tmp_path / "b.yaml")
    assert b == a
    assert (tmp_path / "a.pgm").read_bytes() == (tmp_path / "b.pgm").read_bytes()


def test_foreign_map_load_save_load_is_unchanged(tmp_path):
    """A negated PNG map with other thresholds survives load -> save -> load."""
    rng = np.random.default_rng(3)
    px = rng.integers(0, 256, size=(20, 30), dtype=np.uint8)
    path = write_map(
        tmp_path,
        px,
        suffix=".png",
        negate=1,
        occupied_thresh=0.7,
        free_thresh=0.3,
        origin=[4.0, -1.0, 1.0],
    )
    first = load_ros_map(path)
    save_ros_map(first, tmp_path / "saved.yaml")
    again = load_ros_map(tmp_path / "saved.yaml")
    assert again == first


def test_image_relative_to_yaml_folder(tmp_path, monkeypatch):
    sub = tmp_path / "maps"
    sub.mkdir()
    write_map(sub, np.full((3, 4), 254, np.uint8))
    monkeypatch.chdir(tmp_path)  # the picture is NOT in the working directory
    assert load_ros_map("maps/m.yaml").free.all()


# ----------------------------------------------------------------- bad input
@pytest.mark.parametrize(
    "keys, message",
    [
        ({"image": None}, "no 'image'"),
        ({"resolution": None}, "no 'resolution'"),
        ({"resolution": 0}, "resolution must be > 0"),
        ({"resolution": -0.05}, "resolution must be > 0"),
        ({"occupied_thresh": 1.5}, "occupied_thresh must lie in [0, 1]"),
        ({"free_thresh": -0.1}, "free_thresh must lie in [0, 1]"),
        ({"free_thresh": 0.7}, "must be smaller than occupied_thresh"),
        ({"origin": [0, 0]}, "'origin' must be [x, y, yaw]"),
        ({"mode": "fancy"}, "'mode' must be one of"),
        ({"image": "nowhere.pgm"}, "image file not found"),
    ],
)
def test_bad_yaml_raises_input_error(tmp_path, keys, message):
    path = write_map(tmp_path, np.full((3, 3), 254, np.uint8), **keys)
    with pytest.raises(InputError) as err:
        load_ros_map(path)
    assert message in str(err.value)


def test_corrupt_image_raises_input_error(tmp_path):
    path = write_map(tmp_path, np.full((3, 3), 254, np.uint8))
    (tmp_path / "m.pgm").write_bytes(b"P5\n3 3\n255\n\x00")  # truncated
    with pytest.raises(InputError, match="not a readable image"):
        load_ros_map(path)
    (tmp_path / "m.pgm").write_text("this is not a picture")
    with pytest.raises(InputError, match="not a readable image"):
        load_ros_map(path)


def test_missing_and_non_yaml_files(tmp_path):
    with pytest.raises(InputError, match="file not found"):
        load_ros_map(tmp_path / "absent.yaml")
    bad = tmp_path / "bad.yaml"
    bad.write_text("image: [unclosed\n")
    with pytest.raises(InputError, match="not valid YAML"):
        load_ros_map(bad)
    bad.write_text("just a string\n")
    with pytest.raises(InputError, match="not a map yaml"):
        load_ros_map(bad)
