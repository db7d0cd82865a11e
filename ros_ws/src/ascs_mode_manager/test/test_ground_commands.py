"""Ground-command intake: the schedule parses and sorts; commands come out at a defined step."""

from __future__ import annotations

import pytest
from acds_common.commands import CommandError, ModeCommand
from ascs_mode_manager.ground_commands import GroundCommandQueue, answer, parse, parse_schedule
from ascs_mode_manager.spin_mechanizations import AscsError
from ascs_mode_manager.workshop_modes import WorkshopModeManager


def test_schedule_parses_and_sorts_stably():
    got = parse_schedule(['20: mode celestial_point', '5.5: gain unloading_gain_point 0.03', '5.5:law unloading lead'])
    assert got == [(5.5, 'gain unloading_gain_point 0.03'), (5.5, 'law unloading lead'), (20.0, 'mode celestial_point')]
    assert parse_schedule([]) == []


@pytest.mark.parametrize('bad', ['mode celestial_point', 'x: mode standby', '-1: mode standby', '3:', 'nan: mode 1a',
                                 'inf: sss enable'])
def test_malformed_entry_is_rejected_naming_it(bad):
    with pytest.raises(AscsError, match='ground_commands entry .* is not "T_S: command"'):
        parse_schedule([bad])


def test_commands_are_due_at_the_first_step_at_or_after_their_time_live_ones_at_the_next_step():
    queue = GroundCommandQueue(['1.0: sss enable', '0: sss mode spin'], str.upper)
    assert queue.due(0.0) == [('sss mode spin', 'SSS MODE SPIN', 'scheduled')]
    queue.receive('sss despin')  # arrives between the steps at t = 0 and t = 0.5
    assert queue.due(0.5) == [('sss despin', 'SSS DESPIN', 'live')]
    assert queue.due(1.0) == [('sss enable', 'SSS ENABLE', 'scheduled')]
    assert queue.due(1.5) == []


def test_text_is_parsed_on_entry_and_a_text_that_does_not_parse_is_refused_with_the_parsers_reason():
    core = WorkshopModeManager('cmg_dump')
    queue = GroundCommandQueue(['0: mode cmg_hold', '0: gain x 1'], lambda text: parse(core, text))
    (_, hold, _), (_, gain, _) = queue.due(0.0)
    assert hold == ModeCommand('cmg_hold') and isinstance(gain, CommandError)
    assert answer(core, hold, 0.0).accepted
    refused = answer(core, gain, 0.0)
    assert not refused.accepted and refused.reason == str(gain) and 'takes only "mode <' in refused.reason
