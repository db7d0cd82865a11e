"""The AAP Workshop's dynamics pieces from the scenario (seed 000): the body-fixed disturbance of rigid_body, the
CMG kind of the reaction_wheels stepper, and the actuator bounds for CMGs."""

from __future__ import annotations

import math

import numpy as np
import pytest
from acds_common.environment import EarthFieldConfig, Orbit, OrbitConfig, Sun, SunConfig, TiltedDipoleField
from acds_common.parameters import node_parameters, normalize
from acds_common.scenario import load_scenario
from acds_common.units import ftlbs_to_nms, nms_to_ftlbs
from dynamics.cmg_model import ControlMomentGyros
from dynamics.cmg_step import CmgStep
from dynamics.configuration import actuator_limits, build_disturbance, build_momentum_store
from dynamics.rigid_body_model import RigidBodyModel

ORBIT = Orbit(OrbitConfig(kind='circular', inclination_rad=math.radians(35.0), altitude_m=220 * 1852.0,
                          arg_latitude0_rad=math.radians(30.0)))
ZERO3 = [0.0, 0.0, 0.0]


def section(**given: list[float]) -> dict[str, list[float]]:
    keys = ('bias_momentum_per_orbit', 'once_per_orbit_cos', 'once_per_orbit_sin', 'twice_per_orbit_cos',
            'twice_per_orbit_sin')
    return {k: list(given.get(k, ZERO3)) for k in keys}


def test_disturbance_constant_is_the_bias_per_orbit_and_the_cycles_are_phased_at_the_node() -> None:
    assert build_disturbance(section(), ORBIT) is None
    bias = ftlbs_to_nms(np.array([1.75, 160.0, -160.0]))
    d = build_disturbance(section(bias_momentum_per_orbit=list(bias), twice_per_orbit_sin=[0.0, 2.0, 0.0]), ORBIT)
    assert np.allclose(d.momentum_nms(123.0, 123.0 + ORBIT.period_s), bias, rtol=1e-12)
    # 30° past the node at t = 0: u = 2·(30° + n t) for the second harmonic
    t = 500.0
    u = math.radians(30.0) + ORBIT.mean_motion_rad_s * t
    assert np.allclose(d.torque_body_nm(t), bias / ORBIT.period_s + np.array([0.0, 2.0 * math.sin(2 * u), 0.0]))
    assert ORBIT.node_time_s() == pytest.approx(-math.radians(30.0) / ORBIT.mean_motion_rad_s)


def test_rigid_body_takes_the_disturbance_momentum_over_an_orbit() -> None:
    """No other torque (gravity gradient off, no dipole, no wheels): the body's momentum after one orbit is the
    disturbance's bias per orbit, the cyclic parts integrating to zero. A body 10⁴ times the Workshop's
    inertia, so that it turns by under 0.002° and the body-fixed torque stays put in inertial space."""
    bias = ftlbs_to_nms(np.array([0.0, 0.0, -255.0]))
    d = build_disturbance(section(bias_momentum_per_orbit=list(bias), once_per_orbit_cos=[0.05, 0.0, 0.0]), ORBIT)
    inertia = np.diag([8.6e9, 5.58e10, 5.72e10])
    body = RigidBodyModel(inertia, ORBIT, TiltedDipoleField(EarthFieldConfig()), Sun(SunConfig()),
                          gravity_gradient=False, substeps=2, disturbance=d)
    steps = 300
    for _ in range(steps):
        body.advance(ORBIT.period_s / steps, np.zeros(3), np.zeros(3), np.zeros(3))
    h_eci = body.truth(np.zeros(3)).h_total_eci_nms
    assert np.allclose(nms_to_ftlbs(h_eci), nms_to_ftlbs(bias), rtol=0.0, atol=0.01)


def _cmg_step(sc_name: str = 'aap_workshop_pop') -> CmgStep:
    params = node_parameters(load_scenario(sc_name), 10)['reaction_wheels']
    return CmgStep(normalize('reaction_wheels', params), log=lambda _level, _text: None)


def test_cmg_kind_applies_the_commanded_rate_and_stops_at_its_capacity() -> None:
    step = _cmg_step()
    assert isinstance(step.cmgs, ControlMomentGyros) and not hasattr(step, 'wheels')
    dt = step.control_period_s
    out = step.gimbal(1, dt, {'torque': (0.0, 0.0, 2.0)})
    assert out['momentum'] == (0.0, 0.0, 0.0) and out['torque'] == pytest.approx((0.0, 0.0, 2.0))
    cap = step.cmgs.cfg.capacity_nms
    assert nms_to_ftlbs(cap) == pytest.approx(12000.0)
    k, warned = 2, None
    while warned is None and k < 10000:
        out = step.gimbal(k, k * dt, {'torque': (0.0, 0.0, 500.0)})
        warned = next((s for s in out.get('diagnostics', ()) if s.level == 1), None)
        k += 1
    assert warned is not None and 'reached its capacity' in warned.message
    assert np.linalg.norm(step.cmgs.momentum_body_nms()) == pytest.approx(cap)
    out = step.gimbal(k, k * dt, {'torque': (0.0, 0.0, 500.0)})
    assert out['torque'] == pytest.approx((0.0, 0.0, 0.0))  # nothing beyond the envelope
    out = step.gimbal(k + 1, (k + 1) * dt, {'torque': (float('nan'), 0.0, 0.0)})
    assert 'non-finite CMG torque' in out['diagnostics'][0].message


def test_momentum_store_and_actuator_bounds_follow_the_kind() -> None:
    sc = load_scenario('aap_workshop_pop').values
    store = build_momentum_store(sc['wheels'])
    assert isinstance(store, ControlMomentGyros)
    limits = actuator_limits(sc['em_driver'], sc['wheels'])
    assert np.allclose(limits.wheel_momentum_nms, store.cfg.capacity_nms)
    heao = load_scenario('heao_b_acquisition').values
    assert not isinstance(build_momentum_store(heao['wheels']), ControlMomentGyros)
    beyond = dict(sc['wheels'], initial_momentum=[0.0, 0.0, 2.0 * store.cfg.capacity_nms])
    with pytest.raises(ValueError, match='wheels: .*beyond the CMG capacity'):
        build_momentum_store(beyond)
