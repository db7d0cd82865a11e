"""The ROS host of a node's stepper: lockstep sim time over topics (spec §2, "Time and determinism").

Every ACDS node process is a :class:`LockstepNode` hosting its package's pure stepper
(:mod:`acds_common.stepper`) with the ports the graph declares for it
(:mod:`acds_common.graph`). The time owner (``rigid_body``) publishes the truth of step k
and ``/clock``; every other node fires a stage for step k as soon as it holds each of the
stage's inputs for its step (k − lag), in declared order, one step at a time, so a node is a
deterministic function of its inputs whatever the arrival order. The time owner integrates
t_k → t_k+1 only after it holds every actuator output of step k, and never runs more than
:data:`~acds_common.graph.MONITOR_LAG` steps ahead of the run monitor's acknowledgements.

Messages travel serialized (rclpy ``raw=True`` subscriptions, ``publish(bytes)``) and are
converted by :mod:`acds_common.cdr`, so the bytes on the wire are exactly what the direct
engine records. A node subscribes to ``/clock`` only when a stage has no lag-0 input from a
present node (the arrival of a lag-0 input is itself the news that step k exists); nodes
never read ROS time, so the launcher does not give them ``use_sim_time`` (it still works
for a user who sets it).

Safety: inputs from nodes not in the graph (parameter ``graph_nodes``) are absent (``None``).
A second message for a step already held or consumed means a publisher the graph does not
declare is on the topic: the node fails naming the topic, the step and the publishers it
sees — injected data is never used silently. A stage blocked longer than
``input_timeout_s`` (wall time) fails naming the node, the step and every missing topic
with its source. Step identity is exact: stamps are integer nanoseconds, k = t_ns / Δt_ns.

End of a run: the time owner publishes its last step on ``/acds/lockstep/run_end`` as it
finishes, before it delivers its last messages and leaves. A node then waits for no step after
that one (it stays until the launcher stops it, however long the time owner's exit takes);
a stage of an earlier step still has its timeout.
"""

from __future__ import annotations

import faulthandler
import importlib
import os
import signal
import sys
import time
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

import rclpy
from rcl_interfaces.msg import FloatingPointRange, IntegerRange, ParameterDescriptor
from rclpy.clock import Clock, ClockType
from rclpy.executors import ExternalShutdownException
from rclpy.node import Node
from rclpy.parameter import Parameter
from rclpy.qos import DurabilityPolicy, HistoryPolicy, QoSProfile, ReliabilityPolicy
from rclpy.task import Future

from acds_common import numeric_config, topics
from acds_common.cdr import Codec, stamp_ns
from acds_common.graph import (
    MONITOR_LAG,
    MONITOR_NAME,
    Input,
    NodeSpec,
    Output,
    external_of,
    instance_name,
    monitor_allows,
    node_spec,
    time_owner_among,
)
from acds_common.parameters import (
    FORMATION_VEHICLES,
    LOCKSTEP,
    ConfigError,
    ParamSpec,
    formation_wide,
    node_param_specs,
    normalize,
)
from acds_common.parent_death import die_with
from acds_common.profiling import profiled
from acds_common.stepper import StepError, load_stepper
from acds_common.timing import StepTimes, overrun

#: What a node that is not the time owner waited for when /clock stopped (its failure line; the launcher reads the step
#: back with :func:`clock_step_waited_for`).
CLOCK_WAIT = 'for /clock step {k} from the time owner'

