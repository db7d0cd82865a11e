"""The ACDS node graph (spec §2): the declaration types, their discovery, and the graph of one run.

Each package declares its own nodes (issue 19): a :class:`Package` named in the entry-point group
``acds.nodes`` of its distribution lists its :class:`Node` s (name, the scenario sections they read,
their :class:`Ports`: stepper, stages with inputs and lags, outputs), the scenario sections it
defines and the topics it publishes. This module discovers them (:func:`packages`) and builds the
graph of a run from them; it names no node of any package. Both engines are built from the
declarations and nothing else:

* the per-process graph: each node process hosts its node's pure stepper
  (:mod:`acds_common.lockstep`), subscribing to exactly the inputs declared and
  publishing exactly the outputs; the launcher starts one process per declared node and
  its run monitor records every declared output;
* the direct engine (``acds_runtime.direct``): the same steppers in one process, fired in
  an order that respects every lag-0 edge, values handed over in memory.

A node's ports may depend on its parameters (the em_driver's command source; a variant chosen by
the scenario is its own stepper), so ``ports`` may be a function ``params → Ports``. Stages of a
node fire in declared order, once per step; a stage of step k takes each input of step k − lag
from its source node (``None`` when the source is not in the graph or k − lag < 0).
Outputs are published once per step (``every_step``) unless marked otherwise; the time
owner's truth outputs of step k + 1 come from its stage of step k (``stamp_offset`` 1).
The checks (:func:`build_graph`): one publisher per per-step topic, every input read from a node
that publishes it, exactly one time owner, no lag-0 cycle.
"""

from __future__ import annotations

import functools
import re
from collections.abc import Callable, Iterable
from dataclasses import dataclass, field, replace
from importlib.metadata import entry_points
from typing import Any

from acds_common import topics

#: The launcher's observer (recorder) in the lockstep handshake, and how far the time owner may run ahead of it.
MONITOR_NAME = 'run_monitor'
MONITOR_LAG = 50
#: The run monitor acknowledges every MONITOR_ACK_EVERY-th /clock step (the time owner waits on it).
MONITOR_ACK_EVERY = 10


def monitor_allows(k: int, acked: int) -> bool:
    """Whether the time owner may fire step ``k`` with the run monitor's acknowledgements up to step ``acked``
    (-1: none yet): it runs at most :data:`MONITOR_LAG` steps ahead of them."""
    return acked >= k - MONITOR_LAG


@dataclass(frozen=True)
class Output:
    """A published topic: ``key`` in the stepper's result, the topic (relative to the node's namespace), frames.

    Its message type and unit are those of the :class:`Topic` its package declares (the mechanism's own
    topics, ``/diagnostics``: :data:`acds_common.topics.TYPES`).

    ``stamp_offset``: the value returned at step k is stamped t_(k + offset). ``every_step``: one
    message per step (False: only when the stepper returns one: telemetry, events). ``lockstep``:
    lockstep QoS (False: the command QoS, e.g. acknowledgements). ``many``: the value is a list,
    each item one message (events, acknowledgements).
    """

    key: str
    topic: str
    frame_id: str = ''
    child_frame_id: str = ''
    stamp_offset: int = 0
    every_step: bool = True
    lockstep: bool = True
    many: bool = False

    @property
    def msg_type(self) -> str:
        """'package/msg/Type' of the topic (:func:`acds_common.topics.type_of`: as declared)."""
        return topics.type_of(self.topic)


@dataclass(frozen=True)
class Input:
    """A lockstep input: ``topic`` from node ``source``, ``lag`` steps back, handed to the stage as ``key``."""

    key: str
    topic: str
    source: str
    lag: int = 0


@dataclass(frozen=True)
class Stage:
    """One stage of a node: the stepper's method ``name`` fires once per step with these inputs."""

    name: str
    inputs: tuple[Input, ...]


