"""acds_controller stepper: transfer assembly + DPA (spec §7), or the AAP Workshop computer (seed 000).

Stage ``dpa`` of step k takes the magnetometer volts and bias volts (k), gyro rates (k), sun
sensor (k), the ``mode`` of the mode manager (k, with any forwarded ``command/acds_controller``
law/gain commands, applied before the step is computed), the attitude reference
``truth/odometry`` (k; the ideal attitude of the cruise modes), the wheel momentum and rate of
step k−1 (lag 1, so h(t_k) = h_{k−1} + ḣ_{k−1}·Δt exactly) and the coil current of step k−1
(lag 1, TA telemetry only).

It returns ``moment`` (A·m²) and ``volts`` (wheel drive, V) every step, and DPA + TA telemetry
on ``diagnostics`` every ``controller.telemetry_every`` steps and at once when something is
wrong (a refused command, a non-finite input).

Absent sources: no magnetometer → zero sensed field (the magnetic laws command nothing); no
mode manager → ``mode_1a`` (magnetics-only rate reduction); no wheels → zero wheel momentum.
A non-finite input is rejected with a diagnostic and the step commands zero moment and zero
wheel volts.

With ``wheels.kind`` cmg the node is the AAP Workshop's computer
(:mod:`acds_controller.workshop`): the same stage and inputs (the wheel inputs are the CMG
momentum and rate), modes ``cmg_dump`` / ``cmg_hold`` / ``standby`` (``cmg_dump`` when no mode
manager is in the graph), and every step ``moment`` (A·m², the dump law's command to the coils),
``cmg_torque`` (N·m, the momentum rate the attitude hold asks of the CMGs) and
``sampled_momentum`` (N·m·s, the H_s the dump law used); no wheel volts. Workshop telemetry
(H_s, its initialisation offset, attitude error, the predicted per-orbit loop gains) on
``diagnostics`` every ``controller.telemetry_every`` steps. A non-finite input commands zero
moment and zero CMG torque for the step (H_s held), with a diagnostic.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import numpy as np
from acds_common.messages import WARN, diagnostic, mode_status, vec, vector3, xyz
from acds_common.stepper import Stepper
from acds_common.validation import all_finite

from acds_controller.configuration import build_dpa, build_workshop
from acds_controller.dpa import MODES, Dpa
from acds_controller.magnetic_laws import ControllerError
from acds_controller.workshop import WORKSHOP_MODES

#: Excess-coil-current alarm: |I| above this multiple of the current of the maximum moment.
EXCESS_CURRENT_FACTOR = 1.1
_ZERO = (0.0, 0.0, 0.0)
_MID_SCALE_V = (2.5, 2.5, 2.5)


def apply_command(dpa: Dpa, text: str) -> str:
    """Apply a forwarded 'law <slot> <name>' or 'gain <name> <value>'; return what was done.

    Raises :class:`ControllerError` for anything else (the stepper turns it into a diagnostic).
    """
    words = text.split()
    if len(words) == 3 and words[0].lower() == 'law':
        dpa.set_law(words[1].lower(), words[2].lower())
        return f'law {words[1]} set to {words[2]}'
    if len(words) == 3 and words[0].lower() == 'gain':
        try:
            value = float(words[2])
        except ValueError as exc:
            raise ControllerError(f'gain value {words[2]!r} is not a number') from exc
        dpa.set_gain(words[1].lower(), value)
        return f'gain {words[1]} set to {value:g}'
    raise ControllerError(f'command {text!r} is not "law <slot> <name>" or "gain <name> <value>"')


def _check_finite(inputs: tuple[tuple[str, Sequence[float]], ...]) -> None:
    """Raise :class:`ControllerError` naming the first input that is not finite."""
    for name, v in inputs:
        if not all_finite(v):
            raise ControllerError(f'{name} input is not finite: {[float(x) for x in v]}')


class ControllerStep(Stepper):
    """Transfer assembly and digital processor of the HEAO ACDS."""

    node = 'acds_controller'

    def __init__(self, params: dict[str, Any], log: Any = None) -> None:
        super().__init__(params, log)
        c = self.section('controller')
        self.telemetry_period = c['telemetry_every']
        self.workshop = None
        if self.section('wheels')['kind'] == 'cmg':
            self.ta, self.workshop = build_workshop(self.section('spacecraft'), c, self.section('orbit'),
                                                    self.section('earth'))
            self._h_s = _ZERO
            return
        self.ta, self.dpa = build_dpa(self.section('spacecraft'), c, self.section('magnetometer'))
        self.excess_current_a = EXCESS_CURRENT_FACTOR * c['max_moment_am2'] / self.ta.moment_per_amp_am2_per_a

    def control(self, k: int, t_s: float, inp: dict[str, Any]) -> dict[str, Any]:
        """Stage ``control``: one DPA (or Workshop computer) control period (commands applied first, inputs checked)."""
        if self.workshop is not None:
            return self._workshop_control(k, t_s, inp)
        warnings: list[tuple[str, dict[str, str]]] = []
        mode, commands = mode_status(inp['mode'], self.node)
        self._apply_commands(k, commands, warnings)
        mode = _resolve_mode(mode, 'mode_1a', MODES, warnings, f'unknown mode {mode!r} from the mode manager')
        try:
            result = self._dpa_step(k, mode, inp)
        except ControllerError as exc:
            warnings.append((f'input rejected, zero commands this step: {exc}', {}))
            result = {'moment': _ZERO, 'volts': _ZERO}
        return self._warned(k, result, warnings)

    def _apply_commands(self, k: int, commands: list[str], warnings: list[tuple[str, dict[str, str]]]) -> None:
        """Apply the forwarded law/gain commands to the DPA; a refusal becomes a warning."""
        for text in commands:
            try:
                self.log('info', f'step {k}: {apply_command(self.dpa, text)}')
            except ControllerError as exc:
                warnings.append((f'command refused: {text!r}: {exc}', {'command': text, 'reason': str(exc)}))

    def _warned(self, k: int, result: dict[str, Any], warnings: list[tuple[str, dict[str, str]]]) -> dict[str, Any]:
        """The step's outputs with its warnings logged and put first on ``diagnostics``."""
        if warnings:
            for message, _values in warnings:
                self.log('warn', f'step {k}: {message}')
            result['diagnostics'] = tuple(s for message, values in warnings
                                          for s in diagnostic(self.node, values, message, WARN)) \
                + result.get('diagnostics', ())
        return result

    def _workshop_control(self, k: int, t_s: float, inp: dict[str, Any]) -> dict[str, Any]:
        """One control period of the Workshop computer (seed 000): H_s, the dump law, the CMG hold."""
        assert self.workshop is not None
        warnings: list[tuple[str, dict[str, str]]] = []
        mode, commands = mode_status(inp['mode'], self.node)
        for text in commands:
            warnings.append((f'command refused: {text!r}: the Workshop computer takes no forwarded commands',
                             {'command': text}))
        mode = _resolve_mode(mode, 'cmg_dump', WORKSHOP_MODES, warnings,
                             f'{mode!r} is not a Workshop mode ({", ".join(WORKSHOP_MODES)})')
        try:
            volts, bias = vec(inp['mag_volts'], _MID_SCALE_V), vec(inp['mag_bias'], _MID_SCALE_V)
            omega, h = vec(None if inp['gyro'] is None else inp['gyro'][0]), np.array(self._store_momentum(inp))
            _check_finite((('magnetometer volts', volts), ('bias volts', bias), ('gyro', omega),
                           ('CMG momentum', h)))
            if inp['odometry'] is None:
                raise ControllerError('the CMG attitude hold needs the attitude reference truth/odometry')
            out = self.workshop.step(t_s, mode, self.ta.sense(volts, bias), omega, np.array(inp['odometry'].orientation),
                                     h)
            self._h_s = vector3(out.h_s_nms)
            result: dict[str, Any] = {'moment': vector3(out.moment_am2), 'cmg_torque': vector3(out.cmg_rate_nm),
                                      'sampled_momentum': self._h_s}
            if k % self.telemetry_period == 0:
                result['diagnostics'] = diagnostic(self.node, out.telemetry)
        except ControllerError as exc:
            warnings.append((f'input rejected, zero commands this step: {exc}', {}))
            result = {'moment': _ZERO, 'cmg_torque': _ZERO, 'sampled_momentum': self._h_s}
        return self._warned(k, result, warnings)

    def _store_momentum(self, inp: dict[str, Any]) -> tuple[float, float, float]:
        """h(t_k) of the wheels or CMGs from their step k−1 outputs (lag 1): h_{k−1} + ḣ_{k−1}·Δt, exactly."""
        (hx, hy, hz), (dx, dy, dz), dt = xyz(inp['wheel_h']), xyz(inp['wheel_hdot']), self.control_period_s
        return hx + dx * dt, hy + dy * dt, hz + dz * dt

    def _dpa_step(self, k: int, mode: str, inp: dict[str, Any]) -> dict[str, Any]:
        volts = xyz(inp['mag_volts'], _MID_SCALE_V)
        bias = xyz(inp['mag_bias'], _MID_SCALE_V)
        omega = _ZERO if inp['gyro'] is None else inp['gyro'][0]
        sun = xyz(inp['sun'])
        dt = self.control_period_s
        h = self._store_momentum(inp)
        q = None if inp['odometry'] is None else inp['odometry'].orientation
        coil = xyz(inp['coil_current'])
        if not all_finite((*volts, *bias, *omega, *sun, *h, *coil)):
            _check_finite((('magnetometer volts', volts), ('bias volts', bias), ('gyro', omega), ('sun sensor', sun),
                           ('wheel momentum', h), ('coil current', coil)))
        b = self.ta.sense_xyz(volts, bias)
        out = self.dpa.step(mode, b, omega, sun, h, q, dt)
        result: dict[str, Any] = {'moment': out.moment_xyz, 'volts': out.volts_xyz}
        if k % self.telemetry_period == 0:
            alarms = [abs(i) > self.excess_current_a for i in coil]
            telemetry = {**out.telemetry, **self.ta.telemetry(b, out.moment_xyz, bias, coil, alarms)}
            result['diagnostics'] = diagnostic(self.node, telemetry)
        return result


def _resolve_mode(mode: str | None, default: str, known: Any, warnings: list[tuple[str, dict[str, str]]],
                  unknown: str) -> str:
    """The mode to run: ``default`` before the mode manager speaks, standby (with a warning) for one not ``known``."""
    if mode is None:
        return default
    if mode not in known:
        warnings.append((f'{unknown}: standby', {'mode': mode}))
        return 'standby'
    return mode
