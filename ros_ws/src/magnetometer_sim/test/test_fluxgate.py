"""Tests of the triaxial fluxgate magnetometer model (spec §5, seed 002 Table 4-5)."""

from __future__ import annotations

import numpy as np
import pytest
from acds_common.coupling import CouplingError, coupling_acquisition, coupling_cruise
from hypothesis import given, settings
from hypothesis import strategies as st
from magnetometer_sim.fluxgate import (
    FluxgateAssembly,
    FluxgateAxisParams,
    Magnetometer,
    MagnetometerError,
)

G = 1e-4  # T per gauss


def volts_for(b_g: float) -> np.ndarray:
    return Magnetometer().read([b_g * G, 0.0, -b_g * G]).volts


def test_zero_field_reads_bias() -> None:
    reading = Magnetometer().read([0.0, 0.0, 0.0])
    np.testing.assert_allclose(reading.volts, 2.5, atol=1e-12)
    np.testing.assert_allclose(reading.bias_volts, 2.5)
    np.testing.assert_allclose(reading.field_t, 0.0, atol=1e-18)
    assert reading.active_unit == 'A'


def test_full_scale_reaches_rails_and_beyond_clips() -> None:
    assert volts_for(1.0)[0] == pytest.approx(5.0) and volts_for(1.0)[2] == pytest.approx(0.0)
    assert volts_for(1.5)[0] == 5.0 and volts_for(1.5)[2] == 0.0
    assert volts_for(10.0)[0] == 5.0


def test_quantisation_step_is_0_004_gauss() -> None:
    mag = Magnetometer()
    fields = np.linspace(-0.9, 0.9, 2001)
    volts = np.array([mag.read([b * G, 0.0, 0.0]).volts[0] for b in fields])
    levels = np.unique(np.round(volts, 9))
    np.testing.assert_allclose(np.diff(levels), 0.004 * 2.5, rtol=1e-6)
    # the reading only changes in 0.01 V steps, and stays within half a step of the curve
    ideal = FluxgateAxisParams().ideal_volts(fields)
    assert np.max(np.abs(volts - ideal)) <= 0.005 + 1e-12


def test_nonlinearity_slope_within_one_percent() -> None:
    params = FluxgateAxisParams()
    b = np.linspace(-1.0, 1.0, 4001)
    slope = np.gradient(params.ideal_volts(b), b)
    deviation = slope / 2.5 - 1.0
    assert np.max(np.abs(deviation)) <= 0.01 + 1e-6
    assert np.max(np.abs(deviation)) > 0.009  # the curve really is nonlinear (peaks at full scale)
    # end points exact, and a reading error no larger than the 1 % bound allows
    assert params.ideal_volts(np.array([-1.0, 0.0, 1.0])) == pytest.approx([0.0, 2.5, 5.0])
    assert np.max(np.abs(params.ideal_volts(b) - (2.5 + 2.5 * b))) <= 0.01 * 2.5


@settings(max_examples=50, derandomize=True, deadline=None)
@given(b_g=st.floats(min_value=-0.99, max_value=0.99))
def test_naive_field_within_resolution_and_nonlinearity(b_g: float) -> None:
    reading = Magnetometer().read([b_g * G, 0.0, 0.0])
    # 0.002 G quantisation + ≤ 0.0039 G nonlinearity (c·b·(1 − b²) peaks at 1/√3)
    assert reading.field_t[0] == pytest.approx(b_g * G, abs=0.0060 * G)


def test_coupling_adds_delta_times_dipole_with_sign() -> None:
    delta = coupling_acquisition(signs=[[0, -1, 1], [1, 0, -1], [-1, 1, 0]])
    mag = Magnetometer(coupling_t_per_am2=delta)
    b_true = np.array([0.2, -0.1, 0.3]) * G
    reading = mag.read(b_true, em_dipole_am2=[2000.0, 0.0, 0.0])
    # a saturated x magnet adds 5 % of 0.5 G on y (sign +) and z (sign −), nothing on x
    np.testing.assert_allclose(reading.b_sensed_t - b_true, [0.0, 0.025 * G, -0.025 * G], atol=1e-15)
    assert reading.field_t[1] == pytest.approx((-0.1 + 0.025) * G, abs=0.003 * G)
    assert reading.field_t[2] == pytest.approx((0.3 - 0.025) * G, abs=0.003 * G)
    np.testing.assert_allclose(np.diag(delta), 0.0)


def test_cruise_coupling_is_diagonal_8_75e_6_gauss_per_am2() -> None:
    delta = coupling_cruise()
    np.testing.assert_allclose(delta, np.eye(3) * 8.75e-10)
    mag = Magnetometer(coupling_t_per_am2=delta, residual_field_t=[0.005 * G, 0.0, 0.0])
    reading = mag.read([0.0, 0.0, 0.0], em_dipole_am2=[-2000.0, 0.0, 400.0])
    np.testing.assert_allclose(reading.b_sensed_t, [(0.005 - 0.0175) * G, 0.0, 0.0035 * G], atol=1e-15)


