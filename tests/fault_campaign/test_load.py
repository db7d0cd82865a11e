"""Fault campaign, issue 18: nothing silently wrong under load.

§1: a run whose launcher is starved of CPU (its threads reniced to 19, a busy loop beside it) must still
end with every step in its summary and its bag, and the direct engine's truth digest, or fail; it must never
exit 0 short. Before the fix the launcher took the run monitor's own position as the run's end and closed
the monitor with steps still queued: 950–965 of 1,000 steps, a wrong digest, exit 0.
"""

from __future__ import annotations

import json
import subprocess
import sys
import time
from pathlib import Path

import pytest
import yaml
from acds_runtime.testing import read_until

from .load import starved

ROOT = Path(__file__).resolve().parents[2]
VENV_BIN = Path(sys.executable).parent
#: Its last tenth (60 steps, starved) is more than the MONITOR_LAG (50) steps a starved monitor can fall behind.
STEPS = 600


def _env(tmp_path: Path) -> dict[str, str]:
    return {'PATH': f'{VENV_BIN}:/usr/bin:/bin',
            'ROS_LOG_DIR': str(tmp_path / 'log'), 'CI': 'true'}


def _acds(tmp_path: Path, *args: str) -> subprocess.Popen[str]:
    return subprocess.Popen([sys.executable, '-m', 'acds_cli', *args], cwd=ROOT, stdin=subprocess.DEVNULL,
                            stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True, env=_env(tmp_path))


def _clock_messages(bag: Path) -> int:
    info = yaml.safe_load((bag / 'metadata.yaml').read_text())['rosbag2_bagfile_information']
    return next(t['message_count'] for t in info['topics_with_message_count']
                if t['topic_metadata']['name'] == '/clock')


@pytest.mark.slow
@pytest.mark.timeout(1000)
def test_starved_launcher_never_exits_zero_short(tmp_path):
    """The launcher reniced to 19 beside a busy loop for the run's last tenth (the monitor, starved, falls behind
    the graph it paces, up to MONITOR_LAG steps): exit 0 means all 600 steps, the direct engine's truth digest
    and 601 /clock messages in the bag; anything else must be a non-zero exit."""
    direct = _acds(tmp_path, 'run', 'heao_b_acquisition', '--steps', str(STEPS), '--engine', 'direct', '--no-record',
                   '--quiet', '--summary-json', str(tmp_path / 'direct.json'), '--run-dir', str(tmp_path / 'd'))
    _, err = direct.communicate(timeout=120)
    assert direct.returncode == 0, err
    want = json.loads((tmp_path / 'direct.json').read_text())

    bag = tmp_path / 'bag'
    run = _acds(tmp_path, 'run', 'heao_b_acquisition', '--steps', str(STEPS), '--record', str(bag), '--quiet',
                '--summary-json', str(tmp_path / 'graph.json'), '--run-dir', str(tmp_path / 'g'))
    # starve it for its last tenth (from the run's own progress output; a run that ends before fails with its words)
    read_until(run, lambda line: '[progress]' in line and float(line.split('(')[1].split('%')[0]) >= 90)
    with starved(run.pid, loops=1):  # at nice 19 its pace is the machine's: 17 s quiet, 400-610 s beside 2 busy loops
        _, err = run.communicate(timeout=800)
    assert run.returncode == 0, f'starved run failed (allowed only with a reason, never short): {err[-2000:]}'
    got = json.loads((tmp_path / 'graph.json').read_text())
    assert got['steps'] == STEPS
    assert got['truth_digest'] == want['truth_digest']
    assert got['truth_messages'] == want['truth_messages']
    assert _clock_messages(bag) == STEPS + 1


class _SlowClockReader:
    """A live-view sink slower than the graph on /clock (as a starved monitor is): the monitor acknowledges /clock
    after its sinks, so the time owner runs the full MONITOR_LAG ahead of it and finishes with steps queued."""

    def __call__(self, topic: str, _data: bytes) -> None:
        if topic == '/clock':
            time.sleep(0.05)  # simulated slowness of the consumer, not a synchronisation

    def close(self) -> None:
        """Nothing to release."""


def test_a_monitor_behind_the_graph_drains_every_step_before_the_summary(tmp_path):
    """Completion is the time owner's last step: the run waits for the lagging monitor to take in every step
    (before the fix the summary stopped where the monitor was, ~MONITOR_LAG steps short, and exit was 0)."""
    from acds_common.graph import MONITOR_LAG
    from acds_common.scenario import load_scenario
    from acds_runtime.direct import DirectRun
    from acds_runtime.launcher import GraphRun

    sc = load_scenario('free_tumble_heao_b')
    steps = 3 * MONITOR_LAG
    want = DirectRun(sc, steps=steps).run()
    with GraphRun(sc, tmp_path / 'run', steps=steps, echo=lambda _line: None, keep=True,
                  live=lambda _params: _SlowClockReader()) as graph:
        got = graph.wait()
    assert got.steps == steps
    assert got.monitor is not None and got.monitor.count('/clock') == steps + 1
    assert got.summary['truth_digest'] == want.summary['truth_digest']
    assert got.summary['truth_messages'] == want.summary['truth_messages']
