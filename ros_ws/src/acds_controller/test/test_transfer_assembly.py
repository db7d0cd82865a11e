"""Tests of the transfer assembly (spec §5, §7; seed 002 Table 4-5, §4.2.7)."""

from __future__ import annotations

import numpy as np
import pytest
from acds_controller.magnetic_laws import ControllerError
from acds_controller.transfer_assembly import TransferAssembly


def _volts(b_gauss: np.ndarray, bias_v: float = 2.5) -> np.ndarray:
    return bias_v + 2.5 * b_gauss


def test_default_adc_resolves_the_magnetometer_resolution() -> None:
    ta = TransferAssembly()
    assert ta.adc_bits == 10
    lsb_gauss = ta.lsb_v / 2.5
    assert lsb_gauss <= 0.004 / 2.0  # a count is at most half the sensor resolution
    # field minus bias: quantisation error within ±1 count, inside the 0.004 G resolution
    rng = np.random.default_rng(7)
    for _ in range(200):
        b_g = rng.uniform(-0.95, 0.95, 3)  # inside the rails with the bias drift
        bias = 2.5 + rng.uniform(-0.05, 0.05)
        sensed_g = ta.sense(_volts(b_g, bias), np.full(3, bias)) / 1e-4
        assert np.all(np.abs(sensed_g - b_g) <= lsb_gauss + 1e-12)


def test_0_004_gauss_steps_are_distinguished() -> None:
    ta = TransferAssembly()
    bias = np.full(3, 2.5)
    b1 = ta.sense(_volts(np.array([0.3, -0.2, 0.1])), bias)
    b2 = ta.sense(_volts(np.array([0.304, -0.196, 0.104])), bias)
    assert np.all(b2 > b1)


def test_bias_drift_common_to_field_and_reference_cancels() -> None:
    ta = TransferAssembly()
    b_g = np.array([0.25, -0.1, 0.05])
    nominal = ta.sense(_volts(b_g, 2.5), np.full(3, 2.5))
    drifted = ta.sense(_volts(b_g, 2.6), np.full(3, 2.6))
    np.testing.assert_allclose(drifted, nominal, atol=ta.lsb_v / 2.5 * 1e-4 + 1e-15)
    # a field reading taken against a stale bias reads the drift as field
    stale = ta.sense(_volts(b_g, 2.6), np.full(3, 2.5))
    assert np.all(stale - nominal > 0.035e-4)


def test_adc_clips_at_the_rails() -> None:
    ta = TransferAssembly(adc_bits=12)
    top = ta.digitise(np.array([5.3, -0.2, 2.5]))
    assert top[0] == pytest.approx(5.0 - 5.0 / 4096) and top[1] == 0.0
    assert top[2] == pytest.approx(2.5)


def test_telemetry_keys_and_values() -> None:
    ta = TransferAssembly()
    tm = ta.telemetry(np.array([2.5e-5, -1e-5, 0.0]), np.array([2062.0, -1000.0, 0.0]),
                      np.array([2.5, 2.49, 2.51]), np.array([0.7, -0.35, 0.0]), [True, False, False])
    assert tm['sensed_field_x_gauss'] == '0.25'
    assert tm['sensed_field_y_gauss'] == '-0.1'
    assert float(tm['torquer_current_command_x_a']) == pytest.approx(0.727)
    assert tm['magnetometer_bias_y_v'] == '2.49'
    assert tm['coil_current_y_a'] == '-0.35'
    assert tm['excess_coil_current_alarm_x'] == 'true'
    assert tm['excess_coil_current_alarm_z'] == 'false'
    assert all(isinstance(v, str) for v in tm.values())
    assert len(tm) == 18


def test_invalid_inputs_raise() -> None:
    with pytest.raises(ControllerError, match='adc_bits'):
        TransferAssembly(adc_bits=4)
    ta = TransferAssembly()
    with pytest.raises(ControllerError, match='volts'):
        ta.sense(np.array([np.nan, 2.5, 2.5]), np.full(3, 2.5))
    with pytest.raises(ControllerError, match='3 flags'):
        ta.telemetry(np.zeros(3), np.zeros(3), np.zeros(3), np.zeros(3), [True])
