"""The cold-gas acquisition law (acds_controller.cold_gas_law; seed 002 §3.1)."""

from __future__ import annotations

import math

import pytest
from acds_common.units import rad
from acds_controller.cold_gas_law import GasLawConfig, gas_law
from acds_controller.magnetic_laws import ControllerError

CFG = GasLawConfig(inertia_diag_kg_m2=(2061.0, 10806.0, 10738.0), torque_nm=(2.67, 2.67, 5.34, 5.34, 5.34, 5.34),
                   rate_deadband_rad_s=rad(0.02), position_gain_per_s=0.02, slew_rate_rad_s=rad(0.5),
                   min_on_time_s=0.02, valve_open_delay_s=0.005, valve_close_delay_s=0.003)
SUN_Z = (0.0, 0.0, 1.0)


def test_rate_damping_fires_against_the_rate_sized_to_null_it():
    out = gas_law(CFG, 'gas_rate_damping', (rad(-0.03), rad(0.01), rad(0.05)), SUN_Z, 0.5)
    tx = 2061.0 * rad(0.03) / 2.67 + 0.005 - 0.003  # thrust time + the valve delays
    assert out.on_time_xyz[0] == pytest.approx(tx)  # +x torque against the −x rate
    assert out.on_time_xyz[1] == 0.0  # inside the deadband
    assert out.on_time_xyz[2] == -0.497  # −z, longer than a frame: cut to Δt − t_close


def test_tiny_errors_get_the_minimum_pulse():
    fine = GasLawConfig(**{**CFG.__dict__, 'rate_deadband_rad_s': 0.0})
    out = gas_law(fine, 'gas_rate_damping', (rad(0.0001), 0.0, 0.0), SUN_Z, 0.5)
    assert out.on_time_xyz == (-0.02, 0.0, 0.0)


def test_sun_acquisition_slews_at_the_limited_rate_then_follows_the_switching_line():
    sun = (1.0, 0.0, 0.0)  # sun along +x: 90° off z, a pitch error (θy = −π/2)
    out = gas_law(CFG, 'gas_sun_acquisition', (0.0, 0.0, 0.0), sun, 0.5)
    assert out.sun_error_xyz[1] == pytest.approx(-math.pi / 2)
    assert out.rate_reference_xyz == pytest.approx((0.0, rad(0.5), 0.0))  # saturated
    assert out.on_time_xyz[1] > 0.0 and out.on_time_xyz[0] == 0.0 and out.on_time_xyz[2] == 0.0
    small = (math.sin(rad(2.0)), 0.0, math.cos(rad(2.0)))
    out = gas_law(CFG, 'gas_sun_acquisition', (0.0, rad(0.0398), 0.0), small, 0.5)
    assert out.rate_reference_xyz[1] == pytest.approx(0.02 * rad(2.0))  # ω_ref = −K·θ on the switching line
    assert out.on_time_xyz == (0.0, 0.0, 0.0)  # within the deadband of it


def test_sun_absent_holds_the_rate():
    out = gas_law(CFG, 'gas_sun_acquisition', (0.0, 0.0, 0.0), (0.0, 0.0, 0.0), 0.5)
    assert out.on_time_xyz == (0.0, 0.0, 0.0) and out.rate_reference_xyz == (0.0, 0.0, 0.0)


def test_not_a_gas_mode_and_bad_torques_are_refused():
    with pytest.raises(ControllerError, match="'mode_1b' is not a gas mode"):
        gas_law(CFG, 'mode_1b', (0.0, 0.0, 0.0), SUN_Z, 0.5)
    with pytest.raises(ControllerError, match='six positive thruster torques'):
        GasLawConfig((1.0, 1.0, 1.0), (1.0,) * 5, 0.0, 0.0, 0.0, 0.02, 0.005, 0.003)
