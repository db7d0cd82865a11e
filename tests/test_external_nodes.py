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
                           'no subscription to /acds/em_driver/coil_current, /acds/magnetometer/bias_volts, '), text
    assert '\n' not in text


@pytest.mark.parametrize(('item', 'message'), [
    ('wheel_law', "external node 'wheel_law': not a node of this graph"),
    ('rigid_body', "external node 'rigid_body': it owns sim time"),
    ('acds_controller=9lives', "'9lives' is not a ROS node name"),
])
def test_bad_external_nodes_are_one_line_before_any_process(launch_graph, item, message):
    with pytest.raises(LaunchError, match=message) as err:
        with launch_graph('oresat_detumble', steps=10, external=[item]):
            pass
    assert '\n' not in str(err.value)
