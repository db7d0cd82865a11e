"""reaction_wheels node: square-law wheels with momentum capacity (spec §4).

Step k: take the drive volts of step k (zero without a controller), publish the
wheel momentum h(t_k) and the rate ḣ over [t_k, t_k+1] that rigid_body applies.
Non-finite volts are rejected with a WARN diagnostic (the last valid ones are held).
A consumer that needs h(t_k) before it computes step k (the controller) reads
these with lag 1 and forms h(t_k) = h(t_k−1) + ḣ·Δt exactly.
"""

from __future__ import annotations

from typing import Any

import numpy as np
from acds_common import topics
from acds_common.lockstep import Input, LockstepNode, run_node
from acds_common.messages import diagnostic, vec, vector3_stamped
from diagnostic_msgs.msg import DiagnosticArray, DiagnosticStatus
from geometry_msgs.msg import Vector3Stamped

from dynamics.configuration import build_wheels


class ReactionWheelsNode(LockstepNode):
    """Three orthogonal wheels (or the 4-wheel 20°-cant cluster) driven by volts."""

    def __init__(self) -> None:
        super().__init__('reaction_wheels')
        self.wheels = build_wheels(self.section_params('wheels'))
        self.add_output('momentum', Vector3Stamped, topics.WHEEL_MOMENTUM)
        self.add_output('torque', Vector3Stamped, topics.WHEEL_TORQUE)
        self.add_output('diagnostics', DiagnosticArray, topics.DIAGNOSTICS)
        self._last_volts = np.zeros(3)
        self.add_stage('drive', [Input('volts', topics.WHEEL_VOLTS, Vector3Stamped, 'acds_controller')],
                       self.drive)

    def drive(self, k: int, _t: float, inp: dict[str, Any]) -> None:
        """Apply the step-k volts for one control period."""
        volts = vec(inp['volts'])
        if not np.all(np.isfinite(volts)):
            self.publish('diagnostics', diagnostic(
                self.get_name(), {'rejected_volts': str(volts.tolist())},
                f'non-finite drive volts rejected at step {k}; holding the last valid ones', DiagnosticStatus.WARN), k)
            volts = self._last_volts
        self._last_volts = volts
        h_start, hdot = self.wheels.step(volts, self.control_period_s)
        self.publish('momentum', vector3_stamped(h_start), k)
        self.publish('torque', vector3_stamped(hdot), k)
        if k % 20 == 0:
            per_wheel = self.wheels.wheel_momenta_nms()
            self.publish('diagnostics', diagnostic(self.get_name(), {
                **{f'wheel_{i}_momentum_nms': f'{h:.6g}' for i, h in enumerate(per_wheel)},
                **{f'drive_{a}_volts': f'{v:.4g}' for a, v in zip('xyz', volts, strict=True)},
            }), k)


def main(args: list[str] | None = None) -> int:
    """Console-script entry point ``reaction_wheels``."""
    return run_node('reaction_wheels', ReactionWheelsNode, args)
