"""The scenario's ``cold_gas`` section (SI values) → the subsystem core (pure, no rclpy; seed 002 §5).

The stepper and the launcher's pre-flight build the same core here, so a refusal (an arrangement with no
torque about an axis, a tank loaded below the regulator's set point, …) names the key before any process
starts.
"""

from __future__ import annotations

import math
from typing import Any

from acds_common.thrusters import arrangement_from_section
from acds_common.validation import scenario_key

from cold_gas.rcs import ColdGasError, ColdGasRcs, Fault, RcsConfig


def rcs_config(c: dict[str, Any]) -> RcsConfig:
    """The hardware of a ``cold_gas`` section; raises :class:`ColdGasError` (or the arrangement's error) naming the
    key."""
    arr = arrangement_from_section(c)
    with scenario_key('cold_gas', ColdGasError):
        return RcsConfig(
            arrangement=arr, thrust_n=c['thrust'], isp_s=c['isp'], valve_open_delay_s=c['valve_open_delay'],
            valve_close_delay_s=c['valve_close_delay'], min_on_time_s=c['min_on_time'],
            max_open_valves=c['max_open_valves'],
            tank_volume_m3=c['tank_count'] * math.pi / 6.0 * c['tank_diameter'] ** 3,
            load_mass_kg=c['load_mass'], temperature_k=c['gas_temperature'],
            regulator_set_pa=c['regulator_set_pressure'], switch_trip_pa=c['pressure_switch_pressure'],
            relief_crack_pa=c['relief_pressure'], manifold_volume_m3=c['manifold_volume'],
            regulator_seat_area_m2=c['regulator_seat_area'], isolation_close_delay_s=c['isolation_close_delay'])


def build_rcs(c: dict[str, Any]) -> ColdGasRcs:
    """The subsystem in its t0 state (valves, bank power, fault) from a ``cold_gas`` section."""
    cfg = rcs_config(c)
    with scenario_key('cold_gas.fault', ColdGasError):
        fault = Fault(c['fault'], c['fault_index'] - 1, c['fault_time'])
    return ColdGasRcs(cfg, fault, [c['isolation_valves_open']] * 2, c['bank_power'])
