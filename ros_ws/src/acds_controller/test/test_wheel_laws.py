"""Tests of the wheel control laws and attitude errors (spec §7; seed 002 §4.2.2, §4.2.3, Table 4-2)."""

from __future__ import annotations

import math

import numpy as np
import pytest
from acds_common.attitude import quat_mul
from acds_common.units import rpm_to_rad_s
from acds_controller.magnetic_laws import ControllerError
from acds_controller.wheel_laws import (
    HEAO_A_ACQUISITION,
    HEAO_B_ACQUISITION,
    HEAO_B_ACQUISITION_PRELIMINARY,
    NORMAL_MODE,
    SCAN_RATE_RAD_S,
    V_SAT_V,
    WheelLawGains,
    design_gains,
    inertial_hold_error,
    pointing_error,
    rotate_to_body,
    scan_yaw_volts,
    wheel_volts,
)
from hypothesis import given, settings
from hypothesis import strategies as st


def _quat_axis_angle(axis: np.ndarray, angle_rad: float) -> np.ndarray:
    a = np.asarray(axis, dtype=float) / np.linalg.norm(axis)
    return np.append(a * math.sin(angle_rad / 2.0), math.cos(angle_rad / 2.0))


def test_limiter_caps_the_position_term() -> None:
    """θ^L = ±θ_limit: a 0.5 rad pitch error commands only K_p·θ_limit = 97 × 0.075 V."""
    for sign in (1.0, -1.0):
        v = wheel_volts(np.array([0.0, sign * 0.5, 0.0]), np.zeros(3), HEAO_B_ACQUISITION)
        assert v[1] == pytest.approx(sign * 97.0 * 0.075)
        assert v[0] == 0.0 and v[2] == 0.0


def test_rate_term_is_not_limited_by_the_position_limiter() -> None:
    """ε = K_p (θ^L + K_r ω): the rate term adds after the limiter."""
    v = wheel_volts(np.array([0.0, 0.5, 0.0]), np.array([0.0, 2e-4, 0.0]), HEAO_B_ACQUISITION)
    assert v[1] == pytest.approx(97.0 * (0.075 + 100.0 * 2e-4))


def test_output_clipped_to_v_sat_and_small_errors_linear() -> None:
    v = wheel_volts(np.array([1.0, -1.0, 0.0]), np.array([0.01, 0.0, -0.01]), HEAO_A_ACQUISITION)
    assert v[0] == V_SAT_V and v[1] == pytest.approx(-162.0 * 0.105) and v[2] == -V_SAT_V
    v_small = wheel_volts(np.array([0.01, 0.0, 0.0]), np.zeros(3), HEAO_A_ACQUISITION)
    assert v_small[0] == pytest.approx(8.65)


def test_normal_mode_has_no_limiter() -> None:
    v = wheel_volts(np.array([1e-5, 2e-5, -2e-5]), np.zeros(3), NORMAL_MODE)
    np.testing.assert_allclose(v, [0.364, 4.32, -4.32])
    assert wheel_volts(np.array([0.0, 1.0, 0.0]), np.zeros(3), NORMAL_MODE)[1] == V_SAT_V


def test_table_4_2_values() -> None:
    assert HEAO_B_ACQUISITION.k_p_v_per_rad == (684.0, 97.0, 97.0)
    assert HEAO_B_ACQUISITION.k_r_s == (14.3, 100.0, 100.0)
    assert HEAO_B_ACQUISITION.theta_limit_rad == (0.025, 0.075, 0.075)
    assert NORMAL_MODE.theta_limit_rad == (None, None, None)


@pytest.mark.parametrize('gains', [HEAO_A_ACQUISITION, HEAO_B_ACQUISITION_PRELIMINARY])
def test_design_relations_reproduce_table_4_2(gains: WheelLawGains) -> None:
    """K_p = V_sat/θ_ε and K_r = θ_ε/ω^L (0.1°/s) give the table's gains within 1 %."""
    for i in range(3):
        limit = gains.theta_limit_rad[i]
        assert limit is not None
        k_p, k_r = design_gains(limit)
        assert k_p == pytest.approx(gains.k_p_v_per_rad[i], rel=0.01)
        assert k_r == pytest.approx(gains.k_r_s[i], rel=0.01)


