"""acds_controller node: transfer assembly + DPA (spec §2).

ROS plumbing only: :class:`acds_common.lockstep.LockstepNode` hosts the pure stepper
:class:`acds_controller.controller_step.ControllerStep` with the ports :mod:`acds_common.graph` declares for this node.
"""

from __future__ import annotations

from acds_common.lockstep import run_node

from acds_controller.controller_step import ControllerStep


def main(args: list[str] | None = None) -> int:
    """Console-script entry point ``acds_controller``."""
    return run_node(ControllerStep, args)
