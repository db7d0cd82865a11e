"""ascs_mode_manager node: on-board mode logic (HEAO or SSS) (spec §2).

ROS plumbing only: :class:`acds_common.lockstep.LockstepNode` hosts the pure stepper
:class:`ascs_mode_manager.mode_manager_step.ModeManagerStep` with the ports :mod:`acds_common.graph` declares for this node.
"""

from __future__ import annotations

from acds_common.lockstep import run_node

from ascs_mode_manager.mode_manager_step import ModeManagerStep


def main(args: list[str] | None = None) -> int:
    """Console-script entry point ``ascs_mode_manager``."""
    return run_node(ModeManagerStep, args)
