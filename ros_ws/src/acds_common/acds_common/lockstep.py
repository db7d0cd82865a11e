"""The lockstep runtime every ACDS node plugs into (spec §2, "Time and determinism").

The time owner (``rigid_body``) publishes ``/clock`` and the truth of step k;
every other node computes step k as soon as it holds all of its inputs for
step k (or k−L on a declared feedback edge of lag L) and publishes its
outputs stamped with t_k = k·Δt. The time owner integrates t_k → t_k+1 only
after it holds every actuator output of step k. A node declares:

* outputs: ``add_output(key, type, topic)``;
* stages: ``add_stage(name, inputs, handler)``; a stage fires for step k when
  ``/clock`` has reached k, every input is held for its step, and the
  node's earlier stages have fired for k. Stages of one node run in declared
  order, one step at a time, so a node is a deterministic function of its
  inputs whatever the arrival order.

Inputs whose source node is not part of the graph (parameter
``graph_nodes``) are absent: the handler gets ``None`` for them, as it does
for a lagged input before step L. A stage blocked longer than
``input_timeout_s`` (wall time) fails the node with a message naming the node,
the step and every missing topic with its source.

Step identity is exact: stamps are integer nanoseconds, k = t_ns / Δt_ns.
Lockstep topics are reliable and transient-local with a deep history, so a
subscriber that matches late still receives what was published before.
"""

from __future__ import annotations

import os
import signal
import sys
import time
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import rclpy
from rcl_interfaces.msg import ParameterDescriptor
from rclpy.clock import Clock, ClockType
from rclpy.executors import ExternalShutdownException
from rclpy.node import Node
from rclpy.parameter import Parameter
from rclpy.qos import DurabilityPolicy, HistoryPolicy, QoSProfile, ReliabilityPolicy
from rosgraph_msgs.msg import Clock as ClockMsg
from std_msgs.msg import String

from acds_common import topics
from acds_common.scenario import REQUIRED, SCHEMA

#: QoS of every lockstep data topic: nothing is dropped between matched
#: endpoints, late joiners get the history, and the history is deep enough
#: for an observer (recorder) that runs a few hundred steps behind.
LOCKSTEP_QOS = QoSProfile(
    reliability=ReliabilityPolicy.RELIABLE,
    durability=DurabilityPolicy.TRANSIENT_LOCAL,
    history=HistoryPolicy.KEEP_LAST,
    depth=1000,
)
#: QoS of ground commands and acknowledgements (reliable, volatile).
COMMAND_QOS = QoSProfile(
    reliability=ReliabilityPolicy.RELIABLE,
    durability=DurabilityPolicy.VOLATILE,
    history=HistoryPolicy.KEEP_LAST,
    depth=100,
)
#: Node name of the time owner.
TIME_OWNER = 'rigid_body'
#: Name of the launcher's observer node, and how many steps the time owner may run ahead of it.
MONITOR_NAME = 'run_monitor'
MONITOR_LAG = 50
#: Exit codes of a node process (EXIT_ORPHANED: the launcher that started it died).
EXIT_OK, EXIT_CONFIG, EXIT_LOCKSTEP, EXIT_ORPHANED = 0, 2, 3, 4
#: Environment variable the launcher sets to its own pid: a node whose parent is no longer
#: that process (the launcher was killed, even by SIGKILL) stops within one watchdog tick.
LAUNCHER_PID_ENV = 'ACDS_LAUNCHER_PID'
#: Signals that stop a node cleanly (flush, exit 0): Ctrl-C, kill, a closed terminal.
STOP_SIGNALS = (signal.SIGINT, signal.SIGTERM, signal.SIGHUP)


class LockstepError(RuntimeError):
    """A lockstep contract was broken (missing input past its timeout, bad stamp)."""


class ConfigError(ValueError):
    """A node's parameters are wrong (unknown name, out of range, inconsistent)."""


@dataclass(frozen=True)
class Input:
    """A lockstep input: ``topic`` of ``msg_type`` from node ``source``, ``lag`` steps back."""

    key: str
    topic: str
    msg_type: type
    source: str
    lag: int = 0


