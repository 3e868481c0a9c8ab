"""Parametric drift on synthesized maps (map2map.learn.ab.drift): seeded, per hypothesis,
the parametric model's field, generated maps' own unknown cells kept. No torch needed."""

import numpy as np
import pytest

from map2map.core.errors import InputError
from map2map.core.grid import FREE, OCCUPIED, UNKNOWN, OccupancyMap
from map2map.learn.ab.drift import (
    DriftParams,
    apply_drift,
    drift_field,
    drift_maps,
    drift_params,
    drift_rng,
)

WHOLE = DriftParams(duration=None, smooth_m=0.0, coverage="map")   # the plain model's field


def _plan() -> OccupancyMap:
    """Two rooms joined by a door, 6 x 4 m at 0.1 m."""
    data = np.full((44, 64), UNKNOWN, np.uint8)
    data[2:42, 2:62] = FREE
    data[2, 2:62] = data[41, 2:62] = OCCUPIED
    data[2:42, 2] = data[2:42, 61] = OCCUPIED
    data[2:42, 30] = OCCUPIED
    data[18:26, 30] = FREE
    return OccupancyMap(data, resolution=0.1)


@pytest.mark.parametrize("params", [WHOLE, DriftParams()])
def test_drift_field_is_seeded_per_hypothesis_and_bit_identical(params):
    plan = _plan()
    a = drift_field(plan, drift_rng(3, 0), params)
    b = drift_field(plan, drift_rng(3, 0), params)
    c = drift_field(plan, drift_rng(3, 1), params)
    assert np.array_equal(a.field.dx, b.field.dx) and np.array_equal(a.field.dy, b.field.dy)
    assert not np.array_equal(a.field.dx, c.field.dx)          # hypothesis 1 drifts otherwise
    assert a.stats()["mean"] > 0.1                             # it does move the map
    assert np.array_equal(apply_drift(plan.data, a), apply_drift(plan.data, b))
    assert not np.array_equal(apply_drift(plan.data, a), apply_drift(plan.data, c))
    # carried to the unobserved pixels: every pixel takes its nearest observed one's value
    assert not a.observed.all()
    assert np.count_nonzero(a.field.magnitude[~a.observed] == 0) < np.count_nonzero(~a.observed)


def test_scale_magnitude_and_coverage():
    plan = _plan()
    m = plan.data.copy()
    m[:, 40:] = UNKNOWN                                        # a map that saw one room
    d0 = drift_field(plan, drift_rng(0, 0), DriftParams(scale=0.0, coverage="map"))
    assert np.array_equal(apply_drift(m, d0), m)               # no drift: the map itself
    one = drift_field(plan, drift_rng(0, 0), WHOLE)
    two = drift_field(plan, drift_rng(0, 0), DriftParams(duration=None, smooth_m=0.0,
                                                         coverage="map", scale=2.0))
    assert np.allclose(two.field.dx, 2 * one.field.dx)
    out = apply_drift(m, two)
    assert set(np.unique(out).tolist()) <= {OCCUPIED, UNKNOWN, FREE}
    assert np.count_nonzero(out[:, 50:] != UNKNOWN) == 0       # nothing invented far out
    mag = drift_field(plan, drift_rng(0, 0), DriftParams(magnitude_px=1.5))
    assert mag.stats()["mean"] == pytest.approx(1.5, rel=1e-4)  # set in map pixels
    short = drift_field(plan, drift_rng(0, 0), DriftParams(duration=5.0, coverage="route",
                                                           margin_px=0))
    assert short.trajectory.t[-1] <= 5.0 + 1e-9
    routed = apply_drift(plan.data, short)
    assert not short.observed.all()               # 5 s of route: unknown where it did not see
    assert np.count_nonzero(routed == UNKNOWN) > np.count_nonzero(plan.data == UNKNOWN) + 100


def test_drift_methods_and_bad_choices():
    plan = _plan()
    e = drift_field(plan, drift_rng(0, 0), DriftParams(method="ekf"))
    assert e.params.method == "ekf" and e.field.shape == plan.shape
    assert drift_params("parametric", "ekf", 2.0) == DriftParams(method="ekf", scale=2.0)
    assert drift_params("none") is None
    with pytest.raises(InputError, match="drift_method"):
        DriftParams(method="rigid")
    with pytest.raises(InputError, match="drift_method"):
        drift_params("none", "rigid")
    with pytest.raises(InputError, match="drift_scale"):
        drift_params("parametric", scale=-1)
    with pytest.raises(InputError, match="^drift:"):
        drift_params("wobble")
    with pytest.raises(InputError, match="coverage"):
        DriftParams(coverage="all")


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
