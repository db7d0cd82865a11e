"""HEAO mode logic with the cold-gas acquisition (ascs_mode_manager.cold_gas_modes; seed 002 §3.1)."""

from __future__ import annotations

import math

import pytest
from acds_common.units import rad
from ascs_mode_manager.cold_gas_modes import ColdGasModeManager, GasHandover
from ascs_mode_manager.ground_commands import submit
from ascs_mode_manager.heao_modes import HeaoModeConfig
from ascs_mode_manager.spin_mechanizations import AscsError

GAS = GasHandover(rad(0.05), rad(5.0), rad(0.05))
SUN_Z = (0.0, 0.0, 1.0)
FAST = (rad(1.0), rad(1.0), rad(1.0))
SLOW = (rad(0.01), rad(0.01), rad(0.01))


def core() -> ColdGasModeManager:
    return ColdGasModeManager(HeaoModeConfig(auto_cruise=True), GAS)


def test_gas_rate_damping_then_sun_acquisition_then_hand_over_then_capture():
    m = core()
    assert m.mode == 'gas_rate_damping'
    assert m.step(0.0, FAST, SUN_Z, True) == []
    (tr,) = m.step(0.5, SLOW, (1.0, 0.0, 0.0), True)
    assert (tr.from_mode, tr.to_mode) == ('gas_rate_damping', 'gas_sun_acquisition') and 'rates damped' in tr.cause
    tilt = (math.sin(rad(6.0)), 0.0, math.cos(rad(6.0)))
    assert m.step(1.0, SLOW, tilt, True) == []  # outside the 5° hand-over cone
    assert m.step(1.5, SLOW, SUN_Z, False) == []  # sun absent
    (tr,) = m.step(2.0, SLOW, SUN_Z, True)
    assert (tr.to_mode, m.handover_t_s) == ('mode_1b', 2.0) and 'hand-over to the wheels' in tr.cause
    cap, cruise = m.step(2.5, (0.0, 0.0, 0.0), SUN_Z, True)
    assert cap.kind == 'capture' and cruise.to_mode == 'celestial_point'
    assert m.status()['handover_t_s'] == '2.000'


def test_reacquire_by_ground_command_and_gas_commands_routed():
    m = core()
    assert not submit(m, 'mode reacquire', 0.0).accepted  # already on gas
    m.mode = 'celestial_point'
    res = submit(m, 'mode reacquire', 10.0)
    assert res.accepted and res.route is None
    (tr,) = m.step(10.5, FAST, SUN_Z, True)
    assert tr.to_mode == 'gas_rate_damping' and not m.captured
    res = submit(m, 'gas isolation 2 close', 11.0)
    assert res.accepted and res.route == 'cold_gas' and res.command == 'isolation 2 close'
    assert submit(m, 'gas bank OFF', 11.0).command == 'bank off'
    assert not submit(m, 'gas isolation 3 close', 11.0).accepted
    assert not submit(m, 'mode gas_sun_acquisition', 11.0).accepted
    assert submit(m, 'eea_select x B', 11.0).route == 'em_driver'  # the HEAO grammar still holds


def test_a_gas_acquisition_starts_in_a_gas_mode():
    with pytest.raises(AscsError, match='starts in a gas mode'):
        ColdGasModeManager(HeaoModeConfig(), GAS, 'mode_1a')
