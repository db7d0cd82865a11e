"""Tests of the HEAO mode sequencing and ground commands (spec §8; seed 002 §4.1, §4.3.1, Table 4-7)."""

from __future__ import annotations

import math

import numpy as np
import pytest
from acds_common.units import rad
from ascs_mode_manager.ground_commands import submit
from ascs_mode_manager.heao_modes import (
    CASE_5_RATE_THRESHOLDS_DEG_S,
    HeaoModeConfig,
    HeaoModeManager,
)
from ascs_mode_manager.spin_mechanizations import AscsError
from hypothesis import given, settings
from hypothesis import strategies as st

SUN_Z = np.array([0.0, 0.0, 1.0])
SUN_OFF = np.array([0.0, math.sin(rad(30.0)), math.cos(rad(30.0))])
THRESHOLDS_DEG_S = (0.573, 0.115, 0.115)
LIMITS = {'unloading_gain_point': (0.0, 1.0)}
LAWS = {'acquisition': ('bxh', 'bdot'), 'unloading': ('bxh', 'lead', 'none')}


def _rates_deg(x: float, y: float, z: float) -> np.ndarray:
    return np.array([rad(x), rad(y), rad(z)])


def _manager(**kwargs: object) -> HeaoModeManager:
    return HeaoModeManager(HeaoModeConfig(**kwargs))  # type: ignore[arg-type]


def _to_captured_1b(mgr: HeaoModeManager) -> None:
    mgr.step(0.0, _rates_deg(0.1, 0.05, 0.05), SUN_OFF, True)
    assert mgr.mode == 'mode_1b'
    mgr.step(1.0, np.zeros(3), SUN_Z, True)
    assert mgr.captured


def test_1a_to_1b_exactly_at_thresholds_with_sun() -> None:
    mgr = _manager()
    assert mgr.mode == 'mode_1a'
    at = _rates_deg(*THRESHOLDS_DEG_S) * (1.0 - 1e-12)
    assert mgr.step(0.0, at, SUN_OFF, False) == []  # no sun, no transfer
    assert mgr.step(0.5, at, np.zeros(3), True) == []  # flag set but zero vector: no sun
    assert mgr.mode == 'mode_1a'
    transitions = mgr.step(1.0, -at, SUN_OFF, True)  # signs do not matter, |ω| is compared
    assert [(tr.from_mode, tr.to_mode, tr.kind) for tr in transitions] == [('mode_1a', 'mode_1b', 'mode')]
    assert 'rates below thresholds' in transitions[0].cause and 'sun present' in transitions[0].cause
    assert mgr.mode_1b_entry_t_s == 1.0


@pytest.mark.parametrize('axis', [0, 1, 2])
def test_no_transfer_when_one_rate_is_just_above(axis: int) -> None:
    mgr = _manager()
    rates = _rates_deg(*THRESHOLDS_DEG_S) * 0.5
    rates[axis] = rad(THRESHOLDS_DEG_S[axis]) * (1.0 + 1e-6)
    assert mgr.step(0.0, rates, SUN_Z, True) == []
    assert mgr.mode == 'mode_1a'


@settings(derandomize=True, max_examples=200, deadline=None)
@given(st.tuples(*[st.floats(-2.0, 2.0, allow_nan=False)] * 3), st.booleans())
def test_transfer_iff_all_rates_within_thresholds_and_sun(rates_deg: tuple[float, float, float],
                                                          sun: bool) -> None:
    mgr = _manager()
    mgr.step(0.0, _rates_deg(*rates_deg), SUN_Z, sun)
    expected = sun and all(abs(r) <= t for r, t in zip(_rates_deg(*rates_deg), _rates_deg(*THRESHOLDS_DEG_S),
                                                        strict=True))
    assert (mgr.mode == 'mode_1b') == expected


def test_case_5_thresholds_allow_earlier_transfer() -> None:
    rates = _rates_deg(1.0, 0.3, 0.3)
    baseline = _manager()
    baseline.step(0.0, rates, SUN_Z, True)
    case5 = _manager(rate_thresholds_rad_s=tuple(rad(x) for x in CASE_5_RATE_THRESHOLDS_DEG_S))
    case5.step(0.0, rates, SUN_Z, True)
    assert baseline.mode == 'mode_1a' and case5.mode == 'mode_1b'


