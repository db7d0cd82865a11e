"""The cold-gas subsystem core (seed 002 §5): arrangement, impulse bookkeeping, valves, blowdown, faults."""

from __future__ import annotations

import math
import random

import pytest
from acds_common.commands import CommandError, GasCommand
from acds_common.thrusters import LAYOUTS, ArrangementError, arrangement, arrangement_from_section
from acds_common.units import LB_KG, LBF_N, PSI_PA, STANDARD_GRAVITY_M_S2
from cold_gas.rcs import (
    ColdGasError,
    ColdGasRcs,
    Fault,
    RcsConfig,
    ideal_vacuum_isp_limit_s,
    table_5_3_isp_s,
)

ARR = arrangement(*LAYOUTS['platform'])
OUT = arrangement(*LAYOUTS['outriggers'])
#: §6.2.5's platform: 95.94 in aft of the mass centre, the two places at ±40.25 in on the z centre line (m).
AFT_M, SIDE_M = 95.94 * 0.0254, 40.25 * 0.0254
DT = 0.5


def _gas(text: str) -> GasCommand:
    """A forwarded cold-gas command (the text without the verb 'gas')."""
    return GasCommand.parse(text.split())


def rcs(**kw) -> ColdGasRcs:
    fault = kw.pop('fault', Fault())
    return ColdGasRcs(RcsConfig(kw.pop('arrangement', ARR), **kw), fault)


def test_the_platform_layout_pitches_alone_and_rolls_and_yaws_with_couples():
    """§6.2.5: all six on the platform's lower surface, 95.94 in aft of the mass centre: no single thruster can roll
    (r × d along x needs r in the centre-of-mass station), so roll is a couple across the two places (arm 2 × 40.25
    in, the mass centre's 0.7 in z offset cancels), yaw a couple on one tangential pair (2 × 95.94 in), pitch one
    radial thruster (95.94 in). The mass centre's offsets couple pitch (0.5 in) and yaw (2 × 0.7 in) under 1 % into
    roll. A roll couple's net force is zero."""
    assert [len(g) for g in ARR.thrusters_of_axis] == [2, 2, 1, 1, 2, 2]
    assert ARR.arm_m == pytest.approx((2 * SIDE_M, 2 * SIDE_M, AFT_M, AFT_M, 2 * AFT_M, 2 * AFT_M), rel=1e-12)
    for a in range(6):
        axis, sign = divmod(a, 2)
        tau = [sum(ARR.torque_per_thrust[j][i] for j in ARR.thrusters_of_axis[a]) for i in range(3)]
        assert tau[axis] == pytest.approx((1.0 if sign == 0 else -1.0) * ARR.arm_m[a])
        assert max(abs(tau[i]) for i in range(3) if i != axis) <= 0.008 * ARR.arm_m[a]
    assert sorted(j for g in ARR.thrusters_of_axis for j in g) == [0, 0, 1, 1, 2, 2, 3, 3, 4, 5]
    assert ARR.axis_names(0) == '+x +z'
    frame = rcs().frame(0.0, DT, (0.1, 0.0, 0.0))  # +x roll: both valves of the couple, from the same instant
    i, j = ARR.thrusters_of_axis[0]
    assert frame.thrust_time_s[i] == frame.thrust_time_s[j] > 0.0 and frame.max_open == 2
    impulse = frame.thrust_n * frame.thrust_time_s[i]
    assert frame.torque_nm == pytest.approx((2 * SIDE_M * impulse / DT, 0.0, 0.0), abs=1e-12)
    assert frame.force_n == pytest.approx((0.0, 0.0, 0.0), abs=1e-15)


