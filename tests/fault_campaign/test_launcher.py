"""Fault campaign, issue 9 §2: a launcher that dies takes its nodes with it; a lone time owner runs.

Each case is what a hostile but fair user does: SIGKILL the launcher (or close its terminal),
start the time owner by hand with no other node, stop a node and read who is blamed.
"""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import yaml
from acds_runtime.testing import read_until

ROOT = Path(__file__).resolve().parents[2]
VENV_BIN = Path(sys.executable).parent


def _env(tmp_path: Path) -> dict[str, str]:
    return {'PATH': f'{VENV_BIN}:/usr/bin:/bin',
            'ROS_LOG_DIR': str(tmp_path / 'log'), 'CI': 'true'}


def _node_pids(run_dir: Path) -> list[int]:
    out = subprocess.run(['pgrep', '-f', f'{run_dir}/params.yaml'], capture_output=True, text=True, check=False)
    return [int(p) for p in out.stdout.split()]


def _start_run(tmp_path: Path, scenario: str = 'free_tumble_heao_b') -> tuple[subprocess.Popen[str], Path]:
    run_dir = tmp_path / 'run'
    proc = subprocess.Popen([sys.executable, '-m', 'acds_cli', 'run', scenario, '--steps', '1000000',
                             '--run-dir', str(run_dir), '--quiet', '--no-record'],
                            cwd=ROOT, stdin=subprocess.DEVNULL, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE,
                            text=True, env=_env(tmp_path))
    read_until(proc, lambda line: '[progress]' in line and 'step 0/' not in line)  # the run's own progress output
    return proc, run_dir


def _domain_locked(run_dir: Path) -> bool:
    from acds_runtime.launcher import DomainLease

    return DomainLease.held(int((run_dir / 'domain_id').read_text()))


def test_sigkilled_launcher_takes_its_nodes_within_two_seconds(tmp_path):
    """Even a node that is stopped (or hung in DDS, or holding the interpreter lock) goes with its launcher:
    the kernel's parent-death SIGKILL needs nothing from the node (CI: a stopped node resumed with a
    cooperative signal spent over 2 s in DDS teardown towards its dead peers)."""
    proc, run_dir = _start_run(tmp_path)
    pids = _node_pids(run_dir)
    assert len(pids) == 2
    os.kill(pids[0], signal.SIGSTOP)
    os.kill(proc.pid, signal.SIGKILL)
    proc.wait()
    deadline = time.monotonic() + 2.0
    while _node_pids(run_dir) and time.monotonic() < deadline:
        time.sleep(0.05)  # polling the process table, not synchronising the graph
    left = _node_pids(run_dir)
    for pid in left:  # never leave an orphan behind, even when the test fails
        os.kill(pid, signal.SIGKILL)
    assert left == [], 'a node outlived its SIGKILLed launcher by more than 2 s'
    # A dying process leaves pgrep's sight (its memory, hence its command line, goes first) before the kernel
    # closes its files, the lease among them: the lease gets the same bounded wait (CI, loaded: seen held).
    deadline = time.monotonic() + 2.0
    while _domain_locked(run_dir) and time.monotonic() < deadline:
        time.sleep(0.05)  # polling the lock, not synchronising the graph
    assert not _domain_locked(run_dir), 'the domain lease outlived the nodes of a SIGKILLed launcher by more than 2 s'


def test_the_domain_stays_leased_while_any_holder_lives(tmp_path):
    """The lease is the open lock file every node inherits: a launcher that is gone does not free the
    domain while one of its children still runs."""
    from acds_runtime.launcher import DomainLease

    lease = DomainLease()
    child = subprocess.Popen([sys.executable, '-c', 'import sys; sys.stdin.read()'], stdin=subprocess.PIPE,
                             pass_fds=(lease.fd,))
    try:
        lease.close()  # what the launcher's death does to its own hold
        assert DomainLease.held(lease.domain_id), 'the domain was released while a holder lived'
    finally:
        assert child.stdin is not None
        child.stdin.close()
        child.wait(timeout=30)
    assert not DomainLease.held(lease.domain_id), 'the last holder exited and the domain is still leased'


def test_a_node_whose_launcher_died_before_it_came_up_leaves_at_once(tmp_path):
    """The parent-death request is made by the node itself; a launcher gone before that is seen from the
    parent pid, and the node exits 4 without joining the domain."""
    env = {**_env(tmp_path), 'ACDS_LAUNCHER_PID': '1', 'ROS_DOMAIN_ID': '0',
           'ROS_AUTOMATIC_DISCOVERY_RANGE': 'OFF'}
    done = subprocess.run([str(VENV_BIN / 'rigid_body')], stdin=subprocess.DEVNULL, capture_output=True,
                          text=True, env=env, timeout=120, check=False)
    assert done.returncode == 4, done.stderr[-2000:]
    assert done.stderr.strip().splitlines() == [
        '[rigid_body] STOPPED: the launcher that started it (pid 1) has died']


def test_lone_time_owner_runs_5000_steps_without_recursion(tmp_path):
    """rigid_body started by hand with its params file, no other node and no monitor."""
    from acds_common.parameters import node_parameters
    from acds_common.scenario import load_scenario

    sc = load_scenario('free_tumble_heao_b')
    params = node_parameters(sc, 5000, 0.0)['rigid_body']
    params['graph_nodes'] = ['rigid_body']
    params_file = tmp_path / 'params.yaml'
    params_file.write_text(yaml.safe_dump({'/acds/rigid_body': {'ros__parameters': params}}))
    env = {**_env(tmp_path), 'ROS_DOMAIN_ID': '0', 'ROS_AUTOMATIC_DISCOVERY_RANGE': 'OFF'}
    done = subprocess.run([str(VENV_BIN / 'rigid_body'), '--ros-args', '--params-file', str(params_file)],
                          stdin=subprocess.DEVNULL, capture_output=True, text=True, env=env, timeout=600, check=False)
    assert done.returncode == 0, done.stderr[-2000:]
    assert 'RecursionError' not in done.stderr


def _participants_of_this_process() -> int:
    """Fast DDS participants alive in this process: each holds ``flock`` locks on its /dev/shm files."""
    pid = str(os.getpid())
    return sum(1 for line in Path('/proc/locks').read_text().splitlines() if line.split()[4] == pid)


def test_a_finished_run_leaves_no_participant_in_the_launcher(tmp_path):
    """The run monitor's DDS participant ends with its run: a leftover one kept its transient-local READY
    and acknowledgements on the domain, and the next run there started (and finished) on them before its
    own monitor had matched (CI: 'run monitor received no /clock at all')."""
    from acds_common.scenario import load_scenario
    from acds_runtime.launcher import GraphRun

    before = _participants_of_this_process()
    domains = []
    for i in range(2):
        with GraphRun(load_scenario('free_tumble_heao_b'), tmp_path / f'run{i}', steps=5,
                      echo=lambda _line: None) as graph:
            result = graph.wait()
            domains.append(graph.lease.domain_id)
        assert result.steps == 5
        assert _participants_of_this_process() == before, f'run {i} left its monitor participant alive'
    assert domains[0] == domains[1], 'both runs of one process lease the same domain (the case that failed)'
