"""Tests of dynamics.rigid_body_model (spec §3): conservation, torques, truth conventions."""

from __future__ import annotations

import math
import struct

import numpy as np
import pytest
from acds_common import units
from acds_common.attitude import dcm, dcm_to_quat, quat_to_dcm
from acds_common.environment import (
    EarthFieldConfig,
    Orbit,
    OrbitConfig,
    Sun,
    SunConfig,
    TiltedDipoleField,
    ecliptic_normal_eci,
    rot_x,
    sun_frame_dcm,
)
from acds_common.inertia import InertiaError
from acds_common.vec3 import mat3, mtv
from dynamics.errors import DynamicsError
from dynamics.rigid_body_model import (
    DEFAULT_SUBSTEPS,
    HEAO_A_INERTIA_SLUG_FT2,
    HEAO_B_INERTIA_SLUG_FT2,
    RigidBodyModel,
    gravity_gradient_torque_nm,
    heao_inertia_kg_m2,
    inertia_tensor,
    magnetic_torque_nm,
)
from hypothesis import given, settings
from hypothesis import strategies as st

I_B = heao_inertia_kg_m2(HEAO_B_INERTIA_SLUG_FT2)
ORBIT_225 = Orbit(OrbitConfig(kind="circular", altitude_m=225.0 * units.NMI_M,
                              inclination_rad=math.radians(22.5)))
FIELD = TiltedDipoleField(EarthFieldConfig(greenwich_angle0_rad=math.radians(50.0)))
SUN = Sun(SunConfig.from_sun_angle(math.radians(-120.0)))
Q_TILTED = np.array([0.2, -0.4, 0.1, 0.885])
Q_TILTED = Q_TILTED / np.linalg.norm(Q_TILTED)


def _model(**kw: object) -> RigidBodyModel:
    args: dict[str, object] = {"gravity_gradient": False, "q0_body_to_eci": Q_TILTED}
    args.update(kw)
    return RigidBodyModel(I_B, ORBIT_225, FIELD, SUN, **args)  # type: ignore[arg-type]


def _rot_y(a: float) -> np.ndarray:
    c, s = math.cos(a), math.sin(a)
    return np.array([[c, 0.0, s], [0.0, 1.0, 0.0], [-s, 0.0, c]])


# ------------------------------------------------------------------------------------- inertia


def test_inertia_tensor_sign_convention_and_table_4_1_values() -> None:
    tensor = inertia_tensor(**HEAO_B_INERTIA_SLUG_FT2)
    assert tensor[0, 1] == tensor[1, 0] == -47.0
    assert tensor[0, 2] == -359.0 and tensor[1, 2] == -4.0
    assert np.allclose(np.diag(tensor), [1520.0, 7970.0, 7920.0])
    assert I_B[0, 0] == pytest.approx(1520.0 * 1.3558179)
    assert heao_inertia_kg_m2(HEAO_A_INERTIA_SLUG_FT2)[2, 2] == pytest.approx(4300.0 * 1.3558179)


def test_inertia_tensor_rejects_unphysical_values() -> None:
    with pytest.raises(InertiaError, match="positive definite"):
        inertia_tensor(100.0, 100.0, 100.0, 200.0, 0.0, 0.0)
    with pytest.raises(InertiaError, match="triangle"):
        inertia_tensor(100.0, 100.0, 300.0, 0.0, 0.0, 0.0)
    with pytest.raises(InertiaError, match="finite"):
        inertia_tensor(float("nan"), 100.0, 100.0, 0.0, 0.0, 0.0)


def test_model_rejects_bad_inputs() -> None:
    with pytest.raises(DynamicsError, match="substeps"):
        _model(substeps=0)
    with pytest.raises(DynamicsError):
        RigidBodyModel(np.diag([1.0, 1.0, 5.0]), ORBIT_225, FIELD, SUN)
    model = _model()
    with pytest.raises(DynamicsError, match="dt_s"):
        model.advance(0.0, np.zeros(3), np.zeros(3), np.zeros(3))
    with pytest.raises(DynamicsError, match="dipole"):
        model.advance(0.5, np.array([np.nan, 0.0, 0.0]), np.zeros(3), np.zeros(3))


# ------------------------------------------------------------------------------ torque-free body


