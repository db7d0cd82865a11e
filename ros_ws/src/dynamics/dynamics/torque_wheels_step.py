"""reaction_wheels stepper, formation variant: torque-commanded wheels (seed 004 slide 74; ``wheels.drive: torque``).

Stage ``drive`` of step k takes the formation controller's wanted ḣ of step k
(``controller/wheel_torque``; zero without a controller), clipped per wheel at ``wheels.max_torque``,
and returns the wheels' momentum h(t_k) and rate ḣ over [t_k, t_k+1] that the formation's time owner
applies. A non-finite command is rejected with a WARN diagnostic and zero torque. Telemetry
(per-wheel momenta and currents) every ``TELEMETRY_EVERY`` steps.
"""

from __future__ import annotations

from typing import Any

import numpy as np
from acds_common.messages import WARN, diagnostic, vec, vector3
from acds_common.stepper import Stepper

from dynamics.configuration import build_torque_wheels
from dynamics.reaction_wheels_step import TELEMETRY_EVERY


class TorqueWheelsStep(Stepper):
    """Torque-commanded wheels along ``wheels.torque_axes``."""

    node = 'reaction_wheels'

    def __init__(self, params: dict[str, Any], log: Any = None) -> None:
        super().__init__(params, log)
        self.wheels = build_torque_wheels(self.section('wheels'))

    def drive(self, k: int, _t: float, inp: dict[str, Any]) -> dict[str, Any]:
        """Torque-commanded wheels: the controller's wanted ḣ, clipped per wheel (a non-finite one: zero, WARN)."""
        command = vec(inp['torque'])
        warning = None
        if not np.all(np.isfinite(command)):
            warning = f'non-finite wheel torque command {command.tolist()} rejected at step {k}; zero torque'
            command = np.zeros(3)
        h_start, hdot = self.wheels.step(command, self.control_period_s)
        out: dict[str, Any] = {'momentum': vector3(h_start), 'torque': vector3(hdot)}
        if warning is not None or k % TELEMETRY_EVERY == 0:
            per_wheel = self.wheels.axes_body.T @ self.wheels.momentum_body_nms()
            values = {**{f'wheel_{i}_momentum_nms': f'{h:.6g}' for i, h in enumerate(per_wheel)},
                      **{f'wheel_{i}_current_a': f'{c:.4g}' for i, c in enumerate(self.wheels.current_a)}}
            out['diagnostics'] = (diagnostic(self.instance, values) if warning is None
                                  else diagnostic(self.instance, values, warning, WARN))
        return out

