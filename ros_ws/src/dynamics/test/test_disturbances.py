"""Tests of dynamics.disturbances: the Workshop's bias + cyclic torques (seed 000 §5)."""

from __future__ import annotations

import math

import numpy as np
import pytest
from acds_common import units
from acds_common.environment import Orbit, OrbitConfig
from dynamics.disturbances import (
    MODE_GEOMETRY,
    SEED_BIAS_MOMENTUM_FTLBS,
    DisturbanceTorque,
    Harmonic,
    ModeGeometry,
    gravity_gradient_inertial_hold,
    seed_disturbance,
    workshop_inertia_kg_m2,
)
from dynamics.errors import DynamicsError
from dynamics.rigid_body_model import gravity_gradient_torque_nm
from hypothesis import given, settings
from hypothesis import strategies as st

ORBIT = Orbit(OrbitConfig(kind='circular', inclination_rad=math.radians(35.0), raan_rad=math.radians(40.0),
                          altitude_m=220.0 * units.NMI_M))
N = ORBIT.mean_motion_rad_s
T = ORBIT.period_s


def _simpson(f, t0: float, t1: float, n: int = 2000) -> np.ndarray:
    ts = np.linspace(t0, t1, 2 * n + 1)
    vals = np.array([f(t) for t in ts])
    w = np.ones(2 * n + 1)
    w[1:-1:2], w[2:-1:2] = 4.0, 2.0
    return (w[:, None] * vals).sum(axis=0) * (t1 - t0) / (6 * n)


@pytest.mark.parametrize('mode', list(SEED_BIAS_MOMENTUM_FTLBS))
@pytest.mark.parametrize('rigid_body_gg', [False, True])
def test_one_orbit_of_torque_is_exactly_the_seed_bias(mode: str, rigid_body_gg: bool) -> None:
    """§5 table: integrating the disturbance (+ the body model's own gravity gradient when it has one)
    over one orbit of held attitude gives H_b, from any starting time."""
    d = seed_disturbance(mode, N, rigid_body_gravity_gradient=rigid_body_gg)
    h_b = units.ftlbs_to_nms(np.array(SEED_BIAS_MOMENTUM_FTLBS[mode]))
    gg = gravity_gradient_inertial_hold(workshop_inertia_kg_m2(), MODE_GEOMETRY[mode], N)
    for t0 in (0.0, 1234.5):
        total = d.momentum_nms(t0, t0 + T) + (gg.momentum_nms(t0, t0 + T) if rigid_body_gg else 0.0)
        assert np.allclose(total, h_b, rtol=1e-12, atol=1e-9)
        numeric = _simpson(d.torque_body_nm, t0, t0 + T)
        assert np.allclose(numeric, d.momentum_nms(t0, t0 + T), rtol=1e-9, atol=1e-8)


@settings(max_examples=30)
@given(st.floats(0.0, 3 * 5563.0))
def test_gravity_gradient_decomposition_equals_the_rigid_body_torque(t_s: float) -> None:
    """Bias + 2nd harmonic = 3 μ/r³ r̂ × (I r̂) of rigid_body_model at the orbit position, for every mode."""
    inertia = workshop_inertia_kg_m2()
    r_eci = ORBIT.position_velocity_eci(t_s)[0]
    for geometry in MODE_GEOMETRY.values():
        dcm = geometry.body_to_eci_dcm(math.radians(35.0), math.radians(40.0))
        assert np.allclose(dcm.T @ dcm, np.eye(3), atol=1e-12) and np.linalg.det(dcm) == pytest.approx(1.0)
        expected = gravity_gradient_torque_nm(inertia, dcm.T @ r_eci)
        got = gravity_gradient_inertial_hold(inertia, geometry, N).torque_body_nm(t_s)
        assert np.allclose(got, expected, rtol=1e-9, atol=1e-12 * 3 * N * N * np.trace(inertia))


def test_physical_gravity_gradient_bias_matches_the_seed_table() -> None:
    """The exact gravity-gradient bias of each mode's attitude against §5's H_b: POP 0 (principal axes;
    the seed's 30 ft-lb-sec is axis misalignment), IOP ≈ 575 along x, 45° OP ≈ 19,000 along z (2 figures)."""
    inertia = workshop_inertia_kg_m2()
    per_orbit = {m: units.nms_to_ftlbs(np.array(gravity_gradient_inertial_hold(inertia, g, N).constant_nm) * T)
                 for m, g in MODE_GEOMETRY.items()}
    assert np.allclose(per_orbit['pop'], 0.0, atol=1e-9)
    assert per_orbit['iop'][0] == pytest.approx(575.0, rel=0.01) and np.allclose(per_orbit['iop'][1:], 0.0, atol=1e-9)
    assert round(per_orbit['45op'][2], -3) == 19000.0 and np.allclose(per_orbit['45op'][:2], 0.0, atol=1e-9)
    ix, iy, _ = np.diag(inertia)
    assert per_orbit['45op'][2] == pytest.approx(units.nms_to_ftlbs(1.5 * math.pi * N * (iy - ix)), rel=1e-12)


def test_iop_geometry_puts_the_aerodynamic_bias_perpendicular_to_the_orbit_plane() -> None:
    """§5: for IOP the aerodynamic bias (the seed's H_b minus its in-plane gravity-gradient part) ⟂ the plane."""
    h_b = np.array(SEED_BIAS_MOMENTUM_FTLBS['iop'])
    aero = h_b - np.array([h_b[0], 0.0, 0.0])
    normal = np.array(MODE_GEOMETRY['iop'].orbit_normal_body)
    assert abs(aero @ normal) == pytest.approx(np.linalg.norm(aero), rel=1e-12)
    assert np.linalg.norm(aero) == pytest.approx(226.3, abs=0.1)  # §5: 225 ft-lb-sec aerodynamic bias


def test_harmonics_integrate_in_closed_form() -> None:
    d = DisturbanceTorque((0.1, 0.0, -0.2), (Harmonic(1, (0.3, 0.0, 0.0), (0.0, 0.5, 0.0)),
                                             Harmonic(3, (0.0, 0.0, 0.7), (0.2, 0.0, 0.0))), N, node_time_s=100.0)
    assert np.allclose(d.momentum_nms(500.0, 2600.0), _simpson(d.torque_body_nm, 500.0, 2600.0), rtol=1e-10)
    assert np.allclose(d.momentum_nms(7.0, 7.0 + d.period_s), np.array([0.1, 0.0, -0.2]) * d.period_s, rtol=1e-12)


def test_bad_inputs_are_named() -> None:
    with pytest.raises(DynamicsError, match='mode must be one of'):
        seed_disturbance('sun_point', N, rigid_body_gravity_gradient=False)
    with pytest.raises(DynamicsError, match='orthonormal'):
        ModeGeometry((1.0, 0.0, 0.0), (1.0, 0.0, 0.0))
    with pytest.raises(DynamicsError, match='order'):
        Harmonic(0, (0.0, 0.0, 0.0), (0.0, 0.0, 0.0))
    with pytest.raises(DynamicsError, match='orbit_rate_rad_s'):
        DisturbanceTorque((0.0, 0.0, 0.0), (), -1.0)
