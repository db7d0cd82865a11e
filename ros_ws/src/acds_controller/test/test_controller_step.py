"""Tests of the controller stepper: mode status parsing, forwarded commands, build from a scenario, one stage."""

from __future__ import annotations

import numpy as np
import pytest
from acds_common.cdr import Status
from acds_common.coupling import coupling_from_section
from acds_common.messages import WARN, diagnostic
from acds_common.mode_report import mode_status
from acds_common.parameters import normalize
from acds_common.scenario import load_scenario
from acds_controller.configuration import build_dpa
from acds_controller.controller_step import DpaStep, apply_command, parse_command
from acds_controller.magnetic_laws import ControllerError


def _mode(mode: str, *commands: str) -> tuple[Status, ...]:
    (status,) = diagnostic('ascs_mode_manager', {'mode': mode, 'cause': '', 'captured': 'false'}, mode)
    extra = tuple(('command/acds_controller' if not c.startswith('eea') else 'command/em_driver', c) for c in commands)
    return (status._replace(values=status.values + extra),)


def test_mode_status_reads_mode_and_forwarded_commands():
    value = _mode('mode_1b', 'gain max_moment 1500', 'eea_select x B', 'law unloading lead')
    assert mode_status(value, 'acds_controller') == ('mode_1b', ['gain max_moment 1500', 'law unloading lead'])
    assert mode_status(None, 'acds_controller') == (None, [])
    assert mode_status(diagnostic('someone_else', {'mode': 'mode_1a'}), 'acds_controller') == (None, [])


def test_forwarded_commands_change_the_dpa_and_bad_ones_raise():
    sc = load_scenario('heao_b_acquisition').values
    _ta, dpa = build_dpa(sc['spacecraft'], sc['controller'], sc['magnetometer'])
    assert apply_command(dpa, parse_command('gain max_moment 1500')) == 'gain max_moment set to 1500'
    assert dpa.config.max_moment_am2 == 1500.0
    apply_command(dpa, parse_command('law unloading lead'))
    assert dpa.config.unloading_law == 'lead'
    for bad in ('gain max_moment 1e9', 'gain nonsense 1', 'law unloading magic', 'gain max_moment x', 'reboot'):
        with pytest.raises(ControllerError):
            apply_command(dpa, parse_command(bad))
    assert dpa.config.max_moment_am2 == 1500.0


def test_build_from_scenarios_uses_their_sections():
    sc = load_scenario('heao_b_case3').values
    base = load_scenario('heao_b_acquisition').values
    _, dpa3 = build_dpa(sc['spacecraft'], sc['controller'], sc['magnetometer'])
    _, dpa1 = build_dpa(base['spacecraft'], base['controller'], base['magnetometer'])
    np.testing.assert_allclose(dpa3.config.inertia_kg_m2, dpa1.config.inertia_kg_m2 * 2 / 3)
    assert build_dpa(*(load_scenario('heao_b_case7').values[s] for s in ('spacecraft', 'controller',
                                                                         'magnetometer')))[1].config.max_moment_am2 == 1000
    point = load_scenario('heao_b_point_unloading').values
    np.testing.assert_allclose(coupling_from_section(point['magnetometer']), np.eye(3) * 8.75e-10)
    assert not np.any(coupling_from_section(base['magnetometer']))


def test_oresat_scenario_gain_is_the_seed_formula_on_its_design_values():
    """k_ω = (4π/T_orb)(sin ξ + 1)J_min with the scenario's T_orb, ξ, J_min (seed 003: 2.054e-5 kg·m²/s);
    the orbit and body the scenario builds match those design values."""
    sc = load_scenario('oresat_detumble')
    c = sc.values['controller']
    _, dpa = build_dpa(sc.values['spacecraft'], c, sc.values['magnetometer'])
    assert f'{dpa.config.detumble_gain_kg_m2_s:.4g}' == '2.054e-05'
    assert dpa.config.acquisition_law == 'b_cross_omega' and dpa.config.max_moment_am2 == 0.1552
    assert sc.orbit_period_s() == pytest.approx(c['detumble_orbit_period'], abs=1e-3)
    assert sc.get('orbit', 'inclination') == c['magnetic_inclination']
    assert np.linalg.eigvalsh(dpa.config.inertia_kg_m2)[0] == pytest.approx(c['detumble_j_min'], rel=1e-9)


def _stepper() -> DpaStep:
    from acds_common.parameters import node_parameters

    params = node_parameters(load_scenario('heao_b_acquisition'), 10, 0.0)['acds_controller']
    return DpaStep(normalize('acds_controller', params), log=lambda _l, _t: None)


def _inputs(**over):
    base = {'mag_volts': (2.6, 2.45, 2.5), 'mag_bias': (2.5, 2.5, 2.5), 'gyro': ((1e-4, 0.0, -1e-4), (0.0,) * 9),
            'sun': (0.0, 0.0, 1.0), 'odometry': None, 'mode': _mode('mode_1a'), 'wheel_h': None, 'wheel_hdot': None,
            'coil_current': None}
    return {**base, **over}


def test_control_stage_commands_bxh_in_mode_1a_and_refuses_bad_inputs_with_a_warning():
    step = _stepper()
    out = step.control(0, 0.0, _inputs())
    assert set(out) == {'moment', 'volts', 'diagnostics'}  # step 0 is a telemetry step
    m = np.array(out['moment'])
    b = step.ta.sense(np.array([2.6, 2.45, 2.5]), np.full(3, 2.5))  # what the TA makes of the volts
    assert 0 < np.abs(m).max() < 2000 and abs(m @ b) < 1e-9 * np.linalg.norm(m) * np.linalg.norm(b)  # ⟂ B
    assert out['volts'] == (0.0, 0.0, 0.0)  # wheels off in Mode 1A
    bad = step.control(1, 0.5, _inputs(mag_volts=(float('nan'), 2.5, 2.5)))
    assert bad['moment'] == (0.0, 0.0, 0.0) and bad['diagnostics'][0].level == WARN
    refused = step.control(2, 1.0, _inputs(mode=_mode('mode_1a', 'gain nonsense 3')))
    assert 'command refused' in refused['diagnostics'][0].message
