"""magnetometer_sim node: the triaxial fluxgate's volts, bias volts and the field they mean (spec §5).

Step k: B_true(t_k) from rigid_body (lag 0), the electromagnets' achieved step-average
dipole of step k−1 from em_driver (lag 1: the declared feedback edge — never the
command), and the ``mode`` array of step k−1 from ascs_mode_manager (lag 1) whose
``command/magnetometer_sim`` entries (e.g. ``magnetometer_select B``) are applied before
sampling. The scenario fault (``magnetometer.fault``) is injected at the first step with
t_k ≥ fault_time. Publishes per-axis volts, bias volts, the field a naive reader makes
of the volts (``sensor_msgs/MagneticField``, T, covariance from resolution/accuracy/noise)
and telemetry on ``diagnostics`` every ``telemetry_every`` steps and at every event.
A non-finite input is rejected with an ERROR diagnostic and the last valid one is held.
"""

from __future__ import annotations

from typing import Any

import numpy as np
from acds_common import topics
from acds_common.lockstep import ConfigError, Input, LockstepNode, run_node
from acds_common.messages import diagnostic, field, magnetic_field, mode_status, vec, vector3_stamped
from diagnostic_msgs.msg import DiagnosticArray, DiagnosticStatus
from geometry_msgs.msg import Vector3Stamped
from sensor_msgs.msg import MagneticField

from magnetometer_sim.configuration import build_magnetometer, parse_command
from magnetometer_sim.fluxgate import MagnetometerError

NODE = 'magnetometer_sim'
#: Telemetered bias voltage further than this from 2.5 V raises a WARN (a shift reads as field).
BIAS_WARN_V = 0.02


class MagnetometerNode(LockstepNode):
    """Two fluxgate assemblies (active/standby) seeing B_true + residual + Δ·M."""

    def __init__(self) -> None:
        super().__init__(NODE)
        self.cfg = self.section_params('magnetometer')
        try:
            self.mag = build_magnetometer(self.cfg, self.seed)
        except MagnetometerError as exc:
            raise ConfigError(f'{NODE}: {exc}') from None
        self._fault_pending = self.cfg['fault'] != 'none'
        self._b_true = np.zeros(3)
        self._dipole = np.zeros(3)
        self.add_output('volts', Vector3Stamped, topics.MAG_VOLTS)
        self.add_output('bias_volts', Vector3Stamped, topics.MAG_BIAS_VOLTS)
        self.add_output('field', MagneticField, topics.MAG_FIELD)
        self.add_output('diagnostics', DiagnosticArray, topics.DIAGNOSTICS)
        self.add_stage('sample', [
            Input('b_true', topics.TRUTH_B_BODY, MagneticField, 'rigid_body'),
            Input('dipole', topics.DIPOLE_AVG, Vector3Stamped, 'em_driver', lag=1),
            Input('mode', topics.MODE, DiagnosticArray, 'ascs_mode_manager', lag=1),
        ], self.sample)

    def sample(self, k: int, t_s: float, inp: dict[str, Any]) -> None:
        """Apply commands and faults due at step k, sample both units, publish the active one."""
        events: list[str] = []
        errors: list[str] = []
        for text in mode_status(inp['mode'], NODE)[1]:
            try:
                events.append(parse_command(text).apply(self.mag))
            except MagnetometerError as exc:
                errors.append(f'rejected command {text!r}: {exc}')
        if self._fault_pending and t_s >= self.cfg['fault_time']:
            self._fault_pending = False
            axis = None if self.cfg['fault_axis'] < 0 else self.cfg['fault_axis']
            value = self.cfg['fault_value_v'] if self.cfg['fault'] == 'bias_shift' else None
            self.mag.inject_fault(self.cfg['fault_unit'], self.cfg['fault'], axis, value)
            events.append(f'scenario fault at t={t_s:g} s: unit {self.cfg["fault_unit"]} {self.cfg["fault"]}'
                          + (f' {value:+g} V' if value is not None else '')
                          + (' on all axes' if axis is None else f' on axis {"xyz"[axis]}'))
        b_true = field(inp['b_true'])
        if np.all(np.isfinite(b_true)):
            self._b_true = b_true
        else:
            errors.append(f'rejected non-finite B_true {b_true.tolist()}; holding the last valid field')
        dipole = vec(inp['dipole'])
        if np.all(np.isfinite(dipole)):
            self._dipole = dipole
        else:
            errors.append(f'rejected non-finite achieved dipole {dipole.tolist()}; holding the last valid dipole')
        reading = self.mag.read(self._b_true, self._dipole)
        self.publish('volts', vector3_stamped(reading.volts), k)
        self.publish('bias_volts', vector3_stamped(reading.bias_volts), k)
        self.publish('field', magnetic_field(reading.field_t, reading.covariance_t2.ravel()), k)
        if events or errors or k % self.cfg['telemetry_every'] == 0:
            self.publish('diagnostics', self.telemetry(reading, events, errors), k)
        for line in errors:
            self.get_logger().error(f't={t_s:g} s: {line}')
        for line in events:
            self.get_logger().info(f't={t_s:g} s: {line}')

    def telemetry(self, reading: Any, events: list[str], errors: list[str]) -> DiagnosticArray:
        """Table 4-11 magnetometer telemetry: bias voltage, per-axis volts, active unit; events."""
        bias_off = float(np.max(np.abs(reading.bias_volts - 2.5)))
        level, message = DiagnosticStatus.OK, 'ok'
        if bias_off > BIAS_WARN_V:
            level, message = DiagnosticStatus.WARN, f'bias voltage off nominal 2.5 V by {bias_off:.3f} V'
        if errors:
            level, message = DiagnosticStatus.ERROR, errors[0]
        values: dict[str, object] = {'active_unit': reading.active_unit}
        values.update({f'bias_volts_{a}': f'{v:.4f}' for a, v in zip('xyz', reading.bias_volts, strict=True)})
        values.update({f'volts_{a}': f'{v:.4f}' for a, v in zip('xyz', reading.volts, strict=True)})
        values.update({f'event_{i}': e for i, e in enumerate(events)})
        values.update({f'error_{i}': e for i, e in enumerate(errors)})
        return diagnostic(NODE, values, message, level)


def main(args: list[str] | None = None) -> int:
    """Console-script entry point ``magnetometer_sim``."""
    return run_node(NODE, MagnetometerNode, args)
