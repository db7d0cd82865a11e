"""Formation dynamics of EMFF vehicles (spec §10; seed 004 slides 3, 18, 30, 63, 70–74)."""

from __future__ import annotations

import math

import numpy as np
import pytest
from acds_common.attitude import quat_to_dcm
from acds_common.dipole_field import dipole_force_n
from acds_common.environment import EarthFieldConfig, Orbit, OrbitConfig, TiltedDipoleField
from acds_common.units import NMI_M
from dynamics.errors import DynamicsError
from dynamics.formation import (
    EMFFORCE_COIL_RADII_M,
    EMFFORCE_MASS_KG,
    EMFFORCE_WHEEL_MAX_TORQUE_NM,
    Coil,
    FormationConfig,
    FormationDynamics,
    TorqueWheels,
    VehicleInput,
    VehicleSpec,
    VehicleState,
    emfforce_vehicle,
)
from dynamics.rigid_body_model import gravity_gradient_torque_nm


def _quat(axis: np.ndarray, angle: float) -> np.ndarray:
    axis = np.asarray(axis, dtype=float) / np.linalg.norm(axis)
    return np.concatenate([math.sin(angle / 2) * axis, [math.cos(angle / 2)]])


def _three_axis_vehicle(name: str, mass: float) -> VehicleSpec:
    inertia = np.array([[2.0, 0.1, 0.05], [0.1, 2.5, 0.02], [0.05, 0.02, 3.0]])
    return VehicleSpec(name, mass, inertia, tuple(Coil(a, 0.5, 100, 100.0) for a in np.eye(3)))


def test_emfforce_testbed_data() -> None:
    """Slides 70–74: 19 kg, 2 coils of 100 wraps (0.375 m / 0.345 m) at up to 100 A, in the plane."""
    v = emfforce_vehicle('a')
    assert v.mass_kg == EMFFORCE_MASS_KG == 19.0
    assert [c.radius_m for c in v.coils] == list(EMFFORCE_COIL_RADII_M) == [0.375, 0.345]
    assert [round(c.max_dipole_am2, 1) for c in v.coils] == [4417.9, 3739.3]
    assert np.array_equal(v.coil_axes_body, np.eye(3)[:, :2])
    with pytest.raises(DynamicsError, match='outside the span'):
        v.coil_moments_am2([0.0, 0.0, 10.0])  # the testbed coils cannot make a vertical dipole


def _run(dyn: FormationDynamics, steps: int, dt: float, dipoles: list[np.ndarray],
         wheels: list[TorqueWheels], wheel_cmds: list[np.ndarray]) -> list[np.ndarray]:
    """Constant body dipoles and wheel torque commands; returns the wheel momenta at the end."""
    for _ in range(steps):
        inputs = []
        for d, w, c in zip(dipoles, wheels, wheel_cmds, strict=True):
            h0, hdot = w.step(c, dt)
            inputs.append(VehicleInput(d, h0, hdot))
        dyn.advance(dt, inputs)
    return [w.momentum_body_nms() for w in wheels]


