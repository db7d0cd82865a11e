"""``dynamics.stop_when_detumbled``: the time owner ends the run once |ω| has stayed below the detumbled rate for the
hold, at the same step on both engines, and the run is the plain run cut there (same truth, digest and detumble time);
a paired flight-software study with the rule ends each pair at the same step.

The spacecraft starts just above 0.1°/s about its minimum-inertia axis, so the torque rods bring it below within a
minute (67 s on the tilted dipole at t0)."""

from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path

import pytest
from acds_common.scenario import ScenarioError, load_scenario
from acds_runtime.direct import DirectRun

HOLD_S = 10
ROOT = Path(__file__).resolve().parents[1]


def _scenario(tmp_path, stop: bool):
    path = tmp_path / f'detumbled_{stop}.yaml'
    path.write_text('extends: oresat_detumble\nname: detumbled_stop\nduration_orbits: 0.02\n'
                    'spacecraft:\n  initial_rates_deg_s: [0.0, 0.0, 0.105]\n'
                    f'dynamics:\n  stop_when_detumbled: {str(stop).lower()}\n  detumbled_hold_s: {HOLD_S}\n')
    return load_scenario(str(path))


def _comparable(summary: dict) -> dict:
    return {k: v for k, v in summary.items() if k != 'wall_seconds'}


def test_the_run_ends_after_the_hold_at_the_same_step_on_both_engines(tmp_path, launch_graph):
    plain = DirectRun(_scenario(tmp_path, stop=False)).run()
    detumbled_step = round(plain.summary['detumble_time_min'] * 60)  # 1 s steps; stays below to the plain run's end
    assert 0 < detumbled_step and detumbled_step + HOLD_S < plain.steps
    stopped = DirectRun(_scenario(tmp_path, stop=True)).run()
    assert stopped.steps == detumbled_step + HOLD_S
    assert stopped.summary['detumble_time_min'] == plain.summary['detumble_time_min']
    cut = DirectRun(_scenario(tmp_path, stop=False), steps=stopped.steps).run()
    assert stopped.summary['truth_digest'] == cut.summary['truth_digest']
    with launch_graph(_scenario(tmp_path, stop=True)) as graph:
        result = graph.wait()
    assert result.steps == stopped.steps
    assert _comparable(result.summary) == _comparable(stopped.summary)


def test_a_formation_refuses_the_rule_naming_the_key(tmp_path):
    path = tmp_path / 'formation.yaml'
    path.write_text('extends: emff_two_vehicle_lqr\nname: formation_detumbled\ndynamics:\n  stop_when_detumbled: true\n')
    from acds_runtime.preflight import preflight

    with pytest.raises(ScenarioError, match='dynamics.stop_when_detumbled'):
        preflight(load_scenario(str(path)))


def test_a_paired_study_flown_by_the_example_ends_each_sample_at_detumble_identically(tmp_path):
    """Two samples of a study with the rule (just above the rate at t0, a 10 s hold): the example node and the
    built-in law end every pair at the same step, before the scenario's duration, with the same truth digest."""
    scenario = tmp_path / 'detumbled_study.yaml'
    scenario.write_text('extends: oresat_detumble_to_detumbled\nname: detumbled_study\nduration_orbits: 0.02\n'
                        f'spacecraft:\n  initial_rates_deg_s: [0.0, 0.0, 0.105]\ndynamics:\n  detumbled_hold_s: {HOLD_S}\n')
    out = tmp_path / 'study'
    env = {'PATH': '/usr/bin:/bin', 'ROS_LOG_DIR': str(tmp_path / 'ros_log'), 'HOME': os.environ.get('HOME', '/tmp')}
    proc = subprocess.run([sys.executable, '-m', 'acds_cli', 'montecarlo', str(scenario), '--runs', '2', '--jobs', '1',
                           '--external', 'acds_controller=oresat_detumble_fsw', '--fsw-command',
                           'oresat_detumble_fsw --ros-args --params-file {params}', '--paired', '--out', str(out),
                           '--quiet'], capture_output=True, text=True, cwd=ROOT, env=env, timeout=300, check=False)
    assert proc.returncode == 0, proc.stderr
    assert 'identical in 2 of 2' in proc.stdout, proc.stdout
    total = load_scenario(str(scenario)).total_steps()
    for rec in json.loads((out / 'samples.json').read_text()):
        ours, built_in = rec['flight_software'], rec['built_in']
        assert ours['steps'] == built_in['steps'] < total, rec['index']
        assert ours['steps'] == round(ours['detumble_time_min'] * 60) + HOLD_S
