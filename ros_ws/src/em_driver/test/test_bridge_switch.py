"""Tests of the bridge-switch coil driver (spec §6; seed 002 §4.2.5, eqs. 4-27/4-28)."""

from __future__ import annotations

import math

import numpy as np
import pytest
from em_driver.bridge_switch import (
    BridgeSwitchCoil,
    CoilParams,
    DriverParams,
    EmDriverError,
    band_limits_a,
    duty_cycle_closed_form,
)
from hypothesis import given, settings
from hypothesis import strategies as st

COIL = CoilParams()
DRIVER = DriverParams()
TAU = COIL.tau_s
I_ON = (28.0 - 0.7) / 30.3
I_OFF = (28.0 + 1.2) / 30.3

currents = st.floats(min_value=0.05, max_value=0.85)
signs = st.sampled_from([1.0, -1.0])


def settled(i_c: float) -> BridgeSwitchCoil:
    """A coil run from rest long enough (8 τ) to sit in the band."""
    unit = BridgeSwitchCoil(COIL, DRIVER)
    unit.run(i_c, 8.0 * TAU)
    return unit


def test_table_4_3_defaults() -> None:
    assert COIL.resistance_ohm == 30.3 and COIL.inductance_h == 20.3
    assert COIL.moment_per_amp_am2 == pytest.approx(2836.3, abs=0.1)
    assert COIL.max_current_a == pytest.approx(0.727)
    assert TAU == pytest.approx(0.66997, rel=1e-4)


def test_closed_form_matches_spec_quoted_values() -> None:
    fig = CoilParams(resistance_ohm=30.0)
    duty_005, f_005 = duty_cycle_closed_form(0.05, fig, DRIVER)
    duty_070, f_070 = duty_cycle_closed_form(0.70, fig, DRIVER)
    assert duty_005 == pytest.approx(0.54, abs=0.01)
    assert duty_070 == pytest.approx(0.89, abs=0.01)
    assert 600.0 < f_005 < 800.0 and 15.0 < f_070 < 25.0


@settings(max_examples=15, derandomize=True, deadline=None)
@given(i_c=currents, sign=signs)
def test_measured_duty_matches_corrected_eq_4_28(i_c: float, sign: float) -> None:
    unit = settled(sign * i_c)
    duty_eq, f_eq = duty_cycle_closed_form(i_c, COIL, DRIVER)
    window = 300.0 / f_eq  # ~300 cycles: a partial cycle at the ends costs < 0.4 %
    result = unit.run(sign * i_c, window)
    assert result.duty == pytest.approx(duty_eq, abs=0.01)
    assert result.switch_count / (2.0 * window) == pytest.approx(f_eq, rel=0.01)


@settings(max_examples=15, derandomize=True, deadline=None)
@given(i_c=currents, sign=signs)
def test_current_stays_in_band_once_settled(i_c: float, sign: float) -> None:
    unit = settled(sign * i_c)
    wave = unit.run(sign * i_c, 0.5, record=True, record_step_s=2e-4).waveform
    assert wave is not None
    mag = sign * wave.currents_a
    assert mag.min() >= (1 - DRIVER.epsilon) * i_c - 1e-12
    assert mag.max() <= (1 + DRIVER.epsilon) * i_c + 1e-12
    # and it really uses the band (it is not sitting still)
    assert mag.max() - mag.min() > 1.9 * DRIVER.epsilon * i_c


@settings(max_examples=10, derandomize=True, deadline=None)
@given(i_c=currents, sign=signs)
def test_average_moment_equals_command(i_c: float, sign: float) -> None:
    unit = settled(sign * i_c)
    result = unit.run(sign * i_c, 2.0)
    command_moment = sign * i_c * COIL.moment_per_amp_am2
    assert result.avg_moment_am2 == pytest.approx(command_moment, rel=DRIVER.epsilon)
    assert result.avg_current_a == pytest.approx(sign * i_c, rel=DRIVER.epsilon)