def test_free_space_long_run_conserves_total_momentum() -> None:
    """Three tumbling vehicles with body-fixed dipoles and running wheels for 1000 s: total linear and
    angular momentum (orbital r × p + spin + wheels) conserved to 1e-9 relative (slides 3, 18).
    (What remains is RK4's truncation of the spin, ∝ substep⁴: ~1e-11 here.)"""
    specs = [_three_axis_vehicle(n, m) for n, m in (('a', 19.0), ('b', 25.0), ('c', 31.0))]
    init = [VehicleState((0.0, 0.0, 0.0), (0.002, -0.001, 0.0), _quat([1, 2, 3], 0.4), (0.01, -0.02, 0.015)),
            VehicleState((8.0, 1.0, -0.5), (-0.001, 0.003, 0.001), _quat([0, 1, 1], 1.1), (0.0, 0.01, -0.01)),
            VehicleState((2.0, 7.5, 1.0), (0.0, -0.002, 0.002), _quat([1, 0, 0], 2.0), (-0.015, 0.0, 0.02))]
    dyn = FormationDynamics(FormationConfig(frame='free_space', substeps=2), specs, init)
    wheels = [TorqueWheels(np.eye(3), 0.01) for _ in specs]
    dipoles = [np.array([600.0, -400.0, 300.0]), np.array([-200.0, 500.0, 600.0]), np.array([400.0, 400.0, -500.0])]
    cmds = [np.array([1e-5, -2e-5, 5e-6]), np.array([0.0, 1e-5, 1e-5]), np.array([-1e-5, 0.0, 2e-5])]
    p0, l0 = dyn.momentum([w.momentum_body_nms() for w in wheels])
    h_end = _run(dyn, 1000, 1.0, dipoles, wheels, cmds)
    p1, l1 = dyn.momentum(h_end)
    # the internal wrenches did work: vehicle a's own momentum changed by far more than the bound
    assert np.linalg.norm(dyn.truth().vehicles[0].velocity_m_s - init[0].velocity_m_s) * 19.0 > 1e-2 * np.linalg.norm(p0)
    assert np.linalg.norm(p1 - p0) <= 1e-9 * np.linalg.norm(p0)
    assert np.linalg.norm(l1 - l0) <= 1e-9 * np.linalg.norm(l0)


@pytest.mark.parametrize('em_model', ['far_field', 'near_field'])
def test_planar_testbed_conserves_in_plane_momentum(em_model: str) -> None:
    """Two EMFFORCE vehicles 2.5 m apart, dipoles steered in the plane, yaw wheels running: p_x, p_y and
    L_z are conserved; the table keeps the motion planar. (The EM torques spin the bodies up to
    ~0.4 rad/s here; RK4's truncation of L_z, ∝ substep⁴, is ~1e-10 at 8 substeps of 0.0625 s.)"""
    specs = [emfforce_vehicle('a'), emfforce_vehicle('b')]
    init = [VehicleState((0.0, 0.0, 0.0), (0.0, 0.01, 0.0), _quat([0, 0, 1], 0.3), (0.0, 0.0, 0.02)),
            VehicleState((2.5, 0.3, 0.0), (0.0, -0.01, 0.0), _quat([0, 0, 1], -0.5), (0.0, 0.0, -0.01))]
    dyn = FormationDynamics(FormationConfig(frame='planar', em_model=em_model, substeps=8, segments=32), specs, init)
    wheels = [TorqueWheels(np.array([[0.0], [0.0], [1.0]]), EMFFORCE_WHEEL_MAX_TORQUE_NM) for _ in specs]
    dipoles = [np.array([2000.0, 1000.0, 0.0]), np.array([-500.0, 1500.0, 0.0])]
    cmds = [np.array([0.0, 0.0, 0.02]), np.array([0.0, 0.0, -0.03])]
    p0, l0 = dyn.momentum([w.momentum_body_nms() for w in wheels])
    h_end = _run(dyn, 40 if em_model == 'far_field' else 10, 0.5, dipoles, wheels, cmds)
    p1, l1 = dyn.momentum(h_end)
    scale_p = 19.0 * 0.01
    assert np.linalg.norm(p1 - p0) <= 1e-12 * scale_p
    assert abs(l1[2] - l0[2]) <= 1e-9 * abs(l0[2])
    for v in dyn.truth().vehicles:
        assert v.position_m[2] == 0.0 and v.velocity_m_s[2] == 0.0
        assert np.allclose(v.omega_body_rad_s[:2], 0.0, atol=0) and np.allclose(v.q_body_to_inertial[:2], 0.0)
        assert np.linalg.norm(v.em_force_avg_n[:2]) > 1e-3  # the coils really pushed


