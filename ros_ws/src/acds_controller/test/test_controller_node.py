"""Tests of the controller node's pure helpers: mode status parsing, forwarded commands, build from a scenario."""

from __future__ import annotations

import numpy as np
import pytest
from acds_common.messages import diagnostic, mode_status
from acds_common.scenario import load_scenario
from acds_controller.configuration import build_dpa, coupling_matrix
from acds_controller.controller_node import apply_command
from acds_controller.magnetic_laws import ControllerError
from diagnostic_msgs.msg import KeyValue


def test_mode_status_reads_mode_and_forwarded_commands():
    arr = diagnostic('ascs_mode_manager', {'mode': 'mode_1b', 'cause': '', 'captured': 'false'}, 'mode_1b')
    arr.status[0].values.extend([KeyValue(key='command/acds_controller', value='gain max_moment 1500'),
                                 KeyValue(key='command/em_driver', value='eea_select x B'),
                                 KeyValue(key='command/acds_controller', value='law unloading lead')])
    assert mode_status(arr, 'acds_controller') == ('mode_1b', ['gain max_moment 1500', 'law unloading lead'])
    assert mode_status(None, 'acds_controller') == (None, [])
    assert mode_status(diagnostic('someone_else', {'mode': 'mode_1a'}), 'acds_controller') == (None, [])


def test_forwarded_commands_change_the_dpa_and_bad_ones_raise():
    sc = load_scenario('heao_b_acquisition').values
    _ta, dpa = build_dpa(sc['spacecraft'], sc['controller'], sc['magnetometer'])
    assert apply_command(dpa, 'gain max_moment 1500') == 'gain max_moment set to 1500'
    assert dpa.config.max_moment_am2 == 1500.0
    apply_command(dpa, 'law unloading lead')
    assert dpa.config.unloading_law == 'lead'
    for bad in ('gain max_moment 1e9', 'gain nonsense 1', 'law unloading magic', 'gain max_moment x', 'reboot'):
        with pytest.raises(ControllerError):
            apply_command(dpa, bad)
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
    delta = coupling_matrix(point['magnetometer'])
    np.testing.assert_allclose(delta, np.eye(3) * 8.75e-10)
    assert not np.any(coupling_matrix(base['magnetometer']))
