"""canopen_cards node: the emulated CANopen cards (spec §13).

ROS plumbing only: :class:`acds_common.lockstep.LockstepNode` hosts the pure stepper and ports
``canopen_bus.nodes`` declares for this node.
"""

from __future__ import annotations

from acds_common.lockstep import run_node


def main(args: list[str] | None = None) -> int:
    """Console-script entry point ``canopen_cards``."""
    return run_node('canopen_cards', args)
