"""Flight-software timing (issue 20 §4): each node's step wall time, p50/p99/max, deadlines; never the data."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import pytest
from acds_common import topics
from acds_common.messages import WALL_CLOCK_PREFIX
from acds_common.timing import BINS_PER_DECADE, DECADES, StepTimes, deadline_warnings, parse_line, table
from acds_runtime.launcher import LaunchError

ROOT = Path(__file__).resolve().parents[1]


def test_step_times_are_bounded_and_ordered():
    t = StepTimes(deadline_s=2e-3)
    for k in range(10_000):
        t.add(k, 1e-4 * (1 + k % 100) if k != 5000 else 0.5)
    assert len(t.bins) == BINS_PER_DECADE * DECADES + 1  # fixed, whatever the run's length
    r = t.report()
    assert r['steps'] == 10_000 and r['max_ms'] == pytest.approx(500.0)
    assert 0 < r['p50_ms'] <= r['p99_ms'] <= r['max_ms']
    assert 5.1 <= r['p50_ms'] <= 5.1 * 10 ** (1 / BINS_PER_DECADE)  # the median (5.1 ms) to one bin: ≤ 6 % high
    assert r['over_deadline'] == 1 + 80 * 100 and r['first_over_step'] == 20
    assert parse_line(f'[x] {t.line()}') == r
    assert deadline_warnings({'x': r})[0].startswith('x: 8001 of 10000 steps over the 2 ms deadline (first at step 20')
    assert len(table({'x': r, 'y': None})) == 3


def test_a_graph_run_reports_each_nodes_step_times_beside_unchanged_data(launch_graph):
    with launch_graph('heao_b_acquisition_short', steps=120) as graph:
        result = graph.wait()
        diags = graph.monitor.messages(topics.DIAGNOSTICS)
    assert set(result.timing) == set(graph.graph.nodes)
    for node, t in result.timing.items():
        assert t is not None, f'{node} left no timing report'
        assert t['steps'] >= 120, node
        assert 0 < t['p50_ms'] <= t['p99_ms'] <= t['max_ms'], (node, t)
    assert 'timing' not in result.summary  # the summary (and its digest) is the data's
    keys = {kv.key for m in diags for st in m.status if st.name == 'acds_controller' for kv in st.values}
    assert {f'{WALL_CLOCK_PREFIX}step_p50_ms', f'{WALL_CLOCK_PREFIX}step_max_ms'} <= keys


def test_deadline_strict_fails_the_run_at_the_first_overrun_naming_node_and_step(launch_graph):
    overrides = {'acds_controller': {'deadline_ms': 0.001, 'deadline_strict': True}}
    with launch_graph('heao_b_acquisition_short', steps=50, overrides=overrides) as graph, \
            pytest.raises(LaunchError, match=r'node acds_controller died .*step 0 took [0-9.]+ ms .*over the deadline '
                                             r'of 0.001 ms'):
        graph.wait()


@pytest.mark.parametrize('args', [('--deadline-ms', 'nope=1'), ('--deadline-ms', 'acds_controller=0'),
                                  ('--deadline-ms', 'acds_controller=inf'), ('--deadline-ms', 'acds_controller=-2'),
                                  ('--deadline-strict',),
                                  ('--deadline-ms', 'acds_controller=1', '--engine', 'direct')])
def test_bad_deadlines_are_one_line_exit_2_before_any_process(args, tmp_path):
    out = subprocess.run([sys.executable, '-m', 'acds_cli', 'run', 'heao_b_acquisition_short', '--steps', '5',
                          '--no-record', '--run-dir', str(tmp_path / 'run'), *args],
                         cwd=ROOT, capture_output=True, text=True, timeout=120, check=False)
    assert out.returncode == 2, out.stderr
    assert len(out.stderr.strip().splitlines()) == 1, out.stderr
    assert not (tmp_path / 'run').exists()
