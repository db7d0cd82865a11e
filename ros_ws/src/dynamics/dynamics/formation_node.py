"""formation_dynamics node: a formation's time owner: every vehicle's translation and attitude (spec §10).

ROS plumbing only: :class:`acds_common.lockstep.LockstepNode` hosts the pure stepper
:class:`dynamics.formation_step.FormationDynamicsStep` with the ports :mod:`acds_common.graph` declares for this node.
"""

from __future__ import annotations

from acds_common.lockstep import run_node

from dynamics.formation_step import FormationDynamicsStep


def main(args: list[str] | None = None) -> int:
    """Console-script entry point ``formation_dynamics``."""
    return run_node(FormationDynamicsStep, args)
