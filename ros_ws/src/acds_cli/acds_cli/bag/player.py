"""Play a bag back into a ROS graph: raw CDR with the original types, ``/clock`` included.

Messages go out in sim-time order (at equal times ``/clock`` first), streamed
from the bag's storage, as fast as possible or at ``rate`` × real time. Flow control: every
:data:`ACK_EVERY_STEPS` clock steps the player waits until every matched
reader has acknowledged what it sent, so a subscriber never falls behind the
lockstep history depth (1000). Topic selection and remapping make the player
stand in for any subset of nodes.
"""

from __future__ import annotations

import math
import os
import threading
import time
from collections.abc import Callable, Iterator
from contextlib import closing
from typing import Any

import rclpy
from acds_common import topics
from acds_common.lockstep import message_class, release_node
from acds_runtime.bag.reader import Bag
from acds_runtime.bag.writer import BagError, offered_qos
from acds_runtime.launcher import FASTDDS_PROFILE
from rclpy.context import Context
from rclpy.duration import Duration
from rclpy.executors import SingleThreadedExecutor
from rclpy.node import Node
from rclpy.qos import DurabilityPolicy, HistoryPolicy, QoSProfile, ReliabilityPolicy

#: Wait for acknowledgements after this many /clock steps (well inside the history depth of 1000).
ACK_EVERY_STEPS = 100


def ros_env(domain_id: int | None) -> None:
    """Same discovery set-up as the launcher (localhost, the Fast DDS profile) for this process."""
    os.environ['FASTRTPS_DEFAULT_PROFILES_FILE'] = str(FASTDDS_PROFILE)
    os.environ['ROS_AUTOMATIC_DISCOVERY_RANGE'] = 'LOCALHOST'
    os.environ.pop('ROS_LOCALHOST_ONLY', None)
    os.environ.setdefault('ROS_LOG_DIR', os.path.join(os.environ.get('TMPDIR', '/tmp'), 'acds_ros_log'))
    if domain_id is not None:
        os.environ['ROS_DOMAIN_ID'] = str(domain_id)


def rclpy_qos(q: Any) -> QoSProfile:
    """A rosbags Qos (as stored in the bag) → rclpy QoSProfile."""
    return QoSProfile(
        history=HistoryPolicy.KEEP_ALL if q.history.name == 'KEEP_ALL' else HistoryPolicy.KEEP_LAST,
        depth=max(int(q.depth), 1),
        reliability=ReliabilityPolicy.BEST_EFFORT if q.reliability.name == 'BEST_EFFORT' else ReliabilityPolicy.RELIABLE,
        durability=DurabilityPolicy.TRANSIENT_LOCAL if q.durability.name == 'TRANSIENT_LOCAL'
        else DurabilityPolicy.VOLATILE)


def check_rate(rate: float) -> float:
    """``--rate``: a finite number ≥ 0 (0: as fast as possible); a one-line :class:`BagError` otherwise."""
    if not math.isfinite(rate) or rate < 0:
        raise BagError(f'--rate {rate:g}: must be a finite number >= 0 (sim time per wall time; 0 = as fast as possible)')
    return rate


def parse_remaps(items: list[str] | None) -> dict[str, str]:
    """``['a:=b', ...]`` → {absolute a: absolute b}."""
    out = {}
    for item in items or []:
        src, sep, dst = item.partition(':=')
        if not sep or not src or not dst:
            raise BagError(f'remap {item!r}: expected FROM:=TO')
        out[topics.resolve(src)] = topics.resolve(dst)
    return out