def test_capture_needs_cone_and_nulled_rates_then_waits_for_ground() -> None:
    mgr = _manager()
    mgr.step(0.0, _rates_deg(0.1, 0.05, 0.05), SUN_OFF, True)
    assert mgr.step(1.0, np.zeros(3), SUN_OFF, True) == []  # 30° off the sun
    near = np.array([0.0, math.sin(rad(9.9)), math.cos(rad(9.9))])
    assert mgr.step(2.0, _rates_deg(0.0, 0.0, 0.02), near, True) == []  # z rate not nulled
    assert mgr.step(3.0, _rates_deg(0.005, -0.005, 0.005), near, False) == []  # sun lost
    out = mgr.step(4.0, _rates_deg(0.005, -0.005, 0.005), near, True)
    assert [(tr.kind, tr.from_mode, tr.to_mode) for tr in out] == [('capture', 'mode_1b', 'mode_1b')]
    assert mgr.captured and mgr.capture_t_s == 4.0 and mgr.mode == 'mode_1b'
    assert mgr.step(5.0, np.zeros(3), SUN_Z, True) == []  # reported once


def test_capture_dwell() -> None:
    mgr = _manager(capture_dwell_s=60.0)
    mgr.step(0.0, np.zeros(3), SUN_Z, True)
    assert mgr.mode == 'mode_1b' and not mgr.captured
    mgr.step(30.0, np.zeros(3), SUN_Z, True)
    mgr.step(40.0, np.zeros(3), SUN_OFF, True)  # interrupted: the dwell restarts
    mgr.step(50.0, np.zeros(3), SUN_Z, True)
    assert mgr.step(100.0, np.zeros(3), SUN_Z, True) == [] and not mgr.captured
    assert mgr.step(110.0, np.zeros(3), SUN_Z, True)[0].kind == 'capture'


@pytest.mark.parametrize('target', ['celestial_scan', 'celestial_point'])
def test_auto_cruise_at_capture(target: str) -> None:
    mgr = _manager(auto_cruise=True, cruise_target=target)
    mgr.step(0.0, _rates_deg(0.1, 0.05, 0.05), SUN_OFF, True)
    out = mgr.step(1.0, np.zeros(3), SUN_Z, True)
    assert [(tr.kind, tr.to_mode) for tr in out] == [('capture', 'mode_1b'), ('mode', target)]
    assert mgr.mode == target


def test_ground_cruise_command_applied_at_next_step() -> None:
    mgr = _manager()
    _to_captured_1b(mgr)
    res = submit(mgr, 'MODE celestial_point', 1.2)
    assert res.accepted and res.route is None and res.command == 'mode celestial_point'
    assert mgr.mode == 'mode_1b'  # not yet: applied at the next step boundary
    out = mgr.step(1.5, np.zeros(3), SUN_Z, True)
    assert [(tr.from_mode, tr.to_mode) for tr in out] == [('mode_1b', 'celestial_point')]
    assert "ground command 'mode celestial_point' accepted at t=1.200 s" in out[0].cause
    assert submit(mgr, 'mode celestial_scan', 2.0).accepted  # cruise ↔ cruise
    mgr.step(2.5, np.zeros(3), SUN_Z, True)
    assert mgr.mode == 'celestial_scan'


def test_refused_mode_commands_carry_reasons() -> None:
    mgr = _manager()
    res = submit(mgr, 'mode celestial_point', 0.0)
    assert not res.accepted and res.reason.startswith('wrong mode: mode_1a')
    res = submit(mgr, 'mode mode_1b', 0.0)
    assert not res.accepted and 'on-board transfer' in res.reason
    res = submit(mgr, 'mode mode_1a', 0.0)
    assert not res.accepted and res.reason == 'wrong mode: already in mode_1a'
    mgr.step(0.0, np.zeros(3), SUN_OFF, True)
    assert mgr.mode == 'mode_1b' and not mgr.captured
    res = submit(mgr, 'mode celestial_scan', 0.5)
    assert not res.accepted and 'not reached acquisition capture' in res.reason
    res = submit(mgr, 'mode cruise_fast', 0.5)
    assert not res.accepted and "unknown mode 'cruise_fast'" in res.reason
    res = submit(mgr, 'warp 9', 0.5)
    assert not res.accepted and "unknown command 'warp'" in res.reason
    assert not submit(mgr, '', 0.5).accepted


