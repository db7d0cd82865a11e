"""reaction_wheels node: square-law reaction wheels (spec §2).

ROS plumbing only: :class:`acds_common.lockstep.LockstepNode` hosts the pure stepper
:class:`dynamics.reaction_wheels_step.ReactionWheelsStep` with the ports :mod:`acds_common.graph` declares for this node.
"""

from __future__ import annotations

from acds_common.lockstep import run_node

from dynamics.reaction_wheels_step import ReactionWheelsStep


def main(args: list[str] | None = None) -> int:
    """Console-script entry point ``reaction_wheels``."""
    return run_node(ReactionWheelsStep, args)
