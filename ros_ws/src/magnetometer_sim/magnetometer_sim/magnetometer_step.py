"""magnetometer_sim stepper: the triaxial fluxgate's volts, bias volts and the field they mean (spec §5).

Stage ``sample`` of step k takes B_true(t_k) from rigid_body (lag 0), the electromagnets'
achieved step-average dipole of step k−1 from em_driver (lag 1: the declared feedback edge —
never the command), and the ``mode`` of step k−1 from ascs_mode_manager (lag 1) whose
``command/magnetometer_sim`` entries (e.g. ``magnetometer_select B``) are applied before
sampling. The scenario fault (``magnetometer.fault``) is injected at the first step with
t_k ≥ fault_time. Returns per-axis volts, bias volts, the field a naive reader makes of the
volts (MagneticField, T, covariance from resolution/accuracy/noise) and telemetry every
``telemetry_every`` steps and at every event. A non-finite input is rejected with an ERROR
diagnostic and the last valid one is held.
"""

from __future__ import annotations

import math
from typing import Any

from acds_common import kernels
from acds_common.fused import FusedStage, Output
from acds_common.messages import ERROR, OK, WARN, diagnostic, xyz
from acds_common.mode_report import ModeStatusReader
from acds_common.stepper import Stepper
from acds_common.validation import all_finite, scenario_key

from magnetometer_sim.configuration import apply_command, build_magnetometer, parse_command
from magnetometer_sim.fluxgate import ZERO, MagnetometerError, MagnetometerReading, magnetometer_sample

#: Telemetered bias voltage further than this from 2.5 V raises a WARN (a shift reads as field).
BIAS_WARN_V = 0.02


@kernels.helper
def sample_fused(p: tuple, s: tuple, _k: int, t_s: float, b_true: Any, dipole: Any) -> tuple:
    """Stage ``sample`` as a kernel (:mod:`acds_common.fused`) for noiseless units: quiet unless the scenario fault is
    due or an input is non-finite. ``p``: (:func:`~magnetometer_sim.fluxgate.magnetometer_sample`'s parameters, the
    units' faults, the active unit, the time of the pending fault (infinite: none), the active unit's covariance);
    ``s``: (both units' last volts, the last valid field and dipole)."""
    params, faults, active, fault_time, covariance = p
    last, b_held, d_held = s
    b = b_true[0]
    quiet = math.isfinite(b[0] + b[1] + b[2] + dipole[0] + dipole[1] + dipole[2]) and t_s < fault_time
    last1, out = magnetometer_sample(params, faults, last, b, dipole, (ZERO, ZERO), active)
    volts, bias, field, _sensed = out
    return quiet, ((last1, b, dipole) if quiet else s), volts, bias, (field, covariance)


class MagnetometerStep(Stepper):
    """Two fluxgate assemblies (active/standby) seeing B_true + residual + Δ·M."""

    node = 'magnetometer_sim'

    def __init__(self, params: dict[str, Any], log: Any = None) -> None:
        super().__init__(params, log)
        self.cfg = self.section('magnetometer')
        with scenario_key('magnetometer', MagnetometerError):
            self.mag = build_magnetometer(self.cfg, self.seed)
        self._fault_pending = self.cfg['fault'] != 'none'
        self._b_true = (0.0, 0.0, 0.0)
        self._dipole = (0.0, 0.0, 0.0)
        self._mode_status = ModeStatusReader(self.node)

    def fused(self, stage: str, held: dict[str, Any]) -> FusedStage | None:
        """Stage ``sample`` as :func:`sample_fused` (:mod:`acds_common.fused`); None with telemetry wanted, noise on,
        a source absent or commands forwarded in the ``mode`` the block reads."""
        parts = self.mag.kernel_parts()
        if (stage != 'sample' or parts is None or self.telemetry_wanted or not self.present('rigid_body')
                or not self.present('em_driver') or self._mode_status(held.get('mode'))[1]):
            return None
        params, faults, active, last = parts
        fault_time = float(self.cfg['fault_time']) if self._fault_pending else math.inf
        return FusedStage(sample_fused, (params, faults, active, fault_time, self.mag.covariance9),
                          (last, self._b_true, self._dipole), ('b_true', 'dipole'),
                          (Output('volts', 3), Output('bias_volts', 3), Output('field', (3, 9))), self._restore)

    def _restore(self, s: tuple) -> None:
        last, self._b_true, self._dipole = s
        self.mag.set_kernel_state(last)

    def sample(self, k: int, t_s: float, inp: dict[str, Any]) -> dict[str, Any]:
        """Apply commands and faults due at step k, sample both units, return the active one."""
        commands = self._mode_status(inp['mode'])[1]
        events, errors = self._apply(commands, t_s) if commands or self._fault_pending else ([], [])
        b_true = (0.0, 0.0, 0.0) if inp['b_true'] is None else inp['b_true'][0]
        dipole = xyz(inp['dipole'])
        if all_finite((*b_true, *dipole)):  # the usual step: one check of both
            self._b_true, self._dipole = b_true, dipole
        else:
            if all_finite(b_true):
                self._b_true = b_true
            else:
                errors.append(f'rejected non-finite B_true {list(b_true)}; holding the last valid field')
            if all_finite(dipole):
                self._dipole = dipole
            else:
                errors.append(f'rejected non-finite achieved dipole {list(dipole)}; holding the last valid dipole')
        mag = self.mag
        volts, bias, field, b_sensed = mag.sample_xyz(self._b_true, self._dipole)  # checked finite above
        out: dict[str, Any] = {'volts': volts, 'bias_volts': bias, 'field': (field, mag.covariance9)}
        if events or errors or (self.telemetry_wanted and k % self.cfg['telemetry_every'] == 0):
            reading = MagnetometerReading(volts, bias, field, b_sensed, mag.active_unit, mag.covariance9)
            out['diagnostics'] = self.telemetry(reading, events, errors)
            for line in errors:
                self.log('error', f't={t_s:g} s: {line}')
            for line in events:
                self.log('info', f't={t_s:g} s: {line}')
        return out

    def _apply(self, commands: list[str], t_s: float) -> tuple[list[str], list[str]]:
        """(events, errors) of applying the forwarded ``commands`` and the scenario fault if it is due at t_s."""
        events: list[str] = []
        errors: list[str] = []
        for text in commands:
            try:
                events.append(apply_command(parse_command(text), self.mag))
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
        return events, errors

    def telemetry(self, reading: MagnetometerReading, events: list[str], errors: list[str]) -> Any:
        """Table 4-11 magnetometer telemetry: bias voltage, per-axis volts, active unit; events."""
        bias_off = max(abs(v - 2.5) for v in reading.bias_xyz)
        level, message = OK, 'ok'
        if bias_off > BIAS_WARN_V:
            level, message = WARN, f'bias voltage off nominal 2.5 V by {bias_off:.3f} V'
        if errors:
            level, message = ERROR, errors[0]
        values: dict[str, object] = {'active_unit': reading.active_unit}
        values.update({f'bias_volts_{a}': f'{v:.4f}' for a, v in zip('xyz', reading.bias_xyz, strict=True)})
        values.update({f'volts_{a}': f'{v:.4f}' for a, v in zip('xyz', reading.volts_xyz, strict=True)})
        values.update({f'event_{i}': e for i, e in enumerate(events)})
        values.update({f'error_{i}': e for i, e in enumerate(errors)})
        return diagnostic(self.instance, values, message, level)
