"""Bad cold-gas input through the user command: one line naming the key, exit 2, before any process starts."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
BASE = (ROOT / 'scenarios' / 'heao_b_acquisition_cold_gas_short.yaml').read_text()
# T4 (−y) turned to fire like T3: the six thrusters give no torque about −y.
NO_MINUS_Y = ('  thruster_layout: custom\n'
              '  thruster_positions_m: [0, 0, 1.2, 0, 0, -1.2, -2.4, 0, -1.2, -2.4, 0, -1.2, -2.4, 1.2, 0, -2.4, -1.2, 0]\n'
              '  thruster_directions: [0, -1, 0, 0, -1, 0, 0, 0, 1, 0, 0, 1, 0, -1, 0, 0, 1, 0]\n')


@pytest.mark.parametrize(('section', 'message'), [
    (NO_MINUS_Y, 'cold_gas.thruster_positions_m / thruster_directions: no thruster, nor couple of two, gives a '
                 'torque about -y alone'),
    ('  isp_s: -65\n', 'cold_gas.isp_s: -65 is out of range [1, 400]'),
    ('  load_mass_lb: 0.1\n', 'cold_gas: tank pressure at t0 76 psia (0.1 lb in 7533 cm³ at 293 K) is not above the '
                              'regulator set point 150 psia'),
])
def test_bad_cold_gas_input_is_one_line_exit_2_before_any_process(tmp_path, section, message):
    path = tmp_path / 'bad.yaml'
    path.write_text(BASE + 'cold_gas:\n' + section)
    env = {'PATH': '/usr/bin:/bin', 'ROS_LOG_DIR': str(tmp_path / 'ros_log')}
    proc = subprocess.run([sys.executable, '-m', 'acds_cli', 'run', str(path), '--steps', '5',
                           '--run-dir', str(tmp_path / 'run')],
                          capture_output=True, text=True, cwd=ROOT, env=env, timeout=120, check=False)
    assert proc.returncode == 2
    assert message in proc.stderr, proc.stderr
    assert len(proc.stderr.strip().splitlines()) == 1 and 'Traceback' not in proc.stderr
    assert proc.stdout == ''  # nothing started: the launcher prints its first line when it starts the nodes
    assert not (tmp_path / 'run' / 'params.yaml').exists()


def test_trade_gas_budget_counts_acquisitions_at_the_90th_percentile():
    """The trade's cold-gas lines: percentiles of the GN₂ per acquisition over the draws, the worst draw, and the
    acquisitions the 4.6 lb load supports at the 90th percentile (whole load, and the gas above the set point)."""
    from acds_common.scenario import load_scenario
    from heao_mission.cold_gas_trade import study_budget, study_budget_table

    rows = [{'index': i, 'gas_used_lb': 0.9 + 0.01 * i, 'gas_valve_cycles': 250 + i, 'gas_handover_min': 5.0 + i,
             'acquisition_time_min': 5.0 + i} for i in range(11)] + [{'index': 11, 'error': 'exit 1'}]
    g = study_budget(rows, load_scenario('heao_b_acquisition_cold_gas'))
    assert g['n'] == 11 and g['gas_used_lb']['p90'] == 0.99 and g['gas_used_lb']['worst_index'] == 10
    assert g['gas_handover_min']['median'] == 10.0 and g['gas_valve_cycles']['worst'] == 260
    assert g['acquisitions_at_p90'] == 4  # 4.6 // 0.99
    assert abs(g['residual_at_set_point_lb'] - 4.6 * 150 / 3493.57) < 1e-3
    assert g['acquisitions_at_p90_regulated'] == 4  # (4.6 − 0.198) // 0.99
    text = study_budget_table('heao_b_acquisition_cold_gas', g)
    assert 'the 4.60 lb load supports 4 acquisitions at the 90th percentile' in text
    w = g['within_study_time']  # captured within §2's ten minutes: 5…10 min, 6 of 11; Wilson 95 % 0.280–0.787
    assert (w['count'], w['n']) == (6, 11) and w['interval'] == pytest.approx([0.2801, 0.7873], abs=1e-4)
    assert 'captured within the study\'s 10 min (§2): 6 of 11 (Wilson 95 % interval 28.0–78.7 %)' in text
    assert 'three acquisitions: 3.00 lb at the worst draw (sample 10), 2.97 lb at the 90th percentile' in text


def test_a_gas_acquisition_row_has_no_magnetics_only_phase():
    """A cold-gas sample is not 'censored on magnetics only': it has no such phase; it reaches Mode 1B at the hand-over."""
    from acds_runtime.dispersion_report import QUANTITIES, make_row, percentiles, values_of

    summary = {'time_magnetics_only_min': None, 'time_wheels_magnetics_min': 3.0, 'acquisition_time_min': 8.0,
               'sim_minutes': 8.0, 'gas_handover_min': 5.0, 'gas_used_lb': 1.0}
    row = make_row(0, 's', {}, {}, summary)
    assert 'time_magnetics_only_min' not in row and row['mode_1b_reached'] and row['gas_used_lb'] == 1.0
    assert 'time_magnetics_only_min' not in percentiles([row], seed=1)
    wheels = next(q for q in QUANTITIES if q.key == 'time_wheels_magnetics_min')
    assert list(values_of([row], wheels)[0]) == [3.0]


@pytest.mark.parametrize(('text', 'message'), [
    ('extends: heao_b_acquisition_short\nmodes:\n  initial_mode: gas_rate_damping\n',
     "modes.initial_mode: 'gas_rate_damping' with modes.system 'heao' (the gas modes"),
    ('extends: heao_b_acquisition_cold_gas_short\n'
     'nodes: [rigid_body, reaction_wheels, magnetometer_sim, em_driver, acds_controller, ascs_mode_manager]\n',
     "modes.system: 'heao_cold_gas' with node cold_gas not in the graph"),
])
def test_gas_modes_and_the_cold_gas_node_go_together(tmp_path, text, message):
    """The packages' cross-key checks (ascs_mode_manager.nodes, cold_gas.nodes): the gas modes start only a
    heao_cold_gas acquisition, and that mode logic flies only with node cold_gas."""
    from acds_common.scenario import ScenarioError, load_scenario

    path = tmp_path / 'bad.yaml'
    path.write_text('name: bad\n' + text)
    with pytest.raises(ScenarioError) as err:
        load_scenario(str(path))
    assert message in str(err.value)


def test_budget_json_goes_into_a_folder_it_creates(tmp_path):
    """``--json`` passes the writability check with missing folders (they are created): the budget writes
    there instead of ending in a FileNotFoundError traceback after every acquisition has run."""
    out = tmp_path / 'new' / 'budget.json'
    env = {'PATH': '/usr/bin:/bin', 'ROS_LOG_DIR': str(tmp_path / 'ros_log')}
    proc = subprocess.run([sys.executable, '-m', 'acds_cli', 'cold-gas-budget', 'heao_b_acquisition_cold_gas_short',
                           '--runs', '2', '--acquisitions', '1', '--json', str(out)],
                          capture_output=True, text=True, cwd=ROOT, env=env, timeout=300, check=False)
    assert proc.returncode == 0 and 'Traceback' not in proc.stderr, proc.stderr
    import json
    budget = json.loads(out.read_text())
    assert len(budget['draws']) == 2 and [len(c['acquisitions']) for c in budget['chains']] == [1, 1]
    worst = max(budget['draws'], key=lambda d: d['gas_used_lb'])
    assert budget['chains'][0]['sample'] == worst['index']  # the chain flies the draw that used the most gas
    assert budget['chains'][0]['acquisitions'][0]['truth_digest'] == worst['truth_digest']
