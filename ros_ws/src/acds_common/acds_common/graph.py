"""The ACDS node graph, declared once (spec §2): which node publishes what, who consumes it, with which lag.

Both engines are built from this declaration and nothing else:

* the per-process graph: each node process hosts its node's pure stepper
  (:mod:`acds_common.lockstep`), subscribing to exactly the inputs declared here and
  publishing exactly the outputs; the launcher starts one process per declared node and
  its run monitor records every declared output;
* the direct engine (``acds_runtime.direct``): the same steppers in one process, fired in
  an order that respects every lag-0 edge below, values handed over in memory.

A node's declaration depends on its parameters (the em_driver's command source, the mode
manager's system), so each node has one function ``params → NodeSpec``. Stages of a node
fire in declared order, once per step; a stage of step k takes each input of step k − lag
from its source node (``None`` when the source is not in the graph or k − lag < 0).
Outputs are published once per step (``every_step``) unless marked otherwise; the time
owner's truth outputs of step k + 1 come from its stage of step k (``stamp_offset`` 1).
"""

from __future__ import annotations

from collections.abc import Callable, Iterable
from dataclasses import dataclass
from typing import Any

from acds_common import topics

#: The node that owns sim time (publishes ``/clock`` and the truth).
TIME_OWNER = 'rigid_body'
#: The launcher's observer (recorder) in the lockstep handshake, and how far the time owner may run ahead of it.
MONITOR_NAME = 'run_monitor'
MONITOR_LAG = 50
#: The run monitor acknowledges every MONITOR_ACK_EVERY-th /clock step (the time owner waits on it).
MONITOR_ACK_EVERY = 10


@dataclass(frozen=True)
class Output:
    """A published topic: ``key`` in the stepper's result, the topic (relative to ``/acds``), type, frames.

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
        """'package/msg/Type' of the topic (:data:`acds_common.topics.TYPES`)."""
        return topics.TYPES[self.topic]


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
    """One node: its executable (console script ``name`` of ``package``), its stepper class, its ports."""

    name: str
    package: str
    stepper: str
    stages: tuple[Stage, ...]
    outputs: tuple[Output, ...]
    ground_commands: bool = False

    def output(self, key: str) -> Output:
        """The output declared under ``key``."""
        for out in self.outputs:
            if out.key == key:
                return out
        raise KeyError(f'{self.name} declares no output {key!r}')


def _param(params: dict[str, Any], name: str, default: Any) -> Any:
    return params.get(name, default)


def _rigid_body(_params: dict[str, Any]) -> NodeSpec:
    truth = dict(stamp_offset=1)  # step 0 comes from start(), step k + 1 from the stage of step k
    return NodeSpec(
        'rigid_body', 'dynamics', 'dynamics.rigid_body_step:RigidBodyStep',
        (Stage('integrate', (
            Input('dipole', topics.DIPOLE_AVG, 'em_driver'),
            Input('wheel_h', topics.WHEEL_MOMENTUM, 'reaction_wheels'),
            Input('wheel_hdot', topics.WHEEL_TORQUE, 'reaction_wheels'),
            Input('mode', topics.MODE, 'ascs_mode_manager'),
        )),),
        (Output('odometry', topics.TRUTH_ODOMETRY, 'eci', 'body', **truth),
         Output('b_body', topics.TRUTH_B_BODY, 'body', **truth),
         Output('sun_cosines', topics.TRUTH_SUN_COSINES, 'sun_frame', **truth),
         Output('torque_mag', topics.TRUTH_TORQUE_MAG, 'body', **truth),
         Output('torque_gg', topics.TRUTH_TORQUE_GG, 'body', **truth),
         Output('gyro', topics.GYRO, 'body', **truth),
         Output('sun_sensor', topics.SUN_SENSOR, 'body', **truth)))


def _cmg(params: dict[str, Any]) -> bool:
    """Whether the momentum store is the AAP Workshop's CMGs (``wheels.kind: cmg``) rather than wheels."""
    return _param(params, 'wheels_kind', 'wheels') == 'cmg'


