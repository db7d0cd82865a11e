"""The AAP Workshop mode logic (``modes.system: aap``; seed 000): its modes, ground commands and the stepper part."""

from __future__ import annotations

import pytest
from acds_common.parameters import node_parameters, normalize
from acds_common.scenario import load_scenario
from ascs_mode_manager.ground_commands import submit
from ascs_mode_manager.mode_manager_step import AapModeManagerStep
from ascs_mode_manager.spin_mechanizations import AscsError
from ascs_mode_manager.workshop_modes import WorkshopModeManager


def test_mode_commands_are_applied_at_the_next_step_and_the_rest_refused() -> None:
    core = WorkshopModeManager('cmg_dump')
    assert submit(core, 'mode cmg_dump', 0.0).reason == 'wrong mode: already in cmg_dump'
    ok = submit(core, 'mode cmg_hold', 5.0)
    assert ok.accepted and ok.command == 'mode cmg_hold' and core.mode == 'cmg_dump'
    assert not submit(core, 'mode mode_1a', 5.0).accepted
    assert 'takes only' in submit(core, 'eea_select x B', 5.0).reason
    (tr,) = core.step(10.0)
    assert (tr.from_mode, tr.to_mode, core.mode) == ('cmg_dump', 'cmg_hold', 'cmg_hold')
    assert 't=5.0' in tr.cause and core.step(20.0) == []
    with pytest.raises(AscsError, match='not a Workshop mode to start in'):
        WorkshopModeManager('standby')


def test_the_aap_part_publishes_the_mode_every_step_and_answers_scheduled_commands(tmp_path) -> None:
    path = tmp_path / 'aap_cmd.yaml'
    path.write_text('extends: aap_workshop_pop_test\nname: aap_cmd\nmodes:\n'
                    '  ground_commands: ["100: mode cmg_hold", "100: sss enable"]\n')
    params = normalize('ascs_mode_manager', node_parameters(load_scenario(str(path)), 20)['ascs_mode_manager'])
    step = AapModeManagerStep(params, log=lambda _level, _text: None)
    first = step.mode_logic(0, 0.0, {})
    assert first['mode'][0].message == 'cmg_dump' and 'events' not in first
    out = step.mode_logic(5, 100.0, {})
    assert out['mode'][0].message == 'cmg_hold'
    assert out['events'] == ['t=100.0 cmg_dump->cmg_hold: ground command at t=100.0']
    assert out['ack'][0] == "t=100.00 accepted (scheduled) 'mode cmg_hold': cmg_dump → cmg_hold at the next step"
    assert out['ack'][1].startswith("t=100.00 refused (scheduled) 'sss enable': ") and out['diagnostics'][0].level == 1
