"""Monte Carlo flown by the user's flight software: a short study with the example node, paired with the built-in
law (identical in N of N), each sample the same as ``acds run --sample S:K --external`` with the node started by
hand; on the CAN bus, a study flown by a CANopen master whose samples replay from their CAN logs; a failing node is
one line with its last lines and ``--resume`` runs it again; a node that ignores SIGINT is killed after the grace
period; bad input is one line, exit 2, before any sample."""

from __future__ import annotations

import json
import os
import shlex
import signal
import subprocess
import sys
from pathlib import Path

import pytest
from acds_common.scenario import load_scenario
from acds_runtime.flight_software import start_process, stop_process
from acds_runtime.testing import read_until

ROOT = Path(__file__).resolve().parents[1]
NODE = 'acds_controller=oresat_detumble_fsw'
COMMAND = 'oresat_detumble_fsw --ros-args --params-file {params}'
#: 30 steps of 1 s per sample.
UNTIL_MIN = '0.5'
EXAMPLE = Path(sys.executable).parent / 'oresat_detumble_fsw'


def run_acds(*args: str, timeout: float = 300) -> subprocess.CompletedProcess[str]:
    env = {'PATH': '/usr/bin:/bin', 'ROS_LOG_DIR': '/tmp/acds_ros_log', 'HOME': os.environ.get('HOME', '/tmp')}
    return subprocess.run([sys.executable, '-m', 'acds_cli', *args], capture_output=True, text=True, cwd=ROOT,
                          env=env, timeout=timeout, check=False)


def study(out: Path, *extra: str, command: str = COMMAND) -> subprocess.CompletedProcess[str]:
    return run_acds('montecarlo', 'oresat_detumble', '--runs', '2', '--until-min', UNTIL_MIN, '--external', NODE,
                    '--fsw-command', command, '--out', str(out), '--quiet', *extra)


@pytest.mark.parametrize(('extra', 'message'), [
    (['--external', NODE, '--fsw-command', ''], '--fsw-command: the command template is empty'),
    (['--external', NODE, '--fsw-command', '   '], '--fsw-command: the command template is empty'),
    (['--external', NODE, '--fsw-command', 'no_such_fsw_program --ros-args'], "no executable 'no_such_fsw_program'"),
    (['--external', NODE, '--fsw-command', 'env -i oresat_detumble_fsw'], 'put {domain} where it goes'),
    (['--external', NODE, '--fsw-command', f'{COMMAND} {{domian}}'], 'unknown placeholder {domian}'),
    (['--external', NODE, '--fsw-command', COMMAND, '--engine', 'direct'],
     '--external: the direct engine runs every node in this process, so it cannot fly your node'),
    (['--external', NODE], 'needs the command: --fsw-command'),
    (['--fsw-command', COMMAND], 'give --external NODE[=ROS_NODE_NAME]'),
    (['--paired'], '--paired: an option of a study flown by your own node'),
    (['--external', 'rigid_body', '--fsw-command', COMMAND], "external node 'rigid_body': it owns sim time"),
])
def test_bad_input_is_one_line_before_any_sample(tmp_path, extra, message):
    proc = run_acds('montecarlo', 'oresat_detumble', '--runs', '2', '--out', str(tmp_path / 'study'), *extra)
    assert proc.returncode == 2, proc.stderr
    assert message in proc.stderr, proc.stderr
    assert len(proc.stderr.strip().splitlines()) == 1, proc.stderr
    assert not (tmp_path / 'study').exists(), 'a study folder before the input was checked'


def _by_hand(sample: str, run_dir: Path) -> dict:
    """``acds run oresat_detumble --sample S:K --external ...`` with the example started by hand on the run's domain
    (as docs/flight_software.md shows: ROS_DOMAIN_ID, localhost discovery, the node's defaults)."""
    summary = run_dir / 'summary.json'
    run = subprocess.Popen([sys.executable, '-m', 'acds_cli', 'run', 'oresat_detumble', '--sample', sample,
                            '--until-min', UNTIL_MIN, '--external', NODE, '--no-record', '--quiet',
                            '--run-dir', str(run_dir), '--summary-json', str(summary)],
                           stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True, cwd=ROOT)
    node = None
    try:
        said = read_until(run, lambda line: line.startswith('[acds] ROS domain '))
        domain = said.splitlines()[-1].split()[3].rstrip(';')
        env = {**os.environ, 'ROS_DOMAIN_ID': domain, 'ROS_AUTOMATIC_DISCOVERY_RANGE': 'LOCALHOST'}
        env.pop('FASTRTPS_DEFAULT_PROFILES_FILE', None)
        node = subprocess.Popen([str(EXAMPLE)], env=env, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL,
                                start_new_session=True)
        rest = run.communicate(timeout=240)[1]
        assert run.returncode == 0, said + rest
    finally:
        if run.poll() is None:
            run.kill()
            run.wait()
        if node is not None:
            stop_process(node, 10.0)
    return json.loads(summary.read_text())


