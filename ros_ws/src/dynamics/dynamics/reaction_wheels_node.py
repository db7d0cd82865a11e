"""reaction_wheels node: square-law reaction wheels (spec §2).

ROS plumbing only: :class:`acds_common.lockstep.LockstepNode` hosts the pure stepper and ports
``dynamics.nodes`` declares for this node.
"""

from __future__ import annotations

from acds_common.lockstep import run_node


def main(args: list[str] | None = None) -> int:
    """Console-script entry point ``reaction_wheels``."""
    return run_node('reaction_wheels', args)