def _reaction_wheels(params: dict[str, Any]) -> NodeSpec:
    stage = (Stage('gimbal', (Input('torque', topics.CMG_TORQUE, 'acds_controller'),)) if _cmg(params)
             else Stage('drive', (Input('volts', topics.WHEEL_VOLTS, 'acds_controller'),)))
    return NodeSpec(
        'reaction_wheels', 'dynamics', 'dynamics.reaction_wheels_step:ReactionWheelsStep',
        (stage,),
        (Output('momentum', topics.WHEEL_MOMENTUM, 'body'),
         Output('torque', topics.WHEEL_TORQUE, 'body'),
         Output('diagnostics', topics.DIAGNOSTICS, every_step=False)))


def _magnetometer_sim(_params: dict[str, Any]) -> NodeSpec:
    return NodeSpec(
        'magnetometer_sim', 'magnetometer_sim', 'magnetometer_sim.magnetometer_step:MagnetometerStep',
        (Stage('sample', (
            Input('b_true', topics.TRUTH_B_BODY, 'rigid_body'),
            Input('dipole', topics.DIPOLE_AVG, 'em_driver', lag=1),
            Input('mode', topics.MODE, 'ascs_mode_manager', lag=1),
        )),),
        (Output('volts', topics.MAG_VOLTS, 'magnetometer'),
         Output('bias_volts', topics.MAG_BIAS_VOLTS, 'magnetometer'),
         Output('field', topics.MAG_FIELD, 'magnetometer'),
         Output('diagnostics', topics.DIAGNOSTICS, every_step=False)))


def _em_driver(params: dict[str, Any]) -> NodeSpec:
    source = _param(params, 'em_driver_command_source', 'acds_controller')
    return NodeSpec(
        'em_driver', 'em_driver', 'em_driver.em_driver_step:EmDriverStep',
        (Stage('drive', (
            Input('command', topics.MOMENT_COMMAND, source),
            Input('mode', topics.MODE, 'ascs_mode_manager'),
        )),),
        (Output('dipole_avg', topics.DIPOLE_AVG, 'body'),
         Output('dipole_end', topics.DIPOLE_END, 'body'),
         Output('coil_current', topics.COIL_CURRENT, 'body'),
         Output('e_ft', topics.E_FT, 'body'),
         Output('diagnostics', topics.DIAGNOSTICS, every_step=False)))


def _acds_controller(params: dict[str, Any]) -> NodeSpec:
    store = ((Output('cmg_torque', topics.CMG_TORQUE, 'body'), Output('sampled_momentum', topics.SAMPLED_MOMENTUM,
                                                                      'body'))
             if _cmg(params) else (Output('volts', topics.WHEEL_VOLTS, 'body'),))
    return NodeSpec(
        'acds_controller', 'acds_controller', 'acds_controller.controller_step:ControllerStep',
        (Stage('control', (
            Input('mag_volts', topics.MAG_VOLTS, 'magnetometer_sim'),
            Input('mag_bias', topics.MAG_BIAS_VOLTS, 'magnetometer_sim'),
            Input('gyro', topics.GYRO, 'rigid_body'),
            Input('sun', topics.SUN_SENSOR, 'rigid_body'),
            Input('odometry', topics.TRUTH_ODOMETRY, 'rigid_body'),
            Input('mode', topics.MODE, 'ascs_mode_manager'),
            Input('wheel_h', topics.WHEEL_MOMENTUM, 'reaction_wheels', lag=1),
            Input('wheel_hdot', topics.WHEEL_TORQUE, 'reaction_wheels', lag=1),
            Input('coil_current', topics.COIL_CURRENT, 'em_driver', lag=1),
        )),),
        (Output('moment', topics.MOMENT_COMMAND, 'body'),
         *store,
         Output('diagnostics', topics.DIAGNOSTICS, every_step=False)))


def _ascs_mode_manager(params: dict[str, Any]) -> NodeSpec:
    system = _param(params, 'modes_system', 'heao')
    sss = system == 'sss'
    if sss:
        stage = Stage('sss', (Input('volts', topics.MAG_VOLTS, 'magnetometer_sim'),
                              Input('bias', topics.MAG_BIAS_VOLTS, 'magnetometer_sim')))
    elif system == 'aap':
        stage = Stage('aap', ())  # paced by /clock: the Workshop's modes change by ground command only
    else:
        stage = Stage('heao', (Input('gyro', topics.GYRO, 'rigid_body'),
                               Input('sun', topics.SUN_SENSOR, 'rigid_body')))
    outputs = (Output('mode', topics.MODE),
               *((Output('moment', topics.MOMENT_COMMAND, 'body'),) if sss else ()),
               Output('events', topics.EVENTS, every_step=False, many=True),
               Output('diagnostics', topics.DIAGNOSTICS, every_step=False),
               Output('ack', topics.GROUND_ACK, every_step=False, lockstep=False, many=True))
    return NodeSpec('ascs_mode_manager', 'ascs_mode_manager', 'ascs_mode_manager.mode_manager_step:ModeManagerStep',
                    (stage,), outputs, ground_commands=True)


