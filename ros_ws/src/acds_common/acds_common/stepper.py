"""The ROS-free logic of a node: a stepper, hosted by a node process or by the direct engine (spec §2).

A stepper is built from its node's normalized parameters (:mod:`acds_common.parameters`)
and composes its package's pure cores. For every stage the graph declares
(:mod:`acds_common.graph`) it has a method of that name::

    def integrate(self, k: int, t_s: float, inputs: dict[str, Any]) -> dict[str, Any]

which takes the stage's inputs of step k (values as :mod:`acds_common.cdr` defines them;
``None`` for an absent source or a lagged input before its first step) and returns the
outputs it publishes at this step, by output key. The host stamps each with
t_(k + stamp_offset), encodes and publishes it (node process) or hands it on in memory
(direct engine): the stepper cannot tell which, so both engines give the same data.

A stepper reports through :meth:`log` (the host prints or logs it) and ends the run by
setting :attr:`finished`; a failure the run cannot survive raises :class:`StepError`.

A stepper may also give a compiled form of its stages for the direct engine's fused loop, a method
``fused(stage, held) -> FusedStage | None`` (:mod:`acds_common.fused`); a graph whose every stepper has one runs
its quiet steps in one compiled loop (:mod:`acds_runtime.fused_step`), any other graph runs every step here.
"""

from __future__ import annotations

import importlib
from collections.abc import Callable
from typing import Any, ClassVar

from acds_common.parameters import section

#: ``log(level, text)`` with level 'info' | 'warn' | 'error'.
Log = Callable[[str, str], None]


class StepError(RuntimeError):
    """The step cannot be computed (non-finite physics, impossible actuator values): the run fails with this message."""


def _print_log(level: str, text: str) -> None:
    import sys
    print(f'[{level}] {text}', file=sys.stderr)


class Stepper:
    """Base of every node's stepper: parameters, the control period, logging, run end."""

    #: Node name (the graph's key for it).
    node: ClassVar[str] = ''

    def __init__(self, params: dict[str, Any], log: Log | None = None) -> None:
        self.params = params
        self.control_period_s: float = params['control_period_s']
        self.dt_ns = round(self.control_period_s * 1e9)
        self.graph_nodes: list[str] = list(params['graph_nodes'])
        self.seed: int = params['seed']
        #: The formation vehicle this node belongs to ('' in a single-vehicle graph).
        self.vehicle: str = params.get('vehicle', '')
        self._log = log or _print_log
        #: Set by the stepper to end the run after the current stage (time owner).
        self.finished = False
        #: Whether anyone reads this node's periodic telemetry (``diagnostics`` every N steps): the host clears
        #: it when nobody does (the direct engine with no bag recorded, no live view and no input or summary on
        #: the topic), and the stepper then leaves its periodic telemetry out; what a step reports because
        #: something happened (an event, a warning, an alarm change) it returns regardless.
        self.telemetry_wanted = True

    @property
    def instance(self) -> str:
        """The graph's name of this node: ``VEHICLE/NODE`` for a formation vehicle's node, else the node's name (its
        /diagnostics status is named so: two vehicles' nodes of one kind are told apart)."""
        return f'{self.vehicle}/{self.node}' if self.vehicle else self.node

    def section(self, name: str, vehicle: str = '') -> dict[str, Any]:
        """{field: SI value} of a scenario section this node receives (``vehicle``: that vehicle's copy)."""
        return section(self.params, name, vehicle)

    def present(self, node: str) -> bool:
        """Whether ``node`` is part of this graph (a vehicle's node: one of its own vehicle's, or a qualified name)."""
        return node in self.graph_nodes or (bool(self.vehicle) and f'{self.vehicle}/{node}' in self.graph_nodes)

    def step_time_s(self, k: int) -> float:
        """t_k in seconds (exact integer-ns step identity, as the stamps)."""
        return k * self.dt_ns / 1e9

    def log(self, level: str, text: str) -> None:
        """Report a line (info, warn, error)."""
        self._log(level, text)

    def start(self) -> dict[str, Any]:
        """Outputs of step 0 published before any stage fires (the time owner's initial truth)."""
        return {}

    def close(self) -> None:
        """Release what the stepper holds outside the process (a socket, an open log): the host calls it once when
        the run ends, however it ends. Nothing by default."""

    def receive_command(self, text: str) -> None:
        """A live ground command (nodes that declare ``ground_commands`` override this)."""
        raise NotImplementedError(f'{self.node} takes no ground commands')


def load_stepper(path: str) -> type[Stepper]:
    """'package.module:Class' (a declaration's :attr:`~acds_common.graph.Ports.stepper`) → the stepper class."""
    module, _, name = path.partition(':')
    return getattr(importlib.import_module(module), name)
