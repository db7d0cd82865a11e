"""Tests of the CMG attitude-hold law (seed 000 §1, §4; computed-torque PD, gains assumed)."""

from __future__ import annotations

import numpy as np
import pytest
from acds_controller.cmg_hold import HoldGains, cmg_hold_rate
from acds_controller.magnetic_laws import ControllerError
from hypothesis import given, settings
from hypothesis import strategies as st

INERTIA = np.diag([8.6e5, 5.58e6, 5.72e6])  # Second Workshop, kg·m²
_S = st.floats(-1e-3, 1e-3, allow_nan=False)
SMALL = st.tuples(_S, _S, _S).map(np.array)
_T = st.floats(-10.0, 10.0, allow_nan=False)
TORQUE = st.tuples(_T, _T, _T).map(np.array)


@settings(max_examples=60)
@given(SMALL, SMALL, TORQUE, TORQUE)
def test_body_follows_the_second_order_error_dynamics(theta: np.ndarray, omega: np.ndarray, t_ext: np.ndarray,
                                                      h: np.ndarray) -> None:
    """With T_ff = T_ext, I ω̇ = −ω × (Iω + h) − ḣ + T_ext gives ω̇ = −(ω_n² θ + 2ζω_n ω) exactly."""
    gains = HoldGains(0.05, 0.7)
    h_cmg = h * 1000.0
    hdot = cmg_hold_rate(theta, omega, INERTIA, h_cmg, t_ext, gains)
    wdot = np.linalg.solve(INERTIA, -np.cross(omega, INERTIA @ omega + h_cmg) - hdot + t_ext)
    assert np.allclose(wdot, -(0.05 ** 2 * theta + 2 * 0.7 * 0.05 * omega), rtol=1e-9, atol=1e-15)


def test_at_rest_on_target_the_cmgs_take_the_external_torque() -> None:
    t_ff = np.array([0.3, -0.1, 0.05])
    assert np.array_equal(cmg_hold_rate(np.zeros(3), np.zeros(3), INERTIA, np.array([100.0, 0.0, 0.0]), t_ff), t_ff)


def test_bad_inputs_are_named() -> None:
    with pytest.raises(ControllerError, match='bandwidth_rad_s'):
        HoldGains(bandwidth_rad_s=0.0)
    with pytest.raises(ControllerError, match='inertia_kg_m2'):
        cmg_hold_rate(np.zeros(3), np.zeros(3), np.eye(2), np.zeros(3), np.zeros(3))
    with pytest.raises(ControllerError, match='feedforward_torque_nm'):
        cmg_hold_rate(np.zeros(3), np.zeros(3), INERTIA, np.zeros(3), [np.inf, 0.0, 0.0])
