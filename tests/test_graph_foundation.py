"""Graph tests of the foundation: determinism, no orphans, a dying or hung node is named."""

from __future__ import annotations

import os
import re
import signal

import pytest
from acds_common import topics
from acds_common.scenario import load_scenario
from acds_runtime.launcher import LaunchError
from acds_runtime.testing import alive, failure_of_hung, stream_digests, wait_for_messages

STEPS = 120


def test_two_runs_publish_identical_truth(launch_graph):
    digests, streams = [], []
    for _ in range(2):
        with launch_graph('free_tumble_heao_b', steps=STEPS) as graph:
            result = graph.wait()
            assert result.exit_codes == {'rigid_body': 0, 'reaction_wheels': 0}
            odom = result.monitor.messages(topics.TRUTH_ODOMETRY)
            assert len(odom) == STEPS + 1, 'one truth message per step, 0..N'
            assert [m.header.stamp.nanosec + m.header.stamp.sec * 10**9 for m in odom[:3]] == [0, 500_000_000, 10**9]
            digests.append(result.summary['truth_digest'])
            streams.append(stream_digests(result.monitor))
            pids = [p.popen.pid for p in graph.processes.values()]
        assert not any(alive(pid) for pid in pids)
    assert digests[0] == digests[1]
    assert streams[0] == streams[1]


def test_killed_node_ends_the_run_naming_it(launch_graph):
    with launch_graph('free_tumble_heao_b', steps=100000) as graph:
        wait_for_messages(graph, topics.CLOCK, 20)
        os.kill(graph.processes['reaction_wheels'].popen.pid, signal.SIGKILL)
        with pytest.raises(LaunchError, match=r'node reaction_wheels died \(killed by signal SIGKILL\)'):
            graph.wait()


def test_hung_node_fails_the_run_naming_node_and_topic(launch_graph):
    sc = load_scenario('free_tumble_heao_b')
    # long enough for a run monitor that a loaded machine has put 50 steps behind to catch up (it paces the graph)
    sc.values['']['input_timeout'] = 5.0
    with launch_graph(sc, steps=100000) as graph:
        wait_for_messages(graph, topics.CLOCK, 10)
        text = failure_of_hung(graph, 'reaction_wheels')
    assert text.startswith('reaction_wheels stopped at step'), text  # the node whose outputs stopped
    # which of its outputs (torque, momentum) is missing depends on where in its step the SIGSTOP landed
    assert re.search(r'/acds/wheels/(momentum|torque) \(from reaction_wheels', text), text
    assert 'last lines of reaction_wheels:' in text and 'the process is stopped' in text, text


def test_a_node_the_graph_waits_on_is_asked_for_its_python_stack(launch_graph):
    """A hung node is reported with where it hangs: the launcher asks a live node for its stack (faulthandler on
    STACK_SIGNAL), which costs the node nothing (it steps on)."""
    with launch_graph('free_tumble_heao_b', steps=100000) as graph:
        wait_for_messages(graph, topics.CLOCK, 10)
        report = graph._stack_of(graph.processes['reaction_wheels'])
        before = graph.monitor.clock_step
        graph.monitor.wait_for(lambda: graph.monitor.clock_step > before + 10, timeout_s=60.0)
        assert graph.monitor.clock_step > before + 10, 'the graph stopped stepping after the stack dump'
        assert graph.exit_report() is None
    assert 'last lines of reaction_wheels:' in report and 'File "' in report, report


def test_unknown_node_parameter_is_one_precise_error(launch_graph):
    with launch_graph('free_tumble_heao_b', steps=10,
                      overrides={'reaction_wheels': {'wheels_layuot': 'four_cant20'}}) as graph:
        with pytest.raises(LaunchError, match=r'node reaction_wheels died \(exit code 2\): '
                                              r'.*CONFIGURATION ERROR: reaction_wheels: unknown parameter\(s\) wheels_layuot'):
            graph.wait()


def test_a_node_that_hangs_on_its_way_out_is_killed_and_reported_and_the_run_stands(launch_graph):
    """A node that does not stop on SIGINT once the run is complete is SIGKILLed after the grace period. Every
    step's output is already in, so the run keeps its result, and the report says the launcher killed the node
    (not that it died of a SIGKILL from nowhere)."""
    with launch_graph('free_tumble_heao_b', steps=20) as graph:
        stop_children = graph._stop_children
        stuck: list[str] = []

        def with_a_stuck_node(grace_s: float = 10.0) -> dict[str, int]:
            name, proc = next((n, p) for n, p in graph.processes.items() if p.popen.poll() is None)
            os.kill(proc.popen.pid, signal.SIGSTOP)
            stuck.append(name)
            return stop_children(grace_s=1.0)

        graph._stop_children = with_a_stuck_node
        result = graph.wait()
    assert result.steps == 20 and result.exit_codes[stuck[0]] == -signal.SIGKILL
    assert [w.splitlines()[0] for w in result.warnings] == [
        f'node {stuck[0]} did not stop within 1 s of SIGINT (the launcher killed it)']


def test_a_running_node_that_does_not_stop_is_reported_with_its_stack(launch_graph):
    """A node still running when the grace period ends (here: it never got the SIGINT) has its Python stack
    asked for before the SIGKILL, so the report says where it hung, not only that it did."""
    with launch_graph('free_tumble_heao_b', steps=20) as graph:
        stop_children, deaf = graph._stop_children, []

        def signal_all_but_one(sig: signal.Signals) -> None:
            running = [(n, p) for n, p in graph.processes.items() if p.popen.poll() is None]
            deaf.append(running[0][0])
            for _name, proc in running[1:]:
                os.killpg(proc.popen.pid, sig)

        graph._signal_nodes = signal_all_but_one
        graph._stop_children = lambda grace_s=10.0: stop_children(grace_s=1.0)
        result = graph.wait()
    assert result.steps == 20 and result.exit_codes[deaf[0]] == -signal.SIGKILL
    report = result.warnings[0]
    assert report.splitlines()[0] == f'node {deaf[0]} did not stop within 1 s of SIGINT (the launcher killed it)'
    assert '(its Python stack, asked for by the launcher:)' in report and 'File "' in report, report


def test_publisher_check_counts_unnamed_publishers_against_the_declared_nodes_not_yet_named():
    """A node stopped before discovery learnt its name stays unnamed: not an intruder while a declared node is
    unaccounted for; one more unnamed publisher than that is, after the grace; a named stranger at once."""
    from types import SimpleNamespace

    from acds_common.lockstep import UNNAMED, UNNAMED_GRACE_S, PublisherCheck

    def info(name):
        return SimpleNamespace(node_name=name, node_namespace='/' if name == UNNAMED else '/acds')

    declared = {'rigid_body', 'reaction_wheels'}
    check = PublisherCheck()
    frozen = [info('rigid_body'), info(UNNAMED)]
    assert check.strangers('/diagnostics', frozen, declared, 0.0) == []
    assert check.strangers('/diagnostics', frozen, declared, 10 * UNNAMED_GRACE_S) == []
    extra = frozen + [info(UNNAMED)]
    assert check.strangers('/diagnostics', extra, declared, 100.0) == []  # the grace starts
    assert check.strangers('/diagnostics', extra, declared, 100.0 + UNNAMED_GRACE_S) == \
        ['a publisher without a ROS node name']
    named = [info('rigid_body'), info('reaction_wheels'), info('intruder')]
    assert check.strangers('/diagnostics', named, declared, 0.0) == ['intruder']
    twice = [info('rigid_body'), info('rigid_body')]
    assert check.strangers('/diagnostics', twice, declared, 0.0) == ['a second node named rigid_body']
