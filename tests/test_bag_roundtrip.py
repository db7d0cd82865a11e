"""Bags of a graph run: round trip through rosbags and mcap, sqlite3 storage, errors before the run."""

from __future__ import annotations

import sqlite3

import pytest
import yaml
from acds_cli.bag.info import bag_info
from acds_common import topics
from acds_common.graph import node_spec
from acds_common.scenario import load_scenario
from acds_runtime.bag import writer as bag_writer
from acds_runtime.bag.reader import open_bag
from acds_runtime.launcher import GraphRun, LaunchError
from rosbags.rosbag2 import Reader
from rosbags.typesys import Stores, get_typestore


def _stamp_ns(stamp) -> int:
    return stamp.sec * 10**9 + stamp.nanosec

STEPS = 40
TS = get_typestore(Stores.ROS2_JAZZY)
TRUTH = [topics.resolve(out.topic) for out in node_spec('rigid_body', {}).outputs if out.every_step]
PER_STEP = [topics.CLOCK, *TRUTH, *(topics.resolve(t) for t in (topics.WHEEL_MOMENTUM, topics.WHEEL_TORQUE))]


def _record(launch_graph, tmp_path, storage):
    bag = tmp_path / f'bag_{storage}'
    with launch_graph('free_tumble_heao_b', steps=STEPS, record=bag, record_storage=storage) as graph:
        result = graph.wait()
    assert result.bag == bag
    return bag, result.monitor.snapshot()


def _rosbags_read(bag):
    with Reader(bag) as reader:
        got = {}
        for conn, t, data in reader.messages():
            got.setdefault(conn.topic, []).append((t, bytes(data)))
        conns = {c.topic: c for c in reader.connections}
    return got, conns


def _check_against_monitor(got, monitor):
    for topic in PER_STEP:
        assert len(got[topic]) == STEPS + 1, f'{topic}: one message per step 0..{STEPS}'
    for topic, published in monitor.items():
        recorded = got[topic]
        if topic == topics.resolve(topics.DIAGNOSTICS):  # several publishers: only each one's own order is defined
            recorded, published = sorted(recorded), sorted(published, key=lambda d: (bag_writer.cdr_stamp_ns(d), d))
        assert [d for _, d in recorded] == published, f'{topic}: recorded bytes differ from what was published'
        if bag_writer.stamped(topics.type_of(topic)):
            assert [t for t, _ in recorded] == [bag_writer.cdr_stamp_ns(d) for d in published], \
                f'{topic}: timestamps are not the sim-time stamps'
    assert [t for t, _ in got[topics.CLOCK]][:3] == [0, 500_000_000, 1_000_000_000]


def _check_sample_fields(got, monitor_odometry):
    """Field by field: rosbags' deserialization of step 7 == the rclpy message the monitor received."""
    t, data = got[topics.resolve(topics.TRUTH_ODOMETRY)][7]
    msg = TS.deserialize_cdr(data, 'nav_msgs/msg/Odometry')
    ref = monitor_odometry[7]
    assert t == _stamp_ns(ref.header.stamp) == 3_500_000_000
    assert msg.header.frame_id == ref.header.frame_id and msg.child_frame_id == ref.child_frame_id
    for a, b in ((msg.pose.pose.position, ref.pose.pose.position), (msg.twist.twist.angular, ref.twist.twist.angular),
                 (msg.twist.twist.linear, ref.twist.twist.linear)):
        assert (a.x, a.y, a.z) == (b.x, b.y, b.z)
    q, r = msg.pose.pose.orientation, ref.pose.pose.orientation
    assert (q.x, q.y, q.z, q.w) == (r.x, r.y, r.z, r.w)
    assert list(msg.pose.covariance) == list(ref.pose.covariance)
    assert r.w != 1.0, 'the sample is a moving attitude, not the initial one'


