"""Tests of the CubeSat torque rod and its PWM H-bridge drive (spec §9; seed 003)."""

from __future__ import annotations

import math

import numpy as np
import pytest
from acds_common.units import MU0
from em_driver import rl_circuit
from em_driver.bridge_switch import EmDriverError
from em_driver.drive_assembly import AssemblyResult
from em_driver.torque_rod import (
    CORE_MATERIALS,
    PwmDriverParams,
    TorqueRod,
    TorqueRodAssembly,
    TorqueRodWinding,
    demagnetizing_factor,
    demagnetizing_factor_seed,
    magnet_wire,
)
from hypothesis import given, settings
from hypothesis import strategies as st

DRIVER = PwmDriverParams()
WIRE_36 = magnet_wire(36)
R_COIL = 7.2 ** 2 / 0.5 - DRIVER.bridge_resistance_ohm  # 0.5 W at full duty through the bridge
#: An unsaturated rod (the shape the design routine returns for AWG 35) and a thin one that saturates.
ROD = TorqueRod(0.035, 4.27e-3, CORE_MATERIALS['permalloy'], magnet_wire(35), R_COIL / magnet_wire(35).ohm_per_m)
THIN = TorqueRod(0.035, 1.0e-3, CORE_MATERIALS['permalloy'], WIRE_36, R_COIL / WIRE_36.ohm_per_m)


def test_demagnetizing_factor_limits_and_seed_formula() -> None:
    assert demagnetizing_factor(2.0, 1.0) == pytest.approx(1.0 / 3.0, abs=1e-12)  # l = 2r: the sphere
    near = demagnetizing_factor(np.array([2.0 * (1 - 2e-4), 2.0 * (1 - 5e-5), 2.0 * (1 + 5e-5), 2.0 * (1 + 2e-4)]), 1.0)
    assert np.all(np.diff(near) < 0.0) and np.allclose(near, 1.0 / 3.0, atol=1e-4)  # smooth through m = 1
    assert demagnetizing_factor(1e5, 1.0) < 1e-8  # long rod → 0
    assert demagnetizing_factor(1e-6, 1.0) == pytest.approx(1.0, abs=1e-5)  # thin disc → 1
    aspects = np.geomspace(0.01, 1e4, 200)
    assert np.all(np.diff(demagnetizing_factor(aspects, 1.0)) < 0.0)
    for l_over_r in (20.0, 40.0, 100.0, 1000.0):  # the seed's formula is the long-rod asymptote
        assert demagnetizing_factor_seed(l_over_r, 1.0) == pytest.approx(float(demagnetizing_factor(l_over_r, 1.0)),
                                                                         rel=0.02)
    assert demagnetizing_factor_seed(math.e, 1.0) == pytest.approx(0.0, abs=1e-15)
    assert demagnetizing_factor_seed(2.0, 1.0) == pytest.approx(-1.0)  # outside its range


def test_wire_36_awg_matches_the_seed() -> None:
    assert WIRE_36.bare_diameter_m == pytest.approx(0.127e-3, rel=1e-12)
    assert WIRE_36.ohm_per_m == pytest.approx(1.361, rel=1e-3)  # seed W_w = 0.001361 Ω/mm
    with pytest.raises(EmDriverError, match='AWG 20'):
        magnet_wire(20)


def test_moment_and_flux_formulas_match_the_seed_equations() -> None:
    p = ROD.props
    mu = ROD.material.relative_permeability
    bracket = (mu - 1.0) / (1.0 + p.n_d * (mu - 1.0))
    area = math.pi * ROD.core_radius_m ** 2
    assert p.core_moment_per_a == pytest.approx(p.turns * area * bracket, rel=1e-12)
    assert p.air_moment_per_a > p.turns * area  # turns sit outside the core
    n_i = p.turns * 0.05
    seed_b = MU0 * n_i / (ROD.core_length_m * (p.n_d + (1.0 - p.n_d) / mu))  # with (1 − N_d), see docstring
    assert ROD.core_flux_density_t(0.05) == pytest.approx(seed_b, rel=1e-12)
    assert p.resistance_ohm == pytest.approx(R_COIL, rel=1e-12)
    # Wire length is conserved by the layer geometry: Σ 2π r_j per turn = l_w per winding.
    assert p.turns * 2.0 * math.pi * (ROD.core_radius_m + p.layers * ROD.wire.insulated_diameter_m / 2.0) == \
        pytest.approx(ROD.wire_length_per_winding_m, rel=1e-12)


