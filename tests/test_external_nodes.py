"""External nodes (issue 20 §1): a node of the graph the user runs, joined by plain ROS 2.

The stand-in for a user's node here is this project's own ``acds_controller`` executable, started by the test
(not the launcher) on the graph's domain: the run must give the data of the launcher-run graph, bit for bit,
and the launcher reports its step timing from the run monitor. The worked example (a plain-rclpy controller,
``examples/oresat_detumble_fsw``) has its own test, in its package.
"""

from __future__ import annotations

import shutil

import pytest
from acds_common.scenario import load_scenario
from acds_runtime.launcher import VENV_BIN, LaunchError
from acds_runtime.testing import external_node, stream_digests

STEPS = 150


def _without_diagnostics(digests: dict[str, str]) -> dict[str, str]:
    return {t: d for t, d in digests.items() if t != '/diagnostics'}


def test_a_node_run_by_the_user_gives_the_launchers_data(launch_graph):
    with launch_graph('oresat_detumble', steps=STEPS) as graph:
        reference = graph.wait()
    with launch_graph('oresat_detumble', steps=STEPS, external=['acds_controller']) as graph:
        assert 'acds_controller' not in graph.processes
        exe = shutil.which('acds_controller', path=str(VENV_BIN))
        with external_node(graph, [exe, '--ros-args', '--params-file', str(graph.run_dir / 'params.yaml')]):
            result = graph.wait()
    assert result.summary['truth_digest'] == reference.summary['truth_digest']
    assert _without_diagnostics(stream_digests(result.monitor)) == _without_diagnostics(stream_digests(reference.monitor))
    timing = result.timing['acds_controller']
    assert timing['steps'] == STEPS + 1 and timing['max_ms'] >= timing['p50_ms'] > 0.0, timing


def test_an_external_node_that_never_comes_is_named_with_what_it_should_serve(launch_graph):
    sc = load_scenario('oresat_detumble')
    sc.values['']['input_timeout'] = 1.0  # the readiness floor (20 s) applies
    with launch_graph(sc, steps=10, external=['acds_controller=my_detumble']) as graph:
        with pytest.raises(LaunchError) as err:
            graph.wait()
    text = str(err.value)
    assert text.startswith('the graph never started: after 20 s (scenario key input_timeout): external node '
                           'acds_controller (ROS node my_detumble): no publisher of /acds/controller/moment_command; '
                           'no subscription to any of its inputs /acds/magnetometer/volts, '), text
    assert '\n' not in text


def test_a_harness_wait_before_the_external_node_came_names_it(launch_graph):
    """``wait_for_messages`` on a graph that has not started (its external node not there yet) says so, with what the
    graph waits for, rather than only that nothing arrived."""
    from acds_runtime.testing import wait_for_messages

    with launch_graph('oresat_detumble', steps=10, external=['acds_controller=my_detumble']) as graph:
        with pytest.raises(pytest.fail.Exception) as err:
            wait_for_messages(graph, 'controller/moment_command', 1, timeout_s=3.0)
    text = str(err.value)
    assert 'the graph has not started, it waits for: external node acds_controller (ROS node my_detumble): no ' \
           'publisher of /acds/controller/moment_command' in text, text


@pytest.mark.parametrize(('item', 'message'), [
    ('wheel_law', "external node 'wheel_law': not a node of this graph"),
    ('rigid_body', "external node 'rigid_body': it owns sim time"),
    ('acds_controller=9lives', "'9lives' is not a ROS node name"),
    ('acds_controller=em_driver', "external node 'acds_controller': ROS node name 'em_driver' is that of the node "
                                  'em_driver the launcher starts'),
    ('acds_controller=run_monitor', "ROS node name 'run_monitor' is that of the launcher's run monitor"),
])
def test_bad_external_nodes_are_one_line_before_any_process(launch_graph, item, message):
    with pytest.raises(LaunchError, match=message) as err:
        with launch_graph('oresat_detumble', steps=10, external=[item]):
            pass
    assert '\n' not in str(err.value)


@pytest.mark.parametrize(('fault', 'got'), [
    ('twice', 'faulty_fsw sent a second message for step 3; expected one message for step 4, stamped 4000000000 ns '
              '(t = 4 s)'),
    ('wallclock', 'faulty_fsw sent stamp '),
    ('frame', "/acds/controller/moment_command: faulty_fsw sent step 3 in frame 'eci'; the contract says 'base_link' "
              '(header.frame_id: the axes of its components)'),
    # In lockstep a skipped step stalls the graph (step 4's inputs wait on step 3's output): the stall names it.
    ('skip', 'acds_controller (external, ROS node faulty_fsw) stopped at step 3: its inputs for that step had arrived, '
             'its outputs did not (/acds/controller/moment_command of step 3, t = 3 s)'),
])
def test_an_external_node_that_breaks_the_step_rule_fails_the_run_in_one_line(launch_graph, fault, got):
    """Issue 20 §1: twice for one step, a wrong stamp, a skipped step, another frame than the contract's: one line
    naming the topic, the step and what was expected (the run monitor and the node reading the topic find the
    same; the frame, the run monitor)."""
    import sys
    from pathlib import Path

    from acds_common import topics

    sc = load_scenario('oresat_detumble')
    sc.values['']['input_timeout'] = 3.0  # the stall of a skipped step
    with launch_graph(sc, steps=50, external=['acds_controller=faulty_fsw']) as graph:
        spec = graph.graph.nodes['acds_controller']
        inputs = [f'{spec.topic(i.topic)}={topics.type_of(i.topic)}' for st in spec.stages for i in st.inputs
                  if i.source in graph.graph.nodes]
        argv = [sys.executable, str(Path(__file__).parent / 'fixtures' / 'faulty_external.py'), 'faulty_fsw', fault,
                '/acds/magnetometer/volts', '/acds/controller/moment_command', str(round(1e9)), *inputs]
        with external_node(graph, argv):
            with pytest.raises(LaunchError) as err:
                graph.wait()
    line = str(err.value).splitlines()[0]
    assert got in line, line
    if fault == 'wallclock':
        assert line.endswith('expected one message for step 3, stamped 3000000000 ns (t = 3 s)'), line