@pytest.mark.parametrize("wheel_h_nms", [np.zeros(3), np.array([30.0, -20.0, 45.0])])
def test_torque_free_body_conserves_momentum_and_energy_over_an_orbit(wheel_h_nms: np.ndarray) -> None:
    model = _model(omega0_body_rad_s=np.radians([1.0, 1.0, 1.0]), substeps=DEFAULT_SUBSTEPS)
    first = model.truth(wheel_h_nms)
    zero = np.zeros(3)
    for _ in range(int(ORBIT_225.period_s / 0.5) + 1):
        model.advance(0.5, zero, wheel_h_nms, zero)
    last = model.truth(wheel_h_nms)
    assert last.t_s >= ORBIT_225.period_s
    h0 = np.linalg.norm(first.h_total_eci_nms)
    assert np.linalg.norm(last.h_total_eci_nms) == pytest.approx(h0, rel=1e-6)
    assert np.linalg.norm(last.h_total_eci_nms - first.h_total_eci_nms) < 1e-6 * h0
    assert last.rotational_energy_j == pytest.approx(first.rotational_energy_j, rel=1e-6)
    # The body really tumbled (the test is not trivially satisfied).
    assert np.linalg.norm(last.omega_body_rad_s - first.omega_body_rad_s) > 1e-3
    assert np.linalg.norm(model.q_body_to_eci) == pytest.approx(1.0, abs=1e-14)


def test_wheel_momentum_rate_reacts_on_body() -> None:
    model = _model()
    hdot = np.array([0.1, -0.05, 0.02])
    model.advance(2.0, np.zeros(3), np.zeros(3), hdot)
    # I ω = −∫ ḣ dt to first order: the body feels −ḣ; total momentum stays zero.
    assert np.allclose(I_B @ model.omega_body_rad_s, -hdot * 2.0, rtol=1e-6, atol=1e-12)
    truth = model.truth(hdot * 2.0)
    assert np.linalg.norm(truth.h_total_eci_nms) < 1e-9


# -------------------------------------------------------------------------------- gravity gradient


def test_gravity_gradient_matches_principal_axis_closed_form() -> None:
    principal, axes = np.linalg.eigh(I_B)
    if np.linalg.det(axes) < 0.0:
        axes[:, 2] *= -1.0
    for q in (np.array([0.0, 0.0, 0.0, 1.0]), Q_TILTED, np.array([0.5, 0.5, -0.5, 0.5])):
        model = _model(gravity_gradient=True, q0_body_to_eci=q)
        model.advance(1e-3, np.zeros(3), np.zeros(3), np.zeros(3))
        r_mid = ORBIT_225.position_velocity_eci(0.5e-3)[0]  # step average ≈ mid-step value
        r = np.linalg.norm(r_mid)
        c = axes.T @ (quat_to_dcm(q).T @ r_mid / r)  # direction cosines in principal axes
        i1, i2, i3 = principal
        t_p = 3.0 * units.EARTH_MU_M3_S2 / r ** 3 * np.array(
            [(i3 - i2) * c[1] * c[2], (i1 - i3) * c[2] * c[0], (i2 - i1) * c[0] * c[1]])
        expected = axes @ t_p
        got = model.truth(np.zeros(3)).torque_gravity_gradient_body_nm
        assert np.linalg.norm(expected) > 1e-4
        assert np.allclose(got, expected, rtol=0.0, atol=1e-8 * np.linalg.norm(expected))


@pytest.mark.parametrize("axis", [0, 1, 2])
def test_gravity_gradient_zero_with_a_principal_axis_at_nadir(axis: int) -> None:
    _, axes = np.linalg.eigh(I_B)
    if np.linalg.det(axes) < 0.0:
        axes[:, 2] *= -1.0
    r_eci = ORBIT_225.position_velocity_eci(500.0)[0]
    nadir = -r_eci / np.linalg.norm(r_eci)
    frame = np.linalg.qr(np.column_stack([nadir, [0.0, 0.0, 1.0], [1.0, 0.0, 0.0]]))[0]
    frame[:, 0] = nadir
    frame = np.roll(frame, axis, axis=1)
    if np.linalg.det(frame) < 0.0:
        frame[:, (axis + 1) % 3] *= -1.0
    rmat = frame @ axes.T  # maps principal axis `axis` to nadir
    assert np.allclose(rmat @ axes[:, axis], nadir)
    torque = gravity_gradient_torque_nm(I_B, rmat.T @ r_eci)
    tilted = gravity_gradient_torque_nm(I_B, quat_to_dcm(Q_TILTED).T @ r_eci)
    assert np.linalg.norm(torque) < 1e-12 * np.linalg.norm(tilted)


# ---------------------------------------------------------------------------------- magnetic torque


