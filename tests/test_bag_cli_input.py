"""The bag verbs' input and exits through the user command: one clear line and exit 2 before any ROS context,
Ctrl-C heard while ``play`` waits, no traceback when the reader of the output goes away."""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest
from acds_common.scenario import load_scenario
from acds_runtime.direct import DirectRun
from acds_runtime.testing import read_until

ROOT = Path(__file__).resolve().parents[1]


@pytest.fixture(scope='module')
def bag(tmp_path_factory) -> Path:
    """A 20-step direct-engine bag of heao_b_acquisition_short."""
    path = tmp_path_factory.mktemp('bag_cli') / 'bag'
    DirectRun(load_scenario('heao_b_acquisition_short'), steps=20, record=path).run()
    return path


def run_acds(*args: str, env: dict[str, str] | None = None) -> subprocess.CompletedProcess[str]:
    return subprocess.run([sys.executable, '-m', 'acds_cli', *args], capture_output=True, text=True, cwd=ROOT,
                          env={**os.environ, **(env or {})}, timeout=120, check=False)


def one_line_exit_2(proc: subprocess.CompletedProcess[str], message: str) -> None:
    assert proc.returncode == 2, proc.stderr
    assert 'Traceback' not in proc.stderr and 'RTPS' not in proc.stderr, proc.stderr
    assert message in proc.stderr, proc.stderr
    assert len(proc.stderr.strip().splitlines()) == 1, proc.stderr


@pytest.mark.parametrize(('verb', 'args', 'message'), [
    ('play', ['--domain', '-3'], "argument --domain: expected a ROS domain id in 0..232, got '-3'"),
    ('play', ['--domain', '999'], "argument --domain: expected a ROS domain id in 0..232, got '999'"),
    ('play', ['--wait', 'nan'], "argument --wait: expected a finite number of seconds >= 0, got 'nan'"),
    ('play', ['--wait', '-1'], "argument --wait: expected a finite number of seconds >= 0, got '-1'"),
    ('record', ['--domain', '300'], "argument --domain: expected a ROS domain id in 0..232, got '300'"),
])
def test_bad_domain_and_wait_are_one_line_before_any_ros_context(tmp_path, bag, verb, args, message):
    """Before: ``--domain -3`` was rclpy's RuntimeError traceback, ``--domain 999`` Fast DDS's colour-coded
    error and exit 1, ``--wait nan`` played at once."""
    target = str(bag) if verb == 'play' else str(tmp_path / 'new_bag')
    one_line_exit_2(run_acds(verb, target, *args), message)
    assert not (tmp_path / 'new_bag').exists()


def test_bad_ros_domain_id_environment_is_one_line(bag):
    one_line_exit_2(run_acds('play', str(bag), '--wait', '0', env={'ROS_DOMAIN_ID': 'abc'}),
                    "ROS_DOMAIN_ID 'abc': expected a ROS domain id in 0..232")


def test_record_refuses_a_run_folder_whose_domain_id_is_not_a_domain(tmp_path):
    run = tmp_path / 'run'
    run.mkdir()
    for text in ('garbage', '999'):
        (run / 'domain_id').write_text(f'{text}\n')
        one_line_exit_2(run_acds('record', str(tmp_path / 'bag'), '--run-dir', str(run)),
                        f"its domain_id file holds '{text}', not a ROS domain id")
        assert not (tmp_path / 'bag').exists()


def test_compare_set_with_a_value_that_is_not_yaml_is_one_line(bag):
    one_line_exit_2(run_acds('compare', str(bag), '--node', 'acds_controller', '--set', 'seed:=[1,2'),
                    "--set 'seed:=[1,2': the value is not valid YAML")


def test_info_into_a_closed_pipe_has_no_traceback(bag):
    """``acds info BAG | head -1``: the reader leaves early; acds ends as a SIGPIPE'd process, silently."""
    proc = subprocess.Popen([sys.executable, '-m', 'acds_cli', 'info', str(bag)], stdout=subprocess.PIPE,
                            stderr=subprocess.PIPE, cwd=ROOT)
    proc.stdout.close()  # long before acds has imported its modules and written a line
    _, err = proc.communicate(timeout=120)
    assert b'Traceback' not in err and b'BrokenPipeError' not in err, err.decode()
    assert proc.returncode == 128 + signal.SIGPIPE


def test_ctrl_c_ends_plays_wait_for_a_client_at_once(bag, play_domain):
    """``play --foxglove --wait 60``: Ctrl-C while waiting stops it then (before: only when the wait ran out).
    While it plays it holds its domain: a run asking for that domain is refused (before: a run that landed there
    met the player's publishers as an intruder and failed); once it has ended, the domain is free again."""
    from acds_runtime.launcher import DomainLease

    play = subprocess.Popen([sys.executable, '-m', 'acds_cli', 'play', str(bag), '--domain', str(play_domain),
                             '--foxglove', '0', '--wait', '60'], stderr=subprocess.PIPE, text=True, cwd=ROOT)
    try:
        read_until(play, lambda line: 'waiting up to 60 s for a Foxglove client' in line)
        assert DomainLease.held(play_domain), 'acds play publishes into a domain it does not hold'
        again = run_acds('play', str(bag), '--domain', str(play_domain), '--wait', '0')
        one_line_exit_2(again, f'domain {play_domain} belongs to a running graph (acds run) or another acds play')
        asked = time.monotonic()
        play.send_signal(signal.SIGINT)
        rest = play.communicate(timeout=50)[1]
        assert time.monotonic() - asked < 20, 'the wait ran on after Ctrl-C'
    finally:
        if play.poll() is None:
            play.kill()
            play.wait()
    assert 'published 0 messages (stopped)' in rest, rest
    assert 'no Foxglove client' not in rest and 'Traceback' not in rest, rest
    assert not DomainLease.held(play_domain), 'acds play ended and still holds its domain'


def test_record_refuses_the_folder_of_a_run_that_has_ended(tmp_path):
    """A run folder keeps its domain_id after the run: recording it joined an empty domain and, at Ctrl-C, closed
    a bag of 0 messages with exit 0. Now one line, exit 2, no bag (domain 5: outside the launcher's leases)."""
    run = tmp_path / 'run'
    run.mkdir()
    (run / 'domain_id').write_text('5\n')
    one_line_exit_2(run_acds('record', str(tmp_path / 'bag'), '--run-dir', str(run)),
                    'its graph is not running (no run holds its domain 5)')
    assert not (tmp_path / 'bag').exists()