def test_the_outrigger_layout_gives_each_axis_one_thruster_with_the_stated_arm_and_force():
    """The named alternative: one thruster per signed axis, arm 1.2 m (roll) or 2.4 m (pitch, yaw); its net force is
    its thrust along its direction; chosen by cold_gas.thruster_layout."""
    assert OUT.arm_m == (1.2, 1.2, 2.4, 2.4, 2.4, 2.4)
    for a in range(6):
        (j,) = OUT.thrusters_of_axis[a]
        axis, sign = divmod(a, 2)
        tau = OUT.torque_per_thrust[j]
        assert tau[axis] == pytest.approx((1.0 if sign == 0 else -1.0) * OUT.arm_m[a])
        assert all(tau[i] == 0.0 for i in range(3) if i != axis)
    frame = rcs(arrangement=OUT).frame(0.0, DT, (0.1, 0.0, 0.0))  # +x roll
    (j,) = OUT.thrusters_of_axis[0]
    impulse = frame.thrust_n * frame.thrust_time_s[j]
    assert frame.torque_nm == pytest.approx((1.2 * impulse / DT, 0.0, 0.0), abs=1e-15)
    assert frame.force_n == pytest.approx(tuple(d * impulse / DT for d in OUT.force_per_thrust[j]), abs=1e-15)
    section = {'thruster_layout': 'outriggers', 'max_cross_coupling': 0.05,
               'thruster_positions': LAYOUTS['platform'][0], 'thruster_directions': LAYOUTS['platform'][1]}
    assert arrangement_from_section(section) == OUT
    with pytest.raises(ArrangementError, match='read only with thruster_layout: custom'):
        arrangement_from_section({**section, 'thruster_positions': LAYOUTS['outriggers'][0]})


def test_an_arrangement_without_a_torque_about_an_axis_is_refused_naming_it():
    positions, directions = list(LAYOUTS['outriggers'][0]), list(LAYOUTS['outriggers'][1])
    directions[9:12] = [0.0, 0.0, 1.0]  # T4 turned to fire like T3: +y twice, −y never
    positions[9:12] = [-2.4, 0.0, -1.2]
    with pytest.raises(ArrangementError, match=r'no thruster, nor couple of two, gives a torque about -y alone'):
        arrangement(positions, directions)
    positions, directions = list(LAYOUTS['outriggers'][0]), list(LAYOUTS['outriggers'][1])
    positions[0:3] = [0.5, 0.0, 1.2]  # the +x thruster off the centre-of-mass station: yaw coupling 42 %
    with pytest.raises(ArrangementError, match=r'about \+x alone .*T1 torque \[1.2, 0.0, -0.5\]'):
        arrangement(positions, directions)
    positions, directions = list(LAYOUTS['platform'][0]), list(LAYOUTS['platform'][1])
    directions[12:15] = [0.0, 1.0, 0.0]  # T5 turned tangential: pitch +y lost
    with pytest.raises(ArrangementError, match=r'about \+y alone'):
        arrangement(positions, directions)


def test_propellant_used_is_the_impulse_over_isp_g0_to_rounding():
    """Σ thrust·thrust time / (Isp·g0) over random frames equals the gas used, and the gas left falls by it."""
    sys_ = rcs()
    rng = random.Random(7)
    impulse = 0.0
    load = sys_.propellant_kg
    for k in range(400):
        req = tuple(rng.choice((0.0, rng.uniform(-0.6, 0.6))) for _ in range(3))
        frame = sys_.frame(k * DT, DT, req)
        impulse += sum(frame.thrust_n * t for t in frame.thrust_time_s)
    isp_g0 = 65.0 * STANDARD_GRAVITY_M_S2
    assert sys_.used_kg == pytest.approx(impulse / isp_g0, rel=1e-12)
    assert load - sys_.propellant_kg == pytest.approx(sys_.used_kg, rel=1e-9)
    assert sys_.impulse_ns == pytest.approx(impulse, rel=1e-12)
    assert sys_.vented_kg == 0.0


def test_minimum_impulse_bit_is_honoured():
    cfg = RcsConfig(ARR)
    sys_ = ColdGasRcs(cfg)
    frame = sys_.frame(0.0, DT, (0.0, 0.001, 0.0))  # 1 ms asked: raised to the 20 ms minimum on-time
    (j,) = ARR.thrusters_of_axis[2]
    assert frame.command_s[j] == cfg.min_on_time_s
    assert frame.thrust_time_s[j] == pytest.approx(0.020 - 0.005 + 0.003)
    assert frame.thrust_n * frame.thrust_time_s[j] == pytest.approx(cfg.minimum_impulse_bit_ns)
    assert cfg.minimum_impulse_bit_ns == pytest.approx(0.5 * LBF_N * 0.018)
    assert sum(sys_.frame(DT, DT, (0.0, 0.0, 0.0)).thrust_time_s) == 0.0