def test_near_and_far_field_agree_far_apart_and_differ_close() -> None:
    specs = [emfforce_vehicle('a'), emfforce_vehicle('b')]
    dips = [np.array([3000.0, 1000.0, 0.0]), np.array([2000.0, -2500.0, 0.0])]
    for sep, lo, hi in ((30.0, 0.0, 1e-3), (2.0, 0.03, 0.5)):
        init = [VehicleState(), VehicleState((sep, 0.0, 0.0), q_body_to_inertial=_quat([0, 0, 1], 0.4))]
        far = FormationDynamics(FormationConfig(), specs, init).wrenches_now(dips)
        near = FormationDynamics(FormationConfig(em_model='near_field', segments=128), specs, init).wrenches_now(dips)
        err = np.linalg.norm(far.em_force_n[1] - near.em_force_n[1]) / np.linalg.norm(near.em_force_n[1])
        assert lo <= err < hi, (sep, err)


def test_hill_free_motion_is_the_clohessy_wiltshire_solution() -> None:
    """Slide 63: ẍ = 3n²x + 2nẏ, ÿ = −2nẋ, z̈ = −n²z without forcing; compare the closed-form solution."""
    orbit = Orbit(OrbitConfig(kind='circular', altitude_m=500e3, inclination_rad=math.radians(51.6)))
    n = orbit.mean_motion_rad_s
    x0, y0, z0, vx0, vy0, vz0 = 10.0, -5.0, 3.0, 0.01, -0.02, 0.005
    dyn = FormationDynamics(FormationConfig(frame='hill', orbit=orbit, substeps=5),
                            [_three_axis_vehicle('a', 50.0)], [VehicleState((x0, y0, z0), (vx0, vy0, vz0))])
    for _ in range(300):
        dyn.advance(10.0, [VehicleInput()])
    t = dyn.t_s
    s, c = math.sin(n * t), math.cos(n * t)
    x = 4 * x0 - 3 * x0 * c + vx0 / n * s + 2 * vy0 / n * (1 - c)
    y = 6 * x0 * (s - n * t) + y0 - 2 * vx0 / n * (1 - c) + (4 * s - 3 * n * t) * vy0 / n
    z = z0 * c + vz0 / n * s
    assert np.allclose(dyn.truth().vehicles[0].position_m, [x, y, z], rtol=0, atol=1e-6)
    truth = dyn.truth().vehicles[0]
    r_ref, _ = orbit.position_velocity_eci(t)
    assert np.linalg.norm(truth.r_eci_m - r_ref) == pytest.approx(math.sqrt(x * x + y * y + z * z), rel=1e-6)


def test_earth_field_force_and_torque_on_a_dipole_in_orbit() -> None:
    """The Earth field's force ∇(μ·B) by central differences equals the exact dipole–dipole force with
    the Earth's dipole; the torque is μ × B; the gravity gradient is rigid_body_model's (slide 30)."""
    orbit = Orbit(OrbitConfig(kind='circular', altitude_m=225 * NMI_M, inclination_rad=math.radians(28.5)))
    earth = TiltedDipoleField(EarthFieldConfig(greenwich_angle0_rad=0.7))
    spec = _three_axis_vehicle('a', 600.0)
    q = _quat([1, -1, 2], 0.9)
    dyn = FormationDynamics(FormationConfig(frame='hill', orbit=orbit, earth_field=earth.b_eci, gravity_gradient=True),
                            [spec], [VehicleState((5.0, -20.0, 3.0), q_body_to_inertial=q)], t0_s=1234.0)
    mu_body = np.array([4e4, -2e4, 3e4])
    w = dyn.wrenches_now([mu_body])
    truth = dyn.truth()
    r_eci = truth.vehicles[0].r_eci_m
    rot = quat_to_dcm(q)
    m_earth = -earth.cfg.dipole_moment_am2 * earth.dipole_axis_eci(1234.0)
    f_exact_eci = dipole_force_n(m_earth, rot @ mu_body, r_eci)
    assert np.allclose(truth.hill_to_eci @ w.earth_force_n[0], f_exact_eci, rtol=0, atol=1e-7 * np.linalg.norm(f_exact_eci))
    b_eci = earth.b_eci(r_eci, 1234.0)
    assert np.allclose(w.earth_torque_body_nm[0], np.cross(mu_body, rot.T @ b_eci), rtol=1e-12)
    assert np.allclose(w.gg_torque_body_nm[0], gravity_gradient_torque_nm(spec.inertia_kg_m2, rot.T @ r_eci))
    # slide 30: insignificant force, significant torque
    assert np.linalg.norm(w.earth_force_n[0]) < 1e-5 * np.linalg.norm(w.earth_torque_body_nm[0])