def test_a_study_flown_by_the_example_is_the_built_in_and_each_sample_is_run_sample(tmp_path):
    out = tmp_path / 'study'
    proc = study(out, '--paired', '--jobs', '2', '--deadline-ms', 'acds_controller=50')
    assert proc.returncode == 0, proc.stderr
    assert 'identical in 2 of 2' in proc.stdout, proc.stdout
    assert 'acds_controller: step time over 2 samples (62 steps' in proc.stdout, proc.stdout
    assert 'deadline 50 ms:' in proc.stdout
    records = json.loads((out / 'samples.json').read_text())
    for rec in records:
        ours, built_in = rec['flight_software'], rec['built_in']
        assert ours['truth_digest'] == built_in['truth_digest'], rec['index']
        assert ours['fsw']['stop'] == {'how': 'stopped by SIGINT', 'exit_code': 0}
        assert rec['timing']['acds_controller']['steps'] == 31
        log = Path(ours['fsw']['log'])
        assert log.parent == out / 'samples' / rec['name'] and 'detumble gain' in log.read_text()
    assert records[0]['flight_software']['truth_digest'] != records[1]['flight_software']['truth_digest']
    by_hand = _by_hand('1:1', tmp_path / 'by_hand')
    assert by_hand['truth_digest'] == records[1]['flight_software']['truth_digest']
    assert records[1]['replay'].endswith(f'--sample 1:1 --until-min {UNTIL_MIN} --external {NODE}')


def test_a_failing_node_is_one_line_with_its_last_lines_and_resume_runs_it_again(tmp_path):
    licence = tmp_path / 'licence'
    script = tmp_path / 'fsw.sh'
    script.write_text(f'#!/bin/sh\necho "fsw: checking the licence"\nif [ -e {licence} ]; then exec {EXAMPLE} '
                      f'--ros-args --params-file "$1"; fi\necho "fsw: no licence, giving up" >&2\nexit 3\n')
    script.chmod(0o755)
    out = tmp_path / 'study'
    command = f'{script} {{params}}'
    proc = study(out, '--jobs', '1', '--max-failures', '0', command=command)
    assert proc.returncode == 1, proc.stderr
    assert ('[montecarlo] sample 0 failed: the flight software exited (exit code 3) before it joined the graph\n'
            '    | fsw: checking the licence\n    | fsw: no licence, giving up\n') in proc.stderr, proc.stderr
    assert 'stopped: 1 samples failed, more than --max-failures 0' in proc.stderr
    licence.touch()
    again = study(out, '--jobs', '1', '--resume', str(out), command=command)
    assert again.returncode == 0, again.stderr
    assert '1 failed sample(s) run again' in again.stderr
    records = json.loads((out / 'samples.json').read_text())
    assert [('error' in r['flight_software']) for r in records] == [False, False]


def test_a_node_that_ignores_sigint_is_killed_after_the_grace_period(tmp_path):
    before = signal.signal(signal.SIGINT, signal.SIG_IGN)  # inherited: the child ignores SIGINT from its start
    try:
        proc = start_process(['sleep', '60'], dict(os.environ), tmp_path / 'fsw.log')
    finally:
        signal.signal(signal.SIGINT, before)
    assert stop_process(proc, 0.5) == {'how': 'killed (still running 0.5 s after SIGINT)', 'exit_code': -9}