@dataclass(frozen=True)
class NodeSpec:
    """One node: its executable (console script ``name`` of ``package``), its stepper class, its ports.

    ``instance`` is the node's key in the graph: its name, or ``<vehicle>/<name>`` for a node of one
    vehicle of a formation, which then runs in the ROS namespace ``/acds/<vehicle>`` (``namespace``):
    its relative topics resolve there (:meth:`topic`), so every vehicle's nodes have the single
    vehicle's topic names under their own namespace. ``time_owner``: this node owns sim time.
    """

    name: str
    package: str
    stepper: str
    stages: tuple[Stage, ...]
    outputs: tuple[Output, ...]
    ground_commands: bool = False
    time_owner: bool = False
    instance: str = ''
    namespace: str = topics.NAMESPACE

    def __post_init__(self) -> None:
        if not self.instance:
            object.__setattr__(self, 'instance', self.name)

    @property
    def vehicle(self) -> str:
        """The vehicle this node belongs to ('' for a node of the whole graph)."""
        return self.instance.rpartition('/')[0]

    def topic(self, name: str) -> str:
        """Absolute name of ``name`` (relative names resolve in this node's namespace)."""
        return name if name.startswith('/') else f'{self.namespace}/{name}'

    def output(self, key: str) -> Output:
        """The output declared under ``key``."""
        for out in self.outputs:
            if out.key == key:
                return out
        raise KeyError(f'{self.name} declares no output {key!r}')


@dataclass(frozen=True)
class Topic:
    """A topic a package's nodes publish: its name (relative to the node's namespace, or absolute), message
    type ('package/msg/Type'), unit (SI, '' for none) and meaning.

    ``transfer``: for a topic in raw units (a sensor's volts), a function of the producing node's normalized
    parameters returning the lines that state its transfer to engineering units (zero, scale per axis,
    range, quantisation, what a reference channel means); the contract prints them. ``realism``: what
    reading the topic means for an external flight computer (a calibrated or truth topic it could not
    read on board); the contract prints it where it offers the topic.
    """

    name: str
    type: str
    unit: str = ''
    doc: str = ''
    transfer: Callable[[dict[str, Any]], list[str]] | None = None
    realism: str = ''


@dataclass(frozen=True)
class Ports:
    """What a node runs for given parameters: its stepper ('package.module:Class'), stages and outputs.

    ``ground_commands``: the node takes the ground commands (``ground/command``, handed to the stepper's
    ``receive_command``).
    """

    stepper: str
    stages: tuple[Stage, ...]
    outputs: tuple[Output, ...]
    ground_commands: bool = False


@dataclass(frozen=True)
class Node:
    """A node as its package declares it (docs: Architecture, "Adding a node").

    ``name``: the ROS node name, its console script, its key in a scenario's ``nodes``. ``sections``:
    the scenario sections it reads (each key becomes its parameter ``<section>_<key>_<si unit>``).
    ``ports``: its :class:`Ports`, or a function of its normalized parameters that returns them (the
    scenario picks the variant: each variant its own stepper). ``time_owner``: it owns sim time (a
    graph has one). ``in_graph`` / ``in_vehicle``: it may be listed in a scenario's ``nodes`` / in a
    formation vehicle's ``nodes`` (then it runs in the vehicle's namespace). ``every_vehicle``: a
    formation-wide node, which also reads these sections of every vehicle (``<vehicle>.<parameter>``).
    ``sections_with``: ``(section, node)`` pairs: a section the node reads only when that node is in the
    graph (its ports then take the variant that reads it), so a scenario gives it only the parameters its
    ports read.
    """

    name: str
    sections: tuple[str, ...]
    ports: Ports | Callable[[dict[str, Any]], Ports]
    time_owner: bool = False
    in_graph: bool = True
    in_vehicle: bool = False
    every_vehicle: tuple[str, ...] = ()
    sections_with: tuple[tuple[str, str], ...] = ()

    def sections_in(self, graph_nodes: Iterable[str]) -> tuple[str, ...]:
        """The sections this node reads in a graph of ``graph_nodes`` (instances; a vehicle's by its node name)."""
        present = {g.rpartition('/')[2] for g in graph_nodes}
        return self.sections + tuple(sec for sec, node in self.sections_with if node in present)


@dataclass(frozen=True)
class Package:
    """One package's declarations, named by its entry point in the group :data:`ENTRY_POINT_GROUP`.

    ``sections``: the scenario sections it defines, ``{section: {key: acds_common.schema.Field}}``
    (any node may read any section). ``vehicle_sections``: those of them each formation vehicle has
    of its own. ``topics``: the topics its nodes publish. ``checks``: functions of a loaded
    :class:`~acds_common.scenario.Scenario` returning '' or what is wrong across its keys (one line).
    """

    name: str
    nodes: tuple[Node, ...] = ()
    sections: dict[str, dict[str, Any]] = field(default_factory=dict)
    vehicle_sections: tuple[str, ...] = ()
    topics: tuple[Topic, ...] = ()
    checks: tuple[Callable[[Any], str], ...] = ()


