"""The run monitor: an in-launcher rclpy node that observes the whole graph (spec §2).

It subscribes, as serialized CDR (``raw=True``), to ``/clock`` and to every output the graph declares
(:mod:`acds_common.graph`) when it records a bag, serves a live view or keeps messages; without them, to what a
node, the summaries or the external nodes' watch read (:meth:`RunMonitor._read_topics`). It never deserializes what
it only records.
Each message goes to the recorder (a bag writer), to an optional live-view sink, and to the run's streaming summary
(:class:`~acds_runtime.summary.RunObserver`, which decodes only the topics it reads); nothing
is kept in memory unless ``keep`` asks for it (tests), so a run's memory does not grow with
its length. It acknowledges every :data:`~acds_common.graph.MONITOR_ACK_EVERY`-th ``/clock``
step, so the time owner never runs more than :data:`~acds_common.graph.MONITOR_LAG` steps
ahead of it (it is part of the lockstep handshake as node ``run_monitor``, and announces
itself ready only once its own readers are matched with every declared publisher of every
per-step topic and with the time owner's ``/clock``, so no step of any topic can be missed).

It also watches what no node can: a second message for a step already received on a
per-step topic, or a publisher on a graph topic that the graph does not declare, is data
from outside the graph: :attr:`RunMonitor.intrusion` names it and the launcher fails the run.
"""

from __future__ import annotations

import functools
import sys
import threading
import time
import traceback
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

import rclpy
from acds_common import topics
from acds_common.cdr import Codec, stamp_ns
from acds_common.graph import MONITOR_ACK_EVERY, MONITOR_NAME, Graph
from acds_common.lockstep import (
    COMMAND_QOS,
    LOCKSTEP_QOS,
    SPIN_PERIOD_S,
    PublisherCheck,
    Spinner,
    message_class,
    release_node,
)
from acds_common.profiling import profiling
from rclpy.context import Context
from rclpy.node import Node

from .external import ExternalWatch

#: Seconds between checks of who publishes on the graph's topics.
PUBLISHER_CHECK_PERIOD_S = 1.0
#: Seconds between the checks, while the graph has not started, that this monitor's readers are matched (it then says
#: READY: the time owner waits for it).
READY_CHECK_PERIOD_S = 0.05


@dataclass
class TopicState:
    """What the monitor knows of one topic: declared publishers, per-step or not, last step, count."""

    name: str
    msg_type: str
    publishers: set[str]
    every_step: bool
    stamped: bool
    last_step: int = -1
    count: int = 0
    kept: list[bytes] = field(default_factory=list)
    #: Steps that never arrived between two that did (first missing, last missing), per-step topics of one publisher.
    gaps: list[tuple[int, int]] = field(default_factory=list)


