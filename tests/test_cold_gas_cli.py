"""Bad cold-gas input through the user command: one line naming the key, exit 2, before any process starts."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
BASE = (ROOT / 'scenarios' / 'heao_b_acquisition_cold_gas_short.yaml').read_text()
# T4 (−y) turned to fire like T3: the six thrusters give no torque about −y.
NO_MINUS_Y = ('  thruster_positions_m: [0, 0, 1.2, 0, 0, -1.2, -2.4, 0, -1.2, -2.4, 0, -1.2, -2.4, 1.2, 0, -2.4, -1.2, 0]\n'
              '  thruster_directions: [0, -1, 0, 0, -1, 0, 0, 0, 1, 0, 0, 1, 0, -1, 0, 0, 1, 0]\n')


@pytest.mark.parametrize(('section', 'message'), [
    (NO_MINUS_Y, 'cold_gas.thruster_positions_m / thruster_directions: no thruster gives a torque about -y '
                 '(T3 and T4 torque +y)'),
    ('  isp_s: -65\n', 'cold_gas.isp_s: -65 is out of range [1, 400]'),
    ('  load_mass_lb: 0.1\n', 'cold_gas: tank pressure at t0 76 psia (0.1 lb in 7533 cm³ at 293 K) is not above the '
                              'regulator set point 150 psia'),
])
def test_bad_cold_gas_input_is_one_line_exit_2_before_any_process(tmp_path, section, message):
    path = tmp_path / 'bad.yaml'
    path.write_text(BASE + 'cold_gas:\n' + section)
    env = {'PYTHONPATH': str(ROOT / 'scripts'), 'PATH': '/usr/bin:/bin', 'ROS_LOG_DIR': str(tmp_path / 'ros_log')}
    proc = subprocess.run([sys.executable, '-m', 'acds_cli', 'run', str(path), '--steps', '5',
                           '--run-dir', str(tmp_path / 'run')],
                          capture_output=True, text=True, cwd=ROOT, env=env, timeout=120, check=False)
    assert proc.returncode == 2
    assert message in proc.stderr, proc.stderr
    assert len(proc.stderr.strip().splitlines()) == 1 and 'Traceback' not in proc.stderr
    assert proc.stdout == ''  # nothing started: the launcher prints its first line when it starts the nodes
    assert not (tmp_path / 'run' / 'params.yaml').exists()
