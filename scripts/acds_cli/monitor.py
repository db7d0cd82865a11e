"""The run monitor: an in-launcher rclpy node that observes the whole graph.

It subscribes to every ACDS topic as serialized CDR (``raw=True``), keeps the
bytes per topic in arrival order, acknowledges each ``/clock`` step so the
time owner never runs more than :data:`MONITOR_LAG` steps ahead of it (a
declared lagged input of ``rigid_body``), and reports progress. It is part
of the lockstep handshake as node ``run_monitor``.
"""

from __future__ import annotations

import importlib
import threading
import time
from collections.abc import Callable
from typing import Any

import rclpy
from acds_common import topics
from acds_common.lockstep import LOCKSTEP_QOS, MONITOR_NAME, ns_to_stamp, stamp_to_ns
from rclpy.context import Context
from rclpy.executors import SingleThreadedExecutor
from rclpy.node import Node
from rclpy.serialization import deserialize_message
from rosgraph_msgs.msg import Clock
from std_msgs.msg import String

#: Topics the monitor does not keep (handshake plumbing).
_SKIP = {topics.READY, topics.MONITOR_ACK}


def message_class(type_name: str) -> type:
    """'pkg/msg/Type' → the rclpy message class."""
    pkg, _, name = type_name.split('/')
    return getattr(importlib.import_module(f'{pkg}.msg'), name)


class RunMonitor:
    """Observe one graph (one ROS domain) from inside the launcher process."""

    def __init__(self, domain_id: int, on_clock: Callable[[int], None] | None = None,
                 record: Callable[[Node], Callable[[str, bytes], None]] | None = None) -> None:
        self.context = Context()
        rclpy.init(context=self.context, domain_id=domain_id,
                   signal_handler_options=rclpy.signals.SignalHandlerOptions.NO)
        self.node = Node(MONITOR_NAME, namespace=topics.NAMESPACE, context=self.context)
        self.received: dict[str, list[bytes]] = {}
        self.clock_ns: list[int] = []
        self._lock = threading.Lock()
        self._on_clock = on_clock
        #: Called with (absolute topic, raw CDR) for every message, before the /clock ack (a bag writer).
        self.recorder = record(self.node) if record is not None else None
        for topic, type_name in topics.TYPES.items():
            if topic in _SKIP:
                continue
            qos = LOCKSTEP_QOS if topic not in (topics.GROUND_COMMAND, topics.GROUND_ACK) else 10
            name = topics.resolve(topic)
            self.node.create_subscription(message_class(type_name), topic,
                                          lambda data, t=name: self._on_raw(t, data), qos, raw=True)
        self._ack = self.node.create_publisher(Clock, topics.MONITOR_ACK, LOCKSTEP_QOS)
        self._ready = self.node.create_publisher(String, topics.READY, LOCKSTEP_QOS)
        self._ready.publish(String(data=MONITOR_NAME))
        self._executor = SingleThreadedExecutor(context=self.context)
        self._executor.add_node(self.node)
        self._stop = threading.Event()
        self._thread = threading.Thread(target=self._spin, name='run_monitor', daemon=True)
        self._thread.start()

    def _spin(self) -> None:
        while not self._stop.is_set() and self.context.ok():
            self._executor.spin_once(timeout_sec=0.05)

    def _on_raw(self, topic: str, data: bytes) -> None:
        with self._lock:
            self.received.setdefault(topic, []).append(data)
        if self.recorder is not None:
            self.recorder(topic, data)
        if topic == topics.CLOCK:
            t_ns = stamp_to_ns(deserialize_message(data, Clock).clock)
            self.clock_ns.append(t_ns)
            ack = Clock()
            ns_to_stamp(t_ns, ack.clock)
            self._ack.publish(ack)
            if self._on_clock is not None:
                self._on_clock(t_ns)

    def snapshot(self) -> dict[str, list[bytes]]:
        """A copy of everything received so far, by absolute topic name."""
        with self._lock:
            return {t: list(v) for t, v in self.received.items()}

    def snapshot_last(self, topic: str) -> bytes | None:
        """The latest raw message of ``topic`` (relative or absolute name), None if none yet."""
        with self._lock:
            msgs = self.received.get(topics.resolve(topic))
            return msgs[-1] if msgs else None

    def messages(self, topic: str) -> list[Any]:
        """Deserialized messages of ``topic`` (relative or absolute name)."""
        name = topics.resolve(topic)
        cls = message_class(topics.TYPES[topic])
        with self._lock:
            raw = list(self.received.get(name, []))
        return [deserialize_message(d, cls) for d in raw]

    def wait_for(self, predicate: Callable[[], bool], timeout_s: float) -> bool:
        """Poll ``predicate`` (under the monitor's data) until true or the timeout passes."""
        deadline = time.monotonic() + timeout_s
        while time.monotonic() < deadline:
            if predicate():
                return True
            self._stop.wait(0.02)
        return predicate()

    def close(self) -> None:
        """Stop spinning and release the ROS context."""
        self._stop.set()
        self._thread.join(timeout=5.0)
        if self.recorder is not None and hasattr(self.recorder, 'close'):
            self.recorder.close()  # the bag: index, custom data, metadata.yaml
        self.node.destroy_node()
        rclpy.try_shutdown(context=self.context)
