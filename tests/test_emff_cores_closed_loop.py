"""EMFF closed loop on the pure cores, without ROS (spec §10; seed 004 slides 19, 31–33, 48–49, 70–74).

The formation dynamics (``dynamics.formation``), the formation controller
(``acds_controller.formation_control``) and torque wheels, composed in lockstep order per control
step: truth(t_k) → controller (measurements = truth; ideal sensors) → wheels (ḣ over the step) →
dynamics integrates t_k → t_k+1 with the commanded dipoles (ideal coil drivers: achieved = commanded).
Run with ``-s`` for the numbers.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np
from acds_common.attitude import quat_to_dcm
from acds_common.environment import EarthFieldConfig, Orbit, OrbitConfig, TiltedDipoleField
from acds_controller.formation_control import (
    AttitudeLaw,
    ControlledVehicle,
    DumpLaw,
    FormationController,
    HoldLaw,
    Measurement,
    SpinUpLaw,
    steady_spin_dipole_product_am4,
)
from dynamics.formation import (
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

YAW_WHEEL = np.array([[0.0], [0.0], [1.0]])


def _controlled(spec: VehicleSpec) -> ControlledVehicle:
    return ControlledVehicle(spec.name, spec.mass_kg, spec.inertia_kg_m2, spec.coil_axes_body,
                             np.array([c.max_dipole_am2 for c in spec.coils]))


@dataclass
class Run:
    """Per-step records (SI)."""

    t_s: list[float] = field(default_factory=list)
    rho_m: list[np.ndarray] = field(default_factory=list)
    rho_dot_m_s: list[np.ndarray] = field(default_factory=list)
    dipoles_am2: list[np.ndarray] = field(default_factory=list)
    wheel_cmd_nm: list[np.ndarray] = field(default_factory=list)
    wheel_h_nms: list[np.ndarray] = field(default_factory=list)
    dumping: list[bool] = field(default_factory=list)
    momentum: list[tuple[np.ndarray, np.ndarray]] = field(default_factory=list)


def _loop(dyn: FormationDynamics, ctl: FormationController, wheels: list[TorqueWheels], dt: float,
          steps: int) -> Run:
    run = Run()
    for _ in range(steps):
        truth = dyn.truth()
        meas = [Measurement(v.position_m, v.velocity_m_s, quat_to_dcm(v.q_body_to_inertial), v.omega_body_rad_s,
                            w.momentum_body_nms(), v.b_eci_t) for v, w in zip(truth.vehicles, wheels, strict=True)]
        cmds = ctl.step(truth.t_s, meas, truth.hill_to_eci)
        inputs = []
        for c, w in zip(cmds, wheels, strict=True):
            h0, hdot = w.step(c.wheel_torque_body_nm, dt)
            inputs.append(VehicleInput(c.dipole_body_am2, h0, hdot))
        a, b = truth.vehicles
        run.t_s.append(truth.t_s)
        run.rho_m.append(b.position_m - a.position_m)
        run.rho_dot_m_s.append(b.velocity_m_s - a.velocity_m_s)
        run.dipoles_am2.append(np.array([c.dipole_frame_am2 for c in cmds]))
        run.wheel_cmd_nm.append(np.array([c.wheel_torque_body_nm for c in cmds]))
        run.wheel_h_nms.append(np.array([w.momentum_body_nms() for w in wheels]))
        run.dumping.append(any(c.dumping for c in cmds))
        if dyn.cfg.frame != 'hill':
            run.momentum.append(dyn.momentum([w.momentum_body_nms() for w in wheels]))
        dyn.advance(dt, inputs)
    return run


def _testbed(law: HoldLaw | SpinUpLaw, initial: list[VehicleState], dt: float, em_model: str = 'far_field',
             max_force_n: float = 0.2) -> tuple[FormationDynamics, FormationController, list[TorqueWheels]]:
    specs = [emfforce_vehicle('a'), emfforce_vehicle('b')]
    dyn = FormationDynamics(FormationConfig(frame='planar', em_model=em_model, substeps=2, segments=32), specs, initial)
    ctl = FormationController([_controlled(s) for s in specs], 'planar', law, AttitudeLaw(), dt, max_force_n)
    return dyn, ctl, [TorqueWheels(YAW_WHEEL, EMFFORCE_WHEEL_MAX_TORQUE_NM) for _ in specs]


def test_testbed_hold_converges_from_an_offset() -> None:
    """EMFFORCE pair (slides 70–74) holding 2.5 m from 2.0 m with a 0.3 m lateral offset, far-field truth
    and near-field (Biot–Savart coils) truth under the same far-field controller."""
    target = np.array([2.5, 0.0, 0.0])
    law = HoldLaw(tuple(target), natural_frequency_rad_s=0.1, damping_ratio=0.9)
    dt = 0.5
    for em_model in ('far_field', 'near_field'):
        dyn, ctl, wheels = _testbed(law, [VehicleState(), VehicleState((2.0, 0.3, 0.0))], dt, em_model)
        run = _loop(dyn, ctl, wheels, dt, 300)
        err = np.linalg.norm(np.array(run.rho_m) - target, axis=1)
        settle = next(t for t, e in zip(run.t_s[::-1], err[::-1], strict=True) if e > 0.01)
        dip = np.abs(np.array(run.dipoles_am2)).max()
        print(f'\nhold ({em_model} truth): error {err[0]:.3f} m → {err[-1]:.2e} m at {run.t_s[-1] + dt:.0f} s; '
              f'within 1 cm after {settle:.1f} s; max dipole component {dip:.0f} A·m²; '
              f'max wheel torque {np.abs(np.array(run.wheel_cmd_nm)).max():.4f} N·m')
        assert err[-1] < 1e-3 and settle < 100.0
        assert np.abs(np.array(run.wheel_cmd_nm)).max() < EMFFORCE_WHEEL_MAX_TORQUE_NM
        assert dip < 3739.0  # inside the inner coil's 100 A limit


def test_two_vehicle_spin_up_reaches_the_rate_and_the_closed_form_dipoles() -> None:
    """Slides 18–19, 48–49: from a static 2.5 m baseline to 0.05 rad/s; at steady state the coaxial dipole
    product is 2π μ_red ω² d⁵/(3μ0) (within 1 %); the wheels hold the formation's angular momentum."""
    d, w = 2.5, 0.05
    law = SpinUpLaw(separation_m=d, rate_rad_s=w, ramp_rad_s2=1e-3)
    dt = 0.2
    dyn, ctl, wheels = _testbed(law, [VehicleState(), VehicleState((d, 0.0, 0.0))], dt)
    run = _loop(dyn, ctl, wheels, dt, 750)
    rho, rho_dot = run.rho_m[-1], run.rho_dot_m_s[-1]
    sep = float(np.linalg.norm(rho))
    rate = float(np.cross(rho, rho_dot)[2] / (rho @ rho))
    dip_a, dip_b = run.dipoles_am2[-1]
    product = float(np.linalg.norm(dip_a) * np.linalg.norm(dip_b))
    closed = steady_spin_dipole_product_am4(19.0, 19.0, d, w)
    (p0, l0), (p1, l1) = run.momentum[0], run.momentum[-1]
    h_wheels = run.wheel_h_nms[-1][:, 2]
    orbital = 0.5 * 19.0 * sep ** 2 * rate
    print(f'\nspin-up: rate {rate:.6f} rad/s (command {w}), separation {sep:.5f} m; dipoles '
          f'{np.linalg.norm(dip_a):.1f} and {np.linalg.norm(dip_b):.1f} A·m² ({np.linalg.norm(dip_a) / 3739.3 * 100:.1f} % '
          f'of the inner coil); μAμB = {product:.6e} vs closed form {closed:.6e} ({(product / closed - 1) * 100:+.4f} %); '
          f'wheels {h_wheels[0]:.4f} + {h_wheels[1]:.4f} N·m·s = −orbital {orbital:.4f}; '
          f'peak wheel torque {np.abs(np.array(run.wheel_cmd_nm)).max():.4f} N·m; L_z drift {abs(l1[2] - l0[2]):.1e} N·m·s')
    assert abs(rate / w - 1.0) < 1e-3 and abs(sep / d - 1.0) < 1e-3
    assert abs(product / closed - 1.0) < 0.01
    # coaxial at steady state: both dipoles along the baseline (slide 48)
    r_hat = rho / sep
    assert abs(dip_a @ r_hat) > 0.9999 * np.linalg.norm(dip_a) and abs(dip_b @ r_hat) > 0.9999 * np.linalg.norm(dip_b)
    # free-space momentum bookkeeping: the wheels store exactly what the array's rotation holds
    assert np.linalg.norm(p1 - p0) < 1e-12 and abs(l1[2] - l0[2]) < 1e-9 * orbital
    assert np.abs(np.array(run.wheel_cmd_nm)).max() < EMFFORCE_WHEEL_MAX_TORQUE_NM


