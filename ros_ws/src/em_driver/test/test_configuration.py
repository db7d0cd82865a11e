"""Tests of the scenario-section → drive assembly mapping and the forwarded-command grammar."""

from __future__ import annotations

from typing import Any

import numpy as np
import pytest
from acds_common.scenario import SCHEMA
from em_driver.bridge_switch import EmDriverError
from em_driver.configuration import DriverCommand, axis_configs, build_assembly, parse_command


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
    assert parse_command('eea_select X b') == DriverCommand('select', 0, 'B')
    assert parse_command('eea_failure z A open_winding') == DriverCommand('failure', 2, 'A', 'open_winding')
    assert parse_command('EEA_FAILURE y B none') == DriverCommand('failure', 1, 'B', None)


@pytest.mark.parametrize('text', ['', 'eea_select', 'eea_select w A', 'eea_select x C', 'eea_select x A B',
                                  'eea_failure x A melted', 'magnetometer_select B'])
def test_bad_commands_are_refused_with_a_reason(text: str) -> None:
    with pytest.raises(EmDriverError, match='usage|unknown'):
        parse_command(text)


def test_commands_apply_to_the_assembly() -> None:
    assembly = build_assembly(section())
    assert parse_command('eea_select y B').apply(assembly) == 'eea_select: axis y unit B active'
    assert assembly.active_units == ('A', 'B', 'A')
    parse_command('eea_failure x A dead_driver').apply(assembly)
    assert assembly.unit_fault(0, 'A') == 'dead_driver'
    parse_command('eea_failure x A none').apply(assembly)
    assert assembly.unit_fault(0, 'A') is None
