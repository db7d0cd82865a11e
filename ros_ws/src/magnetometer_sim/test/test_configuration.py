"""Tests of the scenario-section → magnetometer mapping and the forwarded-command grammar."""

from __future__ import annotations

from typing import Any

import numpy as np
import pytest
from acds_common.commands import MagnetometerSelect
from acds_common.coupling import coupling_from_section
from acds_common.scenario import SCHEMA
from magnetometer_sim.configuration import (
    MagnetometerFault,
    apply_command,
    build_magnetometer,
    parse_command,
)
from magnetometer_sim.fluxgate import MagnetometerError

G = 1e-4  # T per gauss


def section(**overrides: Any) -> dict[str, Any]:
    """The schema defaults of the magnetometer section (SI), with overrides."""
    out = {name: f.default for name, f in SCHEMA['magnetometer'].items()}
    out.update(overrides)
    return out


def test_presets_give_the_study_coupling() -> None:
    assert np.array_equal(coupling_from_section(section()), np.zeros((3, 3)))
    np.testing.assert_allclose(coupling_from_section(section(coupling_preset='cruise')),
                               np.eye(3) * 8.75e-6 * G, rtol=1e-12)
    signs = [1, -1, 1, 1, 1, -1, -1, 1, 1]
    acq = coupling_from_section(section(coupling_preset='acquisition', coupling_signs=[float(s) for s in signs]))
    gain = 0.05 * 0.5 * G / 2000.0
    assert np.all(np.diag(acq) == 0.0)
    assert acq[0, 1] == pytest.approx(-gain) and acq[1, 2] == pytest.approx(-gain)
    assert acq[2, 0] == pytest.approx(-gain) and acq[1, 0] == pytest.approx(gain)


def test_custom_coupling_is_row_major_sensor_by_magnet() -> None:
    values = [0.0, 2e-9, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0]  # sensor x sees magnet y
    mag = build_magnetometer(section(coupling_preset='custom', coupling=values), seed=1)
    sensed = mag.read([0.0, 0.0, 0.0], [0.0, 1000.0, 0.0]).b_sensed_t
    np.testing.assert_allclose(sensed, [2e-6, 0.0, 0.0])


def test_build_applies_unit_residual_and_noise_seed() -> None:
    mag = build_magnetometer(section(active_unit='B', residual_field=[0.005 * G, 0.0, -0.005 * G]), seed=3)
    reading = mag.read([0.0, 0.0, 0.0])
    assert reading.active_unit == 'B'
    np.testing.assert_allclose(reading.b_sensed_t, [0.005 * G, 0.0, -0.005 * G])
    noisy = [build_magnetometer(section(noise_std=0.01 * G), seed=7).read([0.1 * G, 0.0, 0.0]).volts
             for _ in range(2)]
    assert np.array_equal(noisy[0], noisy[1]), 'same seed, same noise'


def test_parse_select_and_faults() -> None:
    for text in ('magnetometer_fault a bias_shift Y 0.25', 'magnetometer_fault B stuck_axis', 'magnetometer_select b'):
        assert parse_command(parse_command(text).text) == parse_command(text)  # the text encodes the command
    assert parse_command('magnetometer_select b') == MagnetometerSelect('B')
    assert parse_command('MAGNETOMETER_FAULT A bias_shift y 0.25') == MagnetometerFault('A', 'bias_shift', 1, 0.25)
    assert parse_command('magnetometer_fault B stuck_axis') == MagnetometerFault('B', 'stuck_axis')
    assert parse_command('magnetometer_fault A clear') == MagnetometerFault('A', 'clear')


@pytest.mark.parametrize('text', ['', 'magnetometer_select', 'magnetometer_select C', 'eea_select x B',
                                  'magnetometer_fault A bias_shift x', 'magnetometer_fault A bias_shift x nan',
                                  'magnetometer_fault A melted', 'magnetometer_fault A stuck_axis w',
                                  'magnetometer_fault A dead_unit all 1'])
def test_bad_commands_are_refused_with_a_reason(text: str) -> None:
    with pytest.raises(MagnetometerError, match='usage|unknown|number|finite|empty'):
        parse_command(text)


def test_commands_apply_to_the_model() -> None:
    mag = build_magnetometer(section(), seed=1)
    assert 'unit B active' in apply_command(parse_command('magnetometer_select B'), mag)
    assert mag.active_unit == 'B'
    event = apply_command(parse_command('magnetometer_fault B bias_shift all 0.1'), mag)
    assert event == 'unit B: bias_shift +0.1 V on all axes'
    np.testing.assert_allclose(mag.read([0.0, 0.0, 0.0]).bias_volts, 2.6)
    apply_command(parse_command('magnetometer_select A'), mag)
    np.testing.assert_allclose(mag.read([0.0, 0.0, 0.0]).bias_volts, 2.5)
    apply_command(parse_command('magnetometer_fault B clear'), mag)
    apply_command(parse_command('magnetometer_select B'), mag)
    np.testing.assert_allclose(mag.read([0.0, 0.0, 0.0]).bias_volts, 2.5)