class Player:
    """An rclpy node (own context, own domain) publishing a bag's messages."""

    def __init__(self, bag: Bag, *, domain_id: int | None = None, select: list[str] | None = None,
                 remap: dict[str, str] | None = None, name: str = 'acds_player',
                 sink: Callable[[str, bytes], None] | None = None) -> None:
        self.bag = bag
        #: Also given every published message (topic as recorded, raw CDR): a live view.
        self.sink = sink
        wanted = {topics.resolve(t) for t in select} if select else set(bag.types)
        unknown = sorted(wanted - set(bag.types))
        if unknown:
            raise BagError(f'bag {bag.path}: no topic {", ".join(unknown)} (topics: {", ".join(sorted(bag.types))})')
        if topics.CLOCK in bag.types:
            wanted.add(topics.CLOCK)  # /clock always goes with the data
        self.topics = wanted
        self.remap = remap or {}
        ros_env(domain_id)
        self.context = Context()
        rclpy.init(context=self.context, domain_id=domain_id,
                   signal_handler_options=rclpy.signals.SignalHandlerOptions.NO)
        self.node = Node(name, namespace=topics.NAMESPACE, context=self.context)
        self.publishers: dict[str, Any] = {}
        for topic in sorted(wanted):
            qos = bag.qos.get(topic)
            profile = rclpy_qos(qos[0]) if qos else rclpy_qos(offered_qos(topic))
            self.publishers[topic] = self.node.create_publisher(
                message_class(bag.types[topic]), self.remap.get(topic, topic), profile)
        self.executor = SingleThreadedExecutor(context=self.context)
        self.executor.add_node(self.node)
        self._stop = threading.Event()
        self._thread = threading.Thread(target=self._spin, name='acds_player', daemon=True)
        self._thread.start()
        self.published = 0

    def _spin(self) -> None:
        while not self._stop.is_set() and self.context.ok():
            self.executor.spin_once(timeout_sec=0.05)

    def wait_for_subscribers(self, timeout_s: float, every: set[str] | None = None) -> bool:
        """Wait until some subscriber matched any of the player's topics, or, given ``every`` (absolute
        topics), until each of those has a matched subscriber (True); False when the timeout passed."""
        publishers = [self.publishers[t] for t in sorted(every)] if every else list(self.publishers.values())
        matched = all if every else any
        deadline = time.monotonic() + timeout_s
        while time.monotonic() < deadline and not self._stop.is_set():
            if matched(p.get_subscription_count() > 0 for p in publishers):
                return True
            time.sleep(0.02)
        return False

    def ack(self, timeout_s: float = 30.0) -> bool:
        """Wait until every matched reader acknowledged everything published (flow control)."""
        return all(p.wait_for_all_acked(Duration(seconds=timeout_s)) for p in self.publishers.values())

    def steps(self) -> Iterator[tuple[int, list[tuple[str, bytes]]]]:
        """The selected messages grouped by timestamp, in order, streamed: (t_ns, [(topic, raw), ...])."""
        return self.bag.ordered(self.topics)

    def publish_group(self, items: list[tuple[str, bytes]]) -> None:
        """Publish one timestamp's messages (raw bytes)."""
        for topic, data in items:
            self.publishers[topic].publish(data)
            if self.sink is not None:
                self.sink(topic, data)
            self.published += 1

    def play(self, rate: float = 0.0, before_step: Callable[[int], bool] | None = None,
             stop: threading.Event | None = None) -> int:
        """Publish everything; ``rate`` > 0 paces sim time at rate × wall time. Returns messages published.

        ``before_step(t_ns)`` (optional) is called before each timestamp and may block (flow control);
        returning False stops playback.
        """
        check_rate(rate)
        stop = stop or self._stop
        t_first = wall0 = None
        with closing(self.steps()) as groups:  # stopping early closes the storage reader at once
            for i, (t, items) in enumerate(groups, 1):
                if stop.is_set():
                    break
                if t_first is None or wall0 is None:
                    t_first, wall0 = t, time.monotonic()
                if rate > 0:
                    delay = wall0 + (t - t_first) / 1e9 / rate - time.monotonic()
                    if delay > 0 and stop.wait(delay):
                        break
                if before_step is not None and not before_step(t):
                    break
                self.publish_group(items)
                if i % ACK_EVERY_STEPS == 0:
                    self.ack()
        self.ack(10.0)
        return self.published

    def close(self) -> None:
        """Stop spinning and release the ROS context."""
        self._stop.set()
        self._thread.join(timeout=5.0)
        release_node(self.executor, self.node, self.context)
