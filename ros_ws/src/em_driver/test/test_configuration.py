"""Tests of the scenario-section → drive assembly mapping and the forwarded-command grammar."""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

import numpy as np
import pytest
from acds_common.commands import EeaSelect
from acds_common.scenario import SCHEMA
from acds_common.torque_rod_record import dipole_bound_am2, read_torque_rod_record
from em_driver.bridge_switch import EmDriverError
from em_driver.configuration import EeaFailure, apply_command, axis_configs, build_assembly, parse_command
from em_driver.torque_rod import TorqueRodAssembly
from em_driver.torque_rod_design import DesignRequest, design_torque_rod


def section(**overrides: Any) -> dict[str, Any]:
    """The schema defaults of the em_driver section (SI), with overrides."""
    out = {name: f.default for name, f in SCHEMA['em_driver'].items()}
    out.update(overrides)
    return out


def test_defaults_are_three_table_4_3_bridge_switch_axes() -> None:
    configs = axis_configs(section())
    for c in configs:
        assert c.drive_type == 'bridge_switch'
        assert c.coil.resistance_ohm == 30.3 and c.coil.inductance_h == 20.3
        assert c.coil.max_current_a == pytest.approx(0.727)
        assert c.driver.v_ces_v == 0.35 and c.driver.diode_drop_v == 0.6 and c.driver.epsilon == 0.01


def test_constant_level_axis_reaches_supply_over_resistance() -> None:
    sec = section(drive_types=['constant_level', 'bridge_switch', 'bridge_switch'],
                  coil_resistance_ohm=[56.0, 30.3, 30.3], coil_inductance_h=[0.05, 20.3, 20.3])
    assert axis_configs(sec)[0].driver.v_ces_v == 0.0
    assembly = build_assembly(sec)
    result = None
    for _ in range(10):  # τ = 0.9 ms: settled long before 10 s
        result = assembly.step(np.array([-3.0, 0.0, 0.0]), 1.0)
    assert result is not None
    assert result.coil_current_a[0] == pytest.approx(-28.0 / 56.0, rel=1e-9), 'only the sign of the command counts'


def test_bench_command_default_and_settle_key_reach_the_assembly() -> None:
    assert section()['bench_command'] == [0.0, 0.0, 0.0]
    assembly = build_assembly(section(mismatch_settle=0.75, auto_switch_to_standby=True))
    assert assembly.mismatch_settle_s == 0.75 and assembly.auto_switch_to_standby


def test_parse_commands() -> None:
    assert parse_command('eea_select X b') == EeaSelect(0, 'B')
    assert parse_command('eea_failure z A open_winding') == EeaFailure(2, 'A', 'open_winding')
    assert parse_command('EEA_FAILURE y B none') == EeaFailure(1, 'B', None)


@pytest.mark.parametrize('text', ['', 'eea_select', 'eea_select w A', 'eea_select x C', 'eea_select x A B',
                                  'eea_failure x A melted', 'magnetometer_select B'])
def test_bad_commands_are_refused_with_a_reason(text: str) -> None:
    with pytest.raises(EmDriverError, match='usage|unknown|empty'):
        parse_command(text)


def test_commands_apply_to_the_assembly() -> None:
    assembly = build_assembly(section())
    assert apply_command(parse_command('eea_select y B'), assembly) == 'eea_select: axis y unit B active'
    assert assembly.active_units == ('A', 'B', 'A')
    apply_command(parse_command('eea_failure x A dead_driver'), assembly)
    assert assembly.unit_fault(0, 'A') == 'dead_driver'
    apply_command(parse_command('eea_failure x A none'), assembly)
    assert assembly.unit_fault(0, 'A') is None


@pytest.fixture(scope='module')
def rod_record(tmp_path_factory: pytest.TempPathFactory) -> tuple[Any, Path]:
    """The seed's minimum-mass AWG 35 rod (seed 003) and its `design-torque-rod --json` file."""
    design = design_torque_rod(DesignRequest(awg=35))
    path = tmp_path_factory.mktemp('rod') / 'rod.json'
    path.write_text(json.dumps(design.to_json_dict()))
    return design, path


def test_torque_rod_kind_builds_three_designed_rods_on_pwm_bridges(rod_record) -> None:
    design, path = rod_record
    assembly = build_assembly(section(driver_kind='torque_rod', torque_rod_design=str(path), supply_v=7.2))
    assert isinstance(assembly, TorqueRodAssembly)
    assert assembly.driver.supply_v == 7.2 and assembly.driver.bridge_resistance_ohm == design.request.bridge_resistance_ohm
    np.testing.assert_allclose(assembly.max_moment_am2(), design.moment_am2, rtol=1e-12)
    command = np.array([0.1, -0.05, 0.0])
    result = assembly.step(command, 1.0)  # τ = 1.8 ms: settled within the period, 10-bit duty
    np.testing.assert_allclose(result.avg_dipole_am2, command, atol=2e-3)
    assert np.all(result.power_w >= 0.0) and result.power_w[2] == 0.0 and result.duty[0] == pytest.approx(
        0.1 / design.moment_am2, abs=1e-3)
    apply_command(EeaSelect(1, 'B'), assembly)
    assert assembly.active_units == ('A', 'B', 'A')


@pytest.mark.parametrize(('record', 'message'), [
    (None, 'no design file given'),
    ('missing', 'cannot be read'),
    ('[1, 2]', 'one JSON object'),
    ('{"core": "permalloy"', 'is not a JSON design record'),
    ({'drop': 'moment_am2'}, "lacks key 'moment_am2'"),
    ({'set': ('core_radius_mm', -1.0)}, 'core_radius_mm must be a finite positive number'),
    ({'set': ('core', 'mumetal')}, "unknown core 'mumetal'"),
])
def test_a_bad_rod_design_file_is_refused_naming_the_key(rod_record, tmp_path: Path, record: Any,
                                                         message: str) -> None:
    design, _ = rod_record
    path = tmp_path / 'rod.json'
    if isinstance(record, str) and record != 'missing':
        path.write_text(record)
    elif isinstance(record, dict):
        data = design.to_json_dict()
        data.pop(record.get('drop', ''), None)
        if 'set' in record:
            data[record['set'][0]] = record['set'][1]
        path.write_text(json.dumps(data))
    given = '' if record is None else str(path)
    with pytest.raises(EmDriverError, match='torque_rod_design') as err:
        build_assembly(section(driver_kind='torque_rod', torque_rod_design=given, supply_v=7.2))
    assert message in str(err.value)


def test_the_dipole_bound_holds_for_both_windings_at_the_bus_over_winding_resistance(rod_record) -> None:
    """acds_common's bound (the rigid body's actuator limit) is above anything the rod can make (seed 003)."""
    design, path = rod_record
    record = read_torque_rod_record(path)
    for supply in (3.0, 7.2, 12.0):
        i_max = design.rod.windings * supply / design.rod.props.resistance_ohm
        bound = dipole_bound_am2(record, supply)
        for i in np.linspace(0.0, i_max, 50):
            assert float(design.rod.moment_am2(i)) <= bound * (1.0 + 1e-12)
    saturated = dict(record, moment_am2=0.5 * record['moment_am2'], current_a=record['current_a'])
    assert dipole_bound_am2(saturated, 7.2) == pytest.approx(0.5 * dipole_bound_am2(record, 7.2))
