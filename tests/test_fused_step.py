"""The direct engine's fused loop gives the data of the step program, bit for bit (acds_runtime.fused_step).

Each case runs a scenario with the fused loop and without it (every step through the Python step program):
the summaries — truth digest, every Table 4-7 column, transitions — must be equal key by key (wall time
aside), and the loop must have run (most steps fused). The steps that are not quiet (the Mode 1A → 1B
transfer, the capture that ends the run, a magnetometer fault, an open winding's alarm and the automatic switch,
forwarded ground commands) run through the step program, and the loop takes over again after them.
"""

from __future__ import annotations

import pytest
from acds_common.scenario import load_scenario
from acds_runtime.direct import DirectRun
from acds_runtime.fused_step import BLOCK_STEPS


def _comparable(summary: dict) -> dict:
    return {k: v for k, v in summary.items() if k != 'wall_seconds'}


def _both(sc, steps=None):
    """(summary without the loop, summary with it, the fused run)."""
    plain = DirectRun(sc, steps=steps, fused=False).run()
    run = DirectRun(sc, steps=steps)
    fused = run.run()
    assert fused.steps == plain.steps
    return _comparable(plain.summary), _comparable(fused.summary), run


def test_fused_prefix_equals_the_step_program():
    """3000 steps of case 1 in Mode 1A: one block after the first steps, the same digest and summary."""
    plain, fused, run = _both(load_scenario('heao_b_acquisition'), 3000)
    assert fused == plain
    loop = run.fused_loop
    assert loop is not None and loop.fused_steps >= 2990, 'the quiet steps ran fused'
    assert loop.source() and 'def fused_block' in loop.source()[0]


def test_fused_whole_acquisition_equals_the_step_program():
    """Case 1 to capture: the transfer to Mode 1B and the capture (the run's end) run through the step program, the
    digest and every summary key (acquisition time, transitions) are the same; nearly every step ran fused."""
    sc = load_scenario('heao_b_acquisition')
    plain, fused, run = _both(sc)
    assert fused == plain
    assert [t['to'] for t in fused['mode_transitions']] == ['mode_1b', 'capture']
    loop = run.fused_loop
    assert loop is not None and loop.fused_steps > 0.99 * fused['steps']
    assert loop.blocks > fused['steps'] // BLOCK_STEPS, 'the loop stopped at the transitions and took over again'


#: Sample 2 of seed 2 of the paired sweep's draws (rates just above the Mode 1B thresholds): its steps 2, 3 and 4 are
#: not all quiet, so a block of ONE fused step (step 2) sits between two steps of the step program.
_ONE_STEP_BLOCK = """extends: heao_b_acquisition
name: one_step_block
seed: 981723672
spacecraft:
  initial_quaternion_xyzw: [-0.5616679134241909, -0.7312665121260047, -0.3056443538756509, 0.23740255309646355]
  initial_rates_deg_s: [0.11529732198374719, 0.11511941980755268, 0.11531855401539937]
orbit:
  raan_deg: 316.4220549773804
  arg_latitude0_deg: 133.32912680302064
earth:
  greenwich_angle0_deg: 243.88579719421594
"""


def test_a_block_of_one_step_feeds_every_value():
    """A one-step block has no rows for the summaries' block form: its values go one by one, none left out (was: the
    values stamped from the block's first step on were dropped and the next block refused the run)."""
    from acds_common.scenario import scenario_from_text

    plain, fused, run = _both(scenario_from_text(_ONE_STEP_BLOCK), 60)
    assert fused == plain
    assert run.fused_loop is not None and run.fused_loop.blocks >= 2


def test_faults_alarms_and_commands_fall_back_to_the_step_program():
    """A bias shift on the active magnetometer unit, an open winding on the x driver (the mismatch alarm and the
    automatic switch to unit B), forwarded ground commands (a gain, the y axis's EEA select, the magnetometer's
    unit) and a mode command: each at its step, through the step program; the data are the same bits."""
    sc = load_scenario('heao_b_acquisition')
    sc.values['magnetometer'].update(fault='bias_shift', fault_unit='A', fault_axis=1, fault_value_v=0.05,
                                     fault_time=100.0)
    sc.values['em_driver'].update(failure='open_winding', failure_axis=0, failure_unit='A', failure_time=200.0,
                                  auto_switch_to_standby=True)
    sc.values['modes'].update(ground_commands=['300: gain acquisition_gain 0.04', '350: eea_select y B',
                                               '400: magnetometer_select B', '500: mode standby',
                                               '600: mode mode_1a'])
    plain, fused, run = _both(sc, 2000)
    assert fused == plain
    loop = run.fused_loop
    assert loop is not None and loop.blocks >= 6 and loop.fused_steps > 1900


def test_fused_equals_the_process_graph(launch_graph):
    """The fused loop (no bag) against the six node processes: the same summary, digest included."""
    sc = load_scenario('heao_b_acquisition')
    steps = 300
    run = DirectRun(sc, steps=steps)
    fused = run.run()
    assert run.fused_loop is not None and run.fused_loop.fused_steps > 0
    with launch_graph(sc, steps=steps) as graph:
        result = graph.wait()
    assert _comparable(fused.summary) == _comparable(result.summary)


def test_a_bag_or_a_variant_without_fused_form_runs_the_step_program(tmp_path):
    """Recording a bag (every message encoded) runs every step through the step program; so does a graph with a
    stage that has no fused form (the cold-gas acquisition)."""
    sc = load_scenario('heao_b_acquisition')
    run = DirectRun(sc, steps=50, record=tmp_path / 'bag')
    run.run()
    assert run.fused_loop is None
    cold = DirectRun(load_scenario('heao_b_acquisition_cold_gas_short'), steps=50)
    cold.run()
    assert cold.fused_loop is None or cold.fused_loop.fused_steps == 0


@pytest.mark.parametrize('name', ['heao_b_acquisition_fast_geometry', 'heao_a_acquisition'])
def test_other_heao_cases_equal_the_step_program(name):
    plain, fused, run = _both(load_scenario(name), 1500)
    assert fused == plain
    assert run.fused_loop is not None and run.fused_loop.fused_steps > 0