def test_the_scenario_keys_give_the_node_and_the_command(tmp_path):
    """``external`` and ``fsw_command`` in the scenario: a study flown by the node without the options; the key's
    command is checked as the option's, and named as the key."""
    text = (ROOT / 'scenarios' / 'oresat_detumble.yaml').read_text().replace('name: oresat_detumble\n',
                                                                              'name: oresat_fsw\n')
    path = tmp_path / 'oresat_fsw.yaml'
    design = 'oresat_torque_rod_awg35.json'  # the scenario names its rod design relative to its own folder
    (tmp_path / design).write_text((ROOT / 'scenarios' / design).read_text())
    path.write_text(text + f'external: [{NODE}]\nfsw_command: "env -i oresat_detumble_fsw"\n')
    proc = run_acds('montecarlo', str(path), '--runs', '2', '--engine', 'direct', '--out', str(tmp_path / 'study'))
    assert proc.returncode == 2 and '--external: the direct engine runs every node' in proc.stderr, proc.stderr
    proc = run_acds('montecarlo', str(path), '--runs', '2', '--out', str(tmp_path / 'study'))
    assert proc.returncode == 2, proc.stderr
    assert proc.stderr.startswith('acds montecarlo: error: scenario oresat_fsw key fsw_command: env -i starts your '
                                  'node without'), proc.stderr
    path.write_text(text + f'external: [{NODE}]\nfsw_command: "{COMMAND}"\n')
    proc = run_acds('montecarlo', str(path), '--runs', '1', '--until-min', '0.05', '--jobs', '1', '--paired',
                    '--out', str(tmp_path / 'study'), '--quiet')
    assert proc.returncode == 0, proc.stderr
    assert 'identical in 1 of 1' in proc.stdout and 'flown by `oresat_detumble_fsw --ros-args' in proc.stderr


def test_the_paired_report_counts_identical_pairs_and_names_the_samples_that_differ_most():
    from acds_runtime.fsw_report import paired, paired_table

    def run(i: int, t: float | None, e: float, digest: str) -> dict:
        return {'detumble_time_min': t, 'energy_j': e, 'sim_minutes': 100.0, 'steps': 6000, 'truth_digest': digest,
                'detumble_threshold_deg_s': 0.1}
    built_in = [run(i, 80.0 + i, 50.0 + i, f'd{i}') for i in range(6)]
    ours = [dict(b) for b in built_in]
    ours[2] = run(2, 82.0, 57.0, 'other')  # energy 5 J (10 %) over the built-in's
    ours[4] = run(4, None, 54.0, 'other too')  # not detumbled where the built-in was
    stats = paired([(i, a, b) for i, (a, b) in enumerate(zip(ours, built_in, strict=True))], seed=1)
    assert (stats['identical'], stats['compared']) == (4, 6)
    assert list(stats['quantities']) == ['detumble_time_min', 'energy_j']  # constants and run keys left out
    energy = stats['quantities']['energy_j']
    assert energy['max_abs_difference'] == 5.0 and energy['difference']['p50'] == 0.0
    assert energy['difference']['interval']['p75'][1] == 5.0  # the bootstrap of the differences
    assert energy['difference']['too_few']['p95'] == 20  # a tail percentile needs n >= 100 / min(p, 100 - p) pairs
    assert stats['quantities']['detumble_time_min']['one_sided'] == 1
    assert [(d['index'], d['key']) for d in stats['differ_most']] == [(4, 'detumble_time_min'), (2, 'energy_j')]
    assert paired_table(stats)[0].startswith('identical in 4 of 6')


# On the CAN bus: oresat_c3_detumble flown by the project's own CANopen master (the example's
# oresat_detumble_canopen, the seed 003 law), started for each sample on that sample's bus and stopped after it,
# paced at a stated real-time factor, paired with the built-in law on the same draws; each sample's CAN log kept in
# its folder, and --replay-can of it gives the sample's truth digest bit for bit.
BUS_SCENARIO = 'oresat_c3_detumble'
#: 300 steps of 0.1 s per sample, at 30× real time (1 s of wall per sample once the master's heartbeat came).
UNTIL_MIN, RTF = '0.5', '30'


def master_command() -> str:
    """The master's command template: the law's parameters from the scenario, the bus from the sample."""
    c = load_scenario(BUS_SCENARIO).get
    return ('oresat_detumble_canopen --host {can_host} --port {can_port} '
            f'--orbit-period {c("controller", "detumble_orbit_period")!r} '
            f'--inclination {c("controller", "magnetic_inclination")!r} --j-min {c("controller", "detumble_j_min")!r} '
            f'--max-moment {c("controller", "max_moment_am2")!r} --dipole-per-amp '
            + ' '.join(repr(v) for v in c('can_bus', 'dipole_per_amp')))