#: The entry-point group a distribution names its :class:`Package` in (setup.py ``entry_points``).
ENTRY_POINT_GROUP = 'acds.nodes'


class DeclarationError(ValueError):
    """Two packages declare the same node, section or topic, or an entry point is not a :class:`Package`."""


@functools.cache
def packages() -> tuple[Package, ...]:
    """Every installed package's declarations, by entry-point name (discovered once per process)."""
    found: list[Package] = []
    for ep in sorted(entry_points(group=ENTRY_POINT_GROUP), key=lambda e: e.name):
        pkg = ep.load()
        if not isinstance(pkg, Package):
            raise DeclarationError(f'entry point {ep.name} = {ep.value} ({ENTRY_POINT_GROUP}) is not an '
                                   'acds_common.graph.Package')
        found.append(pkg)
    for what, names in (('node', lambda p: [n.name for n in p.nodes]), ('section', lambda p: list(p.sections)),
                        ('topic', lambda p: [t.name for t in p.topics])):
        owner: dict[str, str] = {}
        for pkg in found:
            for name in names(pkg):
                if name in owner:
                    raise DeclarationError(f'{what} {name!r} is declared by both {owner[name]} and {pkg.name}')
                owner[name] = pkg.name
    return tuple(found)


@functools.cache
def declared_nodes() -> dict[str, tuple[Package, Node]]:
    """Every declared node by name, with its package."""
    return {n.name: (pkg, n) for pkg in packages() for n in pkg.nodes}


def declared_node(name: str) -> tuple[Package, Node]:
    """The package and declaration of node ``name`` (KeyError naming the known ones)."""
    try:
        return declared_nodes()[name]
    except KeyError:
        raise KeyError(f'unknown node {name!r} (known: {", ".join(declared_nodes())})') from None


def declared_sections() -> dict[str, dict[str, Any]]:
    """Every package's scenario sections, ``{section: {key: Field}}``, packages in entry-point order."""
    return {name: keys for pkg in packages() for name, keys in pkg.sections.items()}


@functools.cache
def declared_topics() -> dict[str, Topic]:
    """Every declared topic by name."""
    return {t.name: t for pkg in packages() for t in pkg.topics}


def time_owner_name(formation: bool) -> str:
    """The node that owns sim time in a single-vehicle graph (``formation`` False) or in a formation's."""
    owners = [n.name for _pkg, n in declared_nodes().values() if n.time_owner and bool(n.every_vehicle) == formation]
    if len(owners) != 1:
        raise DeclarationError(f'{"a formation" if formation else "a single-vehicle graph"} needs exactly one declared '
                               f'time owner, found {owners or "none"}')
    return owners[0]


def time_owner_among(instances: Iterable[str]) -> str:
    """The time owner among a graph's instances (a node's ``graph_nodes``), '' when it is not one of them."""
    return next((n for n in instances if n != MONITOR_NAME and declared_node(n.rpartition('/')[2])[1].time_owner), '')


def node_spec(name: str, params: dict[str, Any]) -> NodeSpec:
    """The declaration of node ``name`` for its parameters (its package's :class:`Node`, ports resolved).

    A node of one vehicle of a formation (parameter ``vehicle``) gets the single-vehicle ports under
    the vehicle's namespace; its inputs from the vehicle's own nodes (those of ``graph_nodes`` named
    ``<vehicle>/<node>``) are qualified with the vehicle, inputs from nodes of the whole graph (the
    formation's time owner, the run monitor) stay as they are.
    """
    pkg, node = declared_node(name)
    ports = node.ports(params) if callable(node.ports) else node.ports
    spec = NodeSpec(name, pkg.name, ports.stepper, ports.stages, ports.outputs, ports.ground_commands,
                    node.time_owner)
    vehicle = params.get('vehicle', '')
    if not vehicle:
        return spec
    own = {g.partition('/')[2] for g in params.get('graph_nodes', []) if g.startswith(f'{vehicle}/')}

    def qualify(source: str) -> str:
        return f'{vehicle}/{source}' if '/' not in source and source in own else source

    stages = tuple(Stage(st.name, tuple(replace(i, source=qualify(i.source)) for i in st.inputs))
                   for st in spec.stages)
    return replace(spec, stages=stages, instance=f'{vehicle}/{name}', namespace=f'{topics.NAMESPACE}/{vehicle}')