#: QoS of every lockstep data topic: nothing is dropped between matched endpoints, late joiners
#: get the history, and the history is deep enough for an observer (recorder) that runs up to
#: MONITOR_LAG steps behind.
LOCKSTEP_QOS = QoSProfile(
    reliability=ReliabilityPolicy.RELIABLE,
    durability=DurabilityPolicy.TRANSIENT_LOCAL,
    history=HistoryPolicy.KEEP_LAST,
    depth=1000,
)
#: QoS of ground commands and acknowledgements: reliable, with a history deep enough that a burst
#: of commands (or of their answers) is queued, never overwritten before delivery, and a publisher
#: never blocks (every command gets an ack, spec §8; the mode manager refuses, with an ack, what
#: exceeds its own queue: ``ascs_mode_manager.ground_commands.MAX_PENDING``).
COMMAND_QOS = QoSProfile(
    reliability=ReliabilityPolicy.RELIABLE,
    durability=DurabilityPolicy.VOLATILE,
    history=HistoryPolicy.KEEP_LAST,
    depth=10000,
)
#: Exit codes of a node process (EXIT_ORPHANED: the launcher that started it died).
EXIT_OK, EXIT_CONFIG, EXIT_LOCKSTEP, EXIT_ORPHANED = 0, 2, 3, 4
#: Environment variable the launcher sets to its own pid: a node started by a launcher asks the kernel to
#: SIGKILL it when that launcher dies (``PR_SET_PDEATHSIG``), and leaves at once if it already has.
LAUNCHER_PID_ENV = 'ACDS_LAUNCHER_PID'
#: Environment variable the launcher sets to the CPU it places a node process on (:mod:`acds_runtime.placement`): the
#: process binds itself and its threads there as its first stage fires (:func:`take_cpu`).
CPU_ENV = 'ACDS_CPU'
#: Signals that stop a node cleanly (flush, exit 0): Ctrl-C, kill, a closed terminal.
STOP_SIGNALS = (signal.SIGINT, signal.SIGTERM, signal.SIGHUP)
#: Seconds a launcher gives a node to stop after SIGINT before it SIGKILLs it.
STOP_GRACE_S = 10.0
#: A node still running this long after its main loop ended (its flush takes at most 5 s) prints every thread's
#: stack to its output, so the launcher's report of a hung exit says where it hung.
STUCK_TRACE_S = 7.0
#: How a node announces a lockstep failure on stderr, and the other lines that mean a node has failed (a
#: configuration error, an uncaught exception): the launcher names the first node to print one, even if the
#: process is still leaving.
FAILURE_MARK = 'LOCKSTEP FAILURE: '
FAILURE_LINES = (FAILURE_MARK, 'CONFIGURATION ERROR: ', 'Traceback (most recent call last):')
#: The signal that makes a node print its Python stack (faulthandler): the launcher asks a node the graph
#: waited on for it, so a hang is reported with where it hangs.
STACK_SIGNAL = signal.SIGUSR1
#: What the time owner prints as it leaves a completed run, followed by its last step: the launcher's word for where
#: the run ends (the run monitor may still be draining steps before it; issue 18 §1).
COMPLETE_PREFIX = 'RUN COMPLETE at step '
#: Wall seconds the graph may take to become ready and fire its first step (at least; ``input_timeout_s`` if longer).
READY_TIMEOUT_S = 20.0
#: A watchdog tick (every 0.1 s) this much later than the one before means the process did not run in between
#: (SIGSTOP, a cgroup freezer, a starved or suspended machine): that gap is not time spent waiting (issue 18 §4).
FROZEN_GAP_S = 1.0
#: Seconds between checks that every input topic has only its declared publisher.
INTRUDER_CHECK_PERIOD_S = 1.0
#: What discovery reports for a publisher whose node name it has not learnt yet, and how long it may stay so.
UNNAMED = '_NODE_NAME_UNKNOWN_'
UNNAMED_GRACE_S = 5.0
_PARAM_TYPES = {'float': Parameter.Type.DOUBLE, 'int': Parameter.Type.INTEGER, 'bool': Parameter.Type.BOOL,
                'str': Parameter.Type.STRING, 'floats': Parameter.Type.DOUBLE_ARRAY,
                'strs': Parameter.Type.STRING_ARRAY}


#: Wall seconds a node's :class:`Spinner` runs callbacks before its loop looks at the node again (a stop signal's
#: latency while messages flow).
SPIN_PERIOD_S = 0.1


class Spinner:
    """Runs an ``EventsExecutor``'s callbacks in its C++ loop, from one message to the next, for a period at a time.

    A Python loop around ``spin_once`` returns to the interpreter after every message: with some forty deliveries a
    step, the six-process graph spent 2.70-2.75 CPU ms a step that way, 2.40-2.55 this way (docs/measurements.md).
    :meth:`spin` stays in the executor until :meth:`wake` or ``period_s`` has passed. :meth:`wake` is for callbacks and
    other threads; a signal handler only sets its flag (it may run while this thread holds the future's lock), seen
    within a period.
    """

    def __init__(self, executor: Any) -> None:
        self._executor = executor
        self._wake = Future()

    def spin(self, period_s: float) -> None:
        """Run callbacks for ``period_s`` wall seconds, or until :meth:`wake`."""
        self._wake = Future()
        self._executor.spin_until_future_complete(self._wake, timeout_sec=period_s)

    def wake(self) -> None:
        """End the running :meth:`spin` once the callback running now returns."""
        wake = self._wake
        if not wake.done():
            wake.set_result(None)


def _nothing() -> None:
    """What a node wakes before a :class:`Spinner` runs it."""


class LockstepError(RuntimeError):
    """A lockstep contract was broken (missing input past its timeout, bad stamp, an intruder)."""


def message_class(type_name: str) -> type:
    """'pkg/msg/Type' → the rclpy message class."""
    pkg, _, name = type_name.split('/')
    return getattr(importlib.import_module(f'{pkg}.msg'), name)


def descriptor(spec: ParamSpec) -> ParameterDescriptor:
    """A read-only ROS parameter descriptor carrying the spec's meaning, unit, range and choices."""
    text = spec.description + (f' [{spec.unit}]' if spec.unit else '')
    desc = ParameterDescriptor(description=text, read_only=True)
    if spec.choices:
        desc.additional_constraints = 'one of: ' + ', '.join(spec.choices)
    if spec.lo is not None and spec.hi is not None and spec.kind in ('float', 'int'):
        if spec.kind == 'float':
            desc.floating_point_range = [FloatingPointRange(from_value=float(spec.lo), to_value=float(spec.hi))]
        else:
            desc.integer_range = [IntegerRange(from_value=int(spec.lo), to_value=int(spec.hi), step=1)]
    elif spec.lo is not None or spec.hi is not None:
        desc.additional_constraints = f'range [{spec.lo}, {spec.hi}] {spec.unit}'.strip()
    return desc


@dataclass
class _Stage:
    name: str
    inputs: tuple[Input, ...]
    handler: Callable[[int, float, dict[str, Any]], dict[str, Any]]
    paced_by_clock: bool
    next_step: int = 0
    #: Per input, in declared order: its key, the buffer of its topic (None: its source is not in the graph) and its lag.
    reads: tuple[tuple[str, dict[int, Any] | None, int], ...] = ()

    def values(self, k: int) -> dict[str, Any] | None:
        """Step k's input values by key (None for an input whose source is not in the graph or before its lag's first
        step), or None while one has not arrived."""
        values: dict[str, Any] = {}
        for key, buffer, lag in self.reads:
            if buffer is None or k < lag:
                values[key] = None
                continue
            value = buffer.get(k - lag, _MISSING)
            if value is _MISSING:
                return None
            values[key] = value
        return values

    def missing(self, k: int) -> list[Input]:
        """The inputs of step k that have not arrived."""
        return [inp for inp, (_key, buffer, lag) in zip(self.inputs, self.reads, strict=True)
                if buffer is not None and k >= lag and k - lag not in buffer]