def test_leo_pair_dumps_momentum_into_the_earth_field() -> None:
    """Slides 31–33, 63: a pair 3 m apart radially in a 500 km orbit (Hill frame; the CW force −3 m n² x fed
    forward); vehicle a starts with 0.59 N·m·s in its wheels, goes to full dipole along −(B × h), and the
    Earth's field torque dumps it while b's solved dipole keeps the formation force; then the vehicle
    with the most momentum is picked again (slide 32). A notional pair: 50 kg, three 0.3 m coils of
    100 turns at up to 30 A (848 A·m² each), wheels of 0.05 N·m."""
    orbit = Orbit(OrbitConfig(kind='circular', altitude_m=500e3, inclination_rad=math.radians(51.6)))
    earth = TiltedDipoleField(EarthFieldConfig())

    def spec(name: str) -> VehicleSpec:
        return VehicleSpec(name, 50.0, np.diag([4.0, 5.0, 6.0]), tuple(Coil(a, 0.3, 100, 30.0) for a in np.eye(3)))

    specs = [spec('a'), spec('b')]
    cfg = FormationConfig(frame='hill', orbit=orbit, earth_field=earth.b_eci, gravity_gradient=True, substeps=2)
    dyn = FormationDynamics(cfg, specs, [VehicleState((-1.5, 0.0, 0.0)), VehicleState((1.5, 0.0, 0.0))])
    dt = 1.0
    ctl = FormationController([_controlled(s) for s in specs], 'hill', HoldLaw((3.0, 0.0, 0.0), 0.05, 0.9),
                              AttitudeLaw(0.2, 0.8), dt, 0.01, mean_motion_rad_s=dyn.n_rad_s,
                              dump=DumpLaw(start_nms=0.1, done_nms=0.02))
    wheels = [TorqueWheels(np.eye(3), 0.05, h0_nms=(0.5, -0.3, 0.2)), TorqueWheels(np.eye(3), 0.05, h0_nms=(0.05, 0.0, 0.0))]
    run = _loop(dyn, ctl, wheels, dt, 90)
    h = np.linalg.norm(np.array(run.wheel_h_nms), axis=2)  # (steps, vehicle)
    err = np.linalg.norm(np.array(run.rho_m) - [3.0, 0.0, 0.0], axis=1).max()
    done_at = run.t_s[int(np.argmax(h[:, 0] < 0.02))]
    print(f'\nLEO dump: |h_a| {h[0, 0]:.3f} → {h[:, 0].min():.4f} N·m·s (below 0.02 at {done_at:.0f} s), then b '
          f'(pushed over 0.1 by the pair\'s torques) dumps; stored |h_a| + |h_b| {h[0].sum():.3f} → {h[-1].sum():.3f} '
          f'N·m·s; separation error ≤ {err:.1e} m; dumping on {sum(run.dumping)} of {len(run.dumping)} steps')
    assert run.dumping[0] and h[:, 0].min() < 0.02 and done_at < 40.0
    assert h[-1].sum() < 0.15 * h[0].sum()
    assert err < 1e-3