def test_step_response_time_constant_on_path() -> None:
    """Command above I_on keeps the bridge on: i(t) = I_on (1 − e^{−t/τ}), τ = L/R, exactly."""
    unit = BridgeSwitchCoil(COIL, DRIVER)
    at_tau = unit.run(2.0, TAU)
    assert at_tau.end_current_a == pytest.approx((1 - math.exp(-1)) * I_ON, rel=0.02)
    assert at_tau.end_current_a == pytest.approx((1 - math.exp(-1)) * I_ON, rel=1e-12)
    assert at_tau.switch_count == 1 and at_tau.duty == 1.0
    later = unit.run(2.0, 15 * TAU)
    assert later.end_current_a == pytest.approx(I_ON, rel=1e-6)
    assert later.switch_count == 0  # saturated: bridge stays on
    assert unit.on_current_a == pytest.approx(I_ON)


def test_recorded_waveform_is_the_exact_exponential() -> None:
    unit = BridgeSwitchCoil(COIL, DRIVER)
    wave = unit.run(2.0, 2.0, record=True, record_step_s=0.01).waveform
    assert wave is not None
    expected = I_ON * (1 - np.exp(-wave.times_s / TAU))
    np.testing.assert_allclose(wave.currents_a, expected, rtol=1e-12, atol=1e-15)


def test_energy_drawn_equals_integral_over_on_intervals() -> None:
    unit = BridgeSwitchCoil(COIL, DRIVER)
    result = unit.run(0.4, 2.0, record=True, record_step_s=2e-5)
    wave = result.waveform
    assert wave is not None
    t, i, on = wave.times_s, wave.currents_a, wave.bridge_on
    seg = 0.5 * (i[1:] + i[:-1]) * np.diff(t)  # trapezoid per sample interval
    drawn = 28.0 * np.sum(np.abs(seg[on[:-1]]))
    returned = 28.0 * np.sum(np.abs(seg[~on[:-1]]))
    assert result.energy_drawn_j == pytest.approx(drawn, rel=1e-6)
    assert result.energy_returned_j == pytest.approx(returned, rel=1e-5)
    assert result.power_w == pytest.approx(result.energy_drawn_j / 2.0)
    # Energy balance: net bus energy = R∫i² + ½L i_end² + 2V_ces∫_on|i| + 2ED∫_off|i|.
    seg_sq = 0.5 * (i[1:] ** 2 + i[:-1] ** 2) * np.diff(t)
    losses = (COIL.resistance_ohm * seg_sq.sum() + 0.5 * COIL.inductance_h * i[-1] ** 2
              + 2 * 0.35 * drawn / 28.0 + 2 * 0.6 * returned / 28.0)
    assert result.energy_from_bus_j == pytest.approx(losses, rel=1e-4)


def test_polarity_reversal_passes_through_zero_monotonically() -> None:
    unit = settled(0.5)
    wave = unit.run(-0.5, 3.0, record=True, record_step_s=1e-3).waveform
    assert wave is not None
    i = wave.currents_a
    first_in_band = int(np.argmax(i <= -(1 + DRIVER.epsilon) * 0.5 * 0.98))
    approach = i[: first_in_band + 1]
    assert np.all(np.diff(approach) <= 0.0)  # monotone through zero
    assert approach[0] > 0.49 and approach[-1] < -0.48
    max_slope_a_s = (28.0 + 1.2 + 30.3 * 0.51) / 20.3  # steepest: diode path at the start
    assert np.max(np.abs(np.diff(np.asarray(i)))) <= max_slope_a_s * 1e-3 * 1.0001  # no jump
    # Through the diodes first: zero is reached at τ·ln((i0 + I_off)/I_off).
    t_zero = float(np.interp(0.0, -i[: first_in_band + 1], wave.times_s[: first_in_band + 1]))
    i0 = wave.currents_a[0]
    assert t_zero == pytest.approx(TAU * math.log((i0 + I_OFF) / I_OFF), rel=1e-3)
    assert -0.5 * 1.01 <= unit.current_a <= -0.5 * 0.99


def test_zero_command_decays_to_zero_and_stays() -> None:
    unit = settled(0.6)
    i0 = unit.current_a
    t_zero = TAU * math.log((i0 + I_OFF) / I_OFF)
    before = unit.run(0.0, 0.9 * t_zero)
    assert before.end_current_a > 0.0 and before.duty == 0.0
    after = unit.run(0.0, 5.0)
    assert after.end_current_a == 0.0 and after.switch_count == 0
    assert after.energy_drawn_j == 0.0
    assert unit.run(0.0, 1.0).avg_current_a == 0.0


