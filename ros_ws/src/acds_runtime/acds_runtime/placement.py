"""Which CPU each node process of a graph runs on, when the machine gives the run two (docs/measurements.md,
"Placing the node processes").

A lockstep step is a chain of hand-offs: the time owner's truth wakes its readers, their outputs wake theirs, and
the actuators' outputs wake the time owner for the next step. A hand-off to a thread that sleeps on the other CPU
costs an interprocessor interrupt and that CPU's wake-up: on the 2-core virtual machine of the CI, a pipe round trip
between two processes takes 2.5-2.8 µs on one CPU and 57-63 µs across the two, and the six-process graph took
2.31-2.40 CPU ms a step placed by this module against 2.59 placed by the scheduler (docs/measurements.md). Where the
scheduler puts a woken node is its own choice; this module makes one on purpose.

The rule, from the graph's declaration only (so it is the same on every run of a scenario):

* **levels**: the time owner is level 0; a node is one level after the deepest node it reads at lag 0 (a node
  that reads nothing at lag 0 is paced by /clock: level 1). Nodes of one level run at the same time.
* **weight**: the messages a node handles a step: every input it reads, and every per-step output once for each
  reader (the graph's nodes and the run monitor), since each reader costs the publisher a delivery.
* **the chain's CPU** (the first) takes the time owner and, of every level, its lightest node: the step's hand-offs
  down the chain stay on one CPU. The other nodes of a level go, heaviest first, to the CPU with less weight so far
  (on a tie, the second): they run beside the chain, and the run monitor, which the scheduler places, fills in.

Data are the same wherever a process runs (the lockstep orders every message by step); placement changes only how
fast. The launcher applies it when asked (``acds run``, ``acds bench``; not a study's samples or the tests' graphs,
which run side by side and would all put their chains on the same CPU), when its own CPU set holds exactly two CPUs
(the machine this was measured on), to its own node processes only (an external node is the user's and runs where the
user puts it), and only in a run as fast as it goes: a run paced to the wall clock (``--rtf``, or a bus whose flight
computer expects its answers in real time) gains nothing from it, and there a process bound to one CPU could not move
away from other load and miss a deadline (a C3's SDO write waits 0.3 s for the card's answer).
"""

from __future__ import annotations

import os
from collections.abc import Iterable
from dataclasses import dataclass

from acds_common.graph import Graph

#: Set to ``off`` to leave every node process where the operating system puts it (measurements; ``acds bench``
#: runs the graph both ways).
PLACEMENT_ENV = 'ACDS_PLACEMENT'


@dataclass(frozen=True)
class StepShape:
    """What placement needs of a step: its time owner, each node's lag-0 sources (the nodes it waits for within a
    step) and each node's weight (module docstring)."""

    owner: str
    sources: dict[str, frozenset[str]]
    weight: dict[str, int]


def shape_of(graph: Graph) -> StepShape:
    """The step shape of a graph's declaration (module docstring: levels and weight)."""
    owner = graph.time_owner
    readers: dict[str, int] = {}
    for spec in graph.nodes.values():
        for stage in spec.stages:
            for inp in stage.inputs:
                if inp.source in graph.nodes:
                    readers[spec.topic(inp.topic)] = readers.get(spec.topic(inp.topic), 0) + 1
    sources: dict[str, frozenset[str]] = {}
    weight: dict[str, int] = {}
    for inst, spec in graph.nodes.items():
        inputs = [inp for stage in spec.stages for inp in stage.inputs if inp.source in graph.nodes]
        sources[inst] = frozenset(inp.source for inp in inputs if inp.lag == 0 and inp.source != inst)
        sent = sum(1 + readers.get(spec.topic(out.topic), 0) for out in spec.outputs if out.every_step)
        weight[inst] = len(inputs) + sent
    return StepShape(owner, sources, weight)


def levels(shape: StepShape) -> dict[str, int]:
    """Each node's level (module docstring); the time owner's inputs close the step and do not count."""
    level = {shape.owner: 0}
    pending = [n for n in shape.sources if n != shape.owner]
    while pending:
        ready = [n for n in pending if all(s in level for s in shape.sources[n] if s != shape.owner)]
        if not ready:  # a lag-0 cycle: the graph refuses it when built; never reached from a built graph
            raise ValueError('lag-0 cycle among ' + ', '.join(sorted(pending)))
        for n in ready:
            level[n] = 1 + max((level[s] for s in shape.sources[n]), default=0)
            pending.remove(n)
    return level


def place(shape: StepShape, cpus: tuple[int, int]) -> dict[str, int]:
    """{node: CPU} by the module docstring's rule; ``cpus``: the chain's CPU, then the other."""
    level = levels(shape)
    load = {cpus[0]: 0, cpus[1]: 0}
    out: dict[str, int] = {}
    for lv in sorted(set(level.values())):
        nodes = sorted((n for n in level if level[n] == lv), key=lambda n: (shape.weight[n], n))
        out[nodes[0]] = cpus[0]
        load[cpus[0]] += shape.weight[nodes[0]]
        for n in reversed(nodes[1:]):
            cpu = cpus[0] if load[cpus[0]] < load[cpus[1]] else cpus[1]
            out[n] = cpu
            load[cpu] += shape.weight[n]
    return out


def chain_shape(nodes: Iterable[str]) -> StepShape:
    """The step shape of a ring relaying one message (``acds bench``'s bare ring), its first node owning time."""
    names = list(nodes)
    return StepShape(names[0], {n: frozenset(names[i - 1:i]) if i else frozenset() for i, n in enumerate(names)},
                     dict.fromkeys(names, 2))


def placement_cpus() -> tuple[int, int] | None:
    """The two CPUs to place on: this process's CPU set when it holds exactly two, unless ``ACDS_PLACEMENT=off``."""
    if os.environ.get(PLACEMENT_ENV, '') == 'off':
        return None
    cpus = sorted(os.sched_getaffinity(0))
    return (cpus[0], cpus[1]) if len(cpus) == 2 else None


def node_placement(graph: Graph, external: Iterable[str] = ()) -> dict[str, int]:
    """{instance: CPU} of the node processes a launcher starts for ``graph`` (none of ``external``, the user's); empty
    when it does not place them (:func:`placement_cpus`)."""
    cpus = placement_cpus()
    if cpus is None:
        return {}
    skip = set(external)
    return {n: cpu for n, cpu in place(shape_of(graph), cpus).items() if n not in skip}


def describe(plan: dict[str, int]) -> str:
    """One line: the nodes on each CPU."""
    by_cpu: dict[int, list[str]] = {}
    for node, cpu in plan.items():
        by_cpu.setdefault(cpu, []).append(node)
    return '; '.join(f'CPU {cpu}: {", ".join(nodes)}' for cpu, nodes in sorted(by_cpu.items()))