def test_at_most_two_valves_open_and_the_third_waits_its_turn():
    sys_ = rcs(arrangement=OUT)
    frame = sys_.frame(0.0, DT, (0.3, -0.2, 0.1))
    assert frame.max_open == 2
    by_thruster = {p.thruster: p for p in frame.pulses}
    assert len(by_thruster) == 3
    third = by_thruster[OUT.thrusters_of_axis[4][0]]  # the shortest (+z, 0.1 s) goes when the −y valve has shut
    second = by_thruster[OUT.thrusters_of_axis[3][0]]
    assert third.command_start_s == pytest.approx(second.command_s + 0.003)
    frame = sys_.frame(DT, DT, (0.5, 0.5, 0.5))  # three full-frame requests: two fly, the third is deferred
    assert frame.max_open == 2 and len(frame.pulses) == 2 and frame.deferred == OUT.thrusters_of_axis[4]
    assert all(p.command_start_s + p.command_s + 0.003 <= DT + 1e-12 for p in frame.pulses)


def test_a_couple_opens_both_valves_together_and_a_single_waits_for_one():
    """Platform layout: roll (a couple, 0.3 s) takes both valves from t = 0; pitch (one thruster, 0.25 s) starts when
    they shut, cut to the frame; yaw (a couple) no longer fits and waits for the next frame, both its thrusters."""
    frame = rcs().frame(0.0, DT, (0.3, 0.25, -0.1))
    starts = {p.thruster: p.command_start_s for p in frame.pulses}
    i, j = ARR.thrusters_of_axis[0]
    (k,) = ARR.thrusters_of_axis[2]
    assert starts[i] == starts[j] == 0.0 and starts[k] == pytest.approx(0.3 + 0.003)
    assert frame.max_open == 2 and sorted(frame.deferred) == sorted(ARR.thrusters_of_axis[5])


def test_blowdown_is_isothermal_and_the_regulator_drops_out_below_its_set_point():
    cfg = RcsConfig(ARR)
    p0 = cfg.tank_pressure_pa(cfg.load_mass_kg)
    assert p0 / PSI_PA == pytest.approx(3494, abs=1)  # 4.6 lb in two 7.6-in spheres at 293 K
    sys_ = rcs(load_mass_kg=0.2 * LB_KG)  # 153 psia: just above the 150 psia set point
    feeds = []
    for k in range(600):
        sys_.frame(k * DT, DT, (0.45, 0.45, 0.0))
        feeds.append(sys_.feed_pa)
        assert sys_.tank_pa == pytest.approx(sys_.tank_kg * 296.8037 * 293.0 / cfg.tank_volume_m3, rel=1e-5)
    assert feeds[0] == pytest.approx(cfg.regulator_set_pa)
    assert feeds[-1] < 0.9 * cfg.regulator_set_pa  # blowdown: the feed follows the tank
    assert sys_.feed_pa == pytest.approx(sys_.tank_pa, rel=1e-9)


def test_a_failed_open_regulator_trips_the_pressure_switch_and_closes_both_isolation_valves():
    """The stuck-open (leaking) regulator valve: the manifold rises, the switch closes both isolation valves before
    the relief valve cracks (no gas vented), ground cannot reopen while it is actuated, and reopening the healthy
    branch once the thrusters have bled the manifold restores regulated thrust."""
    sys_ = rcs(fault=Fault('regulator_fail_open', 0, 1.0))
    sys_.frame(0.0, DT, (0.0, 0.0, 0.0))
    assert sys_.isolation_open == [True, True] and not sys_.switch_actuated
    frame = sys_.frame(1.0, DT, (0.0, 0.0, 0.0))
    assert sys_.switch_actuated and sys_.isolation_open == [False, False]
    assert any('pressure switch actuated' in e for e in frame.events)
    assert sys_.vented_kg == 0.0
    assert 200 * PSI_PA <= sys_.feed_pa < 250 * PSI_PA
    accepted, why = sys_.apply(_gas('isolation 2 open'))
    assert not accepted and 'pressure switch actuated' in why
    k = 3
    while sys_.switch_actuated:  # the thrusters bleed the trapped gas
        sys_.frame(k * DT, DT, (0.3, 0.0, 0.0))
        k += 1
    assert sys_.apply(_gas('isolation 2 open')) == (True, 'isolation valve 2 open')
    for i in range(4):
        sys_.frame((k + i) * DT, DT, (0.0, 0.0, 0.0))
    assert sys_.feed_pa == pytest.approx(150 * PSI_PA) and not sys_.switch_actuated


