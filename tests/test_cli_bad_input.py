"""Bad input through the user command: one clear line, non-zero exit, no traceback."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
BASE = (ROOT / 'scenarios' / 'free_tumble_heao_b.yaml').read_text()


def run_acds(*args: str) -> subprocess.CompletedProcess[str]:
    env = {'PATH': '/usr/bin:/bin', 'ROS_LOG_DIR': '/tmp/acds_ros_log'}
    return subprocess.run([sys.executable, '-m', 'acds_cli', *args], capture_output=True, text=True,
                          cwd=ROOT, env=env, timeout=120, check=False)


@pytest.mark.parametrize(('edit', 'message'), [
    (lambda s: s.replace('  substeps: 1\n', '  substeps: 1\n  subteps: 3\n'), 'unknown key "dynamics.subteps"'),
    (lambda s: s.replace('[1520, 7970', '[-1520, 7970'), 'spacecraft.inertia: inertia tensor is not positive definite'),
    (lambda s: s.replace('initial_rates_deg_s: [1.0, 1.0, 1.0]', 'initial_rates_deg_s: [.nan, 1.0, 1.0]'),
     'spacecraft.initial_rates_deg_s: nan is not a finite number'),
    (lambda s: s.replace('altitude_nmi: 225', 'altitude_nmi: [225'), 'is not valid YAML'),
    (lambda s: s.replace('name: free_tumble_heao_b\n', ''), 'missing required key "name"'),
])
def test_bad_scenario_is_one_clear_error(tmp_path, edit, message):
    path = tmp_path / 'bad.yaml'
    path.write_text(edit(BASE))
    proc = run_acds('run', str(path), '--steps', '5')
    assert proc.returncode == 2
    assert message in proc.stderr, proc.stderr
    assert 'Traceback' not in proc.stderr
    assert len(proc.stderr.strip().splitlines()) == 1


def test_unknown_verb_and_option_are_clear_errors():
    proc = run_acds('fly')
    assert proc.returncode == 2 and "invalid choice: 'fly'" in proc.stderr
    proc = run_acds('run', '--warp', '9')
    assert proc.returncode == 2 and 'unrecognized arguments: --warp' in proc.stderr


def test_bench_refuses_too_few_steps_to_measure_before_starting():
    """The graph line measures up to MONITOR_LAG + 2 steps before the end (while every node lives): fewer steps
    than that leave nothing to measure."""
    proc = run_acds('bench', '--steps', '100')
    assert proc.returncode == 2
    assert proc.stderr.strip().splitlines() == [
        'acds bench: error: argument --steps: 100 steps is too few to measure: at least 500 (see acds bench --help)']


@pytest.mark.parametrize(('args', 'message'), [
    (['--external', 'wheel_law'], "--external: external node 'wheel_law': not a node of this graph"),
    (['--external', 'rigid_body'], "external node 'rigid_body': it owns sim time"),
    (['--external', 'acds_controller', '--engine', 'direct'], 'an external node joins the process graph'),
    (['--external', 'acds_controller=1x'], "'1x' is not a ROS node name"),
    (['--external', 'em_driver', '--external', 'em_driver'], "external node 'em_driver' is given twice"),
    (['--domain', '5'], "argument --domain: expected a ROS domain id in 11..99, got '5'"),
    (['--deadline-ms', 'acds_controller=inf'], "expected NODE=MS with a finite MS > 0, got 'acds_controller=inf'"),
    (['--deadline-ms', 'gyro=2'], '--deadline-ms gyro=2: scenario oresat_detumble runs no such node'),
    (['--record', ''], '--record: an empty path'),
    (['--record', ' ', '--engine', 'direct'], '--record: an empty path'),
    (['--external', 'acds_controller=em_driver'], "ROS node name 'em_driver' is that of the node em_driver"),
    (['--peer', 'no such host!'], "argument --peer: cannot resolve host 'no such host!'"),
    (['--peer', '10.0.0.2;10.0.0.3'], 'argument --peer: expected one host name or address (repeat --peer for more)'),
])
def test_bad_external_node_options_are_one_line_before_any_process(tmp_path, args, message):
    """Issue 20, bad input: checked before any process starts (no run folder is made)."""
    proc = run_acds('run', 'oresat_detumble', '--steps', '5', '--run-dir', str(tmp_path / 'run'), *args)
    assert proc.returncode == 2, proc.stderr
    assert message in proc.stderr, proc.stderr
    assert len(proc.stderr.strip().splitlines()) == 1, proc.stderr
    assert not (tmp_path / 'run').exists()


def test_a_scenario_with_a_bad_external_key_is_one_line(tmp_path):
    path = tmp_path / 'bad.yaml'
    path.write_text(BASE.replace('name: free_tumble_heao_b\n', 'name: free_tumble_heao_b\nexternal: [rigid_body]\n'))
    proc = run_acds('run', str(path), '--steps', '5')
    assert proc.returncode == 2
    assert "external: external node 'rigid_body': it owns sim time" in proc.stderr, proc.stderr
    assert len(proc.stderr.strip().splitlines()) == 1


def test_a_reader_that_leaves_early_gets_no_traceback():
    """``acds params SCENARIO | head -1``: the reader may be gone before the command writes (head exits on its first
    line, or is given none); the command stops without a traceback (exit 141, a writer's SIGPIPE status, as the
    shell reports it). Here the pipe has no reader from the start."""
    env = {'PATH': '/usr/bin:/bin', 'ROS_LOG_DIR': '/tmp/acds_ros_log'}
    proc = subprocess.Popen([sys.executable, '-m', 'acds_cli', 'params', 'emff_testbed_hold'], stdout=subprocess.PIPE,
                            stderr=subprocess.PIPE, text=True, cwd=ROOT, env=env)
    assert proc.stdout is not None and proc.stderr is not None
    proc.stdout.close()
    err = proc.stderr.read()
    assert proc.wait(timeout=120) == 141, err
    assert 'Traceback' not in err and err == '', err


def test_a_domain_another_run_holds_is_one_line_before_the_run_folder(tmp_path):
    """``--domain N`` that a running graph holds: refused before the run folder is made (the launcher's lease
    refused it only after, leaving an empty folder)."""
    from acds_runtime.launcher import DomainLease

    lease = DomainLease()  # held by this test as a running graph's launcher holds it
    try:
        proc = run_acds('run', 'oresat_detumble', '--steps', '5', '--run-dir', str(tmp_path / 'run'),
                        '--domain', str(lease.domain_id))
    finally:
        lease.close()
    assert proc.returncode == 2, proc.stderr
    assert f'--domain {lease.domain_id}: another run (or acds play) holds this ROS domain now' in proc.stderr, proc.stderr
    assert len(proc.stderr.strip().splitlines()) == 1, proc.stderr
    assert not (tmp_path / 'run').exists()


def test_the_test_verb_hands_pytest_the_options_it_does_not_know_and_other_verbs_refuse_them():
    from acds_cli.__main__ import build_parser, parse

    parser = build_parser()
    args = parse(parser, ['test', '--durations=20', '-j', '2', 'tests/test_shm.py', '-x'])
    assert args.jobs == 2 and args.pytest_args == ['--durations=20', 'tests/test_shm.py', '-x']
    out = run_acds('scenarios', '--durations=20')
    assert out.returncode == 2 and 'unrecognized arguments: --durations=20' in out.stderr
    assert len(out.stderr.strip().splitlines()) == 1
