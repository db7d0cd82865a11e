"""Tests of the per-step digital processor (spec §7; seed 002 §4.1, §4.2, §4.3)."""

from __future__ import annotations

import math

import numpy as np
import pytest
from acds_common.attitude import quat_mul
from acds_common.dpa_commands import GAIN_LIMITS, GAIN_TABLE
from acds_common.units import SLUG_FT2_KG_M2, rad, rpm_to_rad_s
from acds_controller.b_cross_omega import K_OMEGA_SEED, detumble_moment, dump_moment
from acds_controller.dpa import WHEEL_TORQUE_GAIN_NM_PER_V2, Dpa, DpaConfig
from acds_controller.magnetic_laws import (
    ControllerError,
    bxh_gain_to_si,
    bxh_moment,
    lead_moment,
    saturate,
    wheel_command_momentum_nms,
)

#: HEAO-B inertia (Table 4-1, slug-ft²), products of inertia entered as −I_xy etc. (test use only).
INERTIA_B = SLUG_FT2_KG_M2 * np.array([[1520.0, -47.0, -359.0], [-47.0, 7970.0, -4.0], [-359.0, -4.0, 7920.0]])
B_T = np.array([2e-5, -1e-5, 3e-5])
Q_ID = np.array([0.0, 0.0, 0.0, 1.0])
SUN_Z = np.array([0.0, 0.0, 1.0])


def _q(axis: np.ndarray, angle_rad: float) -> np.ndarray:
    a = np.asarray(axis, dtype=float) / np.linalg.norm(axis)
    return np.append(a * math.sin(angle_rad / 2.0), math.cos(angle_rad / 2.0))


def _dpa(**kwargs: object) -> Dpa:
    return Dpa(DpaConfig(inertia_kg_m2=INERTIA_B, **kwargs))  # type: ignore[arg-type]


def test_standby_outputs_zero() -> None:
    out = _dpa().step('standby', B_T, np.full(3, 0.01), SUN_Z, np.ones(3), Q_ID, 0.5)
    assert not np.any(out.moment_command_am2) and not np.any(out.wheel_volts_v)
    assert out.telemetry['mode'] == 'standby'


@pytest.mark.parametrize('rate_deg_s', [1.0, 0.01])
def test_mode_1a_is_saturated_bxh_on_body_momentum_with_wheels_off(rate_deg_s: float) -> None:
    omega = np.full(3, rad(rate_deg_s))
    out = _dpa().step('mode_1a', B_T, omega, SUN_Z, np.array([5.0, 5.0, 5.0]), Q_ID, 0.5)
    expected = saturate(-bxh_gain_to_si(0.05) * np.cross(B_T, INERTIA_B @ omega), 2000.0)
    np.testing.assert_allclose(out.moment_command_am2, expected, rtol=1e-12)
    assert not np.any(out.wheel_volts_v)
    saturated = rate_deg_s == 1.0
    assert (np.max(np.abs(out.moment_command_am2)) == 2000.0) == saturated
    assert out.telemetry['moment_saturated'] == ('true' if saturated else 'false')


def test_mode_1a_bdot_needs_two_samples_then_opposes_field_rate() -> None:
    dpa = _dpa(acquisition_law='bdot')
    first = dpa.step('mode_1a', B_T, np.zeros(3), SUN_Z, np.zeros(3), Q_ID, 0.5)
    assert not np.any(first.moment_command_am2)
    b2 = B_T + np.array([1e-7, -2e-7, 0.0])
    second = dpa.step('mode_1a', b2, np.zeros(3), SUN_Z, np.zeros(3), Q_ID, 0.5)
    b_dot = (b2 - B_T) / 0.5
    np.testing.assert_allclose(second.moment_command_am2, -1.3558179e8 * b_dot, rtol=1e-6)
    assert not np.any(second.wheel_volts_v)


