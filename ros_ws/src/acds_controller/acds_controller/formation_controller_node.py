"""formation_controller node: one vehicle's electromagnetic formation controller (spec §10).

ROS plumbing only: :class:`acds_common.lockstep.LockstepNode` hosts the pure stepper
:class:`acds_controller.formation_controller_step.FormationControllerStep` with the ports
:mod:`acds_common.graph` declares for this node.
"""

from __future__ import annotations

from acds_common.lockstep import run_node

from acds_controller.formation_controller_step import FormationControllerStep


def main(args: list[str] | None = None) -> int:
    """Console-script entry point ``formation_controller``."""
    return run_node(FormationControllerStep, args)
