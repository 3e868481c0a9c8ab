"""Thesis equations 3.8-3.90 against hand-computed values."""

from __future__ import annotations

import math

import numpy as np
import pytest

from map2map.parametric import additive as add
from map2map.parametric import ekf
from map2map.parametric import lidar as li
from map2map.parametric import odometry as od
from map2map.parametric.params import ParametricParams
from map2map.parametric.visibility import Visibility

# ---------------------------------------------------------------- LIDAR, eqs. 3.8-3.30


def test_eq_3_8_landmark_position():
    x, y = li.landmark_position(1.0, 2.0, 2.0, math.pi / 2)
    assert (float(x), float(y)) == pytest.approx((1.0, 0.0))


def test_eq_3_9_range_error():
    assert float(li.range_error(3.0, 0.01, 0.002)) == pytest.approx(0.016)


def test_eq_3_10_angle_error():
    b = (0.001, 0.002, 0.003, 0.004, 0.005, 0.006)
    # b1 pi/2 + b2 sin(pi/2) + b3 cos(pi/2) + b4 sin(pi) + b5 cos(pi) + b6 / 2
    expected = 0.001 * math.pi / 2 + 0.002 + 0.0 + 0.0 - 0.005 + 0.003
    assert float(li.angle_error(math.pi / 2, 2.0, b)) == pytest.approx(expected)


def test_eqs_3_11_3_12_hit_displacement():
    # D = 2, alpha = 0, Delta D = 0.1, Delta alpha = pi / 2, pm = 10:
    # dx = 10 (2 - 1.9 cos(-pi/2)) = 20, dy = 10 (0 - 1.9 sin(-pi/2)) = 19
    dx, dy = li.polar_displacement(2.0, 0.0, 0.1, math.pi / 2, 10.0)
    assert (float(dx), float(dy)) == pytest.approx((20.0, 19.0))
    # small errors: a range 5 cm short at 20 px/m shifts the point 1 px towards the sensor
    dx, dy = li.polar_displacement(2.0, math.pi, 0.05, 0.0, 20.0)
    assert (float(dx), float(dy)) == pytest.approx((-1.0, 0.0), abs=1e-12)


def test_eqs_3_13_to_3_17_short_readings():
    dens = 0.5 * math.exp(-0.5) / (1 - math.exp(-1.0))  # z = 1, z* = 2, lambda = 0.5
    assert float(li.p_short(1.0, 2.0, 0.5)) == pytest.approx(dens)
    assert float(li.p_short(2.5, 2.0, 0.5)) == 0.0
    # eq. 3.16 inverts eq. 3.13
    z = np.array([0.0, 0.3, 1.0, 1.99])
    assert li.short_range(li.p_short(z, 2.0, 0.5), 2.0, 0.5) == pytest.approx(z)
    assert float(li.short_error(2.0, 0.5)) == pytest.approx(1.5)


def test_eqs_3_14_3_15_3_20_3_21_3_24_max_and_random():
    z = np.array([1.0, 3.0, 2.0])
    z_max = li.max_range(z)
    assert z_max == 3.0
    assert li.p_max(z, z_max).tolist() == [0.0, 1.0, 0.0]
    assert li.max_error(z, z_max, 0.05).tolist() == pytest.approx([0.0, 0.05, 0.0])
    assert li.p_rand(np.array([1.0, 4.0]), z_max).tolist() == pytest.approx([1 / 3, 0.0])
    assert li.rand_error(z, z_max, 0.03).tolist() == pytest.approx([0.01, 0.01, 0.01])


def test_eqs_3_27_3_28_weighted_sum():
    out = li.weighted_field([1.0, 2.0, 3.0, 4.0], (0.4, 0.3, 0.2, 0.1))
    assert float(out) == pytest.approx(2.0)


def test_eqs_3_29_3_30_measured_range_and_angle():
    z, a = li.measured(2.0, 0.0, 0.4, 0.0, 0.0, 20.0)
    assert (float(z), float(a)) == pytest.approx((1.98, 0.0))
    # near alpha = pi/2 the y component carries the range
    z, a = li.measured(2.0, math.pi / 2, 0.0, 0.4, 0.0, 20.0)
    assert float(z) == pytest.approx(1.98)
    # hit-only model with Delta alpha = 0: z_meas = D - Delta D exactly
    D = np.array([1.0, 2.0, 3.0])
    alpha = np.array([0.3, -2.0, 2.9])
    dD = li.range_error(D, 0.01, 0.003)
    dx, dy = li.polar_displacement(D, alpha, dD, 0.0, 20.0)
    z, a = li.measured(D, alpha, dx, dy, 0.0, 20.0)
    assert z == pytest.approx(D - dD)
    assert a == pytest.approx(alpha)