#: What a buffer lookup returns for a step not received yet.
_MISSING = object()


@dataclass
class _Port:
    output: Output
    codec: Codec
    publisher: Any
    stamp_offset: int = 0
    sent: int = 0
    #: The node's /diagnostics: its own status carries the step timing (wall-clock keys).
    diagnostics: bool = False


def publisher_name(info: Any) -> str:
    """The graph name of an endpoint discovery reports (rclpy ``TopicEndpointInfo``): its node's instance name, or
    :data:`UNNAMED` while discovery has not learnt the node's name."""
    return UNNAMED if info.node_name == UNNAMED else instance_name(info.node_namespace, info.node_name)


class PublisherCheck:
    """Who publishes a topic against who may (one rule for the nodes and the run monitor).

    Discovery can report a publisher before its node's name (``_NODE_NAME_UNKNOWN_``, the name travels on a
    separate discovery topic): an unnamed publisher may be a declared node whose name has not arrived, and a
    node stopped (SIGSTOP, a debugger) before it arrived stays unnamed. So unnamed publishers count as strangers
    only beyond the declared nodes not seen by name, and only once that excess has lasted
    :data:`UNNAMED_GRACE_S`; a named publisher that is not declared, or a second node of a declared name, is a
    stranger at once.
    """

    def __init__(self) -> None:
        self._excess_since: dict[str, float] = {}

    def strangers(self, topic: str, infos: Any, declared: set[str], now: float) -> list[str]:
        """The publishers of ``topic`` (rclpy endpoint infos) the graph does not declare, as sorted phrases."""
        names = [publisher_name(i) for i in infos]
        named = [n for n in names if n != UNNAMED]
        out = sorted({n for n in named if n not in declared})
        out += [f'a second node named {s}' for s in sorted(declared) if named.count(s) > 1]
        excess = names.count(UNNAMED) - len(declared - set(named))
        if excess <= 0:
            self._excess_since.pop(topic, None)
        elif now - self._excess_since.setdefault(topic, now) >= UNNAMED_GRACE_S:
            out.append('a publisher without a ROS node name')
        return out


def sequence_error(topic: str, publisher: str, t_ns: int, last: int, dt_ns: int) -> str:
    """'' when a message stamped ``t_ns`` is the next step of a per-step topic whose last step was ``last``; else
    the one line that fails the run: the topic, the publisher, the step expected and what came (issue 20 §1: an
    external node that publishes twice for one step, skips one or stamps a wrong time)."""
    expected = last + 1
    if t_ns == expected * dt_ns:
        return ''
    k, rem = divmod(t_ns, dt_ns)
    if rem:
        got = f'stamp {t_ns} ns, not a step time (a multiple of Δt = {dt_ns} ns)'
    elif k < last:  # a publisher whose steps start over: its transient-local history held another run's steps
        got = (f'step {k} after step {last} (its steps went back: were its earlier messages kept from another run on '
               'this ROS domain? restart the node for each run)')
    elif k == last:
        got = f'a second message for step {k}'
    else:
        got = f'step {k}, skipping step {expected}' if k > expected else f'step {k}'
    return (f'{topic}: {publisher} sent {got}; expected one message for step {expected}, stamped '
            f'{expected * dt_ns} ns (t = {expected * dt_ns / 1e9:g} s)')


@dataclass
class _InputTopic:
    topic: str
    source: str
    codec: Codec
    buffer: dict[int, Any] = field(default_factory=dict)
    consumed_below: int = 0
    #: The last step received (an external source must send every step once, in order).
    last: int = -1


