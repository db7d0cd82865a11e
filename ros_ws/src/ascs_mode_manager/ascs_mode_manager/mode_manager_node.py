"""ascs_mode_manager node: on-board mode logic (HEAO or SSS) (spec §2).

ROS plumbing only: :class:`acds_common.lockstep.LockstepNode` hosts the pure stepper and ports
``ascs_mode_manager.nodes`` declares for this node.
"""

from __future__ import annotations

from acds_common.lockstep import run_node


def main(args: list[str] | None = None) -> int:
    """Console-script entry point ``ascs_mode_manager``."""
    return run_node('ascs_mode_manager', args)
