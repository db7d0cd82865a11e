"""Tests of the rigid_body stepper's actuator-input check (spec §2, §3): what it refuses and how it names it."""

from __future__ import annotations

import math

import pytest
from acds_common import topics
from acds_common.parameters import node_parameters, normalize
from acds_common.scenario import load_scenario
from acds_common.stepper import StepError
from dynamics.rigid_body_step import RigidBodyStep

NAN, INF = math.nan, math.inf


def _body() -> RigidBodyStep:
    params = normalize('rigid_body', node_parameters(load_scenario('free_tumble_heao_b'), 10)['rigid_body'])
    body = RigidBodyStep(params, log=lambda *_: None)
    body.start()
    return body


def _inputs(**given: tuple[float, float, float]) -> dict[str, object]:
    return {'dipole': None, 'wheel_h': None, 'wheel_hdot': None, 'gas_wrench': None, 'mode': None, **given}


@pytest.mark.parametrize(('given', 'message'), [
    ({'dipole': (NAN, 0.0, 0.0)}, f'non-finite {topics.resolve(topics.DIPOLE_AVG)} at step 0'),
    ({'dipole': (0.0, INF, 0.0)}, f'non-finite {topics.resolve(topics.DIPOLE_AVG)} at step 0'),
    ({'dipole': (0.0, 0.0, -INF)}, f'non-finite {topics.resolve(topics.DIPOLE_AVG)} at step 0'),
    ({'wheel_h': (0.0, 0.0, -INF)}, f'non-finite {topics.resolve(topics.WHEEL_MOMENTUM)} at step 0'),
    ({'wheel_h': (NAN, 0.0, 0.0)}, f'non-finite {topics.resolve(topics.WHEEL_MOMENTUM)} at step 0'),
    ({'wheel_hdot': (0.0, NAN, 0.0)}, f'non-finite {topics.resolve(topics.WHEEL_TORQUE)} at step 0'),
    ({'wheel_hdot': (INF, 0.0, 0.0)}, f'non-finite {topics.resolve(topics.WHEEL_TORQUE)} at step 0'),
    ({'wheel_hdot': (0.0, 0.0, -INF)}, f'non-finite {topics.resolve(topics.WHEEL_TORQUE)} at step 0'),
    ({'dipole': (0.0, -1e5, 0.0)}, f'{topics.resolve(topics.DIPOLE_AVG)} at step 0 gives'),
    ({'wheel_h': (0.0, 0.0, 500.0)}, f'{topics.resolve(topics.WHEEL_MOMENTUM)} at step 0 gives'),
    ({'wheel_hdot': (-1e4, 0.0, 0.0)}, 'N·m·s at the step end'),
])
def test_a_non_finite_or_out_of_bound_actuator_input_stops_the_physics(given, message) -> None:
    with pytest.raises(StepError, match=message):
        _body().integrate(0, 0.0, _inputs(**given))


def test_inputs_at_the_hardware_bounds_are_integrated() -> None:
    body = _body()
    (m0, m1, m2), (w0, w1, w2) = body._bounds  # noqa: SLF001 - the stepper's own bounds, the inclusive limits
    out = body.integrate(0, 0.0, _inputs(dipole=(-m0, m1, -m2), wheel_h=(w0, -w1, w2), wheel_hdot=(0.0, 0.0, 0.0)))
    assert 'odometry' in out and not body.finished
