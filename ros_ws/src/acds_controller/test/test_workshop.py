"""Tests of the Workshop computer (seed 000 §3–§5): H_s sampling and its §5 initialisation, modes, the hold's
feedforward, the on-board field prediction, and the controller stepper's per-orbit bookkeeping."""

from __future__ import annotations

import math

import numpy as np
import pytest
from acds_common.cdr import OdometryValue
from acds_common.environment import EarthFieldConfig, Orbit, OrbitConfig, TiltedDipoleField, gravity_gradient_torque_nm
from acds_common.messages import diagnostic
from acds_common.parameters import node_parameters, normalize
from acds_common.scenario import load_scenario
from acds_common.units import ftlbs_to_nms, nms_to_ftlbs
from acds_controller.cmg_dump import DumpLawConfig, OrbitClock, k_to_si, min_energy_vector
from acds_controller.cmg_hold import HoldGains
from acds_controller.magnetic_laws import ControllerError
from acds_controller.wheel_laws import rotate_to_body
from acds_controller.workshop import FieldPrediction, WorkshopComputer, WorkshopConfig
from acds_controller.workshop_step import WorkshopComputerStep

ORBIT = Orbit(OrbitConfig(kind='circular', inclination_rad=math.radians(35.0), altitude_m=220 * 1852.0))
FIELD = TiltedDipoleField(EarthFieldConfig())
Q_POP = np.array([-0.32650558, -0.32650558, -0.62721138, 0.62721138])
INERTIA = np.diag([8.6e5, 5.58e6, 5.72e6])
H_B = ftlbs_to_nms(np.array([0.0, 0.0, -255.0]))


def computer(law: str | None = 'khb', h_s_init: str = 'measured', k: float = 4e6) -> WorkshopComputer:
    dump = None if law is None else DumpLawConfig(law, k_seed=k, h_b_nms=tuple(H_B), prediction_samples=180)
    cfg = WorkshopConfig(INERTIA, Q_POP, dump, HoldGains(0.02, 0.7), h_s_init)
    return WorkshopComputer(cfg, OrbitClock(ORBIT.period_s), FieldPrediction(ORBIT, FIELD, Q_POP))


def test_prediction_is_the_field_model_seen_from_the_held_attitude() -> None:
    pred = FieldPrediction(ORBIT, FIELD, Q_POP)
    for t in (0.0, 1234.5, 4000.0):
        r = ORBIT.position_velocity_eci(t)[0]
        assert np.allclose(pred(t), rotate_to_body(Q_POP, FIELD.b_eci(r, t)), rtol=1e-14, atol=0.0)
        assert np.allclose(pred.gravity_gradient_nm(t, INERTIA, Q_POP),
                           gravity_gradient_torque_nm(INERTIA, rotate_to_body(Q_POP, r)), rtol=1e-14, atol=0.0)


def test_min_energy_initialisation_sets_k_h_s_to_the_bracket_and_keeps_the_offset() -> None:
    """§5: k·H_s of the first orbit = eq. (3)'s bracket c₀ = W₀⁻¹ H_b; later samples are h_CMG + δ, so
    ΔH_s is the CMG momentum's change (§5's H_{n+1} = H_n + ΔH_s)."""
    wc = computer(h_s_init='min_energy')
    h0 = ftlbs_to_nms(np.array([10.0, -20.0, 5.0]))
    b = wc.prediction(0.0)
    out = wc.step(0.0, 'cmg_dump', b, np.zeros(3), Q_POP, h0)
    c0, _ = min_energy_vector(wc.law.predicted_gramian(0), H_B)
    assert np.allclose(k_to_si(4e6) * out.h_s_nms, c0, rtol=1e-12)
    assert np.allclose(wc.h_s_offset_nms, out.h_s_nms - h0, rtol=1e-12)
    assert np.allclose(out.moment_am2, np.cross(c0, b), rtol=1e-9)  # the minimum-energy moment on orbit 0
    h_later = h0 + ftlbs_to_nms(np.array([1.0, 2.0, 3.0]))
    mid = wc.step(0.5 * ORBIT.period_s, 'cmg_dump', b, np.zeros(3), Q_POP, h_later)
    assert np.array_equal(mid.h_s_nms, out.h_s_nms)  # held for the orbit
    nxt = wc.step(ORBIT.period_s + 1.0, 'cmg_dump', b, np.zeros(3), Q_POP, h_later)
    assert np.allclose(nxt.h_s_nms - out.h_s_nms, h_later - h0, rtol=1e-12)


def test_measured_initialisation_takes_the_cmg_momentum_and_modes_switch_the_dump() -> None:
    wc = computer()
    h0 = ftlbs_to_nms(np.array([0.0, 0.0, 100.0]))
    b = np.array([2.6e-5, 1e-5, -3e-5])
    dump = wc.step(0.0, 'cmg_dump', b, np.zeros(3), Q_POP, h0)
    assert np.array_equal(dump.h_s_nms, h0)
    assert np.allclose(dump.moment_am2, k_to_si(4e6) * np.cross(h0, b))
    hold = wc.step(10.0, 'cmg_hold', b, np.zeros(3), Q_POP, h0)
    assert not np.any(hold.moment_am2)
    standby = wc.step(20.0, 'standby', b, np.full(3, 1e-3), Q_POP, h0)
    assert not np.any(standby.moment_am2) and not np.any(standby.cmg_rate_nm)
    with pytest.raises(ControllerError, match='unknown Workshop mode'):
        wc.step(30.0, 'mode_1a', b, np.zeros(3), Q_POP, h0)


