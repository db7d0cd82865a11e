"""The one attitude module (acds_common.attitude): its float kernels and numpy forms agree with each other
and with the conventions (Hamilton, scalar last, body → reference; spec §3)."""

from __future__ import annotations

import math

import numpy as np
import pytest
from acds_common.attitude import (
    AttitudeError,
    conj,
    dcm,
    dcm_to_quat,
    quat_mul,
    quat_rates,
    quat_to_dcm,
    rotation_between,
    to_body,
)
from hypothesis import given
from hypothesis import strategies as st

finite = st.floats(-1.0, 1.0)
quats = st.tuples(finite, finite, finite, finite).filter(lambda q: math.fsum(c * c for c in q) > 1e-3).map(
    lambda q: tuple(c / math.sqrt(math.fsum(x * x for x in q)) for c in q))


def test_a_quarter_turn_about_z_takes_body_x_to_reference_y():
    q = (0.0, 0.0, math.sin(math.pi / 4), math.cos(math.pi / 4))
    np.testing.assert_allclose(quat_to_dcm(q) @ [1.0, 0.0, 0.0], [0.0, 1.0, 0.0], atol=1e-15)
    np.testing.assert_allclose(to_body(q, (0.0, 1.0, 0.0)), [1.0, 0.0, 0.0], atol=1e-15)


@given(quats, quats, st.tuples(finite, finite, finite))
def test_product_composes_rotations_and_to_body_is_the_transpose(q1, q2, v):
    np.testing.assert_allclose(quat_to_dcm(quat_mul(q1, q2)), quat_to_dcm(q1) @ quat_to_dcm(q2), atol=1e-12)
    np.testing.assert_allclose(to_body(q1, v), np.array(dcm(q1)).T @ v, atol=1e-12)
    np.testing.assert_allclose(quat_mul(conj(q1), q1), [0.0, 0.0, 0.0, 1.0], atol=1e-12)


@given(quats)
def test_dcm_to_quat_inverts_quat_to_dcm_up_to_sign(q):
    back = dcm_to_quat(quat_to_dcm(q))
    assert back[3] >= 0.0
    assert abs(float(back @ np.array(q))) == pytest.approx(1.0, abs=1e-9)  # q or −q: the same rotation


def test_dcm_to_quat_refuses_a_reflection():
    with pytest.raises(AttitudeError, match='proper rotation'):
        dcm_to_quat(np.diag([1.0, 1.0, -1.0]))


@given(quats, st.tuples(finite, finite, finite))
def test_quat_rates_is_half_q_times_omega(q, w):
    np.testing.assert_allclose(quat_rates(np.array([q]), np.array([w]))[0],
                               0.5 * np.array(quat_mul(q, (*w, 0.0))), atol=1e-15)


@given(st.tuples(finite, finite, finite), st.tuples(finite, finite, finite))
def test_rotation_between_takes_a_onto_b(a, b):
    a, b = np.array(a), np.array(b)
    if np.linalg.norm(a) < 1e-3 or np.linalg.norm(b) < 1e-3:
        return
    r = rotation_between(a, b)
    np.testing.assert_allclose(r @ r.T, np.eye(3), atol=1e-12)
    np.testing.assert_allclose(r @ (a / np.linalg.norm(a)), b / np.linalg.norm(b), atol=1e-9)
