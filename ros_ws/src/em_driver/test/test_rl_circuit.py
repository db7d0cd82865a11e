"""Tests of the exact RL helpers: closed-form PWM periods against edge-by-edge segments (spec §6, §9)."""

from __future__ import annotations

import math

import numpy as np
import pytest
from em_driver import rl_circuit
from hypothesis import given, settings
from hypothesis import strategies as st


def _edge_by_edge(i0: float, i_on: float, tau: float, period: float, duty: float, n: int) -> tuple[float, float, float]:
    i, area, area_on = i0, 0.0, 0.0
    for _ in range(n):
        i, a_on = rl_circuit.segment(i, i_on, tau, duty * period)
        i, a_off = rl_circuit.segment(i, 0.0, tau, (1.0 - duty) * period)
        area += a_on + a_off
        area_on += a_on
    return i, area, area_on


@settings(max_examples=60)
@given(i0=st.floats(-0.1, 0.1), i_on=st.floats(-0.1, 0.1), tau=st.floats(1e-4, 1e-1), duty=st.floats(0.0, 1.0),
       n=st.integers(0, 400), f_khz=st.sampled_from([1.0, 20.0, 50.0]))
def test_closed_form_periods_equal_edge_by_edge(i0: float, i_on: float, tau: float, duty: float, n: int,
                                               f_khz: float) -> None:
    period = 1e-3 / f_khz
    got = rl_circuit.pwm_periods(i0, i_on, tau, period, duty, n)
    i, area, area_on = _edge_by_edge(i0, i_on, tau, period, duty, n)
    assert got.end_current_a == pytest.approx(i, rel=1e-9, abs=1e-14)
    assert got.area_as == pytest.approx(area, rel=1e-8, abs=1e-15)
    assert got.area_on_as == pytest.approx(area_on, rel=1e-8, abs=1e-15)
    cumulative = rl_circuit.pwm_cumulative_charge(i0, i_on, tau, period, duty, np.array([0, n]))
    np.testing.assert_allclose(cumulative, [0.0, got.area_as], rtol=1e-12, atol=1e-18)


def test_segment_is_the_exponential_and_its_integral() -> None:
    tau, i_inf, i0 = 2e-3, 0.07, -0.01
    for t in (0.0, 1e-4, 2e-3, 1e-2):
        i, area = rl_circuit.segment(i0, i_inf, tau, t)
        assert i == pytest.approx(i_inf + (i0 - i_inf) * math.exp(-t / tau), rel=1e-15)
        assert area == pytest.approx(i_inf * t - (i_inf - i0) * tau * (1.0 - math.exp(-t / tau)), rel=1e-12, abs=1e-20)


def test_time_to_reach_threshold() -> None:
    tau = 1e-3
    t = rl_circuit.time_to_reach_s(0.0, 0.1, 0.05, tau)
    assert t == pytest.approx(tau * math.log(2.0))
    assert rl_circuit.segment(0.0, 0.1, tau, t)[0] == pytest.approx(0.05)
    assert rl_circuit.time_to_reach_s(0.0, 0.1, 0.2, tau) == math.inf  # beyond the asymptote
    assert rl_circuit.time_to_reach_s(0.1, 0.1, 0.05, tau) == math.inf  # already settled
