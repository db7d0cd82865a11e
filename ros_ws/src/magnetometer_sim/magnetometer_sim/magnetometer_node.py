"""magnetometer_sim node: triaxial fluxgate magnetometer (spec §2).

ROS plumbing only: :class:`acds_common.lockstep.LockstepNode` hosts the pure stepper and ports
``magnetometer_sim.nodes`` declares for this node.
"""

from __future__ import annotations

from acds_common.lockstep import run_node


def main(args: list[str] | None = None) -> int:
    """Console-script entry point ``magnetometer_sim``."""
    return run_node('magnetometer_sim', args)
