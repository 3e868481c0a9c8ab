"""Plain pictures as maps: bit depths, colour, alpha, thresholds, round trips."""

import cv2
import numpy as np
import pytest

from map2map.core.errors import InputError
from map2map.core.grid import FREE, OCCUPIED, UNKNOWN, OccupancyMap
from map2map.maps.image import load_image_map, save_image_map

F, O, U = FREE, OCCUPIED, UNKNOWN


def test_grey_png_thresholds_and_negate(tmp_path):
    px = np.array([[0, 89, 90, 127, 205, 206, 255]], np.uint8)
    cv2.imwrite(str(tmp_path / "g.png"), px)
    m = load_image_map(tmp_path / "g.png", resolution=0.1)
    assert m.data.tolist() == [[O, O, U, U, U, F, F]]
    assert m.resolution == 0.1 and m.origin == (0.0, 0.0, 0.0)
    neg = load_image_map(tmp_path / "g.png", resolution=0.1, negate=True)
    assert neg.data.tolist() == [[F, U, U, U, O, O, O]]  # p = v / 255
    loose = load_image_map(tmp_path / "g.png", occupied_thresh=0.4, free_thresh=0.3)
    # p: 1, .65, .647, .502, .196, .192, 0
    assert loose.data.tolist() == [[O, O, O, O, F, F, F]]


def test_sixteen_bit_pgm(tmp_path):
    px = (np.array([[0, 89, 90, 206, 255]], np.uint16) * 257).astype(np.uint16)
    cv2.imwrite(str(tmp_path / "d.pgm"), px)
    assert (tmp_path / "d.pgm").read_bytes().startswith(b"P5\n")
    m = load_image_map(tmp_path / "d.pgm")
    assert m.data.tolist() == [[O, O, U, F, F]]
    assert m.meta["resolution_assumed"] is True and m.resolution == 0.05


def test_rgb_and_rgba(tmp_path):
    rgba = np.array(
        [[[255, 255, 255, 255], [0, 0, 0, 255], [0, 0, 0, 0], [255, 255, 255, 100]]], np.uint8
    )
    cv2.imwrite(str(tmp_path / "a.png"), rgba[:, :, [2, 1, 0, 3]])
    assert load_image_map(tmp_path / "a.png").data.tolist() == [[F, O, U, U]]
    rgb = np.array([[[255, 0, 0], [255, 255, 0], [250, 250, 255]]], np.uint8)
    cv2.imwrite(str(tmp_path / "c.png"), rgb[:, :, ::-1])
    assert load_image_map(tmp_path / "c.png").data.tolist() == [[O, U, F]]


def test_jpeg_is_thresholded_despite_compression_noise(tmp_path):
    img = np.full((64, 64), 255, np.uint8)
    img[20:44, 30:34] = 0
    img[:8] = 127
    cv2.imwrite(str(tmp_path / "j.jpg"), img, [cv2.IMWRITE_JPEG_QUALITY, 90])
    m = load_image_map(tmp_path / "j.jpg")
    assert (m.data[25:40, 31:33] == O).all()
    assert (m.data[50:, 40:] == F).all()
    assert (m.data[2:6] == U).all()


@pytest.mark.parametrize("suffix", [".png", ".pgm"])
def test_round_trip_keeps_values_and_frame(tmp_path, suffix):
    rng = np.random.default_rng(1)
    m = OccupancyMap(
        rng.choice(np.array([O, U, F], np.uint8), size=(23, 31)), 0.0375, (-1.25, 1 / 3, 0.2)
    )
    path = tmp_path / f"m{suffix}"
    save_image_map(m, path)
    raw = cv2.imread(str(path), cv2.IMREAD_UNCHANGED)
    assert raw.dtype == np.uint8 and np.array_equal(raw, m.data)  # our values, as is
    back = load_image_map(path)
    assert back == m and "resolution_assumed" not in back.meta
    assert load_image_map(path, resolution=0.5, origin=(0, 0, 0)).resolution == 0.5


def test_save_rejects_other_suffixes(tmp_path):
    m = OccupancyMap(np.full((2, 2), F, np.uint8), 0.05)
    with pytest.raises(InputError, match="use .png or .pgm"):
        save_image_map(m, tmp_path / "m.gif")
    assert not any(tmp_path.iterdir())


@pytest.mark.parametrize(
    "kwargs, message",
    [
        ({"resolution": 0.0}, "resolution must be > 0"),
        ({"resolution": -1.0}, "resolution must be > 0"),
        ({"occupied_thresh": 1.2}, "occupied_thresh must lie in [0, 1]"),
        ({"free_thresh": 0.8}, "must be smaller than occupied_thresh"),
    ],
)
def test_bad_parameters(tmp_path, kwargs, message):
    cv2.imwrite(str(tmp_path / "g.png"), np.zeros((2, 2), np.uint8))
    with pytest.raises(InputError) as err:
        load_image_map(tmp_path / "g.png", **kwargs)
    assert message in str(err.value)


def test_bad_files(tmp_path):
    with pytest.raises(InputError, match="not found"):
        load_image_map(tmp_path / "none.png")
    (tmp_path / "t.png").write_text("not a picture at all")
    with pytest.raises(InputError, match="not a readable image"):
        load_image_map(tmp_path / "t.png")
    ok, buf = cv2.imencode(".png", np.zeros((50, 50), np.uint8))
    (tmp_path / "cut.png").write_bytes(buf.tobytes()[:40])
    with pytest.raises(InputError, match="not a readable image"):
        load_image_map(tmp_path / "cut.png")
    (tmp_path / "empty.pgm").write_bytes(b"")
    with pytest.raises(InputError, match="empty"):
        load_image_map(tmp_path / "empty.pgm")
