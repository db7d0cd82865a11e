"""The lockstep's Spinner (acds_common.lockstep): callbacks run inside the executor's own loop, for a period at a time,
and a wake from a callback ends the period at once (how a node leaves when it has finished or failed)."""

from __future__ import annotations

import os
import time

import pytest
import rclpy
from acds_common.lockstep import LOCKSTEP_QOS, Spinner, release_node
from acds_runtime.launcher import FASTDDS_PROFILE, DomainLease
from rclpy.clock import Clock, ClockType
from rclpy.context import Context
from rclpy.experimental import EventsExecutor
from rclpy.node import Node
from rclpy.serialization import deserialize_message
from std_msgs.msg import Header


@pytest.fixture
def node(monkeypatch):
    """A node of its own ROS context on a leased domain, with an EventsExecutor (the nodes' executor)."""
    lease = DomainLease()
    monkeypatch.setitem(os.environ, 'ROS_AUTOMATIC_DISCOVERY_RANGE', 'LOCALHOST')
    monkeypatch.setitem(os.environ, 'FASTRTPS_DEFAULT_PROFILES_FILE', str(FASTDDS_PROFILE))
    context = Context()
    rclpy.init(context=context, domain_id=lease.domain_id)
    n = Node('spinner_test', context=context)
    executor = EventsExecutor(context=context)
    executor.add_node(n)
    try:
        yield n, executor
    finally:
        release_node(executor, n, context)
        lease.close()


def test_a_wake_from_a_callback_ends_the_period_at_once(node):
    n, executor = node
    spinner = Spinner(executor)
    fired: list[float] = []

    def wake() -> None:
        fired.append(time.monotonic())
        spinner.wake()

    timer = n.create_timer(0.05, wake, clock=Clock(clock_type=ClockType.STEADY_TIME))
    t0 = time.monotonic()
    spinner.spin(30.0)
    timer.cancel()
    assert fired, 'the timer never ran inside the spin'
    assert time.monotonic() - t0 < 15.0, 'the wake did not end a 30 s period'
    spinner.wake()  # a wake with no spin running is harmless, and the next spin still runs its period
    t1 = time.monotonic()
    spinner.spin(0.2)
    assert time.monotonic() - t1 >= 0.15


def test_every_message_is_taken_within_the_executors_loop(node):
    n, executor = node
    spinner = Spinner(executor)
    got: list[bytes] = []

    def on_message(data: bytes) -> None:
        got.append(data)
        if len(got) == 50:
            spinner.wake()

    n.create_subscription(Header, 'spinner_test', on_message, LOCKSTEP_QOS, raw=True)
    pub = n.create_publisher(Header, 'spinner_test', LOCKSTEP_QOS)
    deadline = time.monotonic() + 20.0
    while pub.get_subscription_count() == 0 and time.monotonic() < deadline:
        spinner.spin(0.05)
    assert pub.get_subscription_count() == 1, 'the subscription never matched its publisher'
    for i in range(50):
        pub.publish(Header(frame_id=f'm{i}'))
    while len(got) < 50 and time.monotonic() < deadline:
        spinner.spin(5.0)
    assert len(got) == 50, f'{len(got)} of 50 messages taken in 20 s'
    assert [deserialize_message(d, Header).frame_id for d in got] == [f'm{i}' for i in range(50)]
