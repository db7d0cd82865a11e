"""rigid_body node: the time owner: rigid body, orbit and environment (spec §2).

ROS plumbing only: :class:`acds_common.lockstep.LockstepNode` hosts the pure stepper
:class:`dynamics.rigid_body_step.RigidBodyStep` with the ports :mod:`acds_common.graph` declares for this node.
"""

from __future__ import annotations

from acds_common.lockstep import run_node

from dynamics.rigid_body_step import RigidBodyStep


def main(args: list[str] | None = None) -> int:
    """Console-script entry point ``rigid_body``."""
    return run_node(RigidBodyStep, args)
