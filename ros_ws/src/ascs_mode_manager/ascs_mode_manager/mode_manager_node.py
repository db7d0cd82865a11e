"""ascs_mode_manager node: the on-board mode logic (spec §8).

One executable; parameter ``modes_system`` selects the part that runs:
``heao`` (Mode 1A → 1B → capture → cruise, :mod:`ascs_mode_manager.heao_part`)
or ``sss`` (perigee automatic turn-on, :mod:`ascs_mode_manager.sss_part`).
Each part declares its own lockstep outputs and stages on this node.
"""

from __future__ import annotations

from acds_common.lockstep import LockstepNode, run_node


class ModeManagerNode(LockstepNode):
    """Hosts the HEAO or the SSS mode logic."""

    def __init__(self) -> None:
        super().__init__('ascs_mode_manager')
        self.modes = self.section_params('modes')
        self.sss = self.section_params('sss')
        if self.modes['system'] == 'sss':
            from ascs_mode_manager.sss_part import SssPart
            self.part = SssPart(self)
        else:
            from ascs_mode_manager.heao_part import HeaoPart
            self.part = HeaoPart(self)


def main(args: list[str] | None = None) -> int:
    """Console-script entry point ``ascs_mode_manager``."""
    return run_node('ascs_mode_manager', ModeManagerNode, args)
