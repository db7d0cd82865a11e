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
from dataclasses import dataclass, replace
from typing import Any

from acds_common import topics
from acds_common.frames import BODY, ECI, FORMATION, MAGNETOMETER, vehicle_body

#: The node that owns sim time (publishes ``/clock`` and the truth) of a single-vehicle graph, and every
#: node that can own it (a formation's is ``formation_dynamics``).
TIME_OWNER = 'rigid_body'
TIME_OWNERS = ('rigid_body', 'formation_dynamics')
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
        """'package/msg/Type' of the topic (:func:`acds_common.topics.type_of`)."""
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
            Input('gas_wrench', topics.COLD_GAS_WRENCH, 'cold_gas'),  # the cold-gas thrusters (node cold_gas)
        )),),
        (Output('odometry', topics.TRUTH_ODOMETRY, ECI, BODY, **truth),
         Output('b_body', topics.TRUTH_B_BODY, BODY, **truth),
         Output('sun_cosines', topics.TRUTH_SUN_COSINES, BODY, **truth),  # the sun frame's z in body components
         Output('torque_mag', topics.TRUTH_TORQUE_MAG, BODY, **truth),
         Output('torque_gg', topics.TRUTH_TORQUE_GG, BODY, **truth),
         Output('gyro', topics.GYRO, BODY, **truth),
         Output('sun_sensor', topics.SUN_SENSOR, BODY, **truth),
         Output('diagnostics', topics.DIAGNOSTICS, every_step=False)),
        time_owner=True)


def _cmg(params: dict[str, Any]) -> bool:
    """Whether the momentum store is the AAP Workshop's CMGs (``wheels.kind: cmg``) rather than wheels."""
    return _param(params, 'wheels_kind', 'wheels') == 'cmg'


def _reaction_wheels(params: dict[str, Any]) -> NodeSpec:
    if _cmg(params):  # the Workshop's CMGs: the controller's momentum-rate command (seed 000)
        stage = Stage('gimbal', (Input('torque', topics.CMG_TORQUE, 'acds_controller'),))
    elif _param(params, 'wheels_drive', 'volts') == 'torque':  # torque-commanded wheels (a formation vehicle)
        stage = Stage('drive', (Input('torque', topics.WHEEL_TORQUE_COMMAND, 'formation_controller'),))
    else:
        stage = Stage('drive', (Input('volts', topics.WHEEL_VOLTS, 'acds_controller'),))
    return NodeSpec(
        'reaction_wheels', 'dynamics', 'dynamics.reaction_wheels_step:ReactionWheelsStep',
        (stage,),
        (Output('momentum', topics.WHEEL_MOMENTUM, BODY),
         Output('torque', topics.WHEEL_TORQUE, BODY),
         Output('diagnostics', topics.DIAGNOSTICS, every_step=False)))


def _magnetometer_sim(_params: dict[str, Any]) -> NodeSpec:
    return NodeSpec(
        'magnetometer_sim', 'magnetometer_sim', 'magnetometer_sim.magnetometer_step:MagnetometerStep',
        (Stage('sample', (
            Input('b_true', topics.TRUTH_B_BODY, 'rigid_body'),
            Input('dipole', topics.DIPOLE_AVG, 'em_driver', lag=1),
            Input('mode', topics.MODE, 'ascs_mode_manager', lag=1),
        )),),
        (Output('volts', topics.MAG_VOLTS, MAGNETOMETER),
         Output('bias_volts', topics.MAG_BIAS_VOLTS, MAGNETOMETER),
         Output('field', topics.MAG_FIELD, MAGNETOMETER),
         Output('diagnostics', topics.DIAGNOSTICS, every_step=False)))


