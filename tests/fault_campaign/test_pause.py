"""Fault campaign, issue 18 §4: a paused run resumes and finishes with the uninterrupted run's data.

Ctrl-Z stops the launcher's process group (SIGTSTP); the nodes run in sessions of their own, so before the fix
they ran on, the time owner timed out on the stopped run monitor and the run failed after SIGCONT. Freezing every
process (docker pause, a suspended machine) made every node's wall-clock input timeout fire on resume. Each
pause here lasts longer than the scenario's input timeout and than Fast DDS's default 20 s participant lease.
A node stopped alone is still named as the one that stopped.
"""

from __future__ import annotations

import json
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest
from acds_runtime.testing import read_until

ROOT = Path(__file__).resolve().parents[2]
VENV_BIN = Path(sys.executable).parent
STEPS = 400
#: Wall seconds of each pause: past the input timeout (3 s) and past Fast DDS's default participant lease (20 s).
PAUSE_S = 22.0


def _scenario(tmp_path: Path) -> Path:
    path = tmp_path / 'paused.yaml'
    path.write_text('extends: heao_b_acquisition\nname: heao_b_paused\ninput_timeout_s: 3\n')
    return path


def _run(tmp_path: Path, *args: str) -> subprocess.Popen[str]:
    env = {'PATH': f'{VENV_BIN}:/usr/bin:/bin',
           'ROS_LOG_DIR': str(tmp_path / 'log'), 'CI': 'true'}
    return subprocess.Popen([sys.executable, '-m', 'acds_cli', 'run', str(_scenario(tmp_path)), '--steps', str(STEPS),
                             '--no-record', '--quiet', *args], cwd=ROOT, stdin=subprocess.DEVNULL,
                            stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True, env=env,
                            start_new_session=True)  # its own process group, as a shell job is


def _after_progress(run: subprocess.Popen[str]) -> None:
    read_until(run, lambda line: '[progress]' in line and 'step 0/' not in line)  # the run's own progress output


def _node_pids(launcher: int) -> list[int]:
    out = subprocess.run(['pgrep', '-P', str(launcher), '-f', 'params.yaml'], capture_output=True, text=True,
                         check=False)
    return [int(p) for p in out.stdout.split()]


def _direct_digest(tmp_path: Path) -> str:
    run = _run(tmp_path, '--engine', 'direct', '--summary-json', str(tmp_path / 'direct.json'),
               '--run-dir', str(tmp_path / 'direct'))
    _, err = run.communicate(timeout=120)
    assert run.returncode == 0, err
    return json.loads((tmp_path / 'direct.json').read_text())['truth_digest']


def _finish(run: subprocess.Popen[str], tmp_path: Path) -> dict:
    _, err = run.communicate(timeout=300)
    assert run.returncode == 0, err[-3000:]
    return json.loads((tmp_path / 'graph.json').read_text())


@pytest.mark.slow
def test_ctrl_z_stops_the_graph_and_fg_finishes_it(tmp_path):
    """SIGTSTP to the launcher's process group (Ctrl-Z), SIGCONT after the pause (fg): the same data."""
    want = _direct_digest(tmp_path)
    run = _run(tmp_path, '--summary-json', str(tmp_path / 'graph.json'), '--run-dir', str(tmp_path / 'g'))
    _after_progress(run)
    nodes = _node_pids(run.pid)
    os.killpg(run.pid, signal.SIGTSTP)
    time.sleep(PAUSE_S)  # the length of the user's pause, the case under test (no synchronisation)
    stopped = [pid for pid in nodes if Path(f'/proc/{pid}/stat').read_text().rpartition(')')[2].split()[0] == 'T']
    os.killpg(run.pid, signal.SIGCONT)
    assert len(stopped) == len(nodes) == 6, f'{len(stopped)} of {len(nodes)} nodes were stopped with the launcher'
    got = _finish(run, tmp_path)
    assert got['steps'] == STEPS and got['truth_digest'] == want


@pytest.mark.slow
def test_a_frozen_graph_resumes(tmp_path):
    """Every process of the run stopped at once (docker pause, a suspended machine), then continued: the
    input timeouts count only time the processes ran, so the run finishes with the same data."""
    want = _direct_digest(tmp_path)
    run = _run(tmp_path, '--summary-json', str(tmp_path / 'graph.json'), '--run-dir', str(tmp_path / 'g'))
    _after_progress(run)
    everyone = [run.pid, *_node_pids(run.pid)]
    for pid in everyone:
        os.kill(pid, signal.SIGSTOP)
    time.sleep(PAUSE_S)  # the length of the freeze, the case under test (no synchronisation)
    for pid in everyone:
        os.kill(pid, signal.SIGCONT)
    got = _finish(run, tmp_path)
    assert got['steps'] == STEPS and got['truth_digest'] == want


def test_a_node_stopped_alone_is_named_by_the_others(tmp_path):
    """em_driver stopped past the others' input timeout, then continued: the run fails naming em_driver as the
    node whose outputs stopped, not with em_driver's own complaint, on resume, that its inputs never arrived."""
    run = _run(tmp_path, '--run-dir', str(tmp_path / 'g'))
    _after_progress(run)
    pid = int(subprocess.run(['pgrep', '-P', str(run.pid), '-f', 'em_driver'], capture_output=True, text=True,
                             check=False).stdout.split()[0])
    os.kill(pid, signal.SIGSTOP)
    time.sleep(5.0)  # past the others' 3 s input timeout: the case under test (no synchronisation)
    os.kill(pid, signal.SIGCONT)
    _, err = run.communicate(timeout=120)
    assert run.returncode == 1, err[-3000:]
    failure = next(line for line in err.splitlines() if line.startswith('[acds] run failed:'))
    assert failure.startswith('[acds] run failed: em_driver stopped at step'), err[-3000:]