def test_moment_vs_current_saturates_at_b_sat() -> None:
    i_sat = THIN.saturation_current_a
    assert THIN.core_flux_density_t(i_sat) == pytest.approx(THIN.material.saturation_t, rel=1e-12)
    k = THIN.linear_moment_per_a
    currents = np.linspace(0.0, i_sat, 11)
    np.testing.assert_allclose(THIN.moment_am2(currents), k * currents, rtol=1e-12)
    above = np.linspace(i_sat, 5 * i_sat, 11)
    slope = np.diff(THIN.moment_am2(above)) / np.diff(above)
    np.testing.assert_allclose(slope, THIN.props.air_moment_per_a, rtol=1e-9)  # only the air core adds
    assert THIN.moment_am2(-2 * i_sat) == pytest.approx(-THIN.moment_am2(2 * i_sat))
    for m in (0.01, 0.5 * float(THIN.moment_am2(i_sat)), float(THIN.moment_am2(3 * i_sat))):
        assert float(THIN.moment_am2(THIN.current_for_moment_a(m))) == pytest.approx(m, rel=1e-12)


@pytest.mark.parametrize('t_s', [1e-4, 5e-4, 2e-3, 7.3e-3, 0.05])
def test_current_rise_is_v_over_r_times_one_minus_exp(t_s: float) -> None:
    winding = TorqueRodWinding(ROD, DRIVER)
    winding.run(1.0, t_s)
    r_loop = ROD.props.resistance_ohm + DRIVER.bridge_resistance_ohm
    tau = ROD.props.inductance_h / r_loop
    assert winding.current_a == pytest.approx(7.2 / r_loop * (1.0 - math.exp(-t_s / tau)), rel=1e-10)


@settings(max_examples=25)
@given(duty_counts=st.integers(1, 1023))
def test_pwm_average_matches_linear_drive_within_the_ripple(duty_counts: int) -> None:
    """PWM at duty D against a linear drive of D·V, from rest and then settled."""
    duty = duty_counts / 1024
    winding = TorqueRodWinding(ROD, DRIVER)
    tau, i_full, period = winding.tau_s, winding.full_current_a, 1.0 / DRIVER.frequency_hz
    ripple = i_full * duty * (1.0 - duty) * period / tau  # peak-to-peak, T ≪ τ
    for dt in (0.01, 0.5):  # from rest through the rise, then settled
        i_start = winding.current_a
        run = winding.run(duty, dt)
        i_lin, q_lin = rl_circuit.segment(i_start, duty * i_full, tau, dt)
        assert abs(run.charge_as - q_lin) / dt <= ripple
        assert abs(winding.current_a - i_lin) <= ripple
    settled = run
    assert settled.bus_energy_j / 0.5 == pytest.approx(7.2 * duty * i_full * duty, rel=2e-3)  # V·D·⟨i_on⟩


def test_duty_resolution_and_interface() -> None:
    assert DRIVER.quantize(0.5004) == 512 / 1024 and DRIVER.quantize(-2.0) == -1.0
    assembly = TorqueRodAssembly([ROD] * 3)
    assembly.step(np.array([0.1, -0.05, 0.0]), 0.5)  # the rise (τ ≈ 1.8 ms) costs 0.3 % of a first period
    result = assembly.step(np.array([0.1, -0.05, 0.0]), 0.5)
    assert isinstance(result, AssemblyResult)
    np.testing.assert_allclose(result.avg_dipole_am2, [0.1, -0.05, 0.0], atol=2e-4)  # 1/1024 of 0.1552 + ripple
    assert np.all(result.duty[:2] > 0.0) and result.duty[2] == 0.0
    assert np.all(result.switch_count[:2] == 2 * 10_000)
    assert np.all(result.power_w[:2] > 0.0) and not result.alarms.any() and result.active_units == ('A', 'A', 'A')
    np.testing.assert_allclose(result.e_ft_v, DRIVER.current_sense_gain_v_per_a * result.coil_current_a)