def test_mode_1a_b_cross_omega_is_the_saturated_seed_003_law_and_quiet_without_a_field() -> None:
    """Seed 003: M = sat(−(k_ω/|B|)(B̂ × ω)) per axis at the rods' moment; zero field (no magnetometer) → 0."""
    omega = np.full(3, rad(5.0))
    dpa = _dpa(acquisition_law='b_cross_omega', max_moment_am2=0.1552)
    assert dpa.config.detumble_gain_kg_m2_s == K_OMEGA_SEED
    out = dpa.step('mode_1a', B_T, omega, SUN_Z, np.ones(3), Q_ID, 1.0)
    raw = detumble_moment(B_T, omega, K_OMEGA_SEED)
    np.testing.assert_allclose(out.moment_command_am2, saturate(raw, 0.1552), rtol=1e-15)
    assert out.telemetry['acquisition_law'] == 'b_cross_omega' and not np.any(out.wheel_volts_v)
    weak = 0.25 * B_T  # |B| 9.4 µT: the command exceeds the rods on some axis and is clipped there
    clipped = dpa.step('mode_1a', weak, omega, SUN_Z, np.ones(3), Q_ID, 1.0)
    assert np.max(np.abs(clipped.moment_command_am2)) == 0.1552 and clipped.telemetry['moment_saturated'] == 'true'
    assert not np.any(dpa.step('mode_1a', np.zeros(3), omega, SUN_Z, np.ones(3), Q_ID, 1.0).moment_command_am2)


def test_unloading_b_cross_h_dumps_wheel_momentum_with_one_gain_in_every_mode() -> None:
    h = np.array([0.01, -0.02, 0.005])
    dpa = _dpa(unloading_law='b_cross_h', dump_gain_per_s=7e-4, max_moment_am2=0.1552)
    for mode in ('mode_1b', 'celestial_point', 'celestial_scan'):
        out = dpa.step(mode, B_T, np.zeros(3), SUN_Z, h, Q_ID, 1.0)
        np.testing.assert_allclose(out.moment_command_am2, saturate(dump_moment(B_T, h, 7e-4), 0.1552))
        assert float(np.cross(out.moment_command_am2, B_T) @ h) < 0.0  # the torque opposes h
    dpa.set_gain('dump_gain', 0.0)
    assert not np.any(dpa.step('mode_1b', B_T, np.zeros(3), SUN_Z, h, Q_ID, 1.0).moment_command_am2)


def _closed_loop_single_axis(axis: int, angle0_rad: float, duration_s: float) -> tuple[float, float]:
    """Rotate the body about one axis, feed the sun vector to mode_1b, apply −ḣ; return final (angle, rate)."""
    dpa = _dpa(unloading_law='none')
    inertia = INERTIA_B[axis, axis]
    angle, rate, dt = angle0_rad, 0.0, 0.5
    for _ in range(int(duration_s / dt)):
        sun = np.array([-math.sin(angle), 0.0, math.cos(angle)]) if axis == 1 else \
            np.array([0.0, math.sin(angle), math.cos(angle)])
        omega = np.zeros(3)
        omega[axis] = rate
        v = dpa.step('mode_1b', B_T, omega, sun, np.zeros(3), Q_ID, dt).wheel_volts_v[axis]
        body_torque = -WHEEL_TORQUE_GAIN_NM_PER_V2 * v * abs(v)
        rate += body_torque / inertia * dt
        angle += rate * dt
    return angle, rate