def test_magnetic_torque_equals_m_cross_b_body_for_a_still_body() -> None:
    model = _model()
    dipole = np.array([1500.0, -800.0, 2000.0])
    before = model.truth(np.zeros(3))
    model.advance(0.5, dipole, np.zeros(3), np.zeros(3))
    after = model.truth(np.zeros(3))
    expected = 0.5 * (np.cross(dipole, before.b_body_t) + np.cross(dipole, after.b_body_t))
    assert np.allclose(after.torque_magnetic_body_nm, expected, rtol=0.0, atol=1e-6 * np.linalg.norm(expected))
    assert np.allclose(magnetic_torque_nm(dipole, before.b_body_t), np.cross(dipole, before.b_body_t))
    # The only torque acting: I Δω = T Δt.
    assert np.allclose(I_B @ after.omega_body_rad_s, expected * 0.5, rtol=1e-5)
    assert np.all(after.torque_gravity_gradient_body_nm == 0.0)
    assert np.all(before.torque_magnetic_body_nm == 0.0)


# ------------------------------------------------------------------------------------------ truth


@settings(derandomize=True, max_examples=40)
@given(st.floats(-0.5, 0.5), st.floats(-0.5, 0.5))
def test_sun_direction_cosines_follow_study_definition(roll: float, pitch: float) -> None:
    sframe = sun_frame_dcm(SUN.direction_eci(0.0), ecliptic_normal_eci())
    q_roll = dcm_to_quat(sframe.T @ rot_x(roll))
    q_pitch = dcm_to_quat(sframe.T @ _rot_y(pitch))
    t_roll = _model(q0_body_to_eci=q_roll).truth(np.zeros(3))
    t_pitch = _model(q0_body_to_eci=q_pitch).truth(np.zeros(3))
    b13, b23, b33 = t_roll.sun_direction_cosines
    assert b23 == pytest.approx(math.sin(roll), abs=1e-12)  # B23 = roll error
    assert b13 == pytest.approx(0.0, abs=1e-12)
    assert b33 == pytest.approx(math.cos(roll), abs=1e-12)
    assert t_roll.attitude_to_sun_deg == pytest.approx(abs(math.degrees(roll)), abs=1e-6)
    assert t_pitch.sun_direction_cosines[0] == pytest.approx(-math.sin(pitch), abs=1e-12)  # B13 = −pitch
    assert np.allclose(t_pitch.sun_body_unit, t_pitch.sun_direction_cosines, atol=1e-12)


@pytest.mark.parametrize("sun_angle_deg", [0.0, -120.0, 30.0, 200.0])
def test_sun_cosines_and_sun_body_are_the_rotations_of_their_own_vectors(sun_angle_deg: float) -> None:
    """The model hands Truth the sun line's row as the Sun's direction when the bits agree (one rotation for both):
    each output still has the bits of its own vector rotated, whichever path it took."""
    sun = Sun(SunConfig.from_sun_angle(math.radians(sun_angle_deg)))
    model = RigidBodyModel(I_B, ORBIT_225, FIELD, sun, gravity_gradient=False, q0_body_to_eci=Q_TILTED)
    line = mat3(sun_frame_dcm(np.array(sun.direction_xyz), ecliptic_normal_eci()))[2]
    same = struct.pack("<3d", *line) == struct.pack("<3d", *sun.direction_xyz)
    assert same == (sun_angle_deg in (0.0, -120.0))  # both paths are exercised
    model.advance(0.5, (100.0, -50.0, 20.0), (0.0, 0.0, 0.0), (0.0, 0.0, 0.0))
    truth = model.truth((0.0, 0.0, 0.0))
    r = dcm(truth.q_xyzw)
    bits = struct.Struct("<3d").pack
    assert bits(*truth.sun_cosines_xyz) == bits(*mtv(r, line))
    assert bits(*truth.sun_body_xyz) == bits(*mtv(r, sun.direction_xyz))


def test_truth_is_deterministic_and_independent_of_truth_calls() -> None:
    a = _model(gravity_gradient=True, omega0_body_rad_s=np.radians([1.0, -0.5, 0.3]))
    b = _model(gravity_gradient=True, omega0_body_rad_s=np.radians([1.0, -0.5, 0.3]))
    dipole = np.array([100.0, 200.0, -300.0])
    h = np.array([1.0, 2.0, 3.0])
    for k in range(20):
        a.advance(0.5, dipole, h, 0.01 * h)
        if k % 3 == 0:
            b.truth(h)
        b.advance(0.5, dipole, h, 0.01 * h)
    ta, tb = a.truth(h), b.truth(h)
    assert np.array_equal(ta.q_body_to_eci, tb.q_body_to_eci)
    assert np.array_equal(ta.omega_body_rad_s, tb.omega_body_rad_s)
    assert np.array_equal(ta.torque_magnetic_body_nm, tb.torque_magnetic_body_nm)
    assert ta.t_s == pytest.approx(10.0)