def test_command_saturates_at_full_duty_moment() -> None:
    assembly = TorqueRodAssembly([ROD] * 3)
    m_max = assembly.max_moment_am2()
    assembly.step(np.array([10.0, -10.0, 0.0]), 0.5)
    result = assembly.step(np.array([10.0, -10.0, 0.0]), 0.5)
    np.testing.assert_allclose(result.duty[:2], 1.0)
    np.testing.assert_allclose(result.avg_dipole_am2[:2], [m_max[0], -m_max[1]], rtol=1e-3)
    assert m_max[0] == pytest.approx(0.1552, rel=1e-3)


def test_saturating_core_averages_the_moment_curve() -> None:
    assembly = TorqueRodAssembly([THIN] * 3)
    result = assembly.step(np.array([1.0, 0.0, 0.0]), 0.2)  # full duty: the thin core saturates
    i_full = 7.2 / (THIN.props.resistance_ohm + DRIVER.bridge_resistance_ohm)
    assert i_full > THIN.saturation_current_a
    assert result.avg_dipole_am2[0] < float(THIN.moment_am2(i_full))
    assert result.avg_dipole_am2[0] > THIN.linear_moment_per_a * THIN.saturation_current_a * 0.9
    settled = assembly.step(np.array([1.0, 0.0, 0.0]), 0.2)
    assert settled.avg_dipole_am2[0] == pytest.approx(float(THIN.moment_am2(i_full)), rel=1e-6)


def test_open_winding_alarms_and_the_standby_winding_restores_the_dipole() -> None:
    assembly = TorqueRodAssembly([ROD] * 3)
    command = np.array([0.1, 0.0, 0.0])
    assembly.step(command, 0.5)
    assembly.inject_failure(0, 'A', 'open_winding')
    failed = assembly.step(command, 0.5)
    assert failed.avg_dipole_am2[0] == 0.0 and failed.alarms[0]
    assert any('mismatch alarm on unit A' in e for e in failed.events)
    assembly.select_eea(0, 'B')
    restored = assembly.step(command, 0.5)
    assert restored.active_units[0] == 'B' and restored.avg_dipole_am2[0] == pytest.approx(0.1, rel=0.005)
    assert not restored.alarms[0] and any('winding select -> unit B' in e for e in restored.events)
    assert assembly.unit_fault(0, 'A') is not None


def test_auto_switch_dead_driver_decays_through_the_diodes() -> None:
    assembly = TorqueRodAssembly([ROD] * 3, auto_switch_to_standby=True)
    command = np.array([0.0, 0.12, 0.0])
    assembly.step(command, 0.5)
    assembly.inject_failure(1, 'A', 'dead_driver')
    result = assembly.step(command, 0.5)
    assert any('auto switch from unit A to standby unit B' in e for e in result.events)
    assert result.power_w[1] < 0.0  # the dead unit's current went back into the bus
    after = assembly.step(command, 0.5)
    assert after.active_units[1] == 'B' and after.avg_dipole_am2[1] == pytest.approx(0.12, rel=0.005)


def test_stuck_on_bridge_alarms_and_non_finite_commands_are_held() -> None:
    assembly = TorqueRodAssembly([ROD] * 3)
    assembly.step(np.array([0.02, 0.0, 0.0]), 0.5)
    assembly.inject_failure(0, 'A', 'stuck_on_bridge')
    result = assembly.step(np.array([0.02, 0.0, 0.0]), 0.5)
    assert result.alarms[0] and result.coil_current_a[0] == pytest.approx(
        7.2 / (ROD.props.resistance_ohm + DRIVER.bridge_resistance_ohm), rel=1e-6)
    held = assembly.step(np.array([math.nan, 0.05, 0.0]), 0.5)
    assert held.diagnostics and 'holding last valid command' in held.diagnostics[0]
    with pytest.raises(EmDriverError, match='unknown winding fault'):
        assembly.inject_failure(0, 'B', 'melted')
    with pytest.raises(EmDriverError, match='exactly 3 rods'):
        TorqueRodAssembly([ROD])