def test_mcap_round_trip_rosbags_and_mcap(launch_graph, tmp_path):
    from mcap.reader import make_reader
    from rclpy.serialization import deserialize_message

    bag, monitor = _record(launch_graph, tmp_path, 'mcap')
    got, conns = _rosbags_read(bag)
    _check_against_monitor(got, monitor)
    from nav_msgs.msg import Odometry
    odom = [deserialize_message(d, Odometry) for d in monitor[topics.resolve(topics.TRUTH_ODOMETRY)]]
    _check_sample_fields(got, odom)
    # message definitions and QoS metadata
    wheels = conns[topics.resolve(topics.WHEEL_MOMENTUM)]
    assert wheels.msgtype == 'geometry_msgs/msg/Vector3Stamped' and 'Header header' in wheels.msgdef.data
    qos = wheels.ext.offered_qos_profiles[0]
    assert (qos.reliability.name, qos.durability.name, qos.depth) == ('RELIABLE', 'TRANSIENT_LOCAL', 1000)

    # the mcap package reads the same messages, schemas and channel metadata
    with (bag / 'bag_mcap.mcap').open('rb') as fh:
        reader = make_reader(fh)
        by_topic = {}
        for schema, channel, message in reader.iter_messages(log_time_order=False):
            assert schema.encoding == 'ros2msg' and channel.message_encoding == 'cdr'
            assert 'offered_qos_profiles' in channel.metadata
            by_topic.setdefault(channel.topic, []).append((message.log_time, message.data))
        summary = reader.get_summary()
    # /diagnostics has several publishers: the file holds their messages in arrival order (a node's step-0 status can
    # arrive after another's of step 20), rosbags reads them in time order; their content is what must agree
    diagnostics = topics.resolve(topics.DIAGNOSTICS)
    assert sorted(by_topic.pop(diagnostics)) == sorted(got.pop(diagnostics))
    assert by_topic == got
    assert summary.statistics.message_count == sum(len(v) for v in monitor.values())

    # the run's scenario and parameters travel with the bag
    data = open_bag(bag)
    assert data.info['scenario_name'] == 'free_tumble_heao_b' and data.info['steps'] == str(STEPS)
    assert yaml.safe_load(data.info['scenario']) == load_scenario('free_tumble_heao_b').raw
    assert yaml.safe_load(data.info['params'])['reaction_wheels']['graph_nodes'] == [
        'rigid_body', 'reaction_wheels', 'run_monitor']
    assert yaml.safe_load(data.info['publishers'])[topics.resolve(topics.WHEEL_MOMENTUM)] == ['reaction_wheels']
    text = bag_info(bag)
    assert '/acds/truth/odometry' in text and f'{STEPS + 1}' in text and '20.000 s' in text
    assert 'name: free_tumble_heao_b' in text


def test_sqlite3_storage(launch_graph, tmp_path):
    bag, monitor = _record(launch_graph, tmp_path, 'sqlite3')
    assert (bag / 'bag_sqlite3.db3').exists() and not list(bag.glob('*.mcap'))
    got, conns = _rosbags_read(bag)
    _check_against_monitor(got, monitor)
    db = sqlite3.connect(bag / 'bag_sqlite3.db3')
    try:
        n = db.execute('SELECT count(*) FROM messages').fetchone()[0]
        qos = db.execute("SELECT offered_qos_profiles FROM topics WHERE name='/clock'").fetchone()[0]
        defs = db.execute('SELECT count(*) FROM message_definitions').fetchone()[0]
    finally:
        db.close()
    assert n == sum(len(v) for v in monitor.values())
    assert 'transient_local' in qos and defs == len({c.msgtype for c in conns.values()})
    assert open_bag(bag).info['scenario_name'] == 'free_tumble_heao_b'


def test_bad_bag_path_is_one_line_error_before_the_run(tmp_path, monkeypatch):
    sc = load_scenario('free_tumble_heao_b')
    blocker = tmp_path / 'a_file'
    blocker.write_text('x')
    existing = tmp_path / 'exists'
    existing.mkdir()
    cases = [(blocker / 'bag', 'cannot write in'), (existing, 'already exists')]
    for path, text in cases:
        graph = GraphRun(sc, tmp_path / 'run', steps=5, record=path)
        with pytest.raises(LaunchError, match=text) as err:
            graph.start()
        assert '\n' not in str(err.value)
        assert graph.processes == {} and graph.lease is None
    monkeypatch.setattr(bag_writer, 'MIN_FREE_BYTES', 2**62)
    graph = GraphRun(sc, tmp_path / 'run', steps=5, record=tmp_path / 'bag')
    with pytest.raises(LaunchError, match=r'MiB free on the disk'):
        graph.start()
    assert graph.processes == {} and not (tmp_path / 'bag').exists()


def test_a_formation_bag_names_every_node_that_ran():
    """A bag's ``nodes`` (``acds info``) are the graph's instances, a formation vehicle's nodes too (it named only
    the scenario's top-level ``nodes``: formation_dynamics)."""
    info = bag_writer.run_info(load_scenario('emff_testbed_hold'), 10)
    nodes = info['nodes'].split(',')
    assert nodes[0] == 'formation_dynamics'
    assert {'a/em_driver', 'a/formation_controller', 'b/em_driver', 'b/formation_controller'} <= set(nodes[1:])
    assert bag_writer.run_info(load_scenario('oresat_detumble'), 10)['nodes'] == \
        ','.join(load_scenario('oresat_detumble').get('', 'nodes'))
