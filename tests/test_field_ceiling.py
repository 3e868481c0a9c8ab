"""Moving walls by a field (map2map.learn.ba.field) and the field-ceiling diagnostic of
Table 5.3 (issue #32): labels, fit and warp on hand-made maps."""

import importlib

import numpy as np
import pytest

fc = importlib.import_module("map2map.experiments.table53.field_ceiling.__main__")
field = importlib.import_module("map2map.learn.ba.field")


def _room(shift: int = 0) -> np.ndarray:
    m = np.full((64, 64), 127, np.uint8)
    m[12:52, 12 + shift:52 + shift] = 255
    m[12:52, 12 + shift] = 0
    m[12:52, 51 + shift] = 0
    m[12, 12 + shift:52 + shift] = 0
    m[51, 12 + shift:52 + shift] = 0
    return m


def test_face_sets_and_offsets_of_a_shifted_wall():
    plan, slam = _room(0), _room(2)
    f = field.face_sets(slam)
    assert f[0][30, 14] and not f[2][30, 14]          # the west wall looks +x, into the room
    off = fc.face_offsets(slam, plan)
    off = off[~np.isnan(off)]
    # x faces are 2 px off (the +x face towards the wall, the -x face away), y faces 0
    assert set(np.unique(np.abs(off))) <= {0.0, 2.0}
    assert np.sum(np.abs(off) == 2) > 60


def test_zero_field_is_the_identity_and_a_translation_moves_walls():
    m = _room(0)
    assert np.array_equal(field.warp(m, np.zeros((2, 64, 64), np.float32)), m)
    u = np.zeros((2, 64, 64), np.float32)
    u[0] = 3.0
    assert np.array_equal(field.warp(m, u)[:, 3:], m[:, :-3])


def test_fitted_field_moves_the_walls_onto_the_plan():
    pytest.importorskip("torch")
    plan, slam = _room(0), _room(2)
    u = field.fit_field(slam, plan, grid=8, smooth=1.0, steps=150)
    walls = slam == 0
    assert abs(float(np.median(u[0][walls])) + 2.0) < 0.35     # moved 2 px back in x
    assert abs(float(np.median(u[1][walls]))) < 0.35
    out = field.warp(slam, u)
    assert np.mean((out == 0) == (plan == 0)) > 0.97