class RunMonitor:
    """Observe one graph (one ROS domain) from inside the launcher process."""

    def __init__(self, domain_id: int, dt_ns: int, graph: Graph, *, on_clock: Callable[[int], None] | None = None,
                 record: Callable[[Node], Callable[[str, bytes, int | None], None]] | None = None,
                 observer: Any = None, keep: bool = False, sink: Callable[[str, bytes], None] | None = None,
                 external: ExternalWatch | None = None) -> None:
        self.context = Context()
        rclpy.init(context=self.context, domain_id=domain_id,
                   signal_handler_options=rclpy.signals.SignalHandlerOptions.NO)
        self.node = Node(MONITOR_NAME, namespace=topics.NAMESPACE, context=self.context)
        self.graph = graph
        self.dt_ns = dt_ns
        self.keep = keep
        self.observer = observer
        self.intrusion: str | None = None
        #: Set when the monitor itself failed (its thread stopped) or an external node broke its contract (a step
        #: twice, skipped or wrongly stamped; over a strict deadline); the launcher fails the run with it.
        self.failure: str | None = None
        #: The nodes the user runs (issue 20), watched here: None when the launcher starts every node.
        self.external = external
        #: What the external nodes do not serve yet (the graph does not start until it is empty).
        self.waiting_for: list[str] = []
        self._on_clock = on_clock
        self._lock = threading.Lock()
        self.clock_step = -1
        #: The last /clock step this monitor acknowledged (-1: none yet): the time owner fires no step beyond
        #: what :func:`~acds_common.graph.monitor_allows` lets it.
        self.acked_step = -1
        self.topics: dict[str, TopicState] = {}
        self._clock = TopicState(topics.CLOCK, topics.TYPES[topics.CLOCK], {graph.time_owner}, True, True)
        for spec, out in graph.outputs():
            name = spec.topic(out.topic)
            state = self.topics.get(name)
            if state is None:
                state = self.topics[name] = TopicState(name, out.msg_type, set(), out.every_step,
                                                       Codec(out.msg_type).stamped)
            state.publishers.add(external.publisher(spec.instance) if external is not None else spec.instance)
        #: Called with (absolute topic, raw CDR, its stamp in ns or None) for every message, before the /clock ack (a
        #: bag writer).
        self.recorder = record(self.node) if record is not None else None
        #: Also called with every message, after the recorder (a live view: :mod:`acds_runtime.foxglove_bridge`).
        self.sink = sink
        self._subs: dict[str, Any] = {}
        read = None if keep or record is not None or sink is not None else self._read_topics()
        for name, state in self.topics.items():
            if read is not None and name not in read:
                continue
            qos = COMMAND_QOS if name.endswith('/' + topics.GROUND_ACK) else LOCKSTEP_QOS
            self._subs[name] = self.node.create_subscription(message_class(state.msg_type), name,
                                                             functools.partial(self._on_raw, name), qos, raw=True)
        #: The per-step topics taken in: what the per-step queries (last steps, gaps, blame) speak of.
        self._watched = [st for name, st in self.topics.items() if st.every_step and name in self._subs]
        self._clock_sub = self.node.create_subscription(message_class(topics.TYPES[topics.CLOCK]), topics.CLOCK,
                                                        self._on_clock_raw, LOCKSTEP_QOS, raw=True)
        self._ack = self.node.create_publisher(message_class(topics.TYPES[topics.MONITOR_ACK]), topics.MONITOR_ACK,
                                               LOCKSTEP_QOS)
        self._ack_codec = Codec(topics.TYPES[topics.MONITOR_ACK])
        self._ready = self.node.create_publisher(message_class(topics.TYPES[topics.READY]), topics.READY,
                                                 LOCKSTEP_QOS)
        self._ready_codec = Codec(topics.TYPES[topics.READY])
        self.ready = False
        self._publisher_check = PublisherCheck()
        self._last_check = 0.0
        from rclpy.experimental import EventsExecutor
        self._executor = EventsExecutor(context=self.context)
        self._executor.add_node(self.node)
        self._spinner = Spinner(self._executor)
        self._stop = threading.Event()
        #: Cleared (with ``_stop`` set) when the monitor closes: what its spinning loop reads per message.
        self._spinning = True
        self._thread = threading.Thread(target=profiling(MONITOR_NAME, self._spin), name='run_monitor', daemon=True)
        self._thread.start()

    def _read_topics(self) -> set[str]:
        """What a run without a bag, a live view or kept messages takes in: the topics a node of the graph, the
        summaries (and the truth digest) or the external nodes' watch read. An output nobody reads changes neither
        the run nor its summary (its publishers are still checked, from the graph's introspection); leaving it out
        saves a delivery a step (``acds run --no-record``, the graph engine's study samples)."""
        return (self.graph.read_topics() | (self.observer.reads() if self.observer is not None else set())
                | (self.external.reads() if self.external is not None else set()))

    @property
    def taken_in(self) -> list[str]:
        """The graph's topics this monitor subscribes to (absolute names; /clock besides)."""
        return list(self._subs)

    # ---- spinning -----------------------------------------------------------------------------------
    def _spin(self) -> None:
        """Take in messages until closed: one per ``spin_once`` while the graph has not started, announcing readiness
        once matched (checked at least every :data:`READY_CHECK_PERIOD_S`); then in the executor's own loop
        (:class:`~acds_common.lockstep.Spinner`), coming back every :data:`~acds_common.lockstep.SPIN_PERIOD_S` to check
        the publishers every :data:`PUBLISHER_CHECK_PERIOD_S` (the stop event and the context are checked with them;
        :meth:`close` wakes the loop)."""
        spin_once, spin, monotonic = self._executor.spin_once, self._spinner.spin, time.monotonic
        try:
            while self._spinning:
                if not self.ready:
                    spin_once(timeout_sec=READY_CHECK_PERIOD_S)
                    self._announce_when_matched()
                    continue
                spin(SPIN_PERIOD_S)
                now = monotonic()
                if now - self._last_check > PUBLISHER_CHECK_PERIOD_S:
                    self._last_check = now
                    if self._stop.is_set() or not self.context.ok():
                        return
                    self._check_publishers(now)
        except Exception as exc:  # noqa: BLE001 (never a silent death of the observer: the launcher reports it)
            import traceback
            traceback.print_exc()
            self.failure = f'the run monitor stopped: {type(exc).__name__}: {exc}'

    def _announce_when_matched(self) -> None:
        """READY once this monitor's own readers are matched with every declared publisher of every per-step
        topic and with the time owner's /clock (matched endpoints, not merely discovered ones)."""
        per_step = [(self._subs[st.name], len(st.publishers)) for st in self._watched]
        if self.external is not None:
            self.waiting_for = self.external.missing(
                self.node, {name: sub.get_publisher_count() for name, sub in self._subs.items()})
            if self.waiting_for:
                return
        if self._clock_sub.get_publisher_count() > 0 and all(sub.get_publisher_count() >= n for sub, n in per_step):
            self._ready.publish(self._ready_codec.encode(0, MONITOR_NAME))
            self.ready = True

    def _check_publishers(self, now: float) -> None:
        """Every graph topic may only have the publishers the graph declares for it."""
        for name, st in self.topics.items():
            strangers = self._publisher_check.strangers(name, self.node.get_publishers_info_by_topic(name),
                                                        st.publishers, now)
            if strangers:
                self._intrude(f'{name} has a publisher the graph does not declare: {", ".join(strangers)} '
                              f'(declared: {", ".join(sorted(st.publishers))})')
                return

    def _intrude(self, text: str) -> None:
        if self.intrusion is None:
            self.intrusion = text

    # ---- callbacks -------------------------------------------------------------------------------------
    def _on_raw(self, topic: str, data: bytes) -> None:
        st = self.topics[topic]
        if self.external is not None:
            self._watch(topic, data)
        t_ns = stamp_ns(data) if st.stamped else None
        k = t_ns // self.dt_ns if t_ns is not None else None
        with self._lock:
            if k is not None and st.every_step:
                if len(st.publishers) == 1:
                    if k <= st.last_step:
                        self._intrude(f'a second message for step {k} on {topic}: data from a publisher outside '
                                      f'the graph (declared: {", ".join(sorted(st.publishers))})')
                    elif st.last_step >= 0 and k > st.last_step + 1:
                        st.gaps.append((st.last_step + 1, k - 1))
                st.last_step = max(st.last_step, k)
            st.count += 1
            if self.keep:
                st.kept.append(data)
        if self.recorder is not None:  # the stamp read once (little-endian CDR, as every node here sends)
            self.recorder(topic, data, t_ns if data[1] == 1 else None)
        if self.sink is not None:
            self.sink(topic, data)
        if self.observer is not None:
            self.observer.feed_raw(topic, data)

    def _watch(self, topic: str, data: bytes) -> None:
        """Hand a message to the external nodes' watch; the first contract breach fails the run."""
        assert self.external is not None
        problem = self.external.on_message(topic, data, time.monotonic())
        if problem and self.failure is None:
            self.failure = problem

    def _on_clock_raw(self, data: bytes) -> None:
        if self.external is not None:
            self._watch(topics.CLOCK, data)
        t_ns = stamp_ns(data)
        k = t_ns // self.dt_ns
        if self.recorder is not None:
            self.recorder(topics.CLOCK, data, t_ns if data[1] == 1 else None)
        if self.sink is not None:
            self.sink(topics.CLOCK, data)
        with self._lock:
            if self.clock_step >= 0 and k > self.clock_step + 1:
                self._clock.gaps.append((self.clock_step + 1, k - 1))
            self.clock_step = max(self.clock_step, k)
            self._clock.count += 1
            if self.keep:
                self._clock.kept.append(data)
        if k % MONITOR_ACK_EVERY == 0:
            self._ack.publish(self._ack_codec.encode(t_ns))
            self.acked_step = max(self.acked_step, k)
        if self._on_clock is not None:
            self._on_clock(t_ns)

    # ---- queries ----------------------------------------------------------------------------------------
    def last_steps(self) -> dict[str, int]:
        """Last step received on each per-step topic taken in."""
        with self._lock:
            return {st.name: st.last_step for st in self._watched}

    def complete_through(self, k: int) -> bool:
        """Whether every per-step topic taken in has arrived up to step ``k``."""
        with self._lock:
            return all(st.last_step >= k for st in self._watched)

    def _per_step(self) -> list[tuple[TopicState, int]]:
        """/clock and every per-step topic taken in, each with its last step (call with the lock held)."""
        return [(self._clock, self.clock_step), *((st, st.last_step) for st in self._watched)]

    def behind(self, k: int) -> list[str]:
        """/clock and the per-step topics not yet received up to step ``k``, with the step each is at."""
        with self._lock:
            return [f'{st.name} (last step {last})' for st, last in self._per_step() if last < k]

    def gaps(self) -> list[str]:
        """Steps that never arrived between two that did, by topic (a step missing for good)."""
        with self._lock:
            return [f'{st.name} steps {a}…{b}' if b > a else f'{st.name} step {a}'
                    for st, _ in self._per_step() for a, b in st.gaps]

    def received(self) -> int:
        """Messages taken in so far, on every topic (a measure of progress)."""
        with self._lock:
            return self._clock.count + sum(st.count for st in self.topics.values())

    def messages(self, topic: str) -> list[Any]:
        """Kept messages of ``topic`` (relative or absolute name) as rclpy objects (``keep=True`` only)."""
        from rclpy.serialization import deserialize_message

        name = topics.resolve(topic)
        st = self._clock if name == topics.CLOCK else self.topics.get(name)
        if st is None:
            return []
        if not self.keep:
            raise RuntimeError('the run monitor keeps no messages (start the graph with keep=True)')
        cls = message_class(st.msg_type)
        with self._lock:
            raw = list(st.kept)
        return [deserialize_message(d, cls) for d in raw]

    def snapshot(self) -> dict[str, list[bytes]]:
        """A copy of the kept messages by absolute topic name (``keep=True`` only; topics with messages)."""
        with self._lock:
            return {name: list(st.kept) for name, st in (*self.topics.items(), (topics.CLOCK, self._clock))
                    if st.kept}

    def count(self, topic: str) -> int:
        """Messages received on ``topic``."""
        name = topics.resolve(topic)
        st = self._clock if name == topics.CLOCK else self.topics.get(name)
        return 0 if st is None else st.count

    def wait_for(self, predicate: Callable[[], bool], timeout_s: float) -> bool:
        """Wait (on the monitor's stop event, polling the received data) until ``predicate`` is true."""
        deadline = time.monotonic() + timeout_s
        while time.monotonic() < deadline:
            if predicate():
                return True
            self._stop.wait(0.02)
        return predicate()

    def settle(self, quiet_s: float = 0.5, timeout_s: float = 5.0) -> None:
        """Let what was in flight when the graph stopped arrive: wait until no per-step topic has advanced for
        ``quiet_s`` (at most ``timeout_s``). A monitor that had fallen behind a stopped graph (a loaded machine)
        then sees where each node truly stopped."""
        def advanced_since(before: dict[str, int]) -> Callable[[], bool]:
            return lambda: self.last_steps() != before

        deadline = time.monotonic() + timeout_s
        while (left := deadline - time.monotonic()) > 0:
            if not self.wait_for(advanced_since(self.last_steps()), timeout_s=min(quiet_s, left)):
                return

    def blame(self, stopped: Callable[[str], bool] = lambda _node: False) -> tuple[str, str] | None:
        """The node whose outputs stopped while its inputs were there (a hung node), from what arrived: its name
        and a sentence.

        For each node of the graph: the first step it has not published on all its per-step
        outputs; the culprit is a node whose lag-0 inputs for that step have all arrived. What was in
        flight is counted first (:meth:`settle`). A node whose process is stopped (``stopped``: SIGSTOP, a
        debugger) is the culprit whatever arrived here: a stop can land inside a publish, after this monitor's copy
        of a message and before another reader's, and that reader then waits for what the monitor has.
        """
        self.settle()
        last = self.last_steps()
        candidates = []
        for name, spec in self.graph.nodes.items():
            watched = [o for o in spec.outputs if o.every_step and spec.topic(o.topic) in last]
            outs = [spec.topic(o.topic) for o in watched]
            if not outs:
                continue
            offset = max(o.stamp_offset for o in watched)
            nxt = min(last.get(t, -1) for t in outs) + 1 - offset
            inputs = [(spec.topic(i.topic), i.lag) for s in spec.stages for i in s.inputs
                      if i.source in self.graph.nodes]
            missing = [t for o in watched if last.get(t := spec.topic(o.topic), -1) < nxt + o.stamp_offset]
            if stopped(name):
                return name, (f'{self._who(name)} stopped at step {nxt}: its process is stopped, its outputs did not '
                              f'({", ".join(missing)} of step {nxt}, t = {nxt * self.dt_ns / 1e9:g} s)')
            if all(last.get(t, -1) >= nxt - lag for t, lag in inputs):
                candidates.append((nxt, name, missing))
        if not candidates:
            return None
        k, name, missing = min(candidates)
        return name, (f'{self._who(name)} stopped at step {k}: its inputs for that step had arrived, its outputs did '
                      f'not ({", ".join(missing)} of step {k}, t = {k * self.dt_ns / 1e9:g} s)')

    def _who(self, name: str) -> str:
        """A node as a failure names it (an external one with its ROS node)."""
        return name if self.external is None or name not in self.external.nodes else \
            f'{name} (external, ROS node {self.external.publisher(name)})'

    def spin_stack(self) -> list[str]:
        """The Python stack of the monitor's spinning thread now: where it is when it stopped taking in messages
        (in the middleware's wait, or in a callback of its own, the recorder's or a live view's)."""
        frame = sys._current_frames().get(self._thread.ident) if self._thread.ident is not None else None
        if frame is None:
            return [f"(its thread has ended{': ' + self.failure if self.failure else ''})"]
        return [line for entry in traceback.format_stack(frame) for line in entry.rstrip().splitlines()]

    def close(self) -> None:
        """Stop spinning and release the ROS context (closes the bag, if recording)."""
        self._spinning = False
        self._stop.set()
        self._spinner.wake()
        self._thread.join(timeout=5.0)
        if self.recorder is not None and hasattr(self.recorder, 'close'):
            self.recorder.close()  # the bag: index, custom data, metadata.yaml
        release_node(self._executor, self.node, self.context)
