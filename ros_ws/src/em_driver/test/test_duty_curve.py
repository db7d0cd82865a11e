"""Tests of the duty-curve core (spec §6, seed 002 Fig. 4-10); its verb: tests/test_tool_verbs.py."""

from __future__ import annotations

import pytest
from em_driver.bridge_switch import duty_cycle_closed_form
from em_driver.duty_curve import FIG_4_10_COIL, FIG_4_10_DRIVER, measure_duty, sweep_currents_a


def test_sweep_points() -> None:
    currents = sweep_currents_a()
    assert len(currents) >= 17
    assert currents[0] == pytest.approx(0.05) and currents[-1] == pytest.approx(0.85)


def test_measured_duty_is_from_the_waveform_not_the_formula() -> None:
    """Saturation (upper threshold above I_on) measures as 100 % and 0 Hz."""
    i_on = (28.0 - 0.7) / 30.0
    assert measure_duty(0.995 * i_on) == (1.0, 0.0)
    duty, freq = measure_duty(0.3, cycles=5)
    duty_eq, f_eq = duty_cycle_closed_form(0.3, FIG_4_10_COIL, FIG_4_10_DRIVER)
    assert duty == pytest.approx(duty_eq, abs=1e-6) and freq == pytest.approx(f_eq, rel=1e-6)
