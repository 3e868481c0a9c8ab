"""Packed paired datasets: round trip, size, identity, bad files."""

import numpy as np
import pytest

from map2map.core.errors import InputError
from map2map.datasets.packed import (
    PackedPairs,
    load_packed,
    pack_ternary,
    save_packed,
    unpack_ternary,
)
from map2map.maps import generate_floorplan, preprocess


def _pairs(n=6, size=64):
    maps = [preprocess(generate_floorplan(s, kind="apartment"), size=size).data for s in range(n)]
    a = np.stack(maps)
    b = a.copy()
    b[:, ::7] = 127
    return PackedPairs(a, b, [f"p{i // 2}" for i in range(n)], ["train"] * (n - 2) + ["test"] * 2,
                       {"seed": 3})


def test_pack_roundtrip_odd_sizes():
    rng = np.random.default_rng(1)
    m = rng.choice(np.array([0, 127, 255], np.uint8), size=(3, 7, 5))
    assert np.array_equal(unpack_ternary(pack_ternary(m), m.shape), m)


def test_pack_rejects_other_values():
    with pytest.raises(ValueError, match="only 0, 127 and 255"):
        pack_ternary(np.array([[0, 128]], np.uint8))


def test_save_load_roundtrip_and_meta(tmp_path):
    pairs = _pairs()
    path = save_packed(tmp_path / "ds.npz", pairs)
    back = load_packed(path)
    assert np.array_equal(back.a, pairs.a) and np.array_equal(back.b, pairs.b)
    assert back.plan_id.tolist() == pairs.plan_id.tolist()
    assert back.meta["splits"] == {"train": 4, "val": 0, "test": 2}
    assert back.meta["digest"] == pairs.digest()
    assert len(back.select("test")) == 2


def test_corrupt_and_foreign_files(tmp_path):
    bad = tmp_path / "bad.npz"
    bad.write_bytes(b"not a zip")
    with pytest.raises(InputError, match="bad.npz"):
        load_packed(bad)
    other = tmp_path / "other.npz"
    np.savez(other, meta=np.array('{"format": "x"}'))
    with pytest.raises(InputError, match="not a map2map packed-pairs file"):
        load_packed(other)
    with pytest.raises(InputError, match="file not found"):
        load_packed(tmp_path / "missing.npz")


def test_shape_checks():
    a = np.zeros((2, 4, 4), np.uint8)
    with pytest.raises(ValueError):
        PackedPairs(a, a[:, :2], ["x", "y"], ["train", "train"])
    with pytest.raises(ValueError, match="split"):
        PackedPairs(a, a, ["x", "y"], ["train", "nope"])
