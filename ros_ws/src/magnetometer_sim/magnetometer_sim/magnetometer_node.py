"""magnetometer_sim node: triaxial fluxgate magnetometer (spec §2).

ROS plumbing only: :class:`acds_common.lockstep.LockstepNode` hosts the pure stepper
:class:`magnetometer_sim.magnetometer_step.MagnetometerStep` with the ports :mod:`acds_common.graph` declares for this node.
"""

from __future__ import annotations

from acds_common.lockstep import run_node

from magnetometer_sim.magnetometer_step import MagnetometerStep


def main(args: list[str] | None = None) -> int:
    """Console-script entry point ``magnetometer_sim``."""
    return run_node(MagnetometerStep, args)