def test_scan_rate_law() -> None:
    """ε_z = K_pz K_rz (ω_z − ω_z0) with the 0.03 rpm baseline rate."""
    assert SCAN_RATE_RAD_S == pytest.approx(rpm_to_rad_s(0.03))
    assert scan_yaw_volts(SCAN_RATE_RAD_S, SCAN_RATE_RAD_S, 2.16e5, 5.65) == 0.0
    v = scan_yaw_volts(SCAN_RATE_RAD_S + 1e-6, SCAN_RATE_RAD_S, 2.16e5, 5.65)
    assert v == pytest.approx(2.16e5 * 5.65 * 1e-6)
    assert scan_yaw_volts(0.0, SCAN_RATE_RAD_S, 2.16e5, 5.65) == -V_SAT_V
    assert scan_yaw_volts(0.0, rpm_to_rad_s(0.1), 1.0, 1.0) == pytest.approx(-rpm_to_rad_s(0.1))


def test_with_axis_and_gain_validation() -> None:
    g = HEAO_B_ACQUISITION.with_axis('k_r_s', 2, 50.0)
    assert g.k_r_s == (14.3, 100.0, 50.0)
    with pytest.raises(ControllerError, match='theta_limit_rad'):
        HEAO_B_ACQUISITION.with_axis('theta_limit_rad', 0, -0.1)
    with pytest.raises(ControllerError, match='3 values'):
        WheelLawGains((1.0, 2.0), (None, None, None), (1.0, 1.0, 1.0))  # type: ignore[arg-type]


def test_pointing_error_small_tilts_match_direction_cosines() -> None:
    """Roll error = B23 = s_y, pitch error = −B13 = −s_x for small tilts (seed §4.3.1)."""
    phi = 0.01
    # body rolled +φ about x: the sun (z of the sun frame) appears at (0, sin φ, cos φ)
    np.testing.assert_allclose(pointing_error(np.array([0.0, math.sin(phi), math.cos(phi)])), [phi, 0, 0],
                               atol=1e-12)
    # body pitched +θ about y: the sun appears at (−sin θ, 0, cos θ)
    np.testing.assert_allclose(pointing_error(np.array([-math.sin(phi), 0.0, math.cos(phi)])), [0, phi, 0],
                               atol=1e-12)


@settings(derandomize=True, max_examples=200, deadline=None)
@given(st.tuples(*[st.floats(-1.0, 1.0, allow_nan=False)] * 3).filter(lambda v: np.linalg.norm(v) > 0.1))
def test_pointing_error_magnitude_is_the_off_axis_angle(v: tuple[float, float, float]) -> None:
    s = np.array(v) / np.linalg.norm(v)
    e = pointing_error(s)
    assert e[2] == 0.0
    assert np.linalg.norm(e) == pytest.approx(math.acos(np.clip(s[2], -1, 1)), abs=1e-9)


def test_pointing_error_sun_behind_and_zero_vector() -> None:
    np.testing.assert_allclose(pointing_error(np.array([0.0, 0.0, -1.0])), [math.pi, 0.0, 0.0])
    with pytest.raises(ControllerError, match='zero vector'):
        pointing_error(np.zeros(3))


def test_inertial_hold_error_sign_and_size() -> None:
    q_t = _quat_axis_angle(np.array([1.0, 2.0, 3.0]), 0.7)
    for axis in range(3):
        e_axis = np.eye(3)[axis]
        q = quat_mul(q_t, _quat_axis_angle(e_axis, 0.002))
        np.testing.assert_allclose(inertial_hold_error(q, q_t), 0.002 * e_axis, atol=1e-9)
    # q and −q are the same attitude
    np.testing.assert_allclose(inertial_hold_error(-q_t, q_t), np.zeros(3), atol=1e-12)


def test_rotate_to_body() -> None:
    """Body yawed +90° about z: the ECI x axis appears along body −y."""
    q = _quat_axis_angle(np.array([0.0, 0.0, 1.0]), math.pi / 2)
    np.testing.assert_allclose(rotate_to_body(q, np.array([1.0, 0.0, 0.0])), [0.0, -1.0, 0.0], atol=1e-12)
    with pytest.raises(ControllerError, match='unit quaternion'):
        rotate_to_body(np.array([0.0, 0.0, 0.0, 2.0]), np.ones(3))
