"""Tests of the CubeSat detumble law M = −(k_ω/|B|)(B̂ × ω) and its dumping form (spec §9; seed 003)."""

from __future__ import annotations

import math

import numpy as np
import pytest
from acds_common.units import G_MM2_KG_M2, rad
from acds_controller.b_cross_omega import (
    detumble_gain,
    detumble_moment,
    dump_gain_per_s,
    dump_moment,
    dump_peak_moment_am2,
    orbit_average_projection,
)
from acds_controller.magnetic_laws import ControllerError, saturate
from hypothesis import assume, given, settings
from hypothesis import strategies as st

#: Seed 003 "Mission Requirements": ISS period and inclination, J_min from the CAD model (g·mm²;
#: the seed prints the unit as "g/mm²").
T_ORB_S = 5560.8
XI_RAD = 0.90129
J_MIN_KG_M2 = 5_094_047.43 * G_MM2_KG_M2

_COMP = st.floats(-1.0, 1.0, allow_nan=False)
UNIT_ISH = st.tuples(_COMP, _COMP, _COMP).map(np.array).filter(lambda v: np.linalg.norm(v) > 1e-3)


def test_seed_gain_and_worst_case_moment() -> None:
    k = detumble_gain(T_ORB_S, XI_RAD, J_MIN_KG_M2)
    assert J_MIN_KG_M2 == pytest.approx(5.094e-3, rel=1e-4)
    assert f'{k:.4g}' == '2.054e-05'
    omega = np.full(3, rad(5.0))  # 5°/s per axis: |ω| = 0.15115 rad/s
    assert np.linalg.norm(omega) == pytest.approx(0.15115, abs=1e-5)
    b_dir = np.cross(omega, [1.0, 0.0, 0.0])
    b = 20e-6 * b_dir / np.linalg.norm(b_dir)  # |B| = 20 µT, B ⟂ ω
    m = detumble_moment(b, omega, k)
    assert f'{np.linalg.norm(m):.4g}' == '0.1552'
    assert float(m @ b) == pytest.approx(0.0, abs=1e-20)


def test_moment_scales_as_one_over_field_and_vanishes_along_it() -> None:
    k = detumble_gain(T_ORB_S, XI_RAD, J_MIN_KG_M2)
    omega = np.array([0.01, -0.02, 0.03])
    b = np.array([1e-5, 2e-5, -3e-5])
    np.testing.assert_allclose(detumble_moment(2.0 * b, omega, k), 0.5 * detumble_moment(b, omega, k))
    np.testing.assert_allclose(detumble_moment(b, 3.0 * b / np.linalg.norm(b), k), 0.0, atol=1e-18)


@settings(max_examples=200)
@given(b=UNIT_ISH, w=UNIT_ISH, limit=st.floats(1e-3, 1.0), scale=st.floats(1e-5, 6e-5))
def test_energy_rate_is_never_positive_with_or_without_saturation(b: np.ndarray, w: np.ndarray, limit: float,
                                                                 scale: float) -> None:
    """dE/dt = ω·(M × B) = −k_ω|B̂ × ω|² ≤ 0 pointwise; per-axis clipping keeps the sign."""
    k = detumble_gain(T_ORB_S, XI_RAD, J_MIN_KG_M2)
    b_t = scale * b
    omega = rad(10.0) * w
    m = detumble_moment(b_t, omega, k)
    rate = float(omega @ np.cross(m, b_t))
    b_hat = b_t / np.linalg.norm(b_t)
    assert rate == pytest.approx(-k * float(np.sum(np.cross(b_hat, omega) ** 2)), rel=1e-9, abs=1e-30)
    assert float(omega @ np.cross(saturate(m, limit), b_t)) <= 1e-30


def _dipole_field_inertial(t_s: float, xi_rad: float, period_s: float) -> np.ndarray:
    """Centred dipole field (T) seen along a circular orbit inclined xi to the magnetic equator."""
    u = 2.0 * math.pi * t_s / period_s
    r = np.array([math.cos(u), math.sin(u) * math.cos(xi_rad), math.sin(u) * math.sin(xi_rad)])
    return -3.0e-5 * (3.0 * r[2] * r - np.array([0.0, 0.0, 1.0]))  # 30 µT at the magnetic equator


def _skew(v: np.ndarray) -> np.ndarray:
    return np.array([[0.0, -v[2], v[1]], [v[2], 0.0, -v[0]], [-v[1], v[0], 0.0]])


def _euler_rates(t_s: float, w: np.ndarray, rot: np.ndarray, m: np.ndarray, j_diag: np.ndarray,
                 xi_rad: float) -> tuple[np.ndarray, np.ndarray]:
    """(ω̇, Ṙ) of a rigid body with principal inertia j_diag under T = M × B (body axes)."""
    torque = np.cross(m, rot.T @ _dipole_field_inertial(t_s, xi_rad, T_ORB_S))
    return (torque - np.cross(w, j_diag * w)) / j_diag, rot @ _skew(w)


