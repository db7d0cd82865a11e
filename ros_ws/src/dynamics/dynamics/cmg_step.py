"""reaction_wheels stepper, AAP Workshop variant: the ideal CMG momentum store (seed 000; ``wheels.kind: cmg``).

Stage ``gimbal`` of step k takes the momentum rate ḣ the controller's attitude hold commands
(``controller/cmg_torque``, N·m; zero without a controller) and applies it to the ideal CMG store
(:mod:`dynamics.cmg_model`: no voltage drive, the spherical capacity ``wheels.cmg_capacity``). It
returns the momentum h(t_k) and the rate ḣ over [t_k, t_k+1] that rigid_body applies, on the wheels'
topics (the store's momentum, whatever the store). A non-finite command is rejected with a WARN
diagnostic and the last valid one is held. Telemetry (CMG momentum, its fraction of the capacity)
every ``TELEMETRY_EVERY`` steps; reaching or leaving the capacity is reported at once (WARN on
reaching it: the hold has lost authority in that direction).
"""

from __future__ import annotations

from typing import Any

import numpy as np
from acds_common.messages import WARN, diagnostic, vec, vector3
from acds_common.stepper import Stepper

from dynamics.configuration import build_cmgs
from dynamics.reaction_wheels_step import TELEMETRY_EVERY


class CmgStep(Stepper):
    """The Workshop's CMGs as an ideal momentum store."""

    node = 'reaction_wheels'

    def __init__(self, params: dict[str, Any], log: Any = None) -> None:
        super().__init__(params, log)
        self.cmgs = build_cmgs(self.section('wheels'))
        self._cmg_saturated = self.cmgs.saturated()
        self._last_hdot = np.zeros(3)

    def gimbal(self, k: int, _t: float, inp: dict[str, Any]) -> dict[str, Any]:
        """Stage ``gimbal``: the step-k commanded momentum rate for one control period."""
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
            out['diagnostics'] = (diagnostic(self.instance, values) if warning is None
                                  else diagnostic(self.instance, values, warning, WARN))
        return out
