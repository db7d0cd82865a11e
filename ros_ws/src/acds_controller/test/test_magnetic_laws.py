"""Tests of the DPA magnetic laws (spec §7; seed 002 §4.2.1, eq. 4-9, 4-17, 4-37)."""

from __future__ import annotations

import numpy as np
import pytest
from acds_common.units import FTLB_PER_GAUSS_AM2, ftlbs_to_nms, gauss_to_tesla
from acds_controller.magnetic_laws import (
    ControllerError,
    bdot_gain_to_si,
    bdot_moment,
    bxh_gain_to_si,
    bxh_moment,
    compensate_coupling,
    lead_moment,
    saturate,
    wheel_command_momentum_nms,
)
from hypothesis import given, settings
from hypothesis import strategies as st

_B_COMPONENT_T = st.floats(-6e-5, 6e-5, allow_nan=False)
_H_COMPONENT_NMS = st.floats(-400.0, 400.0, allow_nan=False)
B_VEC = st.tuples(_B_COMPONENT_T, _B_COMPONENT_T, _B_COMPONENT_T).map(np.array)
H_VEC = st.tuples(_H_COMPONENT_NMS, _H_COMPONENT_NMS, _H_COMPONENT_NMS).map(np.array)
GAIN = st.sampled_from([0.01, 0.02, 0.05, 0.5])


def test_bxh_gain_conversion_matches_study_units() -> None:
    """|M| = G·|B|[G]·|H|[ft-lb-s]·13558.2 A·m² for perpendicular B and H."""
    b = np.array([gauss_to_tesla(0.3), 0.0, 0.0])
    h = np.array([0.0, ftlbs_to_nms(40.0), 0.0])
    m = bxh_moment(b, h, 0.05)
    assert np.linalg.norm(m) == pytest.approx(0.05 * 0.3 * 40.0 * 13558.2, rel=1e-5)
    assert np.linalg.norm(m) == pytest.approx(0.05 * 0.3 * 40.0 * FTLB_PER_GAUSS_AM2, rel=1e-12)
    # −G (x̂ × ŷ) = −G ẑ
    assert m[2] < 0.0 and m[0] == 0.0 and m[1] == 0.0
    assert bxh_gain_to_si(0.05) == pytest.approx(0.05e8, rel=1e-12)


def test_bdot_gain_conversion() -> None:
    """K_D = 1 ft-lb-s/G² is 13558.2/1e-4 A·m²·s/T."""
    assert bdot_gain_to_si(1.0) == pytest.approx(1.3558179e8, rel=1e-7)


@settings(derandomize=True, max_examples=300, deadline=None)
@given(B_VEC, H_VEC, GAIN)
def test_bxh_perpendicular_to_b_and_never_increases_h(b: np.ndarray, h: np.ndarray, g: float) -> None:
    """M ⊥ B, and the torque M × B satisfies dH/dt·H ≤ 0, saturated or not."""
    m = bxh_moment(b, h, g)
    scale = np.linalg.norm(m) * np.linalg.norm(b) + 1e-30
    assert abs(float(m @ b)) <= 1e-9 * scale
    for moment in (m, saturate(m, 2000.0)):
        torque = np.cross(moment, b)
        assert float(torque @ h) <= 1e-12 * (np.linalg.norm(torque) * np.linalg.norm(h) + 1e-30)


@settings(derandomize=True, max_examples=200, deadline=None)
@given(B_VEC, H_VEC)
def test_bxh_torque_is_minus_g_b2_h_perp(b: np.ndarray, h: np.ndarray) -> None:
    """M × B = −G_SI·B²·H⊥ (seed eq. 4-12 with the error torque along B removed)."""
    torque = np.cross(bxh_moment(b, h, 0.02), b)
    b2 = float(b @ b)
    h_perp = h - (h @ b) / b2 * b if b2 > 0 else np.zeros(3)
    expected = -bxh_gain_to_si(0.02) * b2 * h_perp
    np.testing.assert_allclose(torque, expected, rtol=1e-9, atol=1e-15)


@settings(derandomize=True, max_examples=200, deadline=None)
@given(st.tuples(*[st.floats(-1e5, 1e5, allow_nan=False)] * 3).map(np.array),
       st.floats(0.0, 3000.0, allow_nan=False))
