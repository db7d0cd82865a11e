"""One process of the benchmark's bare rclpy ring: ``python -m acds_cli.bare_chain INDEX HOPS CYCLES``.

Process i relays every message from ``ring_i`` to ``ring_{i+1}``; process 0
starts the token once every link is matched, times ``CYCLES`` round trips and
prints cycles/s as its last line; the relays leave after the last cycle. Same QoS, executor and spinning (a
:class:`~acds_common.lockstep.Spinner`) as the lockstep graph, and placed on a CPU the same way when the bench asks
(:func:`~acds_common.lockstep.take_cpu`).
"""

from __future__ import annotations

import sys
import time

import rclpy
from acds_common.lockstep import LOCKSTEP_QOS, SPIN_PERIOD_S, Spinner, take_cpu
from rclpy.experimental import EventsExecutor
from rclpy.node import Node
from std_msgs.msg import Header


def main() -> int:
    """Relay (or, as process 0, drive and time) the token."""
    index, hops, cycles = (int(x) for x in sys.argv[1:4])
    take_cpu(f'bare_chain_{index}')
    rclpy.init()
    node = Node(f'bare_chain_{index}')
    pub = node.create_publisher(Header, f'ring_{(index + 1) % hops}', LOCKSTEP_QOS)
    state = {'count': 0, 't0': 0.0, 't1': 0.0}
    executor = EventsExecutor()
    spinner = Spinner(executor)

    def relay(msg: Header) -> None:
        state['count'] += 1
        if index == 0 and state['count'] == 1:
            state['t0'] = time.perf_counter()
        if index != 0 or state['count'] < cycles + 1:
            pub.publish(msg)
        if state['count'] > cycles:
            state['t1'] = time.perf_counter()
            spinner.wake()

    node.create_subscription(Header, f'ring_{index}', relay, LOCKSTEP_QOS)
    executor.add_node(node)
    if index == 0:
        while pub.get_subscription_count() == 0 or node.count_publishers(f'ring_{index}') == 0:
            executor.spin_once(timeout_sec=0.05)
        pub.publish(Header(frame_id='token'))
    while state['count'] <= cycles:  # the relays pass the token cycles + 1 times, then leave
        spinner.spin(SPIN_PERIOD_S)
    if index == 0:
        print(f'{cycles / (state["t1"] - state["t0"]):.1f}', flush=True)
    else:
        pub.wait_for_all_acked(rclpy.duration.Duration(seconds=5))
    rclpy.try_shutdown()
    return 0


if __name__ == '__main__':
    sys.exit(main())
