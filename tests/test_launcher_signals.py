"""The launcher stops every node on SIGINT/SIGTERM/SIGHUP (exit 128 + signal); pacing holds sim time back."""

from __future__ import annotations

import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest
from acds_runtime.testing import read_until

ROOT = Path(__file__).resolve().parents[1]


def node_processes(run_dir: Path) -> list[str]:
    out = subprocess.run(['pgrep', '-f', f'{run_dir}/params.yaml'], capture_output=True, text=True, check=False)
    return out.stdout.split()


def _ignore_sigint() -> None:
    signal.signal(signal.SIGINT, signal.SIG_IGN)


@pytest.mark.parametrize(('sig', 'inherited'), [(signal.SIGTERM, None), (signal.SIGINT, None), (signal.SIGHUP, None),
                                                (signal.SIGINT, _ignore_sigint)],
                         ids=['SIGTERM', 'SIGINT', 'SIGHUP', 'SIGINT-ignored-by-the-parent'])
def test_signal_stops_every_node(tmp_path, sig, inherited):
    """Also when the parent ignored SIGINT (a job started with & from a script, a harness): Python would keep
    it ignored, and the run would go on."""
    run_dir = tmp_path / 'run'
    proc = subprocess.Popen([sys.executable, '-m', 'acds_cli', 'run', 'free_tumble_heao_b', '--steps', '1000000',
                             '--run-dir', str(run_dir), '--quiet'],
                            cwd=ROOT, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                            env={'PATH': '/usr/bin:/bin',
                                 'ROS_LOG_DIR': str(tmp_path / 'log')}, preexec_fn=inherited)
    read_until(proc, lambda line: '[progress]' in line and 'step 0/' not in line)  # the run's own progress
    assert len(node_processes(run_dir)) == 2
    proc.send_signal(sig)
    rest, _ = proc.communicate(timeout=60)
    assert proc.returncode == 128 + sig  # 143 SIGTERM, 130 SIGINT, 129 SIGHUP
    assert node_processes(run_dir) == []


def test_real_time_factor_paces_sim_time(launch_graph):
    with launch_graph('free_tumble_heao_b', steps=20, rtf=5.0) as graph:  # 10 s of sim time at 5x
        t0 = time.monotonic()
        graph.wait()
        assert time.monotonic() - t0 >= 10.0 / 5.0 * 0.95
