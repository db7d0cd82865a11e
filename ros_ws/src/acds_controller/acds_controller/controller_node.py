"""acds_controller node: transfer assembly + DPA (spec §2).

ROS plumbing only: :class:`acds_common.lockstep.LockstepNode` hosts the pure stepper and ports
``acds_controller.nodes`` declares for this node.
"""

from __future__ import annotations

from acds_common.lockstep import run_node


def main(args: list[str] | None = None) -> int:
    """Console-script entry point ``acds_controller``."""
    return run_node('acds_controller', args)