def _endpoint(node_name: str, topic_type: str):
    from types import SimpleNamespace

    from rclpy.qos import DurabilityPolicy, ReliabilityPolicy
    qos = SimpleNamespace(reliability=ReliabilityPolicy.RELIABLE, durability=DurabilityPolicy.TRANSIENT_LOCAL)
    return SimpleNamespace(node_name=node_name, node_namespace='/acds', topic_type=topic_type, qos_profile=qos)


def test_an_external_node_with_another_message_type_is_named_by_its_type_not_its_qos():
    """A publisher (or a subscription) of another type than the contract's never matches the graph's endpoints:
    the readiness line names the topic and both types, never a QoS problem the node does not have, nor inputs
    "arrived" at a node that cannot read them."""
    from types import SimpleNamespace

    from acds_common.graph import build_graph
    from acds_common.parameters import node_parameters
    from acds_runtime.external import ExternalWatch

    sc = load_scenario('oresat_detumble')
    external = sc.external(['acds_controller=my_fsw'])
    watch = ExternalWatch(build_graph(node_parameters(sc, 10, external=external)), external, 10**9)
    vector3s = 'geometry_msgs/msg/Vector3Stamped'
    pubs = {'/acds/controller/moment_command': [_endpoint('my_fsw', 'geometry_msgs/msg/Vector3')]}
    subs = {'/acds/magnetometer/volts': [_endpoint('my_fsw', 'sensor_msgs/msg/Imu')]}
    node = SimpleNamespace(get_publishers_info_by_topic=lambda t: pubs.get(t, []),
                           get_subscriptions_info_by_topic=lambda t: subs.get(t, []))
    [line] = watch.missing(node, {})
    assert 'QoS' not in line and 'no publisher' not in line, line
    assert line == ('external node acds_controller (ROS node my_fsw): no subscription to any of its inputs '
                    '/acds/magnetometer/volts, /acds/magnetometer/bias_volts, /acds/sensors/gyro, /acds/sensors/sun, '
                    '/acds/truth/odometry, /acds/em_driver/coil_current; publishes another message type than the '
                    "contract's: /acds/controller/moment_command as geometry_msgs/msg/Vector3 (the contract: "
                    f"{vector3s}); subscribes to another message type than the contract's: /acds/magnetometer/volts "
                    f'as sensor_msgs/msg/Imu (the contract: {vector3s})'), line
    # The right types, matched: nothing missing.
    pubs = {'/acds/controller/moment_command': [_endpoint('my_fsw', vector3s)]}
    subs = {'/acds/magnetometer/volts': [_endpoint('my_fsw', vector3s)]}
    assert watch.missing(node, {'/acds/controller/moment_command': 1}) == []


def test_steps_that_go_back_are_named_as_such():
    """A user's node left running from an earlier run on the same domain hands a new run that run's steps from its
    transient-local history, then this run's step 0: the line says the steps went back and what to do, not only
    "a second message" (measured: step 0 after step 200 of the earlier run)."""
    from acds_common.lockstep import sequence_error

    line = sequence_error('/acds/controller/moment_command', 'my_fsw', 0, 200, 10**9)
    assert line == ('/acds/controller/moment_command: my_fsw sent step 0 after step 200 (its steps went back: were '
                    'its earlier messages kept from another run on this ROS domain? restart the node for each run); '
                    'expected one message for step 201, stamped 201000000000 ns (t = 201 s)'), line
    assert 'a second message for step 3;' in sequence_error('/t', 'my_fsw', 3 * 10**9, 3, 10**9)


def test_quiet_keeps_the_line_that_says_how_to_join(tmp_path):
    """``--quiet`` drops the nodes' output, not the launcher's line that tells the user where and how their node
    joins (the domain, the ROS node name, the contract command): without it a quiet run waited without saying for
    what until its timeout. The run is stopped (SIGINT) once the line is read; without the line it fails at its
    20 s readiness floor and the output ends."""
    import signal
    import subprocess
    import sys

    path = tmp_path / 'quiet.yaml'
    path.write_text('extends: oresat_detumble\nname: oresat_quiet\ninput_timeout_s: 1\n')
    proc = subprocess.Popen([sys.executable, '-m', 'acds_cli', 'run', str(path), '--steps', '3', '--no-record',
                             '--quiet', '--external', 'acds_controller=my_fsw', '--run-dir', str(tmp_path / 'run')],
                            stdin=subprocess.DEVNULL, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True,
                            env={'PATH': '/usr/bin:/bin', 'ROS_LOG_DIR': str(tmp_path / 'ros_log')})
    assert proc.stderr is not None
    seen = []
    try:
        for line in proc.stderr:
            seen.append(line)
            if line.startswith('[acds] external node acds_controller: waiting'):
                break
    finally:
        proc.send_signal(signal.SIGINT)
        proc.communicate(timeout=60)
    text = ''.join(seen)
    assert '[acds] external node acds_controller: waiting (at most 20 s) for ROS node my_fsw in namespace /acds on ' \
           'ROS_DOMAIN_ID=' in text, text
    assert 'its contract: ./scripts/acds contract oresat_quiet --node acds_controller' in text, text