@dataclass
class _Stage:
    name: str
    inputs: list[Input]
    handler: Callable[[int, float, dict[str, Any]], None]
    next_step: int = 0


def stamp_to_ns(stamp: Any) -> int:
    """builtin_interfaces/Time → integer nanoseconds."""
    return int(stamp.sec) * 1_000_000_000 + int(stamp.nanosec)


def ns_to_stamp(t_ns: int, stamp: Any) -> Any:
    """Fill a builtin_interfaces/Time from integer nanoseconds."""
    stamp.sec, stamp.nanosec = divmod(t_ns, 1_000_000_000)
    return stamp


def message_time_ns(msg: Any) -> int:
    """Sim time of a lockstep message: ``header.stamp``, or ``clock`` for Clock."""
    if isinstance(msg, ClockMsg):
        return stamp_to_ns(msg.clock)
    return stamp_to_ns(msg.header.stamp)


class LockstepNode(Node):
    """Base class of every ACDS node: parameters, outputs, stages, readiness, watchdog."""

    def __init__(self, node_name: str) -> None:
        super().__init__(node_name, namespace=topics.NAMESPACE)
        self.time_owner = node_name == TIME_OWNER
        self.control_period_s = self.param(
            'control_period_s', 0.5, 'lockstep control period Δt (the DPA cycle), s', lo=1e-4, hi=60.0)
        self.dt_ns = round(self.control_period_s * 1e9)
        self.graph_nodes: list[str] = self.param(
            'graph_nodes', [node_name], 'names of the nodes present in this graph (inputs from others are absent)')
        self.input_timeout_s = self.param(
            'input_timeout_s', 30.0, 'wall seconds a stage may wait for an input before the run fails',
            lo=0.1, hi=3600.0)
        self.seed = self.param('seed', 1, 'scenario random seed (deterministic noise streams)', lo=0)
        self._stages: list[_Stage] = []
        self._buffers: dict[str, dict[int, Any]] = {}
        self._outputs: dict[str, Any] = {}
        self._subscriptions_by_topic: dict[str, Any] = {}
        self._clock_step = -1
        self._firing = False
        self._started = False
        self._ready_sent = False
        self._ready_from: set[str] = set()
        self._last_progress = time.monotonic()
        self._created = time.monotonic()
        self.failure: str | None = None
        self.done = False
        self.orphaned = False
        self.launcher_pid = int(os.environ.get(LAUNCHER_PID_ENV, '0') or 0)
        if self.time_owner:
            self.total_steps = self.param('total_steps', 1, 'number of control steps to run', lo=1, hi=10**9)
            self.real_time_factor = self.param(
                'real_time_factor', 0.0, 'pace sim time at this multiple of wall time (0: as fast as possible)',
                lo=0.0, hi=1e6)
            self._clock_pub = self.create_publisher(ClockMsg, topics.CLOCK, LOCKSTEP_QOS)
            self._pace_timer: Any = None
            self._wall_start = 0.0
            self.create_subscription(String, topics.READY, self._on_ready, LOCKSTEP_QOS)
        else:
            self._subscribe(topics.CLOCK, ClockMsg)
            self._ready_pub = self.create_publisher(String, topics.READY, LOCKSTEP_QOS)
        steady = Clock(clock_type=ClockType.STEADY_TIME)
        self.create_timer(0.1, self._watchdog, clock=steady)

    # ---- declarations -------------------------------------------------------------------------
    def param(self, name: str, default: Any, description: str, *, lo: float | None = None,
              hi: float | None = None, choices: tuple[str, ...] | None = None) -> Any:
        """Declare a typed, described parameter and return its value, range-checked."""
        desc = ParameterDescriptor(description=description)
        if isinstance(default, list) and not default:  # an empty list has no type of its own: strings
            value = self.declare_parameter(name, Parameter.Type.STRING_ARRAY, desc).value or []
        else:
            value = self.declare_parameter(name, default, desc).value
        if isinstance(default, float) and isinstance(value, int):
            value = float(value)
        values = value if isinstance(value, (list, tuple)) else [value]
        for v in values:
            if isinstance(v, (int, float)) and not isinstance(v, bool):
                if v != v or v in (float('inf'), float('-inf')):
                    raise ConfigError(f'{self.get_name()}: parameter {name} is not finite: {value}')
                if lo is not None and v < lo or hi is not None and v > hi:
                    raise ConfigError(f'{self.get_name()}: parameter {name}={value} outside [{lo}, {hi}]')
        if choices is not None and value not in choices:
            raise ConfigError(f'{self.get_name()}: parameter {name}={value!r} not one of {list(choices)}')
        return list(value) if isinstance(value, (list, tuple)) else value

    def section_params(self, section: str) -> dict[str, Any]:
        """Declare every parameter of scenario ``section`` from the schema; return {field: SI value}."""
        out = {}
        for name, f in SCHEMA[section].items():
            default = f.default
            if default is REQUIRED:  # always supplied by the launcher; a typed placeholder
                default = [0.0] * (f.length or 1) if f.kind == 'floats' else 0.0
            lo, hi = (None, None) if f.kind in ('str', 'bool', 'strs') else (f.lo, f.hi)
            out[name] = self.param(f.param_name(section, name), default, f'{f.doc} [{f.si or "-"}]',
                                   lo=lo, hi=hi, choices=f.choices if f.kind == 'str' else None)
        return out

    def add_output(self, key: str, msg_type: type, topic: str) -> None:
        """Declare a lockstep output; publish it with :meth:`publish`."""
        self._outputs[key] = self.create_publisher(msg_type, topic, LOCKSTEP_QOS)

    def add_stage(self, name: str, inputs: list[Input],
                  handler: Callable[[int, float, dict[str, Any]], None]) -> None:
        """Declare a stage: ``handler(k, t_s, inputs)`` runs once per step, in order.

        The time owner's stages also wait for the run monitor's acknowledgement of
        step k − MONITOR_LAG, so an observer (recorder) can never fall behind the
        history the lockstep QoS keeps.
        """
        if self.time_owner:
            inputs = [*inputs, Input('_monitor_ack', topics.MONITOR_ACK, ClockMsg, MONITOR_NAME, MONITOR_LAG)]
        for inp in inputs:
            if inp.source in self.graph_nodes:
                self._subscribe(inp.topic, inp.msg_type)
        self._stages.append(_Stage(name, inputs, handler))

    def present(self, source: str) -> bool:
        """Whether node ``source`` is part of this graph."""
        return source in self.graph_nodes

    def _subscribe(self, topic: str, msg_type: type) -> None:
        if topic in self._subscriptions_by_topic:
            return
        self._subscriptions_by_topic[topic] = self.create_subscription(
            msg_type, topic, lambda msg, t=topic: self._on_input(t, msg), LOCKSTEP_QOS)

    def start(self) -> None:
        """Finish construction: reject unknown parameters; call last in the subclass ``__init__``."""
        declared = set(self._parameters)
        unknown = sorted(set(self._parameter_overrides) - declared)
        if unknown:
            raise ConfigError(f'{self.get_name()}: unknown parameter(s) {", ".join(unknown)} '
                              f'(declared: {", ".join(sorted(declared - {"use_sim_time"}))})')

    # ---- time ------------------------------------------------------------------------------------
    def step_time_s(self, k: int) -> float:
        """t_k in seconds."""
        return k * self.dt_ns / 1e9

    def publish(self, key: str, msg: Any, k: int) -> None:
        """Stamp ``msg`` with t_k and publish it on output ``key``."""
        if hasattr(msg, 'header'):
            ns_to_stamp(k * self.dt_ns, msg.header.stamp)
        self._outputs[key].publish(msg)

    def publish_clock(self, k: int) -> None:
        """Time owner only: announce step k on ``/clock``; stages for k may then fire.

        With ``real_time_factor`` > 0 the announcement waits (on a wall-clock timer, not a
        sleep) until t_k / real_time_factor wall seconds after step 0.
        """
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
        msg = ClockMsg()
        ns_to_stamp(k * self.dt_ns, msg.clock)
        self._clock_pub.publish(msg)
        self._clock_step = k
        self._last_progress = time.monotonic()
        self._try_fire()

    def finish(self) -> None:
        """Mark the run complete: the main loop flushes the outputs and exits 0."""
        self.done = True

    # ---- callbacks -------------------------------------------------------------------------------
    def _on_ready(self, msg: String) -> None:
        self._ready_from.add(msg.data)

    def _on_input(self, topic: str, msg: Any) -> None:
        t_ns = message_time_ns(msg)
        k, rem = divmod(t_ns, self.dt_ns)
        if rem:
            self.fail(f'{topic} carries stamp {t_ns} ns, not a multiple of Δt={self.dt_ns} ns')
            return
        if topic == topics.CLOCK:
            if k > self._clock_step:
                self._clock_step = k
                self._last_progress = time.monotonic()
        else:
            self._buffers.setdefault(topic, {})[k] = msg
        self._try_fire()

    def _input_value(self, inp: Input, k: int) -> tuple[bool, Any]:
        if inp.source not in self.graph_nodes or k - inp.lag < 0:
            return True, None
        buf = self._buffers.get(inp.topic, {})
        if k - inp.lag not in buf:
            return False, None
        return True, buf[k - inp.lag]

    def _try_fire(self) -> None:
        """Fire every stage whose inputs are complete, in order, until none can fire.

        A loop, never recursion: a handler that announces the next step (the time owner's
        ``publish_clock``) re-enters here; the nested call returns at once and the outer
        loop picks the new step up, so a lone time owner runs any number of steps on a
        bounded stack.
        """
        if self._firing:
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
                if k > self._clock_step or (i > 0 and self._stages[i - 1].next_step <= k):
                    continue
                values: dict[str, Any] = {}
                for inp in stage.inputs:
                    ok, values[inp.key] = self._input_value(inp, k)
                    if not ok:
                        break
                else:
                    stage.next_step += 1
                    self._last_progress = time.monotonic()
                    stage.handler(k, self.step_time_s(k), values)
                    self._prune()
                    progressed = True
                    if self.done or self.failure:
                        return

    def _prune(self) -> None:
        oldest = min(s.next_step for s in self._stages) - max(
            (i.lag for s in self._stages for i in s.inputs), default=0) - 1
        for buf in self._buffers.values():
            for k in [k for k in buf if k < oldest]:
                del buf[k]

    # ---- readiness and watchdog --------------------------------------------------------------------
    def _missing_publishers(self) -> list[str]:
        missing = []
        for topic in self._subscriptions_by_topic:
            if self.count_publishers(topic) == 0:
                missing.append(self.resolve_topic_name(topic))
        return missing

    def check_parent(self) -> bool:
        """Whether the launcher that started this node has died (sets :attr:`orphaned`)."""
        if self.launcher_pid and os.getppid() != self.launcher_pid:
            self.orphaned = True
        return self.orphaned

    def _watchdog(self) -> None:
        now = time.monotonic()
        if self.check_parent():
            return
        if not self._started:
            self._check_ready(now)
            return
        if self.done or self.failure:
            return
        waited = now - self._last_progress
        blocked = [s for s in self._stages if s.next_step <= self._clock_step]
        if blocked and waited > self.input_timeout_s:
            stage = blocked[0]
            k = stage.next_step
            missing = [f'{self.resolve_topic_name(i.topic)} (from {i.source}, step {k - i.lag})'
                       for i in stage.inputs if not self._input_value(i, k)[0]]
            if missing:
                self.fail(f'stage {stage.name} waited {waited:.1f} s for step {k} input(s): '
                          + ', '.join(missing))
        elif not blocked and not self.time_owner and waited > 2 * self.input_timeout_s:
            self.fail(f'waited {waited:.1f} s for /clock step {self._clock_step + 1} from {TIME_OWNER}')

    def _check_ready(self, now: float) -> None:
        missing = self._missing_publishers()
        if self.time_owner:
            absent = sorted(set(self.graph_nodes) - self._ready_from - {self.get_name()})
            if not missing and not absent:
                self._started = True
                self._last_progress = now
                self.on_start()
                return
        elif not missing:
            if not self._ready_sent:
                self._ready_pub.publish(String(data=self.get_name()))
                self._ready_sent = True
                self._started = True
                self._last_progress = now
                self._try_fire()
            return
        else:
            absent = []
        if now - self._created > max(self.input_timeout_s, 20.0):
            parts = []
            if missing:
                parts.append('no publisher on ' + ', '.join(missing))
            if absent:
                parts.append('nodes not ready: ' + ', '.join(absent))
            self.fail('graph never became ready: ' + '; '.join(parts))

    def on_start(self) -> None:
        """Time owner hook: every node is ready; publish step 0 (truth, then :meth:`publish_clock`)."""

    def fail(self, message: str) -> None:
        """Record a fatal lockstep failure; the main loop reports it and exits non-zero."""
        if self.failure is None:
            self.failure = message

    def flush(self, timeout_s: float = 5.0) -> None:
        """Wait until every output has been acknowledged by its readers."""
        pubs = list(self._outputs.values())
        if self.time_owner:
            pubs.append(self._clock_pub)
        for pub in pubs:
            pub.wait_for_all_acked(rclpy.duration.Duration(seconds=timeout_s))