def instance_name(namespace: str, node_name: str) -> str:
    """The graph key of a ROS node seen by discovery: its name, prefixed by its vehicle's namespace."""
    prefix = f'{topics.NAMESPACE}/'
    return f'{namespace[len(prefix):]}/{node_name}' if namespace.startswith(prefix) else node_name


#: A ROS node name as rcl accepts it: letters, digits and underscores, not starting with a digit.
ROS_NODE_NAME = re.compile(r'[A-Za-z_][A-Za-z0-9_]*')


def external_nodes(items: Iterable[str], instances: Iterable[str], time_owner: str) -> dict[str, str]:
    """``NODE[=ROS_NODE_NAME]`` items (``acds run --external``, scenario key ``external``; issue 20 §1) → {instance:
    the ROS identity its publishers must carry}, ValueError (one line) for a node not in the graph, the time owner,
    a node given twice, a name rcl would refuse or one a node the launcher starts (or its run monitor) has.

    An external node is one of the graph's nodes that the launcher does not start: the user's own process, in any
    language, takes its place under the given ROS node name (default: the node's own name). A formation vehicle's
    node (``VEHICLE/NODE``) keeps its vehicle's namespace, so its identity is ``VEHICLE/ROS_NODE_NAME``
    (:func:`instance_name`). The time owner cannot be external: it publishes /clock and paces the graph.
    """
    known = list(instances)
    out: dict[str, str] = {}
    for item in items:
        node, sep, ros_name = item.partition('=')
        if node not in known:
            raise ValueError(f'external node {node!r}: not a node of this graph (its nodes: {", ".join(known)})')
        if node == time_owner:
            raise ValueError(f'external node {node!r}: it owns sim time (it publishes /clock and paces the graph), so '
                             'it cannot be external; any other node can')
        if node in out:
            raise ValueError(f'external node {node!r} is given twice')
        name = ros_name if sep else node.rpartition('/')[2]
        if not ROS_NODE_NAME.fullmatch(name):
            raise ValueError(f'external node {item!r}: {name!r} is not a ROS node name (letters, digits and '
                             '_, not starting with a digit)')
        vehicle = node.rpartition('/')[0]
        out[node] = f'{vehicle}/{name}' if vehicle else name
    # ROS node names are unique in a graph, and the graph knows its publishers by them: a name the launcher gives
    # one of its own processes would make the user's node and that one indistinguishable (neither an intruder).
    taken = {i: f'the node {i} the launcher starts' for i in known if i not in out}
    taken[MONITOR_NAME] = "the launcher's run monitor"
    for node, identity in out.items():
        if identity in taken:
            raise ValueError(f'external node {node!r}: ROS node name {identity.rpartition("/")[2]!r} is that of '
                             f'{taken[identity]} (ROS node names are unique in a graph): give yours another')
    return out


def external_parameter(external: dict[str, str]) -> list[str]:
    """The nodes' parameter ``external_nodes``: ``instance=identity`` entries."""
    return [f'{inst}={ident}' for inst, ident in external.items()]


def external_of(params: dict[str, Any]) -> dict[str, str]:
    """{instance: ROS identity} of the external nodes, from a node's parameter ``external_nodes``."""
    return dict(entry.split('=', 1) for entry in params.get('external_nodes', []))


