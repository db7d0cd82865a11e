"""Replay-regression (``acds compare``) and the player with /clock (a use_sim_time node sees recorded time)."""

from __future__ import annotations

import os
import subprocess
import sys
import threading
import time
from pathlib import Path

import pytest
import rclpy
from acds_cli.bag.compare import run_compare
from acds_cli.bag.player import Player
from acds_common import topics
from acds_common.lockstep import LOCKSTEP_QOS, release_node
from acds_common.scenario import load_scenario
from acds_runtime.bag.reader import open_bag
from acds_runtime.launcher import DomainLease, GraphRun
from geometry_msgs.msg import Vector3Stamped
from rclpy.context import Context
from rclpy.executors import SingleThreadedExecutor
from rclpy.node import Node
from rclpy.parameter import Parameter

ROOT = Path(__file__).resolve().parents[1]


def stamp_to_ns(stamp) -> int:
    return stamp.sec * 10**9 + stamp.nanosec
STEPS = 60


@pytest.fixture(scope='module')
def recorded(tmp_path_factory) -> Path:
    """One short free_tumble_heao_b run recorded by the launcher (MCAP)."""
    tmp = tmp_path_factory.mktemp('replay')
    bag = tmp / 'bag'
    sc = load_scenario('free_tumble_heao_b')
    sc.values['wheels']['initial_momentum'] = [1.0, -2.0, 0.5]  # a non-trivial recorded wheel state
    with GraphRun(sc, tmp / 'run', steps=STEPS, echo=lambda _line: None, record=bag, keep=True) as graph:
        graph.wait()
    return bag


def test_compare_passes_on_the_unchanged_node(recorded):
    result = run_compare(recorded, 'reaction_wheels', log=lambda _t: None)
    assert result.ok, result.report()
    assert result.compared[topics.resolve(topics.WHEEL_MOMENTUM)] == STEPS + 1
    assert result.compared[topics.resolve(topics.WHEEL_TORQUE)] == STEPS + 1
    assert result.compared[topics.resolve(topics.DIAGNOSTICS)] == STEPS // 20 + 1
    assert result.max_diff == 0.0
    assert result.report().startswith('PASS reaction_wheels: ')


def test_compare_fails_naming_step_topic_and_field_when_a_parameter_changes(recorded):
    env = dict(os.environ)
    out = subprocess.run([sys.executable, '-m', 'acds_cli', 'compare', str(recorded), '--node', 'reaction_wheels',
                          '--set', 'wheels_initial_momentum_nms:=[1.0, -2.0, 0.75]'],
                         cwd=ROOT, env=env, capture_output=True, text=True, timeout=300, check=False)
    assert out.returncode == 1, out.stdout + out.stderr
    first = out.stdout.splitlines()[0]
    assert first.startswith('FAIL reaction_wheels: topic /acds/wheels/momentum step 0 field vector.z'), first
    assert 'recorded 0.5, now 0.75' in first
    assert 'largest float difference: 0.25' in out.stdout
    # within a tolerance larger than the change, it passes and reports the largest difference
    result = run_compare(recorded, 'reaction_wheels', tolerance=0.3, sets={'wheels_initial_momentum_nms': [1.0, -2.0, 0.75]},
                         log=lambda _t: None)
    assert result.max_diff == pytest.approx(0.25)
    assert not result.ok and 'diagnostics' in result.first, 'text telemetry is compared exactly'


def test_compare_refuses_what_it_cannot_replay(recorded):
    from acds_runtime.bag.writer import BagError
    with pytest.raises(BagError, match='time owner'):
        run_compare(recorded, 'rigid_body', log=lambda _t: None)
    with pytest.raises(BagError, match='has no node em_driver'):  # not in the recorded graph
        run_compare(recorded, 'em_driver', log=lambda _t: None)