def _one_orbit_energy(j_diag: np.ndarray, omega0: np.ndarray, xi_rad: float, limit_am2: float) -> tuple[float, float]:
    """Rotational energy at the start and after one orbit: the law sampled every 1 s and held
    (zero-order hold, as a flight computer does), rigid body + attitude by RK4 at 1 s."""
    dt, sub = 1.0, 1
    k = detumble_gain(T_ORB_S, xi_rad, float(j_diag.min()))
    w, rot = omega0.astype(float), np.eye(3)  # rot: body → inertial
    e0 = 0.5 * float(w @ (j_diag * w))
    h = dt / sub
    for step in range(round(T_ORB_S / dt)):
        b_body = rot.T @ _dipole_field_inertial(step * dt, xi_rad, T_ORB_S)
        m = saturate(detumble_moment(b_body, w, k), limit_am2)
        for s in range(sub):
            t0 = step * dt + s * h
            k1 = _euler_rates(t0, w, rot, m, j_diag, xi_rad)
            k2 = _euler_rates(t0 + h / 2, w + h / 2 * k1[0], rot + h / 2 * k1[1], m, j_diag, xi_rad)
            k3 = _euler_rates(t0 + h / 2, w + h / 2 * k2[0], rot + h / 2 * k2[1], m, j_diag, xi_rad)
            k4 = _euler_rates(t0 + h, w + h * k3[0], rot + h * k3[1], m, j_diag, xi_rad)
            w = w + h / 6 * (k1[0] + 2 * k2[0] + 2 * k3[0] + k4[0])
            rot = rot + h / 6 * (k1[1] + 2 * k2[1] + 2 * k3[1] + k4[1])
            u, _, vt = np.linalg.svd(rot)
            rot = u @ vt
    return e0, 0.5 * float(w @ (j_diag * w))


@settings(max_examples=3)
@given(j=st.tuples(st.floats(4e-3, 2e-2), st.floats(4e-3, 2e-2), st.floats(4e-3, 2e-2)),
       w=st.tuples(st.floats(-5.0, 5.0), st.floats(-5.0, 5.0), st.floats(-5.0, 5.0)),
       xi=st.floats(0.3, 1.5), limit=st.sampled_from([0.05, 0.1552, 1.0]))
def test_law_lowers_rotational_energy_over_an_orbit(j: tuple[float, float, float], w: tuple[float, float, float],
                                                   xi: float, limit: float) -> None:
    j_diag = np.array(j)
    omega0 = np.radians(np.array(w))
    assume(np.linalg.norm(omega0) > 1e-3 and 2 * j_diag.max() <= j_diag.sum())  # spinning, a physical body
    e0, e1 = _one_orbit_energy(j_diag, omega0, xi, limit)
    assert e1 < e0


def test_orbit_average_projection_limits() -> None:
    np.testing.assert_allclose(np.linalg.eigvalsh(orbit_average_projection(0.0)), [0.0, 1.0, 1.0], atol=1e-12)
    np.testing.assert_allclose(np.linalg.eigvalsh(orbit_average_projection(math.pi / 2)), [0.5, 0.5, 1.0],
                               atol=1e-12)
    p = orbit_average_projection(XI_RAD)
    assert np.trace(p) == pytest.approx(2.0)  # I − B̂B̂ᵀ has trace 2 at every instant
    assert np.linalg.eigvalsh(p)[0] == pytest.approx(0.6049, abs=1e-4)


def test_dump_torque_opposes_wheel_momentum_normal_to_field() -> None:
    b = np.array([2e-5, -1e-5, 3e-5])
    h = np.array([0.01, 0.02, -0.005])
    k = 1e-3
    torque = np.cross(dump_moment(b, h, k), b)
    b_hat = b / np.linalg.norm(b)
    np.testing.assert_allclose(torque, -k * (h - (h @ b_hat) * b_hat), rtol=1e-12)


def test_dump_gain_meets_its_requirement_in_an_inertially_held_body() -> None:
    """The wheels hold the body fixed, so ḣ = M × B; after dump_time the slowest mode is at the fraction."""
    t_dump = 5 * T_ORB_S
    k = dump_gain_per_s(t_dump, XI_RAD, 0.5)
    slow = np.linalg.eigh(orbit_average_projection(XI_RAD))[1][:, 0]
    h = 0.02 * slow
    dt = 5.0
    norms = [np.linalg.norm(h)]
    for step in range(round(t_dump / dt)):  # midpoint rule on ḣ = −k(I − B̂B̂ᵀ)h
        b_mid = _dipole_field_inertial((step + 0.5) * dt, XI_RAD, T_ORB_S)
        h_half = h + 0.5 * dt * np.cross(dump_moment(b_mid, h, k), b_mid)
        h = h + dt * np.cross(dump_moment(b_mid, h_half, k), b_mid)
        norms.append(np.linalg.norm(h))
    assert norms[-1] / norms[0] == pytest.approx(0.5, abs=0.02)
    assert all(b <= a + 1e-15 for a, b in zip(norms, norms[1:], strict=False))
    assert dump_peak_moment_am2(k, 0.02, 20e-6) == pytest.approx(k * 0.02 / 20e-6)


def test_bad_inputs_raise_controller_error() -> None:
    with pytest.raises(ControllerError, match='b_t is zero'):
        detumble_moment(np.zeros(3), np.ones(3), 1e-5)
    with pytest.raises(ControllerError, match='xi_rad'):
        detumble_gain(T_ORB_S, 2.0, J_MIN_KG_M2)
    with pytest.raises(ControllerError, match='cannot be dumped'):
        dump_gain_per_s(T_ORB_S, 0.0, 0.5)
    with pytest.raises(ControllerError, match='omega_body_rad_s'):
        detumble_moment(np.ones(3), [np.nan, 0.0, 0.0], 1e-5)
