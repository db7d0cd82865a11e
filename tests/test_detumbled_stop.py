"""``dynamics.stop_when_detumbled``: the time owner ends the run once |ω| has stayed below the detumbled rate for the
hold, at the same step on both engines, and the run is the plain run cut there (same truth, digest and detumble time).

The spacecraft starts just above 0.1°/s about its minimum-inertia axis, so the torque rods bring it below within a
minute (67 s on the tilted dipole at t0)."""

from __future__ import annotations

import pytest
from acds_common.scenario import ScenarioError, load_scenario
from acds_runtime.direct import DirectRun

HOLD_S = 10


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