@pytest.mark.parametrize('axis, angle0', [(0, 0.3), (0, -0.2), (1, 0.3), (1, -0.25)])
def test_mode_1b_wheel_volts_reduce_the_sun_pointing_error(axis: int, angle0: float) -> None:
    """Closed loop on the sun sensor: the square-law wheel torque −ḣ drives the error well inside capture.

    Pitch is underdamped with these gains (as the study notes, §4.3.1), so the bound is 0.02 rad.
    """
    dpa = _dpa()
    sun = np.array([-math.sin(angle0), 0.0, math.cos(angle0)]) if axis == 1 else \
        np.array([0.0, math.sin(angle0), math.cos(angle0)])
    v = dpa.step('mode_1b', B_T, np.zeros(3), sun, np.zeros(3), Q_ID, 0.5).wheel_volts_v
    assert np.sign(v[axis]) == np.sign(angle0)  # V > 0 → ḣ > 0 → body torque < 0 opposes +error
    angle, rate = _closed_loop_single_axis(axis, angle0, 4000.0)
    assert abs(angle) < 0.02
    assert abs(rate) < rad(0.01)


def test_mode_1b_yaw_is_rate_only_and_sun_absent_is_rate_only() -> None:
    dpa = _dpa(unloading_law='none')
    out = dpa.step('mode_1b', B_T, np.array([0.0, 0.0, 1e-4]), SUN_Z, np.zeros(3), Q_ID, 0.5)
    assert out.wheel_volts_v[2] == pytest.approx(97.0 * 100.0 * 1e-4)
    assert out.telemetry['attitude_error_z_deg'] == '0'
    dark = dpa.step('mode_1b', B_T, np.array([1e-4, 0.0, 0.0]), np.zeros(3), np.zeros(3), Q_ID, 0.5)
    np.testing.assert_allclose(dark.wheel_volts_v, [684.0 * 14.3 * 1e-4, 0.0, 0.0])


def test_mode_1b_unloads_wheel_momentum() -> None:
    h = np.array([3.0, -2.0, 1.0])
    out = _dpa().step('mode_1b', B_T, np.zeros(3), SUN_Z, h, Q_ID, 0.5)
    np.testing.assert_allclose(out.moment_command_am2, saturate(bxh_moment(B_T, h, 0.05)), rtol=1e-12)
    assert float(np.cross(out.moment_command_am2, B_T) @ h) < 0.0


def test_celestial_point_holds_target_and_unloads_with_g_0_02() -> None:
    q_t = _q(np.array([0.3, -0.2, 0.9]), 1.1)
    dpa = _dpa(target_q_body_to_eci=q_t)
    q = quat_mul(q_t, _q(np.array([0.0, 1.0, 0.0]), 1e-5))
    h = np.array([1.0, 2.0, -1.5])
    out = dpa.step('celestial_point', B_T, np.zeros(3), SUN_Z, h, q, 0.5)
    np.testing.assert_allclose(out.wheel_volts_v, [0.0, 2.16, 0.0], atol=1e-6)
    np.testing.assert_allclose(out.moment_command_am2, saturate(bxh_moment(B_T, h, 0.02)), rtol=1e-12)


def test_celestial_scan_holds_axis_and_controls_scan_rate() -> None:
    dpa = _dpa()
    q = quat_mul(_q(np.array([0.0, 0.0, 1.0]), 2.0), _q(np.array([1.0, 0.0, 0.0]), 1e-5))
    h = np.array([2.0, -1.0, 0.5])
    omega = np.array([0.0, 0.0, rpm_to_rad_s(0.03)])
    out = dpa.step('celestial_scan', B_T, omega, SUN_Z, h, q, 0.5)
    np.testing.assert_allclose(out.wheel_volts_v, [0.364, 0.0, 0.0], atol=1e-6)
    np.testing.assert_allclose(out.moment_command_am2, saturate(bxh_moment(B_T, h, 0.01)), rtol=1e-12)
    fast = dpa.step('celestial_scan', B_T, omega + [0.0, 0.0, 1e-6], SUN_Z, h, q, 0.5)
    assert fast.wheel_volts_v[2] == pytest.approx(2.16e5 * 5.65 * 1e-6)


def test_cruise_needs_attitude_reference() -> None:
    with pytest.raises(ControllerError, match='q_body_to_eci'):
        _dpa().step('celestial_point', B_T, np.zeros(3), SUN_Z, np.zeros(3), None, 0.5)


