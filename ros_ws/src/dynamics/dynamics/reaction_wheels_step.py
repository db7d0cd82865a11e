"""reaction_wheels stepper: square-law wheels with momentum capacity (spec §4).

Stage ``drive`` of step k takes the controller's drive volts of step k (zero without a
controller) and returns the wheel momentum h(t_k) and the rate ḣ over [t_k, t_k+1] that
rigid_body applies. Non-finite volts are rejected with a WARN diagnostic (the last valid
ones are held). A consumer that needs h(t_k) before it computes step k (the controller)
reads these with lag 1 and forms h(t_k) = h(t_k−1) + ḣ·Δt exactly. Telemetry (per-wheel
momenta, drive volts) every ``TELEMETRY_EVERY`` steps.
"""

from __future__ import annotations

from typing import Any

import numpy as np
from acds_common.messages import WARN, diagnostic, vec, vector3
from acds_common.stepper import Stepper

from dynamics.configuration import build_wheels

#: Wheel telemetry on ``diagnostics`` every this many steps.
TELEMETRY_EVERY = 20


class ReactionWheelsStep(Stepper):
    """Three orthogonal wheels (or the 4-wheel 20°-cant cluster) driven by volts."""

    node = 'reaction_wheels'

    def __init__(self, params: dict[str, Any], log: Any = None) -> None:
        super().__init__(params, log)
        self.wheels = build_wheels(self.section('wheels'))
        self._last_volts = np.zeros(3)

    def drive(self, k: int, _t: float, inp: dict[str, Any]) -> dict[str, Any]:
        """Apply the step-k volts for one control period."""
        volts = vec(inp['volts'])
        warning = None
        if not np.all(np.isfinite(volts)):
            warning = f'non-finite drive volts {volts.tolist()} rejected at step {k}; holding the last valid ones'
            volts = self._last_volts
        self._last_volts = volts
        h_start, hdot = self.wheels.step(volts, self.control_period_s)
        out: dict[str, Any] = {'momentum': vector3(h_start), 'torque': vector3(hdot)}
        if warning is not None or k % TELEMETRY_EVERY == 0:
            values = {**{f'wheel_{i}_momentum_nms': f'{h:.6g}' for i, h in enumerate(self.wheels.wheel_momenta_nms())},
                      **{f'drive_{a}_volts': f'{v:.4g}' for a, v in zip('xyz', volts, strict=True)}}
            out['diagnostics'] = (diagnostic(self.node, values) if warning is None
                                  else diagnostic(self.node, values, warning, WARN))
        return out