def test_the_switch_acts_below_the_relief_valve():
    """A switch set above the relief valve's crack pressure is refused: the pressures must rise
    set point < switch < relief, so the switch always acts first."""
    with pytest.raises(ColdGasError, match='regulator set point 150 < pressure switch 300 < relief 250'):
        RcsConfig(ARR, switch_trip_pa=300 * PSI_PA)


def test_stuck_thruster_valves():
    (j,) = ARR.thrusters_of_axis[2]
    sys_ = rcs(fault=Fault('thruster_stuck_closed', j, 0.0))
    frame = sys_.frame(0.0, DT, (0.0, 0.2, 0.0))
    assert frame.command_s[j] > 0.0 and frame.thrust_time_s[j] == 0.0 and frame.torque_nm == (0.0, 0.0, 0.0)
    (j,) = ARR.thrusters_of_axis[3]
    sys_ = rcs(fault=Fault('thruster_stuck_open', j, 0.0))
    frame = sys_.frame(0.0, DT, (0.0, 0.0, 0.0))
    assert frame.thrust_time_s[j] == DT and frame.torque_nm[1] == pytest.approx(-AFT_M * 0.5 * LBF_N)
    assert not sys_.switch_actuated  # the regulator holds the feed: the switch does not see a stuck thruster
    assert sys_.apply(_gas('isolation 1 close'))[0] and sys_.apply(_gas('isolation 2 close'))[0]
    for k in range(1, 40):
        frame = sys_.frame(k * DT, DT, (0.0, 0.0, 0.0))
    assert frame.torque_nm == (0.0, 0.0, 0.0) and sys_.feed_pa == 0.0  # ground closed it: the manifold emptied


def test_isp_65_s_is_table_5_3():
    """Every Table 5-3 tank's impulse over its capacity is 65 s (±0.3); §5.3's 300 lbf·s for the 4.6 lb system too;
    below the ideal infinite-expansion limit of N₂ at 293 K (79.6 s)."""
    assert all(abs(isp - 65.0) <= 0.3 for isp in table_5_3_isp_s())
    assert 300.0 / 4.6 == pytest.approx(65.2, abs=0.1)
    assert ideal_vacuum_isp_limit_s(293.0) == pytest.approx(79.56, abs=0.005)
    sys_ = rcs()
    sys_.frame(0.0, DT, (0.47, 0.0, 0.0))
    total = sys_.cfg.load_mass_kg * 65.0 * STANDARD_GRAVITY_M_S2 / LBF_N
    assert total == pytest.approx(299.0, abs=0.1)  # the load's impulse capability, lbf·s


def test_a_tank_below_the_regulator_set_point_is_refused():
    with pytest.raises(ColdGasError, match='tank pressure at t0 76 psia .* is not above the regulator set point 150'):
        RcsConfig(ARR, load_mass_kg=0.1 * LB_KG)


def test_ground_commands_and_bank_power():
    sys_ = rcs()
    assert sys_.apply(_gas('bank off')) == (True, 'thruster bank power off')
    assert sum(sys_.frame(0.0, DT, (0.3, 0.3, 0.3)).thrust_time_s) == 0.0
    assert sys_.apply(_gas('transducer off'))[0] and sys_.telemetry()['gas_pressure_psia'] == 'off'
    with pytest.raises(CommandError, match='usage: gas isolation'):
        _gas('isolation 3 open')
    assert math.isfinite(float(sys_.telemetry()['feed_pressure_psia']))