def test_lead_law_option_uses_wheel_command() -> None:
    dpa = _dpa()
    dpa.set_law('unloading', 'lead')
    q = _q(np.array([1.0, 0.0, 0.0]), 2e-5)
    h = np.array([1.0, 2.0, -1.5])
    out = dpa.step('celestial_point', B_T, np.zeros(3), SUN_Z, h, q, 0.5)
    eps = wheel_command_momentum_nms(out.wheel_volts_v, WHEEL_TORQUE_GAIN_NM_PER_V2, 500.0)
    assert eps[0] > 0.0
    np.testing.assert_allclose(out.moment_command_am2, saturate(lead_moment(B_T, h, eps, 0.02)), rtol=1e-12)
    dpa.set_law('unloading', 'none')
    assert not np.any(dpa.step('celestial_point', B_T, np.zeros(3), SUN_Z, h, q, 0.5).moment_command_am2)


def test_coupling_compensation_subtracts_delta_times_previous_command() -> None:
    delta = np.full((3, 3), 8.75e-10)
    dpa = _dpa(coupling_compensation=True, coupling_delta_t_per_am2=delta)
    h = np.array([1.0, -1.0, 0.5])
    first = dpa.step('mode_1b', B_T, np.zeros(3), SUN_Z, h, Q_ID, 0.5)
    np.testing.assert_allclose(first.moment_command_am2, saturate(bxh_moment(B_T, h, 0.05)))
    second = dpa.step('mode_1b', B_T, np.zeros(3), SUN_Z, h, Q_ID, 0.5)
    b_used = B_T - delta @ first.moment_command_am2
    np.testing.assert_allclose(second.moment_command_am2, saturate(bxh_moment(b_used, h, 0.05)), rtol=1e-12)
    assert not np.allclose(second.moment_command_am2, first.moment_command_am2)


def test_set_gain_changes_the_law_and_validates() -> None:
    dpa = _dpa()
    h = np.array([1.0, 2.0, -1.5])
    dpa.set_gain('unloading_gain_point', 0.04)
    out = dpa.step('celestial_point', B_T, np.zeros(3), SUN_Z, h, Q_ID, 0.5)
    np.testing.assert_allclose(out.moment_command_am2, saturate(bxh_moment(B_T, h, 0.04)), rtol=1e-12)
    dpa.set_gain('wheel_acquisition_kp_y', 162.0)
    assert dpa.config.wheel_gains_acquisition.k_p_v_per_rad == (684.0, 162.0, 97.0)
    dpa.set_gain('scan_rate_rpm', 0.1)
    assert dpa.config.scan_rate_rad_s == pytest.approx(rpm_to_rad_s(0.1))
    dpa.set_gain('max_moment', 1000.0)
    assert dpa.config.max_moment_am2 == 1000.0
    with pytest.raises(ControllerError, match='unknown gain'):
        dpa.set_gain('gain_that_does_not_exist', 1.0)
    with pytest.raises(ControllerError, match='out of range'):
        dpa.set_gain('acquisition_gain', -0.05)
    with pytest.raises(ControllerError, match='out of range'):
        dpa.set_gain('wheel_normal_theta_limit_z', float('nan'))
    with pytest.raises(ControllerError, match='lead|bxh'):
        dpa.set_law('acquisition', 'lead')
    assert set(GAIN_LIMITS) == set(GAIN_TABLE)


def test_bad_config_and_mode_raise() -> None:
    with pytest.raises(ControllerError, match='positive definite'):
        DpaConfig(inertia_kg_m2=-INERTIA_B)
    with pytest.raises(ControllerError, match='unloading_law'):
        DpaConfig(inertia_kg_m2=INERTIA_B, unloading_law='magic')
    with pytest.raises(ControllerError, match='unknown mode'):
        _dpa().step('mode_2', B_T, np.zeros(3), SUN_Z, np.zeros(3), Q_ID, 0.5)
