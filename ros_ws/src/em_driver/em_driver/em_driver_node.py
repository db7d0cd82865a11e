"""em_driver node: electromagnets and their bridge-switch drivers (spec §2).

ROS plumbing only: :class:`acds_common.lockstep.LockstepNode` hosts the pure stepper
:class:`em_driver.em_driver_step.EmDriverStep` with the ports :mod:`acds_common.graph` declares for this node.
"""

from __future__ import annotations

from acds_common.lockstep import run_node

from em_driver.em_driver_step import EmDriverStep


def main(args: list[str] | None = None) -> int:
    """Console-script entry point ``em_driver``."""
    return run_node(EmDriverStep, args)
