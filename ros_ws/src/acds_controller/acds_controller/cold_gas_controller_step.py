"""acds_controller variant with the cold-gas acquisition: the study's recommended design (seed 002 §2, §3.1).

Chosen by the declaration (:mod:`acds_controller.nodes`) when the scenario flies node ``cold_gas``. In the gas modes
(:data:`~acds_common.modes.GAS_MODES`) the controller runs the gas law
(:mod:`acds_controller.cold_gas_law`) on the gyros and the sun sensor and asks the cold-gas subsystem for valve
on-times (``gas_on_time``, s per body axis, sign = torque direction); wheels and electromagnets are off (0 V,
0 A·m²). In every other mode it is the HEAO DPA as in :class:`~acds_controller.controller_step.DpaStep`
(Mode 1B and the cruise modes: wheels on, B×H unloading) and asks for no gas. Gas-law telemetry (rate
reference, sun-line error, on-times) on ``diagnostics`` every ``controller.telemetry_every`` steps in a gas mode.

The law knows its actuators as a flight program does: the thrust, valve timing and the arrangement
(:func:`acds_common.thrusters.arrangement_from_section`) of the scenario's ``cold_gas`` section give the torque of each
signed axis; the inertia diagonal comes from ``spacecraft``.
"""

from __future__ import annotations

from typing import Any

import numpy as np
from acds_common.inertia import inertia_tensor
from acds_common.messages import diagnostic, xyz
from acds_common.modes import GAS_MODES
from acds_common.thrusters import arrangement_from_section
from acds_common.units import deg
from acds_common.validation import all_finite, scenario_key

from acds_controller.cold_gas_law import GasLawConfig, gas_law
from acds_controller.controller_step import ZERO, DpaStep, warned
from acds_controller.magnetic_laws import ControllerError


def gas_law_config(sc: dict[str, Any], c: dict[str, Any], gas: dict[str, Any]) -> GasLawConfig:
    """The gas law from the spacecraft, controller and cold_gas sections (SI)."""
    arr = arrangement_from_section(gas)
    inertia = np.diag(inertia_tensor(*sc['inertia']) * sc['inertia_scale'])
    with scenario_key('controller', ControllerError):
        return GasLawConfig(
            inertia_diag_kg_m2=(float(inertia[0]), float(inertia[1]), float(inertia[2])),
            torque_nm=tuple(gas['thrust'] * arm for arm in arr.arm_m),
            rate_deadband_rad_s=c['gas_rate_deadband'], position_gain_per_s=c['gas_position_gain'],
            slew_rate_rad_s=c['gas_slew_rate'], min_on_time_s=gas['min_on_time'],
            valve_open_delay_s=gas['valve_open_delay'], valve_close_delay_s=gas['valve_close_delay'])


class ColdGasControllerStep(DpaStep):
    """Transfer assembly + DPA, and the cold-gas acquisition law in the gas modes."""

    def __init__(self, params: dict[str, Any], log: Any = None) -> None:
        super().__init__(params, log)
        self.gas = gas_law_config(self.section('spacecraft'), self.section('controller'), self.section('cold_gas'))

    def control(self, k: int, t_s: float, inp: dict[str, Any]) -> dict[str, Any]:
        """Stage ``control``: the gas law in a gas mode, else the DPA (and no gas)."""
        mode, commands = self._mode_status(inp['mode'])
        if mode not in GAS_MODES:
            return {**super().control(k, t_s, inp), 'gas_on_time': ZERO}
        warnings: list[tuple[str, dict[str, str]]] = []
        self.apply_commands(k, commands, warnings)
        omega = ZERO if inp['gyro'] is None else inp['gyro'][0]
        sun = xyz(inp['sun'])
        if not all_finite((*omega, *sun)):
            warnings.append((f'input rejected, no pulses this step: gyro {list(omega)} / sun {list(sun)} not finite', {}))
            return warned(self, k, {'moment': ZERO, 'volts': ZERO, 'gas_on_time': ZERO}, warnings)
        out = gas_law(self.gas, mode, omega, sun, self.control_period_s)
        result: dict[str, Any] = {'moment': ZERO, 'volts': ZERO, 'gas_on_time': out.on_time_xyz}
        if k % self.telemetry_period == 0:
            result['diagnostics'] = diagnostic(self.instance, {
                'mode': mode,
                'gas_rate_reference_deg_s': ' '.join(f'{deg(w):.4f}' for w in out.rate_reference_xyz),
                'gas_sun_error_deg': ' '.join(f'{deg(a):.3f}' for a in out.sun_error_xyz),
                'gas_on_time_s': ' '.join(f'{t:.4f}' for t in out.on_time_xyz)})
        return warned(self, k, result, warnings)
