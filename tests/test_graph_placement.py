"""Node processes placed on two CPUs by the launcher (acds_runtime.placement): each binds itself, with every thread
it starts, to the CPU it is given; the data are those of the same run placed by the operating system."""

from __future__ import annotations

import os
import subprocess
import sys

from acds_common.lockstep import CPU_ENV
from acds_common.scenario import load_scenario
from acds_runtime import placement
from acds_runtime.launcher import GraphRun
from acds_runtime.testing import stream_digests

SCENARIO = 'heao_b_acquisition_short'
STEPS = 60


def _allowed() -> tuple[int, int]:
    cpus = sorted(os.sched_getaffinity(0))
    return cpus[0], cpus[-1]


def _affinity(pid: int) -> dict[str, set[int]]:
    """The CPUs each thread of process ``pid`` may run on, by ``name#tid``."""
    out = {}
    for t in os.listdir(f'/proc/{pid}/task'):
        with open(f'/proc/{pid}/task/{t}/comm') as f:
            out[f'{f.read().strip()}#{t}'] = os.sched_getaffinity(int(t))
    return out


def test_a_node_process_binds_itself_to_the_cpu_it_is_given():
    cpu = _allowed()[1]
    code = ('import os; from acds_common.lockstep import take_cpu; take_cpu("n"); '
            'print(sorted(os.sched_getaffinity(0)))')
    out = subprocess.run([sys.executable, '-c', code], env=dict(os.environ, **{CPU_ENV: str(cpu)}), text=True,
                         capture_output=True, check=True)
    assert out.stdout.strip() == f'[{cpu}]' and out.stderr == ''


def test_a_cpu_it_may_not_use_is_said_in_one_line_and_left_to_the_os():
    code = ('import os; from acds_common.lockstep import take_cpu; take_cpu("n"); '
            'print(sorted(os.sched_getaffinity(0)))')
    out = subprocess.run([sys.executable, '-c', code], env=dict(os.environ, **{CPU_ENV: '100000'}), text=True,
                         capture_output=True, check=True)
    assert out.stdout.strip() == str(sorted(os.sched_getaffinity(0)))
    assert out.stderr.startswith("[n] not placed on CPU '100000' (") and out.stderr.count('\n') == 1


def test_placed_nodes_run_where_placed_and_send_the_same_data(launch_graph, monkeypatch):
    monkeypatch.setattr(placement, 'placement_cpus', _allowed)
    seen: dict[str, dict[str, set[int]]] = {}

    def look(k: int, _total: int, _wall: float) -> None:
        if k >= STEPS // 2 and not seen:
            seen.update({name: _affinity(p.popen.pid) for name, p in graph.processes.items()})

    with launch_graph(SCENARIO, steps=STEPS, progress=look, place=True) as graph:
        graph.wait()
        placed = stream_digests(graph.monitor)
    assert graph.placement == placement.place(placement.shape_of(graph.graph), _allowed())
    assert any(line.startswith('[acds] node processes placed on the two CPUs (CPU ') for line in graph.output)
    assert set(seen) == set(graph.processes) == set(graph.placement)
    for name, threads in seen.items():
        assert len(threads) > 3, f'{name}: Fast DDS threads expected'
        elsewhere = {t: cpus for t, cpus in threads.items() if cpus != {graph.placement[name]}}
        assert not elsewhere, f'{name} placed on CPU {graph.placement[name]}; threads elsewhere: {elsewhere}'
    with launch_graph(SCENARIO, steps=STEPS) as unplaced:
        unplaced.wait()
        assert stream_digests(unplaced.monitor) == placed
    assert unplaced.placement == {}
    assert not any('placed on the two CPUs' in line for line in unplaced.output)




def test_placement_is_asked_for_and_never_in_a_run_paced_to_the_wall_clock(tmp_path):
    scenario = load_scenario(SCENARIO)
    assert GraphRun(scenario, tmp_path / 'a', place=True).place
    assert not GraphRun(scenario, tmp_path / 'b', rtf=1.0, place=True).place
    assert not GraphRun(scenario, tmp_path / 'c').place  # a study's samples, the tests' graphs
