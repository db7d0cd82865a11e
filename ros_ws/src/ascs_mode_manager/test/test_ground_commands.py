"""Ground-command intake: the schedule parses and sorts; commands come out at a defined step."""

from __future__ import annotations

import collections
import math

import pytest
from acds_common.commands import CommandError, ModeCommand
from ascs_mode_manager.ground_commands import (
    DUE_SLACK_S,
    MAX_PENDING,
    GroundCommandQueue,
    answer,
    parse,
    parse_schedule,
)
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


def test_next_s_says_when_due_has_commands_as_due_hands_them_out():
    """The steppers' per-step test (``next_s <= t_s + DUE_SLACK_S``) skips exactly the steps where due() is empty."""
    queue = GroundCommandQueue(['1.0: b', '0.5: a', '1.0: c'], str.upper)
    assert queue.next_s == 0.5
    steps = [0.0, 0.5 - 2 * DUE_SLACK_S, 0.5 - DUE_SLACK_S / 2, 0.75, 1.0, 1.25]
    for i, t_s in enumerate(steps):
        if i == 3:
            queue.receive('live')
            assert queue.next_s == -math.inf
        waiting = queue.next_s <= t_s + DUE_SLACK_S
        assert waiting == bool(queue.due(t_s)), t_s
    assert queue.next_s == math.inf and queue.due(1e9) == []
    assert GroundCommandQueue([], str.upper).next_s == math.inf


def test_text_is_parsed_on_entry_and_a_text_that_does_not_parse_is_refused_with_the_parsers_reason():
    core = WorkshopModeManager('cmg_dump')
    queue = GroundCommandQueue(['0: mode cmg_hold', '0: gain x 1'], lambda text: parse(core, text))
    (_, hold, _), (_, gain, _) = queue.due(0.0)
    assert hold == ModeCommand('cmg_hold') and isinstance(gain, CommandError)
    assert answer(core, hold, 0.0).accepted
    refused = answer(core, gain, 0.0)
    assert not refused.accepted and refused.reason == str(gain) and 'takes only "mode <' in refused.reason


@pytest.mark.parametrize('system, scenario, accepted, refused', [
    ('heao', 'heao_b_acquisition', 'eea_select x B', 'sss enable'),
    ('sss', 'sss_a_pass_test', 'sss enable', 'mode mode_1b'),
    ('aap', 'aap_workshop_pop_test', 'mode cmg_hold', 'sss enable'),
])
def test_every_mode_logic_answers_in_the_one_ack_format(tmp_path, system, scenario, accepted, refused):
    """Scheduled and live commands, accepted, refused and dropped (queue full), of HEAO, SSS and AAP: one line
    format (ground_commands.ack_line), a refusal also a WARN diagnostic naming the command."""
    from acds_common.parameters import node_parameters, normalize
    from acds_common.scenario import load_scenario
    from ascs_mode_manager.mode_manager_step import ModeManagerStep

    path = tmp_path / 'cmd.yaml'
    path.write_text(f'extends: {scenario}\nname: cmd\nmodes:\n  ground_commands: ["1: {accepted}", "1: {refused}"]\n')
    params = node_parameters(load_scenario(str(path)), 20)['ascs_mode_manager']
    step_class = next(c for c in ModeManagerStep.__subclasses__() if c.__name__.lower().startswith(system))
    step = step_class(normalize('ascs_mode_manager', params), log=lambda _level, _text: None)
    inputs = collections.defaultdict(lambda: None)  # no sensor input: each logic holds or reads zero
    step.receive_command('warp_drive on')
    out = step.mode_logic(2, 1.0, inputs)
    assert out['ack'][:2] == [f"t=1.00 accepted (scheduled) '{accepted}': " + out['ack'][0].split(': ', 1)[1],
                              f"t=1.00 refused (scheduled) '{refused}': " + out['ack'][1].split(': ', 1)[1]]
    assert out['ack'][2].startswith("t=1.00 refused (live) 'warp_drive on': ")
    refusals = [st for st in out['diagnostics'] if st.message == 'ground command refused']
    assert [dict(st.values)['command'] for st in refusals] == [refused, 'warp_drive on']
    for _ in range(MAX_PENDING + 1):
        step.receive_command('mode mode_1a')
    assert step.mode_logic(3, 1.5, inputs)['ack'][0] == (
        f"refused (live) 'mode mode_1a': dropped, {MAX_PENDING} commands already wait for the next step")
