"""Tests of the SSS part's pure helpers: the published mode names and dipole commands."""

from __future__ import annotations

import math

import numpy as np
import pytest
from acds_common.units import GAUSS_T, rpm_to_rad_s
from ascs_mode_manager.ground_commands import submit
from ascs_mode_manager.spin_mechanizations import MECHANIZATIONS
from ascs_mode_manager.sss_ascs import SssAscs, SssAscsConfig
from ascs_mode_manager.sss_part import dipole_command, mode_name


def _b(amplitude_g: float, t: float) -> np.ndarray:
    theta = 0.3 - rpm_to_rad_s(4.0) * t
    return amplitude_g * GAUSS_T * np.array([math.cos(theta), math.sin(theta), 0.0])


def test_mode_names_follow_enable_pass_and_direct_attitude() -> None:
    ascs = SssAscs()
    out = ascs.step(0.0, 0.05, _b(0.2, 0.0))
    assert mode_name(ascs, out) == 'sss_disabled'
    assert submit(ascs, 'sss enable', 0.05).accepted
    out = ascs.step(0.05, 0.05, _b(0.05, 0.05))
    assert mode_name(ascs, out) == 'sss_spin_idle'
    names = [mode_name(ascs, ascs.step(t, 0.05, _b(0.2, t))) for t in np.arange(0.1, 15.0, 0.05)]
    first = names.index('sss_spin_torquing')  # idle until the comparator first fires, then held on
    assert set(names[:first]) == {'sss_spin_idle'} and set(names[first:]) == {'sss_spin_torquing'}
    ascs2 = SssAscs()
    assert submit(ascs2, 'sss enable', 0.0).accepted and submit(ascs2, 'sss mode attitude', 0.0).accepted
    assert mode_name(ascs2, ascs2.step(0.0, 0.05, _b(0.01, 0.0))) == 'sss_attitude_idle'
    names = [mode_name(ascs2, ascs2.step(t, 0.05, _b(0.2, t))) for t in np.arange(0.05, 15.0, 0.05)]
    assert set(names[names.index('sss_attitude_torquing'):]) == {'sss_attitude_torquing'}
    ascs3 = SssAscs()
    assert submit(ascs3, 'sss direct_attitude on', 0.0).accepted
    out = ascs3.step(0.0, 0.05, _b(0.0, 0.0))
    assert mode_name(ascs3, out) == 'sss_direct_attitude' and out.attitude_coil == 1


@pytest.mark.parametrize('key', list(MECHANIZATIONS))
@pytest.mark.parametrize('direction', ['spin_up', 'despin'])
def test_dipole_command_keeps_the_spin_torque_sign_for_every_mechanization(key: str, direction: str) -> None:
    mech = MECHANIZATIONS[key]
    ascs = SssAscs(SssAscsConfig(spin_coil=mech.coil))
    for text in ('sss enable', 'sss mode spin', f'sss {direction}'):
        assert submit(ascs, text, 0.0).accepted
    sign = 1.0 if direction == 'spin_up' else -1.0
    torques = []
    for t in np.arange(0.0, 30.0, 0.05):
        b = _b(0.25, t)
        dipole = dipole_command(mech, ascs, ascs.step(t, 0.05, b), b)
        assert dipole[2] == 0.0
        if mech.channels == 1:
            assert dipole[1] == 0.0
        torques.append(np.cross(dipole, b)[2])
    torques = np.array(torques)
    assert np.all(sign * torques >= 0.0) and sign * torques.mean() > 0.0
    assert np.max(np.abs(dipole_command(mech, ascs, ascs.step(30.0, 0.05, b), b))) <= mech.peak_moment_am2 + 1e-12


def test_dipole_command_is_the_core_output_outside_a_spin_pass() -> None:
    mech = MECHANIZATIONS['two_channel_constant']
    ascs = SssAscs()
    assert submit(ascs, 'sss direct_attitude on', 0.0).accepted
    b = _b(0.25, 0.0)
    out = ascs.step(0.0, 0.05, b)
    assert np.array_equal(dipole_command(mech, ascs, out, b), out.dipole_body_am2)
    assert out.dipole_body_am2[2] > 9.0