class LockstepNode(Node):
    """Hosts one node's stepper in the lockstep: parameters, ports, stages, readiness, watchdog."""

    def __init__(self, name: str) -> None:
        super().__init__(name, namespace=topics.NAMESPACE)
        vehicles: list[str] = []
        wide = formation_wide(name)
        if wide:  # the formation's vehicles decide which parameters there are
            vehicles = list(self.declare_parameter(FORMATION_VEHICLES.name, Parameter.Type.STRING_ARRAY,
                                                   descriptor(FORMATION_VEHICLES)).value or [])
        # The graph's nodes decide which sections the node reads (Node.sections_with): declared first.
        graph_spec = next(s for s in LOCKSTEP if s.name == 'graph_nodes')
        given = self.declare_parameter(graph_spec.name, Parameter.Type.STRING_ARRAY, descriptor(graph_spec)).value
        declared = {graph_spec.name: None if given is None else list(given)}
        if wide:
            declared[FORMATION_VEHICLES.name] = vehicles
        self.params = normalize(name, self._declare_parameters(
            [s for s in node_param_specs(name, vehicles, declared[graph_spec.name] or ()) if s.name not in declared],
            declared))
        self.spec: NodeSpec = node_spec(name, self.params)
        if self.get_namespace() != self.spec.namespace:
            raise ConfigError(f'{name}: runs in namespace {self.get_namespace()} but its parameter vehicle='
                              f'{self.params["vehicle"]!r} means {self.spec.namespace} (--ros-args -r __ns:=...)')
        self.instance = self.spec.instance
        self.time_owner = self.spec.time_owner
        self.dt_ns = round(self.params['control_period_s'] * 1e9)
        self.graph_nodes: list[str] = self.params['graph_nodes']
        #: The nodes the user runs (issue 20): their ROS identity; they send no READY.
        self.external = external_of(self.params)
        self.input_timeout_s: float = self.params['input_timeout_s']
        self.stepper = load_stepper(self.spec.stepper)(self.params, log=self._log)
        self.failure: str | None = None
        self.done = False
        #: Called when the node's main loop should look at it again (it has failed or finished): its Spinner's wake.
        self.wake: Callable[[], None] = _nothing
        #: The step whose stage found the stepper finished (the run's last step), once done.
        self.last_step: int | None = None
        self._ports: dict[str, _Port] = {}
        for out in self.spec.outputs:
            qos = LOCKSTEP_QOS if out.lockstep else COMMAND_QOS
            self._ports[out.key] = _Port(out, Codec(out.msg_type, out.frame_id, out.child_frame_id),
                                         self.create_publisher(message_class(out.msg_type), out.topic, qos),
                                         out.stamp_offset, diagnostics=out.topic == topics.DIAGNOSTICS)
        self._inputs: dict[str, _InputTopic] = {}
        self._stages: list[_Stage] = []
        for st in self.spec.stages:
            present = [i for i in st.inputs if i.source in self.graph_nodes]
            for inp in present:
                self._add_input(inp.topic, inp.source)
            paced = not any(i.lag == 0 for i in present)
            reads = tuple((i.key, self._inputs[i.topic].buffer if i in present else None, i.lag) for i in st.inputs)
            self._stages.append(_Stage(st.name, st.inputs, getattr(self.stepper, st.name), paced, reads=reads))
        self._clock_step = -1
        #: The run's last step, once the time owner has announced it (no stage waits for a later one).
        self._final_step: int | None = None
        self._monitor_acked = -1
        #: Whether the run monitor paces this node (the time owner of a graph that has one).
        self._paced_by_monitor = self.time_owner and MONITOR_NAME in self.graph_nodes
        self._firing = False
        #: Bound to the CPU the launcher placed it on (:func:`take_cpu`): done as the first stage fires, once the graph
        #: is up, so discovery and the start run wherever the OS puts them.
        self._placed = False
        self._started = False
        self._ready_sent = False
        self._ready_from: set[str] = set()
        self._last_progress = time.monotonic()
        self._created = time.monotonic()
        self._last_tick = time.monotonic()
        #: The launcher that started this node (0: started by hand); while it is stopped the graph is paused.
        self._launcher = int(os.environ.get(LAUNCHER_PID_ENV, '0') or 0)
        self._last_intruder_check = 0.0
        self._publisher_check = PublisherCheck()
        self._max_lag = max((i.lag for s in self._stages for i in s.inputs), default=0)
        #: Wall time per step (issue 20 §4): each stage from ready to published, summed over the step's stages.
        self.timing = StepTimes(self.params['deadline_ms'] / 1e3)
        self._step_wall = 0.0
        if self.time_owner:
            self.total_steps: int = self.params['total_steps']
            self.real_time_factor: float = self.params['real_time_factor']
            self._clock_pub = self.create_publisher(message_class(topics.TYPES[topics.CLOCK]), topics.CLOCK,
                                                    LOCKSTEP_QOS)
            self._clock_codec = Codec(topics.TYPES[topics.CLOCK])
            self._end_pub = self.create_publisher(message_class(topics.TYPES[topics.RUN_END]), topics.RUN_END,
                                                  LOCKSTEP_QOS)
            self._pace_timer: Any = None
            self._wall_start = 0.0
            self._raw_sub(topics.READY, self._on_ready)
            if MONITOR_NAME in self.graph_nodes:
                self._raw_sub(topics.MONITOR_ACK, self._on_monitor_ack)
        else:
            if any(s.paced_by_clock for s in self._stages):
                self._raw_sub(topics.CLOCK, self._on_clock)
            self._raw_sub(topics.RUN_END, self._on_run_end)
            self._ready_pub = self.create_publisher(message_class(topics.TYPES[topics.READY]), topics.READY,
                                                    LOCKSTEP_QOS)
        if self.spec.ground_commands:
            text = Codec(topics.TYPES[topics.GROUND_COMMAND])
            self.create_subscription(message_class(topics.TYPES[topics.GROUND_COMMAND]), topics.GROUND_COMMAND,
                                     lambda data: self.stepper.receive_command(text.decode(data)[1]),
                                     COMMAND_QOS, raw=True)
        self.create_timer(0.1, self._watchdog, clock=Clock(clock_type=ClockType.STEADY_TIME))

    # ---- declarations -------------------------------------------------------------------------
    def _declare_parameters(self, specs: list[ParamSpec], declared: dict[str, Any]) -> dict[str, Any]:
        """Declare every parameter (typed, described, ranged, read-only); {name: value or None if not given}.

        ``declared``: parameters already declared, with their values (merged into the result).
        """
        given: dict[str, Any] = dict(declared)
        for spec in specs:
            desc = descriptor(spec)
            if spec.required or spec.default == []:
                param = self.declare_parameter(spec.name, _PARAM_TYPES[spec.kind], desc)
            else:
                param = self.declare_parameter(spec.name, spec.default, desc)
            value = param.value
            given[spec.name] = list(value) if isinstance(value, (list, tuple)) or hasattr(value, 'tolist') else value
        unknown = sorted(set(self._parameter_overrides) - {s.name for s in specs} - set(declared) - {'use_sim_time'})
        if unknown:
            raise ConfigError(f'{self.get_name()}: unknown parameter(s) {", ".join(unknown)} '
                              f'(declared: {", ".join(sorted(s.name for s in specs))})')
        return given

    def _raw_sub(self, topic: str, callback: Callable[[bytes], None]) -> None:
        self.create_subscription(message_class(topics.type_of(topic)), topic, callback, LOCKSTEP_QOS, raw=True)

    def _add_input(self, topic: str, source: str) -> None:
        if topic in self._inputs:
            return
        self._inputs[topic] = _InputTopic(topic, source, Codec(topics.type_of(topic)))
        self._raw_sub(topic, lambda data, t=topic: self._on_input(t, data))

    def _log(self, level: str, text: str) -> None:
        logger = self.get_logger()  # rclpy ties a severity to each call site: one call per level
        if level == 'error':
            logger.error(text)
        elif level == 'warn':
            logger.warning(text)
        else:
            logger.info(text)

    # ---- time --------------------------------------------------------------------------------------
    def step_time_s(self, k: int) -> float:
        """t_k in seconds."""
        return k * self.dt_ns / 1e9

    def _publish(self, outputs: dict[str, Any], k: int, *, initial: bool = False) -> None:
        """Publish a stage's outputs of step k (each stamped k + its offset; ``initial``: step 0 itself)."""
        for key, value in outputs.items():
            port = self._ports.get(key)
            if port is None:
                raise LockstepError(f'{self.get_name()}: stepper returned undeclared output {key!r}')
            t_ns = (k + (0 if initial else port.stamp_offset)) * self.dt_ns
            if port.diagnostics:
                value = self._with_timing(value)
            for item in (value if port.output.many else (value,)):
                port.publisher.publish(port.codec.encode(t_ns, item))
                port.sent += 1

    def _with_timing(self, statuses: Any) -> Any:
        """The node's diagnostics with its step timing added to its own status (wall-clock keys)."""
        own = next((i for i, st in enumerate(statuses) if st.name == self.instance), 0)
        return tuple(st._replace(values=st.values + self.timing.diagnostic_values()) if i == own else st
                     for i, st in enumerate(statuses))

    def _publish_clock(self, k: int) -> None:
        """Time owner only: announce step k on ``/clock`` (paced at ``real_time_factor``, on a timer)."""
        if k == 0:
            self._wall_start = time.monotonic()
        delay = self._wall_start + self.step_time_s(k) / self.real_time_factor - time.monotonic() \
            if self.real_time_factor > 0 else 0.0
        if delay > 1e-3:
            def fire() -> None:
                self._pace_timer.cancel()
                self.destroy_timer(self._pace_timer)
                self._announce(k)
            self._pace_timer = self.create_timer(delay, fire, clock=Clock(clock_type=ClockType.STEADY_TIME))
        else:
            self._announce(k)

    def _announce(self, k: int) -> None:
        self._clock_pub.publish(self._clock_codec.encode(k * self.dt_ns))
        self._clock_step = k
        self._last_progress = time.monotonic()
        self._try_fire()

    # ---- callbacks -------------------------------------------------------------------------------
    def _on_ready(self, data: bytes) -> None:
        self._ready_from.add(Codec(topics.TYPES[topics.READY]).decode(data)[1])

    def _on_monitor_ack(self, data: bytes) -> None:
        self._monitor_acked = max(self._monitor_acked, stamp_ns(data) // self.dt_ns)
        self._try_fire()

    def _on_run_end(self, data: bytes) -> None:
        self._final_step = self._step_of(topics.RUN_END, stamp_ns(data))

    def _step_of(self, topic: str, t_ns: int) -> int | None:
        k, rem = divmod(t_ns, self.dt_ns)
        if rem:
            self.fail(f'{self.resolve_topic_name(topic)} carries stamp {t_ns} ns, not a multiple of '
                      f'Δt={self.dt_ns} ns')
            return None
        return k

    def _on_clock(self, data: bytes) -> None:
        k = self._step_of(topics.CLOCK, stamp_ns(data))
        if k is not None and k > self._clock_step:
            self._clock_step = k
            self._last_progress = time.monotonic()
            self._try_fire()

    def _on_input(self, topic: str, data: bytes) -> None:
        entry = self._inputs[topic]
        t_ns, value = entry.codec.decode(data)
        if entry.source in self.external:
            problem = sequence_error(self.resolve_topic_name(topic), self.external[entry.source], t_ns, entry.last,
                                     self.dt_ns)
            if problem:
                self.fail(problem)
                return
        k = self._step_of(topic, t_ns)
        if k is None:
            return
        if k in entry.buffer or k < entry.consumed_below:
            names = sorted({publisher_name(i)
                            for i in self.get_publishers_info_by_topic(self.resolve_topic_name(topic))})
            self.fail(f'a second message for step {k} on {self.resolve_topic_name(topic)}: a publisher other '
                      f'than {entry.source} injects data (publishers seen: {", ".join(names) or "none left"}); '
                      'refusing to use it')
            return
        entry.last = max(entry.last, k)
        entry.buffer[k] = value
        self._try_fire()

    def _ready_to_fire(self, i: int, stage: _Stage, k: int) -> bool:
        if i > 0 and self._stages[i - 1].next_step <= k:
            return False
        if self.time_owner:
            return k <= self._clock_step and (not self._paced_by_monitor or monitor_allows(k, self._monitor_acked))
        return not stage.paced_by_clock or k <= self._clock_step

    def _try_fire(self) -> None:
        """Fire every stage whose inputs are complete, in order, until none can fire.

        A loop, never recursion: a handler that announces the next step (the time owner)
        re-enters here; the nested call returns at once and the outer loop picks the new
        step up, so a lone time owner runs any number of steps on a bounded stack.
        """
        if self._firing or not self._started:
            return
        self._firing = True
        try:
            self._fire_ready_stages()
        finally:
            self._firing = False

    def _fire_ready_stages(self) -> None:
        progressed = True
        while progressed and self.failure is None and not self.done:
            progressed = False
            for i, stage in enumerate(self._stages):
                k = stage.next_step
                if not self._ready_to_fire(i, stage, k):
                    continue
                values = stage.values(k)
                if values is None:
                    continue
                stage.next_step += 1
                self._last_progress = ready = time.monotonic()
                self._run_stage(stage, k, values)
                self._step_wall += time.monotonic() - ready
                if stage is self._stages[-1]:
                    self._step_done(k)
                self._prune()
                progressed = True
                if self.done or self.failure:
                    return

    def _run_stage(self, stage: _Stage, k: int, values: dict[str, Any]) -> None:
        if not self._placed:
            self._placed = True
            take_cpu(self.get_name())
        try:
            outputs = stage.handler(k, self.step_time_s(k), values)
        except StepError as exc:
            self.fail(str(exc))
            return
        except Exception as exc:  # noqa: BLE001 (a bug in a core: fail loudly, never hang the graph)
            import traceback
            traceback.print_exc()
            self.fail(f'stage {stage.name} raised {type(exc).__name__} at step {k}: {exc}')
            return
        self._publish(outputs, k)
        if self.stepper.finished:
            self.done = True
            self.last_step = k
            self.wake()
            if self.time_owner:
                self._end_pub.publish(self._clock_codec.encode(k * self.dt_ns))
        elif self.time_owner and stage is self._stages[-1]:
            self._publish_clock(k + 1)

    def _step_done(self, k: int) -> None:
        """Step k's stages have all fired: record its wall time; over the deadline with ``deadline_strict``: fail."""
        wall, self._step_wall = self._step_wall, 0.0
        if self.timing.add(k, wall) and self.params['deadline_strict']:
            self.fail(overrun(k, wall, self.params['deadline_ms']))

    def _prune(self) -> None:
        oldest = min(s.next_step for s in self._stages) - self._max_lag
        for entry in self._inputs.values():
            if oldest > entry.consumed_below:
                for k in [k for k in entry.buffer if k < oldest]:
                    del entry.buffer[k]
                entry.consumed_below = oldest

    # ---- readiness and watchdog --------------------------------------------------------------------
    def _missing_publishers(self) -> list[str]:
        return [self.resolve_topic_name(t) for t in self._inputs if self.count_publishers(t) == 0]

    def _check_intruders(self, now: float) -> None:
        """Every input topic must have exactly the publishers the graph declares (here: its source node)."""
        self._last_intruder_check = now
        for topic, sources in self._declared_publishers().items():
            strangers = self._publisher_check.strangers(topic, self.get_publishers_info_by_topic(topic), sources,
                                                        now)
            if strangers:
                self.fail(f'{topic} has a publisher the graph does not declare ({", ".join(strangers)}); '
                          f'only {", ".join(sorted(sources))} may drive this input')
                return

    def _declared_publishers(self) -> dict[str, set[str]]:
        """Absolute topic → the instances that may publish it: each input's source and, for the time owner,
        the handshake (every other node's READY, the run monitor's acknowledgements; a participant left
        on the domain by an earlier run must not start or pace this one)."""
        out = {self.resolve_topic_name(e.topic): {self.external.get(e.source, e.source)} for e in self._inputs.values()}
        owner = time_owner_among(self.graph_nodes)
        if not self.time_owner and owner:
            out[topics.RUN_END] = {owner}
        if self.time_owner:
            # An external node need not say READY (plain ROS 2), but may: one of this project's nodes run by hand.
            out[self.resolve_topic_name(topics.READY)] = (set(self.graph_nodes) - {self.instance} - set(self.external)
                                                          | set(self.external.values()))
            if MONITOR_NAME in self.graph_nodes:
                out[self.resolve_topic_name(topics.MONITOR_ACK)] = {MONITOR_NAME}
        return out

    def _paused_for(self, now: float) -> float:
        """Seconds since the last watchdog tick that were a pause, not waiting: the whole gap when this process was
        not running, or the tick when its launcher is stopped (Ctrl-Z, SIGSTOP: it paces the graph)."""
        gap, self._last_tick = now - self._last_tick, now
        return gap if gap > FROZEN_GAP_S or (self._launcher and is_stopped(self._launcher)) else 0.0

    def _watchdog(self) -> None:
        now = time.monotonic()
        paused = self._paused_for(now)
        self._last_progress += paused
        self._created += paused
        if not self._started:
            self._check_ready(now)
            return
        if self.done or self.failure:
            return
        if now - self._last_intruder_check > INTRUDER_CHECK_PERIOD_S:
            self._check_intruders(now)
        waited = now - self._last_progress
        # Until its first stage fires, a node waits on the graph's start (the last nodes' discovery), not on a
        # step's inputs: the start has the readiness timeout.
        first = all(st.next_step == 0 for st in self._stages)
        if waited <= (max(self.input_timeout_s, READY_TIMEOUT_S) if first else self.input_timeout_s):
            return
        for i, stage in enumerate(self._stages):
            k = stage.next_step
            if self._final_step is not None and k > self._final_step:
                continue  # the run ended before step k: nothing of it will come
            missing = [f'{self.resolve_topic_name(inp.topic)} (from {inp.source}, step {k - inp.lag})'
                       for inp in stage.missing(k)]
            if self.time_owner and k <= self._clock_step and not monitor_allows(k, self._monitor_acked) \
                    and MONITOR_NAME in self.graph_nodes:
                missing.append(f'{self.resolve_topic_name(topics.MONITOR_ACK)} (from {MONITOR_NAME}, '
                               f'step {k - MONITOR_LAG})')
            if missing:
                self.fail(f'stage {stage.name} waited {waited:.1f} s for step {k} input(s): ' + ', '.join(missing))
                return
            if not self.time_owner and stage.paced_by_clock and k > self._clock_step and i == 0:
                self.fail(f'waited {waited:.1f} s ' + CLOCK_WAIT.format(k=k))
                return

    def _check_ready(self, now: float) -> None:
        missing = self._missing_publishers()
        absent: list[str] = []
        if self.time_owner:
            absent = sorted(set(self.graph_nodes) - self._ready_from - {self.instance} - set(self.external))
            if not missing and not absent:
                self._check_intruders(now)
                self._started = True
                self._last_progress = now
                self._publish(self.stepper.start(), 0, initial=True)
                self._publish_clock(0)
                return
        elif not missing:
            self._check_intruders(now)
            self._ready_pub.publish(Codec(topics.TYPES[topics.READY]).encode(0, self.instance))
            self._started = True
            self._last_progress = now
            self._try_fire()
            return
        if now - self._created > max(self.input_timeout_s, READY_TIMEOUT_S):
            parts = []
            if missing:
                parts.append('no publisher on ' + ', '.join(missing))
            if absent:
                parts.append('nodes not ready: ' + ', '.join(absent))
            self.fail('graph never became ready: ' + '; '.join(parts))

    def may_exit(self) -> bool:
        """Whether a finished node may leave: the time owner first waits (at most ``input_timeout_s``) until the
        run monitor has acknowledged a step, so its /clock reader is matched and the final flush reaches it
        (a run of a few steps can otherwise end before discovery has matched the monitor's readers)."""
        if not self.done:
            return False
        if not self.time_owner or MONITOR_NAME not in self.graph_nodes or self._monitor_acked >= 0:
            return True
        return time.monotonic() - self._last_progress > self.input_timeout_s

    def fail(self, message: str) -> None:
        """Record a fatal lockstep failure; the main loop reports it and exits non-zero."""
        if self.failure is None:
            self.failure = message
            self.wake()

    def flush(self, timeout_s: float = 5.0) -> None:
        """Wait until every output has been acknowledged by its readers, ``timeout_s`` in all."""
        pubs = [p.publisher for p in self._ports.values()]
        if self.time_owner:
            pubs.append(self._clock_pub)
        deadline = time.monotonic() + timeout_s
        for pub in pubs:
            pub.wait_for_all_acked(rclpy.duration.Duration(seconds=max(0.0, deadline - time.monotonic())))


def release_node(executor: Any, node: Any, context: Any = None) -> None:
    """Shut down a node with its executor and context (either may be None: not created), so its DDS
    participant ends now.

    The executor holds the node's entities: without its shutdown the participant outlives its owner and
    keeps serving its transient-local history (a run's READY and acknowledgements) on the domain, where
    the next run leasing it would take them for its own. A node process ends its executor's threads here
    too, before it leaves.
    """
    if executor is not None:
        executor.shutdown()
    if node is not None:
        node.destroy_node()
    rclpy.try_shutdown(context=context)


def is_stopped(pid: int) -> bool:
    """Whether process ``pid`` is stopped (state T: SIGSTOP/SIGTSTP, or t: traced); False when it is gone."""
    try:
        with open(f'/proc/{pid}/stat', 'rb') as fh:
            stat = fh.read()
    except OSError:
        return False
    return stat[stat.rindex(b')') + 2:stat.rindex(b')') + 3] in (b'T', b't')


def _die_with_launcher() -> bool:
    """Ask the kernel to SIGKILL this node the moment the launcher that started it dies (issue 9 §2).

    ``prctl(PR_SET_PDEATHSIG, SIGKILL)``: the kernel acts even on a node that is stopped, hung in DDS or
    holding the interpreter lock, so no orphan outlives its launcher and none can reach the next run on
    the domain. The parent pid is checked after the call, which covers a launcher that died before it.
    Returns False when that launcher is already gone. A node started by hand (no ``ACDS_LAUNCHER_PID``)
    has no launcher to follow.
    """
    launcher = int(os.environ.get(LAUNCHER_PID_ENV, '0') or 0)
    return die_with(launcher) if launcher else True


def numeric_mismatch() -> str | None:
    """How this node process's numeric configuration differs from the launcher's (:mod:`acds_common.numeric_config`,
    passed in its environment), as the node's failure line; None when they agree or no launcher started it."""
    expected = numeric_config.from_env()
    if expected is None:
        return None
    mine = numeric_config.numeric_configuration()
    diff = numeric_config.differences(expected, mine, 'the launcher')
    if not diff:
        return None
    return f'numeric configuration on host {mine["host"]} differs from the launcher\'s: {"; ".join(diff)}'


def take_cpu(name: str) -> None:
    """Bind this process to the CPU the launcher placed it on (:data:`CPU_ENV`; unset: where the OS puts it): every
    thread it has (Fast DDS's, numpy's BLAS workers) and, by inheritance, every thread it starts later.
    A CPU the process may not use is said in one line and left to the OS: placement changes speed, never data."""
    cpu = os.environ.get(CPU_ENV, '')
    if not cpu:
        return
    try:
        cpus = {int(cpu)}
        for tid in sorted(int(t) for t in os.listdir('/proc/self/task')):
            try:
                os.sched_setaffinity(tid, cpus)
            except ProcessLookupError:  # a thread that ended meanwhile
                continue
    except (OSError, ValueError) as exc:
        print(f'[{name}] not placed on CPU {cpu!r} ({exc}): the operating system places it', file=sys.stderr, flush=True)


def run_node(name: str, args: list[str] | None = None) -> int:
    """Entry-point body of every node (``name``, as its package declares it): init, spin, report, shut down
    cleanly, end the process. The stepper is the one the node's declaration names for its parameters.

    The exit code (returned before ROS is up, the process's own once it is): 0 on completion or
    SIGINT/SIGTERM/SIGHUP, 2 on a configuration error (a numeric configuration other than the launcher's among
    them: :func:`numeric_mismatch`, checked before ROS starts), 3 on a lockstep failure, 4 when the launcher that
    started it had died before the node came up (once up, the kernel kills it with its launcher).
    Errors are one line on stderr, prefixed by the node name, without a traceback.
    """
    if not _die_with_launcher():
        print(f'[{name}] STOPPED: the launcher that started it (pid {os.environ[LAUNCHER_PID_ENV]}) has died',
              file=sys.stderr, flush=True)
        return EXIT_ORPHANED
    mismatch = numeric_mismatch()
    if mismatch is not None:
        print(f'[{name}] CONFIGURATION ERROR: {mismatch}', file=sys.stderr, flush=True)
        return EXIT_CONFIG
    os.environ.setdefault('ROS_LOG_DIR', os.path.join(os.environ.get('TMPDIR', '/tmp'), 'acds_ros_log'))
    try:
        rclpy.init(args=args, signal_handler_options=rclpy.signals.SignalHandlerOptions.NO)
    except RuntimeError as exc:  # rclpy's RCLError: bad --ros-args or params file
        print(f'[{name}] CONFIGURATION ERROR: {str(exc).splitlines()[0]}', file=sys.stderr, flush=True)
        return EXIT_CONFIG
    stop: dict[str, Any] = {'signal': None}

    def on_signal(signum: int, _frame: Any) -> None:
        stop['signal'] = signum

    for sig in STOP_SIGNALS:
        signal.signal(sig, on_signal)
    faulthandler.register(STACK_SIGNAL, file=sys.stderr, all_threads=True)
    node: LockstepNode | None = None
    executor: Any = None
    code = EXIT_OK
    try:
        node = LockstepNode(name)
        from rclpy.experimental import EventsExecutor
        executor = EventsExecutor()
        executor.add_node(node)
        spinner = Spinner(executor)
        node.wake = spinner.wake
        with profiled(node.instance):
            while not (node.may_exit() or node.failure is not None or stop['signal'] is not None):
                spinner.spin(SPIN_PERIOD_S)
        faulthandler.dump_traceback_later(STUCK_TRACE_S, file=sys.stderr)
        if node.failure is not None:
            print(f'[{name}] {FAILURE_MARK}{node.failure}', file=sys.stderr, flush=True)
            code = EXIT_LOCKSTEP
        else:  # completed, or stopped by a signal: deliver what was published before leaving
            node.flush(timeout_s=2.0 if stop['signal'] is not None else 5.0)
            print(f'[{name}] {node.timing.line()}', flush=True)
            if node.time_owner and node.done:
                print(f'[{name}] {COMPLETE_PREFIX}{node.last_step}', flush=True)
    except (ConfigError, ValueError) as exc:
        print(f'[{name}] CONFIGURATION ERROR: {exc}', file=sys.stderr, flush=True)
        code = EXIT_CONFIG
    except (KeyboardInterrupt, ExternalShutdownException):
        code = EXIT_OK
    finally:
        if node is not None:
            node.stepper.close()
        release_node(executor, node)
    # Leave without the interpreter's finalization: it deletes the DDS participant, which then talks to peers
    # that are leaving too (stalls of 2 s measured there; the likely place of a >10 s exit hang seen in suite
    # runs). Nothing is left to deliver: the outputs are
    # acknowledged (flush), the context is shut down and its log closed; the kernel releases the SHM locks
    # and the launcher removes the files.
    sys.stdout.flush()
    sys.stderr.flush()
    os._exit(code)


def clock_step_waited_for(line: str) -> int | None:
    """The /clock step a node's failure line says it waited for from the time owner (:data:`CLOCK_WAIT`), or None."""
    _, mark, rest = line.partition(CLOCK_WAIT.partition('{k}')[0])
    step = rest.partition(' ')[0]
    return int(step) if mark and step.isdigit() else None


def completed_step(line: str) -> int | None:
    """The last step a time owner's output line announces (:data:`COMPLETE_PREFIX`), or None."""
    _, mark, rest = line.partition(COMPLETE_PREFIX)
    return int(rest) if mark and rest.strip().isdigit() else None


__all__ = ['CLOCK_WAIT', 'COMMAND_QOS', 'COMPLETE_PREFIX', 'LOCKSTEP_QOS', 'ConfigError', 'LockstepError', 'LockstepNode',
           'clock_step_waited_for', 'completed_step', 'message_class', 'release_node', 'run_node']
