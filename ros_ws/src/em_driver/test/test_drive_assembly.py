"""Tests of the three-axis drive assembly: redundancy, failures, alarms, drive types (spec §6)."""

from __future__ import annotations

import math

import numpy as np
import pytest
from em_driver.bridge_switch import CoilParams, EmDriverError
from em_driver.drive_assembly import AssemblyResult, AxisConfig, DriveAssembly

DT = 0.5  # HEAO DPA cycle, s
K = CoilParams().moment_per_amp_am2


def run(assembly: DriveAssembly, command: list[float], seconds: float) -> list[AssemblyResult]:
    return [assembly.step(np.array(command), DT) for _ in range(round(seconds / DT))]


def test_average_dipole_tracks_moment_command() -> None:
    assembly = DriveAssembly()
    command = [1000.0, -500.0, 200.0]
    last = run(assembly, command, 6.0)[-1]
    np.testing.assert_allclose(last.avg_dipole_am2, command, rtol=0.01)
    np.testing.assert_allclose(last.commanded_current_a, np.array(command) / K)
    assert np.all(last.duty > 0.5) and np.all(last.duty < 1.0)
    assert np.all(last.switch_count > 0)
    assert np.all(last.power_w > 0.0)
    assert last.active_units == ('A', 'A', 'A')
    assert not last.alarms.any() and last.events == () and last.diagnostics == ()


def test_moment_command_saturates_at_coil_max() -> None:
    assembly = DriveAssembly()
    last = run(assembly, [5000.0, -5000.0, 0.0], 6.0)[-1]
    np.testing.assert_allclose(last.commanded_current_a, [0.727, -0.727, 0.0], rtol=1e-9)
    np.testing.assert_allclose(last.avg_dipole_am2[:2], [2062.0, -2062.0], rtol=0.01)
    assert last.avg_dipole_am2[2] == 0.0


@pytest.mark.parametrize('bad', [math.nan, math.inf, -math.inf])
def test_non_finite_command_component_holds_last_valid(bad: float) -> None:
    assembly = DriveAssembly()
    run(assembly, [800.0, 300.0, 0.0], 6.0)
    result = assembly.step(np.array([bad, 0.0, 0.0]), DT)
    assert len(result.diagnostics) == 1 and 'axis 0' in result.diagnostics[0]
    assert result.commanded_current_a[0] == pytest.approx(800.0 / K)
    assert result.avg_dipole_am2[0] == pytest.approx(800.0, rel=0.01)
    assert result.commanded_current_a[1] == 0.0  # the valid components still apply
    assert assembly.step(np.array([bad, 0.0, 0.0]), DT).avg_dipole_am2[0] == pytest.approx(800.0, rel=0.01)


def test_bad_shape_or_period_raises() -> None:
    assembly = DriveAssembly()
    with pytest.raises(EmDriverError, match='shape'):
        assembly.step(np.zeros(2), DT)
    with pytest.raises(EmDriverError, match='dt_s'):
        assembly.step(np.zeros(3), 0.0)
    with pytest.raises(EmDriverError, match='unit'):
        assembly.select_eea(0, 'C')
    with pytest.raises(EmDriverError, match='axis'):
        assembly.inject_failure(3, 'A', 'open_winding')


def test_constant_level_reaches_supply_over_resistance_with_tau() -> None:
    coil = CoilParams(resistance_ohm=369.0, inductance_h=0.9, moment_per_amp_am2=34.8, max_moment_am2=2.65)
    tau = coil.tau_s
    assembly = DriveAssembly(axes=[AxisConfig.constant_level(coil), AxisConfig(), AxisConfig()])
    at_tau = assembly.step(np.array([1.0, 0.0, 0.0]), tau)
    i_level = 28.0 / 369.0
    assert at_tau.coil_current_a[0] == pytest.approx((1 - math.exp(-1)) * i_level, rel=1e-9)
    settled = assembly.step(np.array([1.0, 0.0, 0.0]), 20 * tau)
    assert settled.coil_current_a[0] == pytest.approx(i_level, rel=1e-6)
    assert settled.end_dipole_am2[0] == pytest.approx(34.8 * i_level, rel=1e-6)
    assert settled.duty[0] == 1.0 and settled.switch_count[0] == 0
    steady = assembly.step(np.array([1.0, 0.0, 0.0]), 1.0)
    assert steady.power_w[0] == pytest.approx(28.0 * i_level, rel=1e-6)  # 2.12 W (seed 001: 2.13 W)
    # Only the sign of the command matters in this mode; reversal drives −28/R.
    reverse = assembly.step(np.array([-123.0, 0.0, 0.0]), 30 * tau)
    assert reverse.coil_current_a[0] == pytest.approx(-i_level, rel=1e-6)
    off = assembly.step(np.array([0.0, 0.0, 0.0]), 30 * tau)
    assert off.coil_current_a[0] == 0.0
    assert not (at_tau.alarms.any() or settled.alarms.any() or reverse.alarms.any() or off.alarms.any())