def test_reacquisition_from_cruise_resets_capture() -> None:
    mgr = _manager(auto_cruise=True)
    _to_captured_1b(mgr)
    assert mgr.mode == 'celestial_point'
    assert submit(mgr, 'mode mode_1a', 2.0).accepted
    # a second command is checked against the queued mode
    assert not submit(mgr, 'mode mode_1b', 2.0).accepted
    out = mgr.step(3.0, _rates_deg(1.0, 1.0, 1.0), SUN_Z, True)
    assert out[0].to_mode == 'mode_1a' and mgr.mode == 'mode_1a' and not mgr.captured


def test_routed_commands_are_validated_and_normalised() -> None:
    mgr = _manager(gain_limits=LIMITS, law_choices=LAWS)
    res = submit(mgr, 'eea_select Y b', 0.0)
    assert res.accepted and res.route == 'em_driver' and res.command == 'eea_select y B'
    res = submit(mgr, 'magnetometer_select a', 0.0)
    assert res.accepted and res.route == 'magnetometer_sim' and res.command == 'magnetometer_select A'
    res = submit(mgr, 'law unloading LEAD', 0.0)
    assert res.accepted and res.route == 'acds_controller' and res.command == 'law unloading lead'
    res = submit(mgr, 'gain unloading_gain_point 0.04', 0.0)
    assert res.accepted and res.route == 'acds_controller' and res.command == 'gain unloading_gain_point 0.04'
    assert mgr.mode == 'mode_1a'  # routed commands do not change the mode
    for text, reason in [('eea_select w A', 'usage: eea_select'), ('magnetometer_select C', 'usage'),
                         ('law unloading bdot', "unknown unloading law 'bdot'"),
                         ('law attitude bxh', "unknown law slot 'attitude'"),
                         ('gain unloading_gain_point 2', 'out of range [0, 1]'),
                         ('gain unloading_gain_point nan', 'not finite'),
                         ('gain unloading_gain_point x', 'not a number'),
                         ('gain warp_factor 1', "unknown gain 'warp_factor'")]:
        res = submit(mgr, text, 0.0)
        assert not res.accepted and reason in res.reason and res.route is None, text


def test_without_injected_limits_only_syntax_is_checked() -> None:
    res = submit(_manager(), 'gain anything 3.5', 0.0)
    assert res.accepted and res.route == 'acds_controller'


def test_wheels_on_from_separation_starts_in_mode_1b() -> None:
    """Table 4-7 case 6: wheels activated at separation, magnetics unloading; no magnetics-only phase."""
    mgr = _manager(wheels_on_from_separation=True)
    assert mgr.mode == 'mode_1b'
    assert mgr.step(0.0, _rates_deg(1.0, 1.0, 1.0), SUN_OFF, True) == []
    assert mgr.mode == 'mode_1b' and mgr.mode_1b_entry_t_s == 0.0


def test_bad_config_and_inputs_raise() -> None:
    with pytest.raises(AscsError, match='cruise_target'):
        HeaoModeConfig(cruise_target='maneuver')
    with pytest.raises(AscsError, match='rate_thresholds'):
        HeaoModeConfig(rate_thresholds_rad_s=(0.01, -0.002, 0.002))
    with pytest.raises(AscsError, match='initial_mode'):
        HeaoModeConfig(wheels_on_from_separation=True, initial_mode='standby')
    mgr = _manager()
    mgr.step(10.0, np.zeros(3), SUN_Z, False)
    with pytest.raises(AscsError, match='back in time'):
        mgr.step(5.0, np.zeros(3), SUN_Z, False)
    with pytest.raises(AscsError, match='finite'):
        mgr.step(11.0, np.array([np.nan, 0.0, 0.0]), SUN_Z, False)


def test_status() -> None:
    mgr = _manager()
    _to_captured_1b(mgr)
    st_ = mgr.status()
    assert mgr.mode == 'mode_1b' and mgr.captured and st_['capture_t_s'] == '1.000'