#: Every node the graph knows, by name: params → its declaration.
NODES: dict[str, Callable[[dict[str, Any]], NodeSpec]] = {
    'rigid_body': _rigid_body,
    'reaction_wheels': _reaction_wheels,
    'magnetometer_sim': _magnetometer_sim,
    'em_driver': _em_driver,
    'acds_controller': _acds_controller,
    'ascs_mode_manager': _ascs_mode_manager,
}


def node_spec(name: str, params: dict[str, Any]) -> NodeSpec:
    """The declaration of node ``name`` for its parameters."""
    try:
        return NODES[name](params)
    except KeyError:
        raise KeyError(f'unknown node {name!r} (known: {", ".join(NODES)})') from None


@dataclass(frozen=True)
class Graph:
    """The declared nodes of one run and the order the direct engine fires their stages in."""

    nodes: dict[str, NodeSpec]

    def present(self, node: str) -> bool:
        """Whether ``node`` is part of this graph."""
        return node in self.nodes

    def outputs(self) -> Iterable[tuple[NodeSpec, Output]]:
        """Every (node, output) of the graph."""
        for spec in self.nodes.values():
            for out in spec.outputs:
                yield spec, out

    def publisher_of(self, topic: str) -> list[str]:
        """The nodes declared to publish ``topic``."""
        return [spec.name for spec, out in self.outputs() if out.topic == topic]

    def firing_order(self) -> list[tuple[str, Stage]]:
        """(node, stage) of every non-time-owner stage, ordered so every lag-0 input is produced first.

        Within a node, stages keep their declared order. The time owner's stages close the step
        and come last. Raises ValueError on a lag-0 cycle (it would deadlock the per-process graph).
        """
        pending = [(name, stage) for name, spec in self.nodes.items() if name != TIME_OWNER for stage in spec.stages]
        producers = {out.topic: spec.name for spec, out in self.outputs() if spec.name != TIME_OWNER}
        done_nodes_stages: dict[str, int] = {name: 0 for name in self.nodes}
        order: list[tuple[str, Stage]] = []
        fired_topics: set[str] = set()
        while pending:
            for i, (name, stage) in enumerate(pending):
                spec = self.nodes[name]
                if spec.stages.index(stage) != done_nodes_stages[name]:
                    continue
                needs = {inp.topic for inp in stage.inputs
                         if inp.lag == 0 and inp.source in self.nodes and inp.source != TIME_OWNER
                         and producers.get(inp.topic) == inp.source}
                if needs <= fired_topics:
                    order.append((name, stage))
                    done_nodes_stages[name] += 1
                    if done_nodes_stages[name] == len(spec.stages):
                        fired_topics.update(out.topic for out in spec.outputs)
                    del pending[i]
                    break
            else:
                raise ValueError('lag-0 cycle among ' + ', '.join(f'{n}.{s.name}' for n, s in pending))
        owner = self.nodes.get(TIME_OWNER)
        return order + ([(TIME_OWNER, s) for s in owner.stages] if owner else [])


def build_graph(params_by_node: dict[str, dict[str, Any]]) -> Graph:
    """The graph of the given nodes (name → its parameters), in the given order.

    Raises ValueError when a per-step topic would have two publishers (the lockstep needs one
    message per step per topic) or when lag-0 inputs form a cycle.
    """
    graph = Graph({name: node_spec(name, params) for name, params in params_by_node.items()})
    for _spec, out in graph.outputs():
        publishers = graph.publisher_of(out.topic)
        if out.every_step and len(publishers) > 1:
            raise ValueError(f'{topics.resolve(out.topic)} would be published by {" and ".join(publishers)}; '
                             'a per-step topic has one publisher')
    graph.firing_order()
    return graph
