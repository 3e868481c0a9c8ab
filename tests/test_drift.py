"""Parametric drift on synthesized maps (map2map.learn.drift): seeded, per hypothesis,
the parametric model's field, generated maps' own unknown cells kept. No torch needed."""

import numpy as np
import pytest

from map2map.core.grid import FREE, OCCUPIED, UNKNOWN, OccupancyMap
from map2map.errors import InputError
from map2map.learn.drift import (
    apply_drift,
    check_drift,
    drift_field,
    drift_maps,
    drift_rng,
)


def _plan() -> OccupancyMap:
    """Two rooms joined by a door, 6 x 4 m at 0.1 m."""
    data = np.full((44, 64), UNKNOWN, np.uint8)
    data[2:42, 2:62] = FREE
    data[2, 2:62] = data[41, 2:62] = OCCUPIED
    data[2:42, 2] = data[2:42, 61] = OCCUPIED
    data[2:42, 30] = OCCUPIED
    data[18:26, 30] = FREE
    return OccupancyMap(data, resolution=0.1)


def test_drift_field_is_seeded_per_hypothesis_and_bit_identical():
    plan = _plan()
    a = drift_field(plan, drift_rng(3, 0))
    b = drift_field(plan, drift_rng(3, 0))
    c = drift_field(plan, drift_rng(3, 1))
    assert np.array_equal(a.field.dx, b.field.dx) and np.array_equal(a.field.dy, b.field.dy)
    assert not np.array_equal(a.field.dx, c.field.dx)          # hypothesis 1 drifts otherwise
    assert a.field.stats(a.observed)["mean"] > 0.1             # it does move the map
    assert np.array_equal(apply_drift(plan.data, a), apply_drift(plan.data, b))
    assert not np.array_equal(apply_drift(plan.data, a), apply_drift(plan.data, c))
    # carried to the unobserved pixels: every pixel takes its nearest observed one's value
    assert not a.observed.all()
    assert np.count_nonzero(a.field.magnitude[~a.observed] == 0) < np.count_nonzero(~a.observed)


def test_drift_scale_zero_is_the_identity_and_unknown_cells_stay():
    plan = _plan()
    m = plan.data.copy()
    m[:, 40:] = UNKNOWN                                        # a map that saw one room
    d0 = drift_field(plan, drift_rng(0, 0), scale=0.0)
    assert np.array_equal(apply_drift(m, d0), m)
    d = drift_field(plan, drift_rng(0, 0), scale=2.0)
    one = drift_field(plan, drift_rng(0, 0))
    assert np.allclose(d.field.dx, 2 * one.field.dx)
    out = apply_drift(m, d)
    assert set(np.unique(out).tolist()) <= {OCCUPIED, UNKNOWN, FREE}
    assert np.count_nonzero(out[:, 50:] != UNKNOWN) == 0       # nothing invented far out


def test_drift_methods_and_bad_choices():
    plan = _plan()
    e = drift_field(plan, drift_rng(0, 0), method="ekf")
    assert e.method == "ekf" and e.field.shape == plan.shape
    with pytest.raises(InputError, match="--drift-method"):
        drift_field(plan, drift_rng(0, 0), method="rigid")
    with pytest.raises(InputError, match="--drift-scale"):
        drift_field(plan, drift_rng(0, 0), scale=-1)
    with pytest.raises(InputError, match="--drift:"):
        check_drift("wobble", "additive")


def test_drift_maps_per_plan_and_a_plan_without_room_keeps_its_map():
    plan = _plan()
    plans = np.stack([plan.data, plan.data, np.full(plan.shape, OCCUPIED, np.uint8)])
    out, warns = drift_maps(plans, plans, 0.1, seed=1)
    again, _ = drift_maps(plans, plans, [0.1, 0.1, 0.1], seed=1)
    assert np.array_equal(out, again)
    assert not np.array_equal(out[0], out[1])                  # plan i has its own draw
    assert np.array_equal(out[2], plans[2]) and len(warns) == 1 and "map 2" in warns[0]
    with pytest.raises(ValueError, match="shape"):
        apply_drift(plans[0][:10], drift_field(plan, drift_rng(0, 0)))