def test_runs_are_deterministic() -> None:
    def run() -> np.ndarray:
        specs = [emfforce_vehicle('a'), emfforce_vehicle('b')]
        init = [VehicleState(), VehicleState((2.5, 0.0, 0.0), omega_body_rad_s=(0.0, 0.0, 0.01))]
        dyn = FormationDynamics(FormationConfig(substeps=3), specs, init)
        wheels = [TorqueWheels(np.array([[0.0], [0.0], [1.0]]), 0.1) for _ in specs]
        _run(dyn, 50, 0.2, [np.array([1000.0, 200.0, 0]), np.array([900.0, -300.0, 0])], wheels,
             [np.array([0, 0, 0.01]), np.array([0, 0, -0.02])])
        tr = dyn.truth()
        return np.concatenate([np.concatenate([v.position_m, v.velocity_m_s, v.q_body_to_inertial]) for v in tr.vehicles])
    assert np.array_equal(run(), run())


def test_torque_wheels_limit_torque_and_capacity() -> None:
    w = TorqueWheels(np.array([[0.0], [0.0], [1.0]]), 0.1, capacity_nms=0.25)
    h0, hdot = w.step(np.array([0.0, 0.0, 0.5]), 1.0)
    assert np.allclose(h0, 0.0) and np.allclose(hdot, [0, 0, 0.1])
    assert w.current_a[0] == pytest.approx(10.0)  # slide 74: 0.1 N·m at 10 A
    h0, hdot = w.step(np.array([0.0, 0.0, 0.5]), 2.0)
    assert np.allclose(h0, [0, 0, 0.1]) and np.allclose(hdot, [0, 0, 0.075])  # stops at capacity
    assert np.allclose(w.momentum_body_nms(), [0, 0, 0.25])


def test_inputs_are_checked() -> None:
    a, b = emfforce_vehicle('a'), emfforce_vehicle('b')
    with pytest.raises(DynamicsError, match="planar"):
        FormationDynamics(FormationConfig(), [a], [VehicleState(omega_body_rad_s=(0.1, 0, 0))])
    with pytest.raises(DynamicsError, match="unique"):
        FormationDynamics(FormationConfig(), [a, a], [VehicleState(), VehicleState((3, 0, 0))])
    with pytest.raises(DynamicsError, match="circular reference orbit"):
        FormationConfig(frame='hill')
    with pytest.raises(DynamicsError, match="frame 'hill' only"):
        FormationConfig(frame='free_space', gravity_gradient=True)
    dyn = FormationDynamics(FormationConfig(), [a, b], [VehicleState(), VehicleState((3, 0, 0))])
    with pytest.raises(DynamicsError, match="collided"):
        FormationDynamics(FormationConfig(), [a, b], [VehicleState(), VehicleState((0.7, 0, 0))])
    with pytest.raises(DynamicsError, match="outside the span"):
        dyn.advance(0.1, [VehicleInput((0, 0, 5.0)), VehicleInput()])
    with pytest.raises(DynamicsError, match="one VehicleInput per vehicle"):
        dyn.advance(0.1, [VehicleInput()])
    with pytest.raises(DynamicsError, match="b wheel_hdot_body_nm must be finite"):
        dyn.advance(0.1, [VehicleInput(), VehicleInput(wheel_hdot_body_nm=(0, 0, math.nan))])
