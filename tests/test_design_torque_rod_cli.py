"""``acds design-torque-rod`` through the user command: report, JSON record, infeasible and bad requests."""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]


def run_acds(*args: str) -> subprocess.CompletedProcess[str]:
    env = {'PATH': '/usr/bin:/bin', 'ROS_LOG_DIR': '/tmp/acds_ros_log'}
    return subprocess.run([sys.executable, '-m', 'acds_cli', *args], capture_output=True, text=True,
                          cwd=ROOT, env=env, timeout=120, check=False)


def test_design_prints_every_quantity_and_writes_the_record(tmp_path: Path) -> None:
    out = tmp_path / 'rod.json'
    proc = run_acds('design-torque-rod', '--awg', '35', '--json', str(out))
    assert proc.returncode == 0, proc.stderr
    for label in ('core length', 'core radius', 'turns per winding', 'resistance per winding', 'inductance per winding',
                  'time constant', 'demagnetising factor', 'core flux density', 'core saturates at full current',
                  'dipole moment at full current', 'mass'):
        assert label in proc.stdout
    record = json.loads(out.read_text())
    assert record['moment_am2'] >= 0.1552 and record['mass_g'] <= 100.0 and record['power_w'] <= 0.5 + 1e-12
    assert record['core_saturates'] is False and record['awg'] == 35


def test_infeasible_and_bad_requests_exit_non_zero_with_one_line() -> None:
    proc = run_acds('design-torque-rod', '--moment-am2', '5', '--mass-g', '10')
    assert proc.returncode == 1 and 'binding: moment, mass' in proc.stderr and 'Traceback' not in proc.stderr
    proc = run_acds('design-torque-rod', '--envelope-mm', '35x35')
    assert proc.returncode == 2 and 'envelope must be AxBxC' in proc.stderr
    proc = run_acds('design-torque-rod', '--awg', '20')  # named as typed: not the core's insulation_build_m
    assert proc.returncode == 2 and proc.stderr.strip().splitlines() == [
        'acds design-torque-rod: error: --awg 20: the heavy-build insulation table covers AWG 30–40; give '
        '--insulation-mm (the enamel build on the diameter) for another gauge']
    for option, value, rule in (('--awg', '60', 'a whole wire gauge 0…56'), ('--bridge-ohm', 'nan', 'a finite number >= 0'),
                                ('--bridge-ohm', '-1', 'a finite number >= 0')):
        proc = run_acds('design-torque-rod', f'{option}={value}')
        assert proc.returncode == 2 and proc.stderr.strip().splitlines() == [
            f'acds design-torque-rod: error: argument {option}: must be {rule}, got {value} '
            '(see acds design-torque-rod --help)'], proc.stderr


def test_json_path_is_checked_before_the_search_and_its_folder_created(tmp_path: Path) -> None:
    proc = run_acds('design-torque-rod', '--awg', '35', '--json', '/proc/acds_rod.json')
    assert proc.returncode == 2 and proc.stdout == '' and 'Traceback' not in proc.stderr
    assert proc.stderr.strip().splitlines() == [
        'acds design-torque-rod: error: --json /proc/acds_rod.json: cannot write in /proc: No such file or directory']
    out = tmp_path / 'new' / 'rod.json'
    proc = run_acds('design-torque-rod', '--awg', '35', '--json', str(out))
    assert proc.returncode == 0, proc.stderr
    assert json.loads(out.read_text())['awg'] == 35


def test_a_bad_value_is_named_by_its_option_in_the_unit_typed() -> None:
    """Not 'DesignRequest.mass_max_kg must be a finite positive number, got 0.0' for --mass-g 0, nor
    'insulation_build_m must be > 0 m, got -0.001' for --insulation-mm -1."""
    for option, value in (('--mass-g', '0'), ('--insulation-mm', '-1'), ('--power-w', 'inf'),
                          ('--min-core-radius-mm', 'nan')):
        proc = run_acds('design-torque-rod', '--awg', '35', f'{option}={value}')
        assert proc.returncode == 2 and proc.stdout == ''
        assert proc.stderr.strip().splitlines() == [
            f'acds design-torque-rod: error: argument {option}: must be a finite number > 0, got {value} '
            '(see acds design-torque-rod --help)'], proc.stderr
