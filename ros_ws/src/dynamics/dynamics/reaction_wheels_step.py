"""reaction_wheels stepper: square-law wheels with momentum capacity (spec §4), or CMGs (seed 000).

``wheels.kind`` selects the store. ``wheels``: stage ``drive`` of step k takes the controller's
drive volts of step k (zero without a controller), or with ``wheels.drive: torque`` (a formation
vehicle, seed 004) the formation controller's wanted ḣ, clipped per wheel at ``max_torque``.
``cmg``: stage ``gimbal`` takes the momentum rate ḣ the controller's attitude hold commands
(``controller/cmg_torque``, N·m; zero without a controller) and applies it to the ideal CMG store
(:mod:`dynamics.cmg_model`: no voltage drive, the spherical capacity ``wheels.cmg_capacity``).
Each returns the momentum h(t_k) and the rate ḣ over [t_k, t_k+1] that rigid_body applies.
Non-finite commands are rejected with a WARN diagnostic (the last valid ones are held; a torque
command: zero). A consumer that needs h(t_k) before it computes step k (the controller) reads these
with lag 1 and forms h(t_k) = h(t_k−1) + ḣ·Δt exactly. Telemetry (per-wheel momenta and drive
volts; CMG momentum, its fraction of the capacity) every ``TELEMETRY_EVERY`` steps; the CMGs
reaching or leaving their capacity is reported at once (WARN on reaching it: the hold has lost
authority in that direction).
"""

from __future__ import annotations

from typing import Any

import numpy as np
from acds_common.messages import WARN, diagnostic, vec, vector3, xyz
from acds_common.stepper import Stepper
from acds_common.validation import all_finite

from dynamics.configuration import build_cmgs, build_torque_wheels, build_wheels

#: Wheel telemetry on ``diagnostics`` every this many steps.
TELEMETRY_EVERY = 20


class ReactionWheelsStep(Stepper):
    """Three orthogonal wheels (or the 4-wheel 20°-cant cluster) driven by volts, torque-commanded wheels, or CMGs."""

    node = 'reaction_wheels'

    def __init__(self, params: dict[str, Any], log: Any = None) -> None:
        super().__init__(params, log)
        section = self.section('wheels')
        self.torque_drive = section['kind'] == 'wheels' and section['drive'] == 'torque'
        if section['kind'] == 'cmg':
            self.cmgs = build_cmgs(section)
            self._cmg_saturated = self.cmgs.saturated()
            self._last_hdot = np.zeros(3)
        else:
            self.wheels: Any = build_torque_wheels(section) if self.torque_drive else build_wheels(section)
        self._last_volts = (0.0, 0.0, 0.0)

    def drive(self, k: int, _t: float, inp: dict[str, Any]) -> dict[str, Any]:
        """Apply the step-k drive (volts, or a torque command) for one control period."""
        if self.torque_drive:
            return self._torque_drive(k, inp)
        volts = xyz(inp['volts'])
        warning = None
        if not all_finite(volts):
            warning = f'non-finite drive volts {list(volts)} rejected at step {k}; holding the last valid ones'
            volts = self._last_volts
        self._last_volts = volts
        h_start, hdot = self.wheels.step_xyz(volts, self.control_period_s)
        out: dict[str, Any] = {'momentum': h_start, 'torque': hdot}
        if warning is not None or k % TELEMETRY_EVERY == 0:
            values = {**{f'wheel_{i}_momentum_nms': f'{h:.6g}' for i, h in enumerate(self.wheels.wheel_momenta_nms())},
                      **{f'drive_{a}_volts': f'{v:.4g}' for a, v in zip('xyz', volts, strict=True)}}
            out['diagnostics'] = (diagnostic(self.node, values) if warning is None
                                  else diagnostic(self.node, values, warning, WARN))
        return out

    def _torque_drive(self, k: int, inp: dict[str, Any]) -> dict[str, Any]:
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
            out['diagnostics'] = (diagnostic(self.node, values) if warning is None
                                  else diagnostic(self.node, values, warning, WARN))
        return out

    def gimbal(self, k: int, _t: float, inp: dict[str, Any]) -> dict[str, Any]:
        """Stage ``gimbal`` (``wheels.kind`` cmg): the step-k commanded momentum rate for one control period."""
        hdot = vec(inp['torque'])
        warning = None
        if not np.all(np.isfinite(hdot)):
            warning = (f'non-finite CMG torque command {hdot.tolist()} rejected at step {k}; holding the last valid '
                       'one')
            hdot = self._last_hdot
        self._last_hdot = hdot
        h_start, hdot_mean = self.cmgs.step(hdot, self.control_period_s)
        saturated = self.cmgs.saturated()
        if saturated != self._cmg_saturated:
            self._cmg_saturated = saturated
            h = float(np.linalg.norm(self.cmgs.momentum_body_nms()))
            change = (f'CMG momentum reached its capacity ({h:.6g} N·m·s) at step {k}: no momentum beyond it, the '
                      'hold has lost authority outward' if saturated else
                      f'CMG momentum back inside its capacity at step {k}')
            self.log('warn' if saturated else 'info', change)
            warning = change if saturated else warning
        out: dict[str, Any] = {'momentum': vector3(h_start), 'torque': vector3(hdot_mean)}
        if warning is not None or k % TELEMETRY_EVERY == 0:
            h_end = self.cmgs.momentum_body_nms()
            values = {**{f'cmg_momentum_{a}_nms': f'{h:.6g}' for a, h in zip('xyz', h_end, strict=True)},
                      'cmg_capacity_fraction': f'{np.linalg.norm(h_end) / self.cmgs.cfg.capacity_nms:.4f}',
                      'cmg_saturated': 'true' if saturated else 'false',
                      **{f'torque_command_{a}_nm': f'{v:.4g}' for a, v in zip('xyz', hdot, strict=True)}}
            out['diagnostics'] = (diagnostic(self.node, values) if warning is None
                                  else diagnostic(self.node, values, warning, WARN))
        return out
