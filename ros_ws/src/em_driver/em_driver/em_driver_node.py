"""em_driver node: electromagnets and their bridge-switch drivers (spec §2).

ROS plumbing only: :class:`acds_common.lockstep.LockstepNode` hosts the pure stepper and ports
``em_driver.nodes`` declares for this node.
"""

from __future__ import annotations

from acds_common.lockstep import run_node


def main(args: list[str] | None = None) -> int:
    """Console-script entry point ``em_driver``."""
    return run_node('em_driver', args)
