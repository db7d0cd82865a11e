"""cold_gas node: the HEAO cold-gas reaction control subsystem (seed 002 §5).

ROS plumbing only: :class:`acds_common.lockstep.LockstepNode` hosts the pure stepper and ports
``cold_gas.nodes`` declares for this node.
"""

from __future__ import annotations

from acds_common.lockstep import run_node


def main(args: list[str] | None = None) -> int:
    """Console-script entry point ``cold_gas``."""
    return run_node('cold_gas', args)