def test_player_clock_drives_a_use_sim_time_node(recorded):
    bag = open_bag(recorded)
    clock = [t for _, t, _ in bag.messages([topics.CLOCK])]
    lease = DomainLease()
    context = Context()
    rclpy.init(context=context, domain_id=lease.domain_id)
    node = Node('listener', namespace=topics.NAMESPACE, context=context,
                parameter_overrides=[Parameter('use_sim_time', Parameter.Type.BOOL, True)])
    seen: list[tuple[int, int]] = []
    node.create_subscription(Vector3Stamped, topics.WHEEL_MOMENTUM,
                             lambda m: seen.append((stamp_to_ns(m.header.stamp), node.get_clock().now().nanoseconds)),
                             LOCKSTEP_QOS)
    executor = SingleThreadedExecutor(context=context)
    executor.add_node(node)
    stop = threading.Event()

    def spin_until_stopped() -> None:
        while not stop.is_set():
            executor.spin_once(timeout_sec=0.05)

    spin = threading.Thread(target=spin_until_stopped)
    spin.start()
    player = Player(bag, domain_id=lease.domain_id, select=[topics.WHEEL_MOMENTUM])
    try:
        assert player.wait_for_subscribers(30.0, every={topics.resolve(topics.WHEEL_MOMENTUM), topics.CLOCK}), \
            'the listener (wheel momentum and its /clock time source) never matched the player'
        assert player.play() == 2 * (STEPS + 1), 'wheel momentum and /clock, one each per step'
        deadline = time.monotonic() + 30.0
        while time.monotonic() < deadline and (len(seen) < STEPS + 1 or node.get_clock().now().nanoseconds != clock[-1]):
            time.sleep(0.02)
        final_now = node.get_clock().now().nanoseconds
    finally:
        player.close()
        stop.set()
        spin.join()
        release_node(executor, node, context)
        lease.close()
    assert [s for s, _ in seen] == [t for _, t, _ in bag.messages([topics.WHEEL_MOMENTUM])]
    assert len(clock) == STEPS + 1 and clock[-1] == STEPS * 500_000_000
    now = [n for _, n in seen]
    assert set(now) <= set(clock), 'the node only ever saw recorded sim times'
    assert now == sorted(now) and now[-1] > 0
    assert final_now == clock[-1], 'after playback the node is at the last recorded sim time'


def test_compare_replays_a_formation_vehicles_node_under_its_namespace(tmp_path):
    """``--node VEHICLE/NODE``: the vehicle's node, its topics under /acds/VEHICLE, its own /diagnostics status
    (each vehicle's em_driver and wheels name theirs VEHICLE/NODE: before, both vehicles' statuses were
    'em_driver', and compare refused 'unknown node a/em_driver')."""
    from acds_runtime.bag.writer import typestore
    from acds_runtime.direct import DirectRun

    bag = tmp_path / 'bag'
    DirectRun(load_scenario('emff_two_vehicle_lqr'), steps=40, record=bag).run()
    names = set()
    for _topic, _t, raw in open_bag(bag).messages([topics.resolve(topics.DIAGNOSTICS)]):
        names |= {s.name for s in typestore().deserialize_cdr(raw, 'diagnostic_msgs/msg/DiagnosticArray').status}
    assert {'a/em_driver', 'b/em_driver', 'a/reaction_wheels', 'b/reaction_wheels'} <= names, names
    for node in ('a/em_driver', 'b/reaction_wheels'):
        result = run_compare(bag, node, log=lambda _t: None)
        assert result.ok, result.report()
        assert result.compared[topics.resolve(topics.DIAGNOSTICS)] >= 1
        assert all(t.startswith(f'/acds/{node.partition("/")[0]}/') for t in result.compared if t != '/diagnostics')
    result = run_compare(bag, 'b/em_driver', sets={'em_driver_coil_resistance_ohm': [99.0, 99.0, 99.0]}, log=lambda _t: None)
    assert not result.ok and result.first.startswith('topic /acds/b/em_driver/'), result.first
