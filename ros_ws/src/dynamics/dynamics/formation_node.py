"""formation_dynamics node: a formation's time owner: every vehicle's translation and attitude (spec §10).

ROS plumbing only: :class:`acds_common.lockstep.LockstepNode` hosts the pure stepper and ports
``dynamics.nodes`` declares for this node.
"""

from __future__ import annotations

from acds_common.lockstep import run_node


def main(args: list[str] | None = None) -> int:
    """Console-script entry point ``formation_dynamics``."""
    return run_node('formation_dynamics', args)
