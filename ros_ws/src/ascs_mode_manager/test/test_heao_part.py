"""Tests of the HEAO part's pure helpers: event lines, the core from a scenario."""

from __future__ import annotations

from acds_common.scenario import load_scenario
from ascs_mode_manager.ground_commands import submit
from ascs_mode_manager.heao_modes import Transition
from ascs_mode_manager.heao_part import build_core, event_text


def test_event_lines():
    assert event_text(Transition(12.25, 'mode_1a', 'mode_1b', 'rates below')) == 't=12.2 mode_1a->mode_1b: rates below'
    assert event_text(Transition(99.0, 'mode_1b', 'mode_1b', 'z 3°', kind='capture')) == \
        't=99.0 capture in mode_1b: z 3°'


def test_core_from_scenarios():
    base = build_core(load_scenario('heao_b_acquisition').values['modes'])
    assert base.mode == 'mode_1a' and not base.captured
    assert build_core(load_scenario('heao_b_case6').values['modes']).mode == 'mode_1b'
    point = build_core(load_scenario('heao_b_point_unloading').values['modes'])
    assert point.mode == 'celestial_point' and point.captured
    scan = build_core(load_scenario('heao_a_scan_unloading').values['modes'])
    assert scan.mode == 'celestial_scan'
    # the controller's gain table bounds the mode manager's validation of gain commands
    assert not submit(base, 'gain unloading_gain_point 7', 0.0).accepted
    assert 'out of range' in submit(base, 'gain unloading_gain_point 7', 0.0).reason
    assert submit(base, 'gain unloading_gain_point 0.03', 0.0).route == 'acds_controller'