def test_saturate_keeps_each_axis_within_limit(m: np.ndarray, limit: float) -> None:
    s = saturate(m, limit)
    assert np.all(np.abs(s) <= limit)
    inside = np.abs(m) <= limit
    np.testing.assert_array_equal(s[inside], m[inside])
    assert np.all(s[~inside] == np.sign(m[~inside]) * limit)


def test_bdot_opposes_field_rate_and_has_the_right_size() -> None:
    b_prev = np.array([1.0e-5, -2.0e-5, 3.0e-5])
    b_now = b_prev + np.array([1.0e-6, -5.0e-7, 0.0])
    m = bdot_moment(b_now, b_prev, 0.5, 1.0)
    b_dot = (b_now - b_prev) / 0.5
    assert np.all(m * b_dot <= 0.0)
    assert m[0] < 0.0 and m[1] > 0.0 and m[2] == 0.0
    # 1 ft-lb-s/G² × 2e-6 T/s = 1.3558e8 × 2e-6 = 271.16 A·m²
    assert m[0] == pytest.approx(-271.16358, rel=1e-6)


def test_bdot_rejects_zero_period() -> None:
    with pytest.raises(ControllerError, match='dt_s'):
        bdot_moment(np.zeros(3), np.zeros(3), 0.0, 1.0)


def test_lead_law_reduces_to_bxh_without_command() -> None:
    b = np.array([2e-5, -1e-5, 1.5e-5])
    h = np.array([3.0, -1.0, 7.0])
    np.testing.assert_allclose(lead_moment(b, h, np.zeros(3), 0.02), bxh_moment(b, h, 0.02))


@settings(derandomize=True, max_examples=200, deadline=None)
@given(B_VEC, H_VEC, H_VEC)
def test_lead_law_unloads_the_anticipated_momentum(b: np.ndarray, h: np.ndarray, eps: np.ndarray) -> None:
    """The torque never increases |H + ε| (it is the B×H law on H + ε)."""
    torque = np.cross(lead_moment(b, h, eps, 0.02), b)
    anticipated = h + eps
    assert float(torque @ anticipated) <= 1e-12 * (np.linalg.norm(torque) * np.linalg.norm(anticipated) + 1e-30)


def test_lead_law_acts_harder_when_wheels_are_loading() -> None:
    """A wheel command in the direction of h (momentum building) raises the unloading torque."""
    b = np.array([0.0, 0.0, 3e-5])
    h = np.array([5.0, 0.0, 0.0])
    eps = wheel_command_momentum_nms(np.array([4.0, 0.0, 0.0]), 5e-4, 500.0)
    assert eps[0] == pytest.approx(500.0 * 5e-4 * 16.0)
    t_plain = np.cross(bxh_moment(b, h, 0.02), b)
    t_lead = np.cross(lead_moment(b, h, eps, 0.02), b)
    assert t_lead[0] < t_plain[0] < 0.0


def test_wheel_command_momentum_is_square_law_with_sign() -> None:
    eps = wheel_command_momentum_nms(np.array([-2.0, 0.0, 3.0]), 1e-3, 100.0)
    np.testing.assert_allclose(eps, [-0.4, 0.0, 0.9])


def test_coupling_compensation_recovers_earth_field() -> None:
    delta = 8.75e-10 * np.array([[0.0, 1.0, -1.0], [1.0, 0.0, 1.0], [-1.0, 1.0, 0.0]])
    m = np.array([2000.0, -1500.0, 300.0])
    b_earth = np.array([2e-5, -1e-5, 3e-5])
    np.testing.assert_allclose(compensate_coupling(b_earth + delta @ m, delta, m), b_earth, atol=1e-18)


@pytest.mark.parametrize('bad', [np.array([np.nan, 0.0, 0.0]), np.array([1.0, 2.0]), 'abc'])
def test_bad_vectors_raise_controller_error(bad: object) -> None:
    with pytest.raises(ControllerError, match='b_t'):
        bxh_moment(bad, np.ones(3), 0.05)  # type: ignore[arg-type]


def test_negative_gain_is_refused() -> None:
    with pytest.raises(ControllerError, match='out of range'):
        bxh_moment(np.ones(3), np.ones(3), -0.01)
