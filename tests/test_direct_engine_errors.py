"""The direct engine's compiled step (acds_runtime.step_program) fails as a node process would: one line
naming the node, stage, step and, for a missing input, the producer and topic (spec §2; issue 24)."""

from __future__ import annotations

import pytest
from acds_common.scenario import load_scenario
from acds_common.stepper import StepError
from acds_runtime.direct import DirectRun
from acds_runtime.launcher import LaunchError

SCENARIO = 'heao_b_acquisition_short'


def _run_with(stage: str, wrap) -> str:
    """Run 10 steps with ``node.stage`` replaced by ``wrap(original)``; the LaunchError's text. Without the fused
    loop: its quiet steps call no stage method (a stage's kernel calls a step that would fail not quiet, and the
    step program then runs it, as here)."""
    run = DirectRun(load_scenario(SCENARIO), steps=10, fused=False)
    node, name = stage.split('.')
    setattr(run.steppers[node], name, wrap(getattr(run.steppers[node], name)))
    with pytest.raises(LaunchError) as err:
        run.run()
    return str(err.value)


def _at_step(n, change):
    def wrap(method):
        def stage(k, t_s, inputs):
            out = method(k, t_s, inputs)
            return change(dict(out)) if k == n else out
        return stage
    return wrap


def test_a_stepper_exception_names_node_stage_and_step():
    def change(_out):
        raise ZeroDivisionError('boom')
    text = _run_with('em_driver.drive', _at_step(4, change))
    assert text == 'node em_driver failed: stage drive raised ZeroDivisionError at step 4: boom'


def test_a_step_error_is_the_node_failing_at_its_step():
    def change(_out):
        raise StepError('coil open')
    assert _run_with('em_driver.drive', _at_step(6, change)) == 'node em_driver failed at step 6: coil open'


def test_an_output_nobody_declared_is_named():
    text = _run_with('acds_controller.control', _at_step(3, lambda out: {**out, 'thrust': (0.0, 0.0, 0.0)}))
    assert text == "acds_controller: stepper returned undeclared output 'thrust'"


def test_a_missing_input_names_its_producer_topic_step_and_consumer():
    def drop(out):
        del out['volts']
        return out
    text = _run_with('acds_controller.control', _at_step(5, drop))
    assert text == ('node acds_controller produced no /acds/controller/wheel_volts for step 5 '
                    '(reaction_wheels.drive needs it)')


def test_recorded_and_unrecorded_runs_route_the_same_values(tmp_path):
    """The step compiled for a bag (every message published) and without one (only what is read) give the
    same summary and truth digest."""
    sc = load_scenario(SCENARIO)
    bare = DirectRun(sc, steps=300, fused=False).run().summary
    recorded = DirectRun(sc, steps=300, record=tmp_path / 'bag').run().summary
    assert {k: v for k, v in bare.items() if k != 'wall_seconds'} == \
        {k: v for k, v in recorded.items() if k != 'wall_seconds'}