def test_lidar_field_zero_coefficients_is_zero():
    p = ParametricParams().zero_error()
    rng = np.random.default_rng(0)
    D, a = li.random_range_angle((20, 30), 0.12, 3.5, 5, rng)
    f = li.lidar_field(D, a, li.draw_lidar_coefficients(p, rng), p, 20.0, rng)
    assert np.abs(f.dx).max() == 0 and np.abs(f.dy).max() == 0
    assert f.z_meas == pytest.approx(D)


def test_lidar_field_is_the_weighted_hit_field_when_only_calibration_errors():
    p = ParametricParams(max_err_bound=0.0, rand_err_bound=0.0, short_scale=0.0)
    rng = np.random.default_rng(1)
    D, a = li.random_range_angle((10, 10), 0.12, 3.5, 3, rng)
    c = li.draw_lidar_coefficients(p, rng)
    f = li.lidar_field(D, a, c, p, 20.0, rng)
    hx, hy = li.polar_displacement(
        D, a, li.range_error(D, c.a0, c.a1), li.angle_error(a, D, c.b), 20.0
    )
    # E_short = E_max = E_rand = 0: the four fields share the angle error, weights sum to 1
    # so d_L = 0.4 d_hit + 0.6 (pure angle-error field)
    ax, ay = li.polar_displacement(D, a, 0.0, li.angle_error(a, D, c.b), 20.0)
    assert f.dx == pytest.approx(0.4 * hx + 0.6 * ax)
    assert f.dy == pytest.approx(0.4 * hy + 0.6 * ay)


# ------------------------------------------------------------ odometry, eqs. 3.31-3.53


def test_eqs_3_31_to_3_37_wheel_geometry():
    e_b = od.wheelbase_error(0.5, 0.4)
    assert e_b == pytest.approx(90 / 89.1)
    assert od.actual_wheelbase(e_b, 0.287) == pytest.approx(0.287 * 90 / 89.1)
    assert od.curvature_radius(4.0, 2.0) == pytest.approx(2.0 / math.sin(math.radians(1.0)))
    assert math.isinf(od.curvature_radius(4.0, 0.0))
    assert od.diameter_ratio(100.0, 0.3) == pytest.approx(100.15 / 99.85)
    assert od.diameter_ratio(math.inf, 0.3) == 1.0
    assert od.average_diameter(0.066, 0.064) == pytest.approx(0.065)
    d_l, d_r = od.actual_diameters(1.1, 0.065)
    assert d_l == pytest.approx(2 / 2.1 * 0.065)
    assert d_r == pytest.approx(2 / (1 / 1.1 + 1) * 0.065)
    assert d_r / d_l == pytest.approx(1.1) and (d_r + d_l) / 2 == pytest.approx(0.065)


def test_eqs_3_38_to_3_47_increments():
    assert float(od.wheel_displacement(10.0, 0.066)) == pytest.approx(0.66)
    dd, dth = od.centre_increment(0.3, 0.1, 0.2)
    assert (float(dd), float(dth)) == pytest.approx((0.2, 1.0))
    dx, dy = od.pose_increment(0.2, 1.0, 0.5)
    assert (float(dx), float(dy)) == pytest.approx((0.2 * math.cos(1.0), 0.2 * math.sin(1.0)))


def test_eqs_3_48_to_3_53_error_terms():
    nom = {"dx": 1.0, "dy": 0.5, "dth": 0.2}
    act = {"dx": 0.9, "dy": 0.6, "dth": 0.1}
    e = od.error_terms(nom, act)
    assert float(e["x"]) == pytest.approx(0.1)
    assert float(e["y"]) == pytest.approx(-0.1)
    assert float(e["t"]) == pytest.approx(0.1)
    assert float(e["xy"]) == pytest.approx(0.5 - 0.54)
    assert float(e["xt"]) == pytest.approx(0.2 - 0.09)
    assert float(e["yt"]) == pytest.approx(0.1 - 0.06)


