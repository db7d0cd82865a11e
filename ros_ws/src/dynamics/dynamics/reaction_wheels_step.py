"""reaction_wheels stepper: square-law wheels with momentum capacity, driven by volts (spec §4).

Stage ``drive`` of step k takes the controller's drive volts of step k (zero without a controller)
and returns the wheels' momentum h(t_k) and the rate ḣ over [t_k, t_k+1] that rigid_body applies.
Non-finite volts are rejected with a WARN diagnostic (the last valid ones are held). A consumer that
needs h(t_k) before it computes step k (the controller) reads these with lag 1 and forms
h(t_k) = h(t_k−1) + ḣ·Δt exactly. Telemetry (per-wheel momenta and drive volts) every
``TELEMETRY_EVERY`` steps. The node's other variants, chosen by the scenario (``dynamics.nodes``):
torque-commanded wheels (:mod:`dynamics.torque_wheels_step`) and the Workshop's CMGs
(:mod:`dynamics.cmg_step`).
"""

from __future__ import annotations

import math
from typing import Any

from acds_common import kernels
from acds_common.fused import FusedStage, Output
from acds_common.messages import WARN, diagnostic, xyz
from acds_common.stepper import Stepper
from acds_common.validation import all_finite

from dynamics.configuration import build_wheels
from dynamics.errors import positive_dt
from dynamics.wheels_model import wheels_step

#: Wheel telemetry on ``diagnostics`` every this many steps.
TELEMETRY_EVERY = 20


@kernels.helper
def drive_fused(p: tuple, s: tuple, _k: int, _t: float, volts: Any) -> tuple:
    """Stage ``drive`` as a kernel (:mod:`acds_common.fused`): quiet unless the volts are non-finite (the Python
    stage then warns). ``p``: (wheel parameters, Δt); ``s``: (momenta, torques, last valid volts)."""
    params, dt = p
    h, torque, _last = s
    quiet = math.isfinite(volts[0] + volts[1] + volts[2])
    h1, torque1, start, hdot = wheels_step(params, h, volts, dt)
    return quiet, ((h1, torque1, volts) if quiet else s), start, hdot


class ReactionWheelsStep(Stepper):
    """Three orthogonal wheels (or the 4-wheel 20°-cant cluster) driven by volts."""

    node = 'reaction_wheels'

    def __init__(self, params: dict[str, Any], log: Any = None) -> None:
        super().__init__(params, log)
        self.wheels = build_wheels(self.section('wheels'))
        self._last_volts = (0.0, 0.0, 0.0)
        self._dt = positive_dt(self.control_period_s)

    def fused(self, stage: str, _held: dict[str, Any]) -> FusedStage | None:
        """Stage ``drive`` as :func:`drive_fused` (:mod:`acds_common.fused`); None with telemetry wanted."""
        if stage != 'drive' or self.telemetry_wanted or not self.present('acds_controller'):
            return None
        params, (h, torque) = self.wheels.kernel_parts()
        return FusedStage(drive_fused, (params, self._dt), (h, torque, self._last_volts), ('volts',),
                          (Output('momentum', 3), Output('torque', 3)), self._restore)

    def _restore(self, s: tuple) -> None:
        h, torque, self._last_volts = s
        self.wheels.set_kernel_state(h, torque)

    def drive(self, k: int, _t: float, inp: dict[str, Any]) -> dict[str, Any]:
        """Apply the step-k drive volts for one control period."""
        volts = xyz(inp['volts'])
        warning = None
        if not all_finite(volts):
            warning = f'non-finite drive volts {list(volts)} rejected at step {k}; holding the last valid ones'
            volts = self._last_volts
        self._last_volts = volts
        h_start, hdot = self.wheels.step_xyz_unchecked(volts, self._dt)  # volts checked above
        out: dict[str, Any] = {'momentum': h_start, 'torque': hdot}
        if warning is not None or (self.telemetry_wanted and k % TELEMETRY_EVERY == 0):
            values = {**{f'wheel_{i}_momentum_nms': f'{h:.6g}' for i, h in enumerate(self.wheels.wheel_momenta_nms())},
                      **{f'drive_{a}_volts': f'{v:.4g}' for a, v in zip('xyz', volts, strict=True)}}
            out['diagnostics'] = (diagnostic(self.instance, values) if warning is None
                                  else diagnostic(self.instance, values, warning, WARN))
        return out