def _em_driver(params: dict[str, Any]) -> NodeSpec:
    source = _param(params, 'em_driver_command_source', 'acds_controller')
    rods = _param(params, 'em_driver_driver_kind', 'electromagnet') == 'torque_rod'
    # The torque rods' bus power and duty every step: the CubeSat summary's energy and duty (seed 003).
    electrical = (Output('power', topics.COIL_POWER, BODY), Output('duty', topics.COIL_DUTY, BODY)) if rods else ()
    return NodeSpec(
        'em_driver', 'em_driver', 'em_driver.em_driver_step:EmDriverStep',
        (Stage('drive', (
            Input('command', topics.MOMENT_COMMAND, source),
            Input('mode', topics.MODE, 'ascs_mode_manager'),
        )),),
        (Output('dipole_avg', topics.DIPOLE_AVG, BODY),
         Output('dipole_end', topics.DIPOLE_END, BODY),
         Output('coil_current', topics.COIL_CURRENT, BODY),
         Output('e_ft', topics.E_FT, BODY),
         *electrical,
         Output('diagnostics', topics.DIAGNOSTICS, every_step=False)))


def _acds_controller(params: dict[str, Any]) -> NodeSpec:
    store = ((Output('cmg_torque', topics.CMG_TORQUE, BODY), Output('sampled_momentum', topics.SAMPLED_MOMENTUM, BODY))
             if _cmg(params) else (Output('volts', topics.WHEEL_VOLTS, BODY),))
    stepper, gas = 'acds_controller.controller_step:ControllerStep', ()
    if _cold_gas_in_graph(params):  # the variant that also flies the cold-gas acquisition (seed 002 §3.1)
        stepper = 'acds_controller.cold_gas_controller_step:ColdGasControllerStep'
        gas = (Output('gas_on_time', topics.GAS_ON_TIME, BODY),)
    return NodeSpec(
        'acds_controller', 'acds_controller', stepper,
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
        (Output('moment', topics.MOMENT_COMMAND, BODY),
         *store,
         *gas,
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
               *((Output('moment', topics.MOMENT_COMMAND, BODY),) if sss else ()),
               Output('events', topics.EVENTS, every_step=False, many=True),
               Output('diagnostics', topics.DIAGNOSTICS, every_step=False),
               Output('ack', topics.GROUND_ACK, every_step=False, lockstep=False, many=True))
    return NodeSpec('ascs_mode_manager', 'ascs_mode_manager', 'ascs_mode_manager.mode_manager_step:ModeManagerStep',
                    (stage,), outputs, ground_commands=True)


def _formation_dynamics(params: dict[str, Any]) -> NodeSpec:
    """The formation's time owner: every vehicle's translation and attitude (spec §10; seed 004).

    Step k takes each vehicle's achieved dipole and wheel momentum/rate of step k (from that vehicle's
    em_driver and reaction_wheels, in its namespace) and returns each vehicle's truth of step k + 1
    under ``/acds/<vehicle>/``: the single-vehicle topic names, so each vehicle's nodes read them as a
    single vehicle's nodes would.
    """
    truth = dict(stamp_offset=1)
    inputs: list[Input] = []
    outputs: list[Output] = []
    for v in _param(params, 'formation_vehicles', []):
        inputs += [Input(f'{v}/dipole', f'{v}/{topics.DIPOLE_AVG}', f'{v}/em_driver'),
                   Input(f'{v}/wheel_h', f'{v}/{topics.WHEEL_MOMENTUM}', f'{v}/reaction_wheels'),
                   Input(f'{v}/wheel_hdot', f'{v}/{topics.WHEEL_TORQUE}', f'{v}/reaction_wheels')]
        body = vehicle_body(v)
        outputs += [Output(f'{v}/odometry', f'{v}/{topics.TRUTH_ODOMETRY}', FORMATION, body, **truth),
                    Output(f'{v}/gyro', f'{v}/{topics.GYRO}', body, **truth),
                    Output(f'{v}/b_body', f'{v}/{topics.TRUTH_B_BODY}', body, **truth),
                    Output(f'{v}/wrench', f'{v}/{topics.TRUTH_WRENCH}', body, **truth)]
    return NodeSpec('formation_dynamics', 'dynamics', 'dynamics.formation_step:FormationDynamicsStep',
                    (Stage('integrate', tuple(inputs)),), tuple(outputs), time_owner=True)


def _formation_controller(params: dict[str, Any]) -> NodeSpec:
    """One vehicle's formation controller: every vehicle's truth of step k and wheel momentum of step k − 1
    (the RF link of seed 004 slide 70); it returns its own vehicle's dipole and wheel torque commands."""
    inputs: list[Input] = []
    for w in _param(params, 'formation_vehicles', []):
        ns = f'{topics.NAMESPACE}/{w}'
        inputs += [Input(f'{w}/odometry', f'{ns}/{topics.TRUTH_ODOMETRY}', 'formation_dynamics'),
                   Input(f'{w}/gyro', f'{ns}/{topics.GYRO}', 'formation_dynamics'),
                   Input(f'{w}/b_body', f'{ns}/{topics.TRUTH_B_BODY}', 'formation_dynamics'),
                   Input(f'{w}/wheel_h', f'{ns}/{topics.WHEEL_MOMENTUM}', f'{w}/reaction_wheels', lag=1),
                   Input(f'{w}/wheel_hdot', f'{ns}/{topics.WHEEL_TORQUE}', f'{w}/reaction_wheels', lag=1)]
    return NodeSpec('formation_controller', 'acds_controller',
                    'acds_controller.formation_controller_step:FormationControllerStep',
                    (Stage('control', tuple(inputs)),),
                    (Output('moment', topics.MOMENT_COMMAND, BODY),
                     Output('wheel_torque', topics.WHEEL_TORQUE_COMMAND, BODY),
                     Output('diagnostics', topics.DIAGNOSTICS, every_step=False)))


# ---- cold_gas (seed 002 §5): the whole declaration of the node, and how the others see it --------------------
def _cold_gas_in_graph(params: dict[str, Any]) -> bool:
    """Whether the graph flies the cold-gas reaction control subsystem (node ``cold_gas`` in the scenario's nodes)."""
    return 'cold_gas' in _param(params, 'graph_nodes', [])


def _cold_gas(_params: dict[str, Any]) -> NodeSpec:
    """The cold-gas subsystem: the controller's on-time requests and the mode (forwarded ground commands) of step k
    in; the thrusters' step-average wrench (to the rigid body), the subsystem state every step, telemetry out."""
    return NodeSpec(
        'cold_gas', 'cold_gas', 'cold_gas.cold_gas_step:ColdGasStep',
        (Stage('fire', (Input('pulse', topics.GAS_ON_TIME, 'acds_controller'),
                        Input('mode', topics.MODE, 'ascs_mode_manager'))),),
        (Output('wrench', topics.COLD_GAS_WRENCH, BODY),
         Output('state', topics.COLD_GAS_STATE),
         Output('diagnostics', topics.DIAGNOSTICS, every_step=False)))
# ---- end cold_gas ----------------------------------------------------------------------------------------------


#: Every node the graph knows, by name: params → its declaration.
NODES: dict[str, Callable[[dict[str, Any]], NodeSpec]] = {
    'rigid_body': _rigid_body,
    'reaction_wheels': _reaction_wheels,
    'magnetometer_sim': _magnetometer_sim,
    'em_driver': _em_driver,
    'acds_controller': _acds_controller,
    'ascs_mode_manager': _ascs_mode_manager,
    'formation_dynamics': _formation_dynamics,
    'formation_controller': _formation_controller,
    'cold_gas': _cold_gas,
}


def node_spec(name: str, params: dict[str, Any]) -> NodeSpec:
    """The declaration of node ``name`` for its parameters.

    A node of one vehicle of a formation (parameter ``vehicle``) gets the single-vehicle ports under
    the vehicle's namespace; its inputs from the vehicle's own nodes (those of ``graph_nodes`` named
    ``<vehicle>/<node>``) are qualified with the vehicle, inputs from nodes of the whole graph (the
    formation's time owner, the run monitor) stay as they are.
    """
    try:
        spec = NODES[name](params)
    except KeyError:
        raise KeyError(f'unknown node {name!r} (known: {", ".join(NODES)})') from None
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

    def publisher_of(self, topic: str) -> list[str]:
        """The instances declared to publish ``topic`` (absolute name)."""
        return [spec.instance for spec, out in self.outputs() if spec.topic(out.topic) == topic]

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
    for _spec, out in graph.outputs():
        publishers = graph.publisher_of(_spec.topic(out.topic))
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