def test_healthy_full_scale_reversals_raise_no_alarm() -> None:
    assembly = DriveAssembly()
    results = []
    for k in range(6):
        results += run(assembly, [2062.0 * (-1) ** k, -2062.0 * (-1) ** k, 1000.0 * (-1) ** k], 5.0)
    assert not any(r.alarms.any() for r in results)
    assert all(r.events == () for r in results)


@pytest.mark.parametrize('kind', ['open_winding', 'stuck_on_bridge', 'dead_driver'])
def test_failure_raises_mismatch_alarm_after_settling(kind: str) -> None:
    assembly = DriveAssembly(mismatch_settle_s=3.0)
    run(assembly, [0.0, 700.0, 0.0], 6.0)
    assembly.inject_failure(1, 'A', kind)
    assert assembly.unit_fault(1, 'A') == kind
    results = run(assembly, [0.0, 700.0, 0.0], 6.0)
    alarm_times = [DT * (k + 1) for k, r in enumerate(results) if r.alarms[1]]
    assert alarm_times, f'{kind} never raised the alarm'
    assert 3.0 < alarm_times[0] <= 3.0 + 2.5  # after the settle time (+ the current's own transient)
    assert not any(r.alarms[0] or r.alarms[2] for r in results)
    assert any('mismatch alarm' in e for r in results for e in r.events)
    assert results[-1].active_units[1] == 'A'  # no auto switch by default
    expected = {'open_winding': 0.0, 'dead_driver': 0.0, 'stuck_on_bridge': (28.0 - 0.7) / 30.3}[kind]
    assert results[-1].coil_current_a[1] == pytest.approx(expected, abs=1e-3)
    # Ground selects the standby unit: the axis recovers and the alarm clears.
    assembly.select_eea(1, 'B')
    after = run(assembly, [0.0, 700.0, 0.0], 8.0)
    assert after[0].events[0] == 'axis 1: EEA select -> unit B'
    assert after[-1].avg_dipole_am2[1] == pytest.approx(700.0, rel=0.01)
    assert not after[-1].alarms[1]
    assert after[-1].active_units == ('A', 'B', 'A')


def test_auto_switch_to_standby_on_open_winding() -> None:
    assembly = DriveAssembly(auto_switch_to_standby=True)
    run(assembly, [1500.0, 0.0, 0.0], 4.0)
    assembly.inject_failure(0, 'A', 'open_winding')
    results = run(assembly, [1500.0, 0.0, 0.0], 10.0)
    switched = [r for r in results if any('auto switch' in e for e in r.events)]
    assert len(switched) == 1
    assert switched[0].active_units[0] == 'B' and switched[0].alarms[0]
    assert results[-1].active_units == ('B', 'A', 'A')
    assert results[-1].avg_dipole_am2[0] == pytest.approx(1500.0, rel=0.01)
    assert not results[-1].alarms[0]


def test_stuck_unit_is_unpowered_after_switch_over() -> None:
    """The TA removes power from the deselected unit: a stuck bridge stops driving its winding."""
    assembly = DriveAssembly(auto_switch_to_standby=True)
    assembly.inject_failure(2, 'A', 'stuck_on_bridge')
    results = run(assembly, [0.0, 0.0, 300.0], 12.0)
    assert results[-1].active_units[2] == 'B'
    assert results[-1].avg_dipole_am2[2] == pytest.approx(300.0, rel=0.01)