def test_hold_feedforward_is_the_commanded_magnetic_and_the_model_gravity_gradient_torque() -> None:
    """On the target attitude at rest with no CMG momentum, ḣ is exactly the known external torque, so the
    body feels nothing of it."""
    wc = computer()
    t = 777.0
    h = ftlbs_to_nms(np.array([0.0, 0.0, 50.0]))
    b = wc.prediction(t)
    out = wc.step(t, 'cmg_dump', b, np.zeros(3), Q_POP, h)
    expected = np.cross(out.moment_am2, b) + wc.prediction.gravity_gradient_nm(t, INERTIA, Q_POP)
    assert np.allclose(out.attitude_error_rad, 0.0, atol=1e-12)
    assert np.allclose(out.cmg_rate_nm, expected, rtol=1e-9, atol=1e-9)


def test_laws_none_and_min_energy_and_their_initialisation() -> None:
    assert computer(None).law is None
    b = np.array([2e-5, 0.0, 3e-5])
    assert not np.any(computer(None).step(0.0, 'cmg_dump', b, np.zeros(3), Q_POP, np.zeros(3)).moment_am2)
    me = computer('min_energy')
    out = me.step(0.0, 'cmg_dump', b, np.zeros(3), Q_POP, ftlbs_to_nms(np.array([0.0, 0.0, 999.0])))
    assert np.allclose(out.moment_am2, np.cross(me.law.min_energy_vector, b))  # H_s plays no part
    for law in (None, 'min_energy'):
        with pytest.raises(ControllerError, match="h_s_init 'min_energy'"):
            computer(law, 'min_energy')
    with pytest.raises(ControllerError, match='h_s_init must be one of'):
        computer('khb', 'guess')


def _step_inputs(sc, t: float, h_nms: np.ndarray, mode: str | None = 'cmg_dump') -> dict:
    """Stage inputs of the controller at ``t`` on the held attitude: magnetometer volts of the predicted field
    (Table 4-5 transfer: 2.5 V bias, 2.5 V/G)."""
    q = np.array(sc.get('controller', 'target_quaternion_xyzw'))
    pred = FieldPrediction(ORBIT, FIELD, q)
    volts, bias = 2.5 + 2.5 * pred(t) / 1e-4, np.full(3, 2.5)
    odom = OdometryValue((7e6, 0.0, 0.0), tuple(q), (0.0, 7.5e3, 0.0), (0.0, 0.0, 0.0))
    modes = None if mode is None else diagnostic('ascs_mode_manager', {'mode': mode}, mode)
    return {'mag_volts': tuple(volts), 'mag_bias': tuple(bias), 'gyro': ((0.0, 0.0, 0.0), (0.0,) * 9), 'sun': None,
            'odometry': odom, 'mode': modes, 'wheel_h': tuple(h_nms), 'wheel_hdot': (0.0, 0.0, 0.0),
            'coil_current': None}


def test_controller_stepper_publishes_h_s_that_changes_only_at_orbit_starts() -> None:
    """The stepper's per-orbit bookkeeping: ``sampled_momentum`` holds over an orbit, takes the CMG momentum
    (+ the §5 offset) at the first step of the next, and its change is the CMG momentum's change."""
    sc = load_scenario('aap_workshop_pop')
    params = normalize('acds_controller', node_parameters(sc, 10)['acds_controller'])
    step = WorkshopComputerStep(params, log=lambda _level, _text: None)
    period = step.workshop.clock.period_s
    dt = step.control_period_s
    samples, h_at = [], []
    h = np.zeros(3)
    for k in range(0, int(2.2 * period / dt)):
        t = k * dt
        out = step.control(k, t, _step_inputs(sc, t, h))
        assert set(out) >= {'moment', 'cmg_torque', 'sampled_momentum'} and 'volts' not in out
        samples.append(np.array(out['sampled_momentum']))
        h_at.append(h.copy())
        h = h + ftlbs_to_nms(np.array([0.01, -0.02, 0.03]))  # some drift of the CMG momentum
    samples = np.array(samples)
    orbit_of = np.array([step.workshop.clock.index(k * dt) for k in range(len(samples))])
    firsts = [int(np.flatnonzero(orbit_of == n)[0]) for n in range(3)]
    for n in range(3):
        assert np.all(samples[orbit_of == n] == samples[firsts[n]])
    for a, b in zip(firsts, firsts[1:], strict=False):
        assert np.allclose(samples[b] - samples[a], h_at[b] - h_at[a], rtol=1e-12)
    offset = samples[0] - h_at[0]
    assert float(np.linalg.norm(nms_to_ftlbs(offset))) > 1.0  # the §5 initialisation is on in this scenario


def test_controller_stepper_without_mode_manager_dumps_and_refuses_heao_modes() -> None:
    sc = load_scenario('aap_workshop_pop')
    params = normalize('acds_controller', node_parameters(sc, 10)['acds_controller'])
    step = WorkshopComputerStep(params, log=lambda _level, _text: None)
    out = step.control(0, 0.0, _step_inputs(sc, 0.0, np.zeros(3), mode=None))
    assert np.linalg.norm(out['moment']) > 100.0  # cmg_dump by default
    refused = step.control(1, 10.0, _step_inputs(sc, 10.0, np.zeros(3), mode='celestial_point'))
    assert refused['moment'] == (0.0, 0.0, 0.0) and refused['cmg_torque'] == (0.0, 0.0, 0.0)
    assert "'celestial_point' is not a Workshop mode" in refused['diagnostics'][0].message
