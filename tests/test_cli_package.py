"""The CLI is an installed package (issue 19 §5): the ``acds`` console script works from any folder without
``PYTHONPATH``, finds the shipped scenarios as package data, and ``run --record PATH`` keeps its plots in
its own run folder (not in ``dirname(PATH)/plots``, shared by every bag recorded beside it)."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

VENV_BIN = Path(sys.executable).parent


def _acds(args: list[str], cwd: Path) -> subprocess.CompletedProcess:
    env = {'PATH': '/usr/bin:/bin', 'ROS_LOG_DIR': str(cwd / 'ros_log'), 'HOME': str(cwd)}
    return subprocess.run([str(VENV_BIN / 'acds'), *args], cwd=cwd, env=env, capture_output=True, text=True,
                          timeout=300, check=False)


def test_console_script_lists_the_shipped_scenarios_from_any_folder(tmp_path):
    out = _acds(['scenarios'], tmp_path)
    assert out.returncode == 0, out.stderr
    names = [line.split()[0] for line in out.stdout.splitlines()]
    assert 'heao_b_acquisition' in names and 'sss_a_spin_up' in names
    assert not any(line.split()[1] == 'INVALID:' for line in out.stdout.splitlines())


def test_run_record_puts_the_plots_in_the_run_folder_and_says_where(tmp_path):
    bag, run_dir = tmp_path / 'acq_bag', tmp_path / 'run'
    out = _acds(['run', 'free_tumble_heao_b', '--engine', 'direct', '--steps', '20', '--quiet', '--record', str(bag),
                 '--run-dir', str(run_dir)], tmp_path)
    assert out.returncode == 0, out.stderr
    plots = sorted((run_dir / 'plots').glob('*.png'))
    assert plots, 'no plots in the run folder'
    assert not (tmp_path / 'plots').exists(), 'plots written beside the bag, where the next recorded run would overwrite them'
    assert f'{len(plots)} plots in {run_dir / "plots"}' in out.stderr.splitlines()[-1]
    assert (bag / 'metadata.yaml').is_file()