def test_odometry_errors_on_key_poses():
    p = ParametricParams()
    poses = np.array([[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [1.0, 0.0, 1.0]])
    zero = od.odometry_errors(poses, od.OdometryCoefficients(), p, 4.0)
    assert all(np.abs(v).max() == 0 for v in zero.sigma.values())
    assert zero.nominal["dd"] == pytest.approx([1.0, 0.0])
    assert zero.nominal["dth"] == pytest.approx([0.0, 1.0])
    # wheelbase error only: straight steps exact, a 1 rad turn becomes 1 / E_b
    e = od.odometry_errors(poses, od.OdometryCoefficients(alpha_eb=0.9), p, 4.0)
    e_b = 90 / 89.1
    assert e.e_b == pytest.approx(e_b) and e.e_d == 1.0
    assert e.sigma["t"] == pytest.approx([0.0, 1.0 - 1.0 / e_b])
    assert e.sigma["x"] == pytest.approx([0.0, 0.0], abs=1e-15)
    # curvature error: a straight 1 m step drifts sideways
    c = od.odometry_errors(poses, od.OdometryCoefficients(beta=2.0), p, 4.0)
    assert c.e_d != 1.0 and abs(c.sigma["t"][0]) > 0 and abs(c.sigma["y"][0]) > 0


# ------------------------------------------------------ additive method, eqs. 3.81-3.90


def test_eqs_3_81_to_3_88_additive_pieces():
    assert float(add.linear_error(1.0, 0.02)) == pytest.approx(0.11)
    assert float(add.angular_error(0.1, 0.01)) == pytest.approx(0.0195)
    s_mz = add.map_range_error(2.0, 0.01, 0.11)
    assert float(s_mz) == pytest.approx(0.13)
    beta = math.radians(1.0)
    s_mt = add.map_angle_error(beta, 0.0195)
    assert float(s_mt) == pytest.approx(beta / 2 + 0.0195)
    s_mx, s_my = add.beam_frame_error(s_mz, s_mt)
    assert float(s_mx) == pytest.approx(0.13 * math.cos(s_mt))
    assert float(s_my) == pytest.approx(0.13 * math.sin(s_mt))
    d_mx, d_my = add.map_frame_error(s_mx, s_my, 0.0, 1.0)  # bearing pi / 2
    assert (float(d_mx), float(d_my)) == pytest.approx((-float(s_my), float(s_mx)))


def test_eqs_3_89_3_90_accumulate():
    d = np.zeros(5)
    add.accumulate(d, np.array([1, 3]), np.array([0.5, 1.0]))
    add.accumulate(d, np.array([3, 4]), 2.0)
    assert d.tolist() == [0.0, 0.5, 0.0, 3.0, 2.0]


def test_additive_field_hand_computed_single_pose():
    # one pose at pixel (5, 5), eta = 1 %, no odometry error, beam aperture 0:
    # each seen pixel moves radially by eta * range, i.e. eta * distance in pixels
    vis = Visibility(np.array([0, 2]), np.array([5 * 11 + 9, 1 * 11 + 5], np.int32), (11, 11))
    poses = np.array([[5.0, 5.0, 0.0]])
    odo = od.odometry_errors(np.zeros((1, 3)), od.OdometryCoefficients(), ParametricParams(), 4)
    p = ParametricParams(eta=0.01, beam_aperture_deg=0.0)
    z = np.zeros((11, 11))
    dx, dy = add.additive_field(vis, poses, z, z, odo, p, 20.0, np.random.default_rng(0))
    assert dx[5, 9] == pytest.approx(0.04) and dy[5, 9] == pytest.approx(0.0, abs=1e-15)
    assert dx[1, 5] == pytest.approx(0.0, abs=1e-15) and dy[1, 5] == pytest.approx(-0.04)
    assert (np.abs(dx) > 1e-12).sum() + (np.abs(dy) > 1e-12).sum() == 2


# ----------------------------------------------------------------- EKF, eqs. 3.54-3.80


def test_eqs_3_54_to_3_57_and_3_60():
    assert float(ekf.heading_change(0.2)) == 0.2
    assert float(ekf.thrust(0.3, 0.4, math.atan2(0.4, 0.3))) == pytest.approx(0.5)
    assert float(ekf.thrust(0.5, 0.0, 0.0)) == pytest.approx(0.5)
    dx, dy = ekf.jacobian_terms(2.0, math.pi / 6)
    assert (float(dx), float(dy)) == pytest.approx((1.0, math.sqrt(3)))
    A = ekf.motion_jacobian(1.0, 2.0)
    assert A.tolist() == [[1, 0, -1.0], [0, 1, 2.0], [0, 0, 1]]


def test_eqs_3_58_3_61_process_noise_is_psd():
    sig = {"x": np.array([0.1]), "y": np.array([0.2]), "t": np.array([0.05]),
           "xy": np.array([0.02]), "xt": np.array([0.005]), "yt": np.array([0.01])}  # fmt: skip
    Q = ekf.process_noise(sig)[0]  # sigma sigma^T: already PSD, unchanged
    assert Q == pytest.approx(np.outer([0.1, 0.2, 0.05], [0.1, 0.2, 0.05]))
    assert ekf.initial_covariance(sig) == pytest.approx(Q)
    bad = dict(sig, xy=np.array([0.5]))
    assert np.linalg.eigvalsh(ekf.process_noise(bad)[0]).min() >= -1e-12


def test_eqs_3_62_3_63_prediction():
    rng = np.random.default_rng(0)
    M = rng.normal(size=(7, 7))
    P = M @ M.T
    P0 = P.copy()
    A = ekf.motion_jacobian(0.3, -0.2)
    Q = np.diag([0.01, 0.02, 0.03])
    ekf.predict_covariance(P, 7, A, Q)
    F = np.eye(7)
    F[:3, :3] = A
    expected = F @ P0 @ F.T
    expected[:3, :3] += Q
    assert P == pytest.approx(expected)


def test_eqs_3_64_to_3_69_measurement_and_noise():
    c = li.LidarCoefficients(a0=0.01, a1=0.0)
    z_r, z_b = ekf.measurement(np.array([2.0]), np.array([0.3]), c)
    assert z_r == pytest.approx([1.99]) and z_b == pytest.approx([0.3])
    R = ekf.measurement_noise(np.array([2.0, 1.0]), np.array([0.5, 0.0]), 0.01, 0.02, 1e-4, 3e-4)
    assert R == pytest.approx(np.array([[0.02, 0.01], [0.01, 3e-4]]))


def test_eqs_3_70_3_71_measurement_jacobian_matches_numerical_derivative():
    x, y, th, lx, ly = 0.3, -0.2, 0.4, 2.0, 1.5

    def h(v):
        return np.array(
            [math.hypot(v[3] - v[0], v[4] - v[1]), math.atan2(v[4] - v[1], v[3] - v[0]) - v[2]]
        )

    v0 = np.array([x, y, th, lx, ly])
    num = np.stack([(h(v0 + e) - h(v0 - e)) / 2e-6 for e in np.eye(5) * 1e-6], 1)
    hr, hl = ekf.measurement_jacobian(x, y, np.array([lx]), np.array([ly]))
    assert hr[0] == pytest.approx(num[:, :3], abs=1e-6)
    assert hl[0] == pytest.approx(num[:, 3:], abs=1e-6)
    assert hl[0] == pytest.approx(-hr[0][:, :2])


def test_eqs_3_72_3_73_stacked_update_equals_textbook_formula():
    rng = np.random.default_rng(3)
    n = 3 + 2 * 3
    M = rng.normal(size=(n, n))
    P = M @ M.T + n * np.eye(n)
    X = rng.normal(size=n)
    cols = np.array([3, 7])
    hr, hl = ekf.measurement_jacobian(X[0], X[1], X[cols], X[cols + 1])
    H = np.zeros((4, n))
    for i, c in enumerate(cols):
        H[2 * i : 2 * i + 2, :3] = hr[i]
        H[2 * i : 2 * i + 2, c : c + 2] = hl[i]
    rdiag = np.array([[0.01, 0.02], [0.03, 0.04]])
    innov = np.array([[0.1, -0.05], [0.2, 0.01]])
    K = P @ H.T @ np.linalg.inv(H @ P @ H.T + np.diag(rdiag.ravel()))
    X_exp = X + K @ innov.ravel()
    P_exp = P - K @ H @ P
    ekf.kalman_update(X, P, n, cols, hr, hl, innov, rdiag)
    assert X == pytest.approx(X_exp)
    assert P == pytest.approx(P_exp)


def test_eqs_3_74_to_3_80_augmentation_equals_full_jacobian_form():
    rng = np.random.default_rng(4)
    n = 5
    M = rng.normal(size=(n, n))
    P = np.zeros((n + 4, n + 4))
    P[:n, :n] = M @ M.T
    r = np.array([1.0, 2.0])
    ang = np.array([0.3, -1.2])
    jxr, jz = ekf.landmark_jacobians(r, ang)
    # 3.74-3.75 are the derivatives of lambda = (x + r cos a, y + r sin a)
    s0, c0, s1, c1 = math.sin(ang[0]), math.cos(ang[0]), math.sin(ang[1]), math.cos(ang[1])
    assert jxr[0] == pytest.approx(np.array([[1, 0, -r[0] * s0], [0, 1, r[0] * c0]]))
    assert jz[1] == pytest.approx(np.array([[c1, -r[1] * s1], [s1, r[1] * c1]]))
    rdiag = np.array([[0.01, 0.001], [0.02, 0.002]])
    F = np.zeros((n + 4, n))
    F[:n] = np.eye(n)
    G = np.zeros((n + 4, 4))
    for i in range(2):
        F[n + 2 * i : n + 2 * i + 2, :3] = jxr[i]
        G[n + 2 * i : n + 2 * i + 2, 2 * i : 2 * i + 2] = jz[i]
    expected = F @ P[:n, :n] @ F.T + G @ np.diag(rdiag.ravel()) @ G.T
    assert ekf.augment_covariance(P, n, jxr, jz, rdiag) == n + 4
    assert P == pytest.approx(expected)


def test_choose_landmarks_decimates_walls():
    walls = np.zeros((40, 40), bool)
    walls[0, :] = walls[:, 0] = True
    lm = ekf.choose_landmarks(walls, 20)
    assert 0 < lm.size <= 20
    assert walls.ravel()[lm].all()
    assert ekf.choose_landmarks(walls, 10_000).size == walls.sum()