def test_continuity_across_periods() -> None:
    whole = BridgeSwitchCoil(COIL, DRIVER).run(0.3, 1.3)
    split = BridgeSwitchCoil(COIL, DRIVER)
    split.run(0.3, 0.45)
    part = split.run(0.3, 0.85)
    assert part.end_current_a == pytest.approx(whole.end_current_a, abs=1e-9)


def test_band_floor_limits_switching_frequency_and_small_commands() -> None:
    for i_c in np.linspace(DRIVER.band_floor_a, 0.05, 60):
        assert duty_cycle_closed_form(float(i_c), COIL, DRIVER)[1] <= 1000.0
    assert band_limits_a(0.5 * DRIVER.band_floor_a, DRIVER) == (0.0, 0.0)
    unit = BridgeSwitchCoil(COIL, DRIVER)
    assert unit.run(0.5 * DRIVER.band_floor_a, 1.0).end_current_a == 0.0
    small = 2.0 * DRIVER.band_floor_a
    unit.run(small, 1.0)
    result = unit.run(small, 0.2)
    assert result.avg_current_a == pytest.approx(small, rel=0.25)
    assert result.switch_count / 0.4 <= 1000.0


def test_e_ft_telemetry_is_signed_current_times_gain() -> None:
    unit = settled(-0.3)
    result = unit.run(-0.3, 0.1)
    assert result.e_ft_v == pytest.approx(DRIVER.current_sense_gain_v_per_a * result.end_current_a)
    assert result.e_ft_v < 0.0


@pytest.mark.parametrize('bad', [math.nan, math.inf, -math.inf])
def test_non_finite_command_rejected(bad: float) -> None:
    unit = settled(0.3)
    before = unit.current_a
    with pytest.raises(EmDriverError, match='finite'):
        unit.run(bad, 0.5)
    assert unit.current_a == before


@pytest.mark.parametrize('duration', [0.0, -1.0, math.nan])
def test_bad_duration_rejected(duration: float) -> None:
    with pytest.raises(EmDriverError, match='duration_s'):
        BridgeSwitchCoil(COIL, DRIVER).run(0.3, duration)


def test_faults_change_the_physics() -> None:
    stuck = settled(0.3)
    stuck.set_fault('stuck_on_bridge')
    assert stuck.run(0.3, 15 * TAU).end_current_a == pytest.approx(I_ON, rel=1e-6)
    dead = settled(0.3)
    dead.set_fault('dead_driver')
    assert dead.run(0.3, 2.0).end_current_a == 0.0
    open_ = settled(0.3)
    open_.set_fault('open_winding')
    res = open_.run(0.3, 1.0)
    assert res.end_current_a == 0.0 and res.energy_drawn_j == 0.0 and res.duty == 1.0
    with pytest.raises(EmDriverError, match='unknown coil fault'):
        open_.set_fault('melted')


def test_invalid_parameters_rejected() -> None:
    with pytest.raises(EmDriverError):
        CoilParams(resistance_ohm=0.0)
    with pytest.raises(EmDriverError):
        DriverParams(epsilon=1.5)
    with pytest.raises(EmDriverError):
        DriverParams(supply_v=0.5, v_ces_v=0.35)


@pytest.mark.parametrize('command_a', [0.003, 0.05, 0.3, -0.6])
def test_whole_cycle_skipping_equals_edge_by_edge_integration(command_a):
    """Settled periods add whole band cycles in closed form; recording forces every edge: same result."""
    fast, exact = BridgeSwitchCoil(CoilParams(), DriverParams()), BridgeSwitchCoil(CoilParams(), DriverParams())
    for _ in range(6):  # rise, settle, then several settled periods
        a = fast.run(command_a, 0.5)
        b = exact.run(command_a, 0.5, record=True, record_step_s=0.5)
        assert a.switch_count == b.switch_count
        for field in ('avg_current_a', 'end_current_a', 'duty', 'energy_drawn_j', 'energy_returned_j'):
            assert getattr(a, field) == pytest.approx(getattr(b, field), rel=1e-9, abs=1e-15), field