def test_standby_takes_over_on_command() -> None:
    mag = Magnetometer()
    mag.inject_fault('A', 'dead_unit')
    dead = mag.read([0.3 * G, 0.0, 0.0])
    np.testing.assert_allclose(dead.volts, 0.0)
    np.testing.assert_allclose(dead.bias_volts, 0.0)
    mag.select_unit('B')
    alive = mag.read([0.3 * G, 0.0, 0.0])
    assert alive.active_unit == 'B'
    assert alive.volts[0] == pytest.approx(2.5 + 0.75 * (1 - 0.005 * 0.91), abs=0.006)
    assert alive.field_t[0] == pytest.approx(0.3 * G, abs=0.004 * G)


def test_bias_shift_shows_in_bias_output_and_reads_as_field() -> None:
    mag = Magnetometer()
    mag.inject_fault('A', 'bias_shift', value=0.05)
    reading = mag.read([0.0, 0.0, 0.0])
    np.testing.assert_allclose(reading.bias_volts, 2.55)
    np.testing.assert_allclose(reading.volts, 2.55, atol=1e-9)
    np.testing.assert_allclose(reading.field_t, 0.02 * G, atol=1e-12)  # false field to a naive reader
    mag.clear_faults()
    np.testing.assert_allclose(mag.read([0.0, 0.0, 0.0]).bias_volts, 2.5)
    mag.inject_fault('B', 'bias_shift', axis=2, value=-0.1)
    mag.select_unit('B')
    np.testing.assert_allclose(mag.read([0.0, 0.0, 0.0]).bias_volts, [2.5, 2.5, 2.4])


def test_stuck_axis_freezes_output() -> None:
    mag = Magnetometer()
    first = mag.read([0.2 * G, 0.1 * G, 0.0])
    mag.inject_fault('A', 'stuck_axis', axis=0)
    later = mag.read([-0.4 * G, -0.3 * G, 0.0])
    assert later.volts[0] == first.volts[0]
    assert later.volts[1] == pytest.approx(2.5 - 0.75, abs=0.01)


def test_accuracy_error_bounded_and_seeded() -> None:
    params = FluxgateAxisParams(accuracy_error_enabled=True)
    b = np.array([0.8, -0.5, 0.0]) * G
    for seed in range(20):
        unit = FluxgateAssembly(FluxgateAxisParams(accuracy_error_enabled=True, resolution_g=1e-9), seed)
        exact = FluxgateAssembly(FluxgateAxisParams(resolution_g=1e-9), seed)
        err_v = unit.sample(b)[0] - exact.sample(b)[0]
        assert np.all(np.abs(err_v) <= 0.001 * 2.5 * 1.011 + 1e-8)  # ±0.1 % of 1 G, through the slope
    a1 = Magnetometer(params, seed=3).read(b).volts
    a2 = Magnetometer(params, seed=3).read(b).volts
    np.testing.assert_array_equal(a1, a2)


def test_noise_is_seeded_and_off_by_default() -> None:
    params = FluxgateAxisParams(noise_std_g=0.01)
    r1 = [Magnetometer(params, seed=7).read([0.1 * G, 0.0, 0.0]).volts for _ in range(2)]
    np.testing.assert_array_equal(r1[0], r1[1])
    mag = Magnetometer()
    quiet = {tuple(mag.read([0.1 * G, 0.0, 0.0]).volts) for _ in range(5)}
    assert len(quiet) == 1


def test_covariance_from_resolution_and_accuracy() -> None:
    cov = Magnetometer().read([0.0, 0.0, 0.0]).covariance_t2
    expected = (0.004**2 / 12 + 0.001**2 / 3) * G**2
    np.testing.assert_allclose(cov, np.eye(3) * expected)


def test_invalid_inputs_rejected() -> None:
    mag = Magnetometer()
    with pytest.raises(MagnetometerError, match='finite'):
        mag.read([np.nan, 0.0, 0.0])
    with pytest.raises(MagnetometerError, match='3-vector'):
        mag.read([0.0, 0.0])
    with pytest.raises(MagnetometerError, match='unit'):
        mag.select_unit('C')
    with pytest.raises(MagnetometerError, match='unknown magnetometer fault'):
        mag.inject_fault('A', 'on_fire')
    with pytest.raises(MagnetometerError, match='bias_shift'):
        mag.inject_fault('A', 'bias_shift')
    with pytest.raises(CouplingError, match='signs'):
        coupling_acquisition(signs=np.full((3, 3), 2.0))
    with pytest.raises(MagnetometerError):
        FluxgateAxisParams(resolution_g=0.0)
