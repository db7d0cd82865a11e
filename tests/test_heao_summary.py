"""Unit tests of the HEAO summary helpers and the sweep verb's pure parts (no graph)."""

from __future__ import annotations

import numpy as np
import pytest
from acds_cli import __main__ as acds_main
from acds_cli.verbs import sweep
from acds_cli.verbs.sweep import GROUPS, expand, table
from acds_common.mode_report import transitions
from heao_mission.heao_summary import acquisition_times, saturated


def _history(modes: list[tuple[float, str, bool]]) -> list[tuple[float, str, str, bool]]:
    return [(t, m, f'cause {i}', c) for i, (t, m, c) in enumerate(modes)]


def test_acquisition_times_from_mode_history():
    h = _history([(0.0, 'mode_1a', False), (60.0, 'mode_1a', False), (120.0, 'mode_1b', False),
                  (600.0, 'mode_1b', True)])
    times = acquisition_times(h)
    assert times == {'time_magnetics_only_min': 2.0, 'time_wheels_magnetics_min': 8.0, 'acquisition_time_min': 10.0}


def test_acquisition_times_not_reached_are_none_and_wheels_from_start_is_zero():
    assert acquisition_times(_history([(0.0, 'mode_1a', False), (30.0, 'mode_1a', False)])) == {
        'time_magnetics_only_min': None, 'time_wheels_magnetics_min': None, 'acquisition_time_min': None}
    case6 = acquisition_times(_history([(0.0, 'mode_1b', False), (300.0, 'mode_1b', True)]))
    assert case6 == {'time_magnetics_only_min': 0.0, 'time_wheels_magnetics_min': 5.0, 'acquisition_time_min': 5.0}
    cruise = acquisition_times(_history([(0.0, 'celestial_point', True)]))
    assert set(cruise.values()) == {None}


def test_transitions_list_mode_changes_and_capture():
    h = _history([(0.0, 'mode_1a', False), (120.0, 'mode_1b', False), (600.0, 'mode_1b', True),
                  (660.0, 'celestial_point', True)])
    tr = transitions(h)
    assert [(x['t_min'], x['from'], x['to']) for x in tr] == [
        (2.0, 'mode_1a', 'mode_1b'), (10.0, 'mode_1b', 'capture'), (11.0, 'mode_1b', 'celestial_point')]
    assert tr[0]['cause'] == 'cause 1'


def test_saturation_is_any_axis_at_its_capacity():
    caps = np.array([5.0, 3.0, 4.0])
    assert saturated(np.array([2.0, -3.0, 0.0]), caps)
    assert not saturated(np.array([2.0, -3.0, 0.0]) * 0.99, caps)
    assert saturated(np.array([0.0, 0.0, -4.0 * (1 - 1e-10)]), caps)  # relative tolerance 1e-9


def test_sweep_groups_and_table():
    assert expand(['table-4-7'])[:2] == ['heao_b_acquisition', 'heao_a_acquisition']
    assert len(GROUPS['table-4-7']) == 11 and GROUPS['table-4-7'][-1] == 'heao_b_case11'
    assert expand(['heao_b_case5', 'table-4-7']).count('heao_b_case5') == 1
    text = table([{'scenario': 'a', 'time_magnetics_only_min': 1.5, 'time_wheels_magnetics_min': None,
                   'acquisition_time_min': None, 'final_wheel_momentum_ftlbs': 2.0,
                   'peak_wheel_momentum_ftlbs': {'x': 1, 'y': 1, 'z': 1, 'rss': 3.0},
                   'peak_moment_am2': {'x': 2000.0, 'y': 10.0, 'z': 0.0}, 'wheel_saturation_time_min': None,
                   'sim_minutes': 20.0, 'wall_seconds': 12.0},
                  {'scenario': 'b', 'error': 'exit code 1: boom'}])
    row_a = next(line for line in text.splitlines() if line.startswith('a '))
    assert '1.5' in row_a and '2000' in row_a and '—' in row_a
    assert 'b' in text and 'FAILED: exit code 1: boom' in text


@pytest.mark.parametrize(('given', 'engine'), [((), 'direct'), (('--engine', 'graph'), 'graph'),
                                               (('--engine', 'direct'), 'direct')])
def test_sweep_without_runs_runs_each_scenario_on_the_engine_asked_direct_by_default(monkeypatch, capsys,
                                                                                    given, engine):
    """Issue 24 §4: ``sweep A B`` (no ``--runs``) ignored ``--engine`` and ran every scenario on the graph;
    each scenario's ``run`` process now gets the engine asked for, direct when none is (as ``--help`` says)."""
    calls = []

    def fake_run_one(name, workdir, extra):
        calls.append((name, extra))
        return {'scenario': name, 'sim_minutes': 0.1, 'wall_seconds': 0.0}
    monkeypatch.setattr(sweep, 'run_one', fake_run_one)
    assert acds_main.main(['sweep', 'heao_b_case5', 'heao_b_case6', '--until-min', '0.1', *given]) == 0
    assert [name for name, _ in calls] == ['heao_b_case5', 'heao_b_case6']
    for _name, extra in calls:
        assert extra[extra.index('--engine') + 1] == engine, extra
    assert 'heao_b_case6' in capsys.readouterr().out
