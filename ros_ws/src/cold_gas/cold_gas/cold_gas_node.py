"""cold_gas node: the HEAO cold-gas reaction control subsystem (seed 002 §5).

ROS plumbing only: :class:`acds_common.lockstep.LockstepNode` hosts the pure stepper
:class:`cold_gas.cold_gas_step.ColdGasStep` with the ports :mod:`acds_common.graph` declares for this node.
"""

from __future__ import annotations

from acds_common.lockstep import run_node

from cold_gas.cold_gas_step import ColdGasStep


def main(args: list[str] | None = None) -> int:
    """Console-script entry point ``cold_gas``."""
    return run_node(ColdGasStep, args)