@dataclass(frozen=True)
class Graph:
    """The declared nodes of one run (by instance) and the order the direct engine fires their stages in."""

    nodes: dict[str, NodeSpec]

    @property
    def time_owner(self) -> str:
        """The instance that owns sim time."""
        owners = [i for i, spec in self.nodes.items() if spec.time_owner]
        if len(owners) != 1:
            raise ValueError(f'a graph has exactly one time owner, found {owners or "none"}')
        return owners[0]

    def present(self, node: str) -> bool:
        """Whether instance ``node`` is part of this graph."""
        return node in self.nodes

    def outputs(self) -> Iterable[tuple[NodeSpec, Output]]:
        """Every (node, output) of the graph."""
        for spec in self.nodes.values():
            for out in spec.outputs:
                yield spec, out

    def truth_topics(self) -> list[str]:
        """Absolute names of the truth: the time owner's per-step outputs (hashed into a run's truth digest)."""
        spec = self.nodes[self.time_owner]
        return sorted(spec.topic(out.topic) for out in spec.outputs if out.every_step)

    def read_topics(self) -> set[str]:
        """Absolute names of the topics some node of the graph reads (its inputs whose source is in the graph)."""
        return {spec.topic(i.topic) for spec in self.nodes.values() for st in spec.stages for i in st.inputs
                if i.source in self.nodes}

    def publisher_of(self, topic: str) -> list[str]:
        """The instances declared to publish ``topic`` (absolute name)."""
        return self.publishers().get(topic, [])

    def publishers(self) -> dict[str, list[str]]:
        """Per topic published (absolute name), the instances declared to publish it, in the order of :meth:`outputs`."""
        publishers: dict[str, list[str]] = {}
        for spec, out in self.outputs():
            publishers.setdefault(spec.topic(out.topic), []).append(spec.instance)
        return publishers

    def firing_order(self) -> list[tuple[str, Stage]]:
        """(instance, stage) of every non-time-owner stage, ordered so every lag-0 input is produced first.

        Within a node, stages keep their declared order. The time owner's stages close the step
        and come last. Raises ValueError on a lag-0 cycle (it would deadlock the per-process graph).
        """
        owner = self.time_owner
        pending = [(i, st) for i, spec in self.nodes.items() if i != owner for st in spec.stages]
        producers = {spec.topic(out.topic): spec.instance for spec, out in self.outputs() if spec.instance != owner}
        fired_stages: dict[str, int] = dict.fromkeys(self.nodes, 0)
        order: list[tuple[str, Stage]] = []
        fired_topics: set[str] = set()
        while pending:
            for n, (inst, stage) in enumerate(pending):
                spec = self.nodes[inst]
                if spec.stages.index(stage) != fired_stages[inst]:
                    continue
                needs = {spec.topic(inp.topic) for inp in stage.inputs
                         if inp.lag == 0 and inp.source in self.nodes and inp.source != owner
                         and producers.get(spec.topic(inp.topic)) == inp.source}
                if needs <= fired_topics:
                    order.append((inst, stage))
                    fired_stages[inst] += 1
                    if fired_stages[inst] == len(spec.stages):
                        fired_topics.update(spec.topic(out.topic) for out in spec.outputs)
                    del pending[n]
                    break
            else:
                raise ValueError('lag-0 cycle among ' + ', '.join(f'{i}.{st.name}' for i, st in pending))
        return order + [(owner, st) for st in self.nodes[owner].stages]


def build_graph(params_by_node: dict[str, dict[str, Any]]) -> Graph:
    """The graph of the given instances (``<node>`` or ``<vehicle>/<node>`` → its parameters), in order.

    Raises ValueError when a per-step topic would have two publishers (the lockstep needs one
    message per step per topic), when an input names a topic its source does not publish, when
    there is not exactly one time owner, or when lag-0 inputs form a cycle.
    """
    graph = Graph({}) if not params_by_node else Graph(
        {spec.instance: spec for spec in (node_spec(inst.rpartition('/')[2], params)
                                          for inst, params in params_by_node.items())})
    by_topic = graph.publishers()
    for _spec, out in graph.outputs():
        publishers = by_topic[_spec.topic(out.topic)]
        if out.every_step and len(publishers) > 1:
            raise ValueError(f'{_spec.topic(out.topic)} would be published by {" and ".join(publishers)}; '
                             'a per-step topic has one publisher')
    for spec in graph.nodes.values():
        for st in spec.stages:
            for inp in st.inputs:
                source = graph.nodes.get(inp.source)
                if source is not None and spec.topic(inp.topic) not in {source.topic(o.topic) for o in source.outputs}:
                    raise ValueError(f'{spec.instance}.{st.name} reads {spec.topic(inp.topic)} from {inp.source}, '
                                     'which does not publish it')
    graph.firing_order()
    return graph