@pytest.mark.parametrize(('extra', 'message'), [
    (['--fsw-command', 'oresat_detumble_canopen --host {can_host}'], 'the command must take it: put {can_port}'),
    (['--fsw-command', 'oresat_detumble_canopen --port {can_port} --ros-args --params-file {params}'],
     'unknown placeholder {params}'),
    (['--fsw-command', 'oresat_detumble_canopen --port {can_port}', '--external', 'acds_controller'],
     'is flown by a flight computer on its CAN bus, not by a ROS node'),
    (['--fsw-command', 'oresat_detumble_canopen --port {can_port}', '--can-port', '29536', '--jobs', '2'],
     '--can-port 29536: one bus on one port serves one sample at a time; give --jobs 1'),
])
def test_bad_input_on_the_bus_is_one_line_before_any_sample(tmp_path, extra, message):
    proc = run_acds('montecarlo', BUS_SCENARIO, '--runs', '2', '--out', str(tmp_path / 'study'), *extra)
    assert proc.returncode == 2, proc.stderr
    assert message in proc.stderr, proc.stderr
    assert len(proc.stderr.strip().splitlines()) == 1, proc.stderr
    assert not (tmp_path / 'study').exists(), 'a study folder before the input was checked'


def test_a_bus_study_flown_by_the_canopen_master_keeps_each_sample_replayable(tmp_path):
    out = tmp_path / 'study'
    proc = run_acds('montecarlo', BUS_SCENARIO, '--runs', '2', '--until-min', UNTIL_MIN, '--rtf', RTF, '--paired',
                    '--fsw-command', master_command(), '--out', str(out), '--quiet', '--jobs', '1')
    assert proc.returncode == 0, proc.stdout + proc.stderr
    assert f'paced at R = {float(RTF):g}' in proc.stderr, proc.stderr
    records = json.loads((out / 'samples.json').read_text())
    assert [r['index'] for r in records] == [0, 1]
    for rec in records:
        ours, fsw = rec['flight_software'], rec['flight_software']['fsw']
        folder = Path(fsw['run_dir'])
        assert folder.parent == out / 'samples'
        assert fsw['stop']['how'] == 'stopped by SIGINT', fsw
        assert (folder / 'can.asc').is_file() and (folder / 'can.asc.run.json').is_file()
        written = sum(s['count'] for s in fsw['flight_computer']['setpoints'].values())
        assert written > 0 and fsw['flight_computer']['heartbeats'] > 0, fsw['flight_computer']
        assert ours['can_setpoint_changes'] > 0, ours
        # The built-in law on the same draws: the same spacecraft and tumble, flown by the graph's own controller.
        assert rec['built_in']['scenario'] == ours['scenario'] and 'error' not in rec['built_in']
        assert rec['drawn'], rec
    report = (out / 'report.md').read_text()
    assert 'paired with the built-in node' in report, report
    # A sample again from its CAN log, without the flight computer: the same truth, bit for bit.
    rec = records[1]
    argv = shlex.split(rec['replay'])
    assert argv[:2] == ['./scripts/acds', 'run'] and '--replay-can' in argv, rec['replay']
    summary = tmp_path / 'replay.json'
    again = run_acds(*argv[1:], '--no-record', '--quiet', '--run-dir', str(tmp_path / 'replay'), '--summary-json',
                     str(summary))
    assert again.returncode == 0, again.stdout + again.stderr
    assert json.loads(summary.read_text())['truth_digest'] == rec['flight_software']['truth_digest']


def test_a_flight_computer_that_dies_before_its_heartbeat_fails_its_sample_at_once(tmp_path):
    out = tmp_path / 'study'
    proc = run_acds('montecarlo', BUS_SCENARIO, '--runs', '1', '--until-min', UNTIL_MIN, '--rtf', RTF,
                    '--fsw-command', "sh -c 'echo no bus for me at port $0; exit 3' {can_port}", '--max-failures', '0',
                    '--out', str(out), '--quiet')
    assert proc.returncode == 1, proc.stdout + proc.stderr
    assert ('sample 0 failed: the flight computer exited (exit code 3) before its heartbeat (node 0x01) came on '
            'socketcand:127.0.0.1:') in proc.stderr, proc.stderr
    assert '| no bus for me at port ' in proc.stderr, proc.stderr
