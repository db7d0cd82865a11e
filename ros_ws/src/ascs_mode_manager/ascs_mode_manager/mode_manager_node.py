"""ascs_mode_manager node: the on-board mode logic (spec §8).

One executable; parameter ``modes_system`` selects the part that runs:
``heao`` (Mode 1A → 1B → capture → cruise, :mod:`ascs_mode_manager.heao_part`)
or ``sss`` (perigee automatic turn-on, :mod:`ascs_mode_manager.sss_part`).
The host owns what both share: the ``mode``, ``events`` and ``diagnostics``
outputs, the ground-command intake (:mod:`ascs_mode_manager.ground_commands`)
and the acknowledgements on ``ground/ack``; each part adds its stage.
"""

from __future__ import annotations

from acds_common import topics
from acds_common.lockstep import COMMAND_QOS, ConfigError, LockstepNode, run_node
from diagnostic_msgs.msg import DiagnosticArray
from std_msgs.msg import String

from ascs_mode_manager.ground_commands import GroundCommandQueue
from ascs_mode_manager.spin_mechanizations import AscsError


class ModeManagerNode(LockstepNode):
    """Hosts the HEAO or the SSS mode logic."""

    def __init__(self) -> None:
        super().__init__('ascs_mode_manager')
        self.modes = self.section_params('modes')
        self.sss = self.section_params('sss')
        try:
            self.commands = GroundCommandQueue(self.modes['ground_commands'])
        except AscsError as exc:
            raise ConfigError(f'ascs_mode_manager: {exc}') from None
        self.add_output('mode', DiagnosticArray, topics.MODE)
        self.add_output('events', String, topics.EVENTS)
        self.add_output('diagnostics', DiagnosticArray, topics.DIAGNOSTICS)
        self._ack = self.create_publisher(String, topics.GROUND_ACK, COMMAND_QOS)
        self.create_subscription(String, topics.GROUND_COMMAND, lambda m: self.commands.receive(m.data), COMMAND_QOS)
        if self.modes['system'] == 'sss':
            from ascs_mode_manager.sss_part import SssPart
            self.part = SssPart(self)
        else:
            from ascs_mode_manager.heao_part import HeaoPart
            self.part = HeaoPart(self)

    def acknowledge(self, line: str, accepted: bool) -> None:
        """Answer a ground command on ``ground/ack`` (refusals carry the reason) and log it."""
        self._ack.publish(String(data=line))
        if accepted:
            self.get_logger().info(f'ground command {line}')
        else:
            self.get_logger().warning(f'ground command {line}')


def main(args: list[str] | None = None) -> int:
    """Console-script entry point ``ascs_mode_manager``."""
    return run_node('ascs_mode_manager', ModeManagerNode, args)
