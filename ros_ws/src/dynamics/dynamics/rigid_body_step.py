"""rigid_body stepper: the time owner's logic; integrates the spacecraft and gives the truth (spec §2, §3).

Step 0's truth is published at start. Stage ``integrate`` of step k takes the actuator
outputs of step k (the em_driver's step-average achieved dipole, the wheels' momentum
h(t_k) and rate ḣ over [t_k, t_k+1]; absent nodes mean zero) and the step's ``mode``,
integrates t_k → t_k+1 and returns the truth of step k + 1. The run ends after step k
when the total step count is reached or when the ``mode`` of step k carries
``run_complete: true`` (stop at acquisition capture). A non-finite actuator input, or one
beyond what the hardware can produce (:func:`~dynamics.configuration.actuator_limits`),
fails the run naming the topic and the step.
"""

from __future__ import annotations

from typing import Any

import numpy as np
from acds_common import topics
from acds_common.cdr import OdometryValue
from acds_common.messages import MODE_STATUS, magnetic_field, status_value, vec, vector3
from acds_common.stepper import StepError, Stepper

from dynamics.configuration import actuator_limits, build_rigid_body
from dynamics.rigid_body_model import Truth

_ZERO_COV = (0.0,) * 9


def run_complete(mode: Any) -> bool:
    """Whether the step's ``mode`` value asks to end the run (key ``run_complete`` = 'true')."""
    return status_value(mode, MODE_STATUS, 'run_complete') == 'true'


def truth_outputs(truth: Truth) -> dict[str, Any]:
    """Truth and ideal sensors of one step (spec §3 "Sensors in the study are ideal")."""
    omega = vector3(truth.omega_body_rad_s)
    return {
        'odometry': OdometryValue(vector3(truth.r_eci_m), tuple(float(c) for c in truth.q_body_to_eci),
                                  vector3(truth.v_eci_m_s), omega),
        'b_body': magnetic_field(truth.b_body_t),
        'sun_cosines': vector3(truth.sun_direction_cosines),
        'torque_mag': vector3(truth.torque_magnetic_body_nm),
        'torque_gg': vector3(truth.torque_gravity_gradient_body_nm),
        'gyro': (omega, _ZERO_COV),
        'sun_sensor': vector3(truth.sun_body_unit if truth.sun_present else (0.0, 0.0, 0.0)),
    }


class RigidBodyStep(Stepper):
    """Spacecraft rigid body in its orbit and environment; owner of sim time."""

    node = 'rigid_body'

    def __init__(self, params: dict[str, Any], log: Any = None) -> None:
        super().__init__(params, log)
        self.total_steps: int = params['total_steps']
        self.model = build_rigid_body(*(self.section(s) for s in ('spacecraft', 'orbit', 'earth', 'sun', 'dynamics',
                                                                   'disturbance')))
        self.limits = actuator_limits(self.section('em_driver'), self.section('wheels'))
        self._wheel_h = np.zeros(3)

    def start(self) -> dict[str, Any]:
        """The truth of step 0."""
        return truth_outputs(self.model.truth(self._wheel_h))

    def integrate(self, k: int, _t: float, inp: dict[str, Any]) -> dict[str, Any]:
        """All actuator outputs of step k are in: integrate to t_k+1 and return its truth."""
        if k >= self.total_steps or run_complete(inp['mode']):
            self.finished = True
            return {}
        h, hdot, dipole = vec(inp['wheel_h']), vec(inp['wheel_hdot']), vec(inp['dipole'])
        for topic, value in ((topics.WHEEL_MOMENTUM, h), (topics.WHEEL_TORQUE, hdot), (topics.DIPOLE_AVG, dipole)):
            if not np.all(np.isfinite(value)):
                raise StepError(f'non-finite {topics.resolve(topic)} at step {k}: {value.tolist()}; '
                                'the physics cannot go on')
        dt = self.control_period_s
        for topic, value, limit, unit in (
                (topics.DIPOLE_AVG, dipole, self.limits.dipole_am2, 'A·m²'),
                (topics.WHEEL_MOMENTUM, h, self.limits.wheel_momentum_nms, 'N·m·s'),
                (topics.WHEEL_TORQUE, h + hdot * dt, self.limits.wheel_momentum_nms, 'N·m·s at the step end')):
            if np.any(np.abs(value) > limit * (1.0 + 1e-9)):
                raise StepError(f'{topics.resolve(topic)} at step {k} gives {value.tolist()} {unit}, beyond what '
                                f'the hardware can produce (±{limit.tolist()} per axis): not from this graph\'s '
                                'actuators; the run stops')
        self.model.advance(self.control_period_s, dipole, h, hdot)
        self._wheel_h = h + hdot * self.control_period_s
        return truth_outputs(self.model.truth(self._wheel_h))
