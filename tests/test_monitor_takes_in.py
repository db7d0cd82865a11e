"""The run monitor without a bag takes in only what some node, the summaries or the truth digest read.

With a bag (or kept messages, or a live view) it subscribes to every output of the graph; without, an output nobody
reads (OreSat's ``magnetometer/field``, ``em_driver/dipole_end``, ``em_driver/e_ft``) is not delivered to it: the
run's summary and truth digest are the same, and a hung node is still named with an output it stopped.
"""

from __future__ import annotations

import re

from acds_common import topics
from acds_common.scenario import load_scenario
from acds_runtime.testing import failure_of_hung

UNREAD = {topics.resolve(t) for t in (topics.MAG_FIELD, topics.DIPOLE_END, topics.E_FT)}


def test_a_run_without_a_bag_leaves_out_what_nobody_reads_and_summarises_the_same(launch_graph):
    summaries, taken = [], []
    for keep in (True, False):
        with launch_graph('oresat_detumble', steps=40, keep=keep) as graph:
            result = graph.wait()
            taken.append(set(graph.monitor.taken_in))
            summaries.append({k: v for k, v in result.summary.items() if k != 'wall_seconds'})
    everything, some = taken
    assert UNREAD <= everything and not UNREAD & some, (everything, some)
    assert everything - some == UNREAD | {'/diagnostics'}, everything - some
    assert summaries[0] == summaries[1]


def test_a_hung_node_is_named_without_a_bag(launch_graph):
    sc = load_scenario('heao_b_acquisition')
    sc.values['']['input_timeout'] = 5.0
    with launch_graph(sc, keep=False) as graph:
        assert topics.resolve(topics.E_FT) not in graph.monitor.taken_in
        assert graph.monitor.wait_for(lambda: graph.monitor.count(topics.CLOCK) >= 10, timeout_s=60.0), 'no step 10'
        text = failure_of_hung(graph, 'em_driver')
    assert text.startswith('em_driver stopped at step'), text
    # the outputs it stopped, among those taken in (which node's input wait ran out first depends on the load)
    blame = text.split(' (the graph stopped waiting for it)')[0]
    assert re.search(r'its outputs did not \(/acds/em_driver/(dipole_avg|coil_current)', blame), text
    assert 'e_ft' not in blame and 'dipole_end' not in blame, text