def run_node(name: str, factory: Callable[[], LockstepNode], args: list[str] | None = None) -> int:
    """Entry-point body shared by every node: init, spin, report, shut down cleanly.

    Returns the process exit code: 0 on completion or SIGINT/SIGTERM/SIGHUP, 2 on a
    configuration error, 3 on a lockstep failure, 4 when the launcher that started it
    died. Errors are one line on stderr, prefixed by the node name, without a traceback.
    """
    os.environ.setdefault('ROS_LOG_DIR', os.path.join(os.environ.get('TMPDIR', '/tmp'), 'acds_ros_log'))
    try:
        rclpy.init(args=args, signal_handler_options=rclpy.signals.SignalHandlerOptions.NO)
    except RuntimeError as exc:  # rclpy's RCLError: bad --ros-args or params file
        print(f'[{name}] CONFIGURATION ERROR: {str(exc).splitlines()[0]}', file=sys.stderr, flush=True)
        return EXIT_CONFIG
    stop = {'signal': None}

    def on_signal(signum: int, _frame: Any) -> None:
        stop['signal'] = signum

    for sig in STOP_SIGNALS:
        signal.signal(sig, on_signal)
    node: LockstepNode | None = None
    code = EXIT_OK
    try:
        node = factory()
        node.start()
        from rclpy.experimental import EventsExecutor
        executor = EventsExecutor()
        executor.add_node(node)
        while not node.done and node.failure is None and stop['signal'] is None and not node.orphaned:
            executor.spin_once(timeout_sec=0.1)
        node.check_parent()  # a parent-death SIGTERM: nobody is left to flush to
        if node.orphaned:
            print(f'[{name}] STOPPED: its launcher (pid {node.launcher_pid}) died', file=sys.stderr, flush=True)
            code = EXIT_ORPHANED
        elif node.failure is not None:
            print(f'[{name}] LOCKSTEP FAILURE: {node.failure}', file=sys.stderr, flush=True)
            code = EXIT_LOCKSTEP
        else:  # completed, or stopped by SIGINT/SIGTERM: deliver what was published before leaving
            node.flush(timeout_s=2.0 if stop['signal'] is not None else 5.0)
    except (ConfigError, ValueError) as exc:
        print(f'[{name}] CONFIGURATION ERROR: {exc}',
              file=sys.stderr, flush=True)
        code = EXIT_CONFIG
    except (KeyboardInterrupt, ExternalShutdownException):
        code = EXIT_OK
    finally:
        if node is not None:
            node.destroy_node()
        rclpy.try_shutdown()
    return code


__all__ = ['COMMAND_QOS', 'LOCKSTEP_QOS', 'ConfigError', 'Input', 'LockstepError', 'LockstepNode', 'run_node']
