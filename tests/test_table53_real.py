"""Table 5.3 on real maps (map2map.experiments.table53_real.measure): a generated pair with a known
ground truth, and one real Halmstad map when the shared data is there."""

from __future__ import annotations

import numpy as np
import pytest

pytest.importorskip("torch")

from map2map.core.grid import FREE, OCCUPIED, UNKNOWN, OccupancyMap  # noqa: E402
from map2map.evaluate.nonrigid import warp_image  # noqa: E402
from map2map.experiments.table53_real.measure import (  # noqa: E402
    real_pair_row,
    run_table53_real,
    summarise_real,
)


def _plan(n=160) -> np.ndarray:
    """Three rooms with 4-px walls, unknown outside."""
    a = np.full((n, n), UNKNOWN, np.uint8)
    a[20:140, 20:140] = OCCUPIED
    a[24:136, 24:136] = FREE
    a[24:136, 78:82] = OCCUPIED
    a[78:82, 82:136] = OCCUPIED
    a[50:70, 78:82] = FREE          # doors
    a[78:82, 100:115] = FREE
    return a


def _pair():
    """The plan, a 'sensor map' of it turned by 90 deg at 1.25x its scale, and keypoints."""
    plan = _plan()
    T = np.array([[0.0, -0.8, 170.0], [0.8, 0.0, 10.0], [0.0, 0.0, 1.0]])  # sensor -> plan
    sensor = warp_image(plan, np.linalg.inv(T), (200, 200))
    kt = np.array([[20.0, 20], [140, 20], [20, 140], [140, 140], [80, 80], [80, 136]])
    ks = (kt - T[:2, 2]) @ np.linalg.inv(T[:2, :2]).T
    return plan, sensor, T, ks, kt


def test_identity_pair_ties_and_guards_in_both_frames():
    plan, sensor, T, ks, kt = _pair()
    kt_noisy = kt.copy()
    kt_noisy[-1] += 60                                   # one wrong association
    row = real_pair_row("toy", OccupancyMap(sensor, 0.05), OccupancyMap(sensor, 0.05),
                        OccupancyMap(plan, 0.05), ks, kt_noisy)
    assert row["gt_inliers"] == "5/6"                    # the robust fit drops it
    assert row["gt_scale"] == pytest.approx(0.8)
    assert row["diff"] == 0.0 and row["counted"]
    assert row["align_ok_real"] and row["kp_real"] < 3
    for pre in ("", "lf_"):
        assert row[f"{pre}real_wall_recall"] > 0.95
        assert row[f"{pre}real_wall_recall"] == row[f"{pre}gen_wall_recall"]


def test_a_dropped_wall_shows_in_the_guards():
    plan, sensor, T, ks, kt = _pair()
    worse = sensor.copy()
    worse[worse == OCCUPIED] = FREE                      # every wall gone
    row = real_pair_row("toy", OccupancyMap(sensor, 0.05), OccupancyMap(worse, 0.05),
                        OccupancyMap(plan, 0.05), ks, kt)
    assert row["gen_wall_recall"] == 0.0 < row["real_wall_recall"]
    assert not row["counted"]                            # no walls: the metric fails
    s = summarise_real([row])
    assert s["counted"] == 0 and s["flagged"] + s["failed"] == 1


@pytest.mark.filterwarnings("ignore::UserWarning")
def test_autocorrect_does_not_read_the_resolution():
    """What the docs state: the output pixels are the same at any metres per pixel."""
    from map2map.learn.ba.autocorrect import autocorrect

    plan = _plan()
    a = autocorrect(OccupancyMap(plan, 0.05))
    b = autocorrect(OccupancyMap(plan, 0.2))
    assert np.array_equal(a.data, b.data)


def test_one_real_halmstad_map(shared_data):
    """About 12 s: one apartment map, auto-corrected and measured four times."""
    root = shared_data / "halmstad"
    if not root.is_dir():
        pytest.skip("no Halmstad data")
    t = run_table53_real(root, ["HIH_03"], progress=False)
    (r,) = t.rows
    assert r["map"] == "HIH_03" and 1.1 < r["gt_scale"] < 1.2
    assert np.isfinite(r["error_real"]) and r["align_ok_real"]
    assert 1.0 < r["shrink"] < 3.0                       # HIH maps: about 2x the dataset's size
    assert t.summary["n"] == 1 and t.summary["s1_n"] == 1
    assert 0 <= r["ob_real_wall_recall"] <= 1 and r["layout_wall_px"] > 1
    assert "HIH_03" in t.format()
