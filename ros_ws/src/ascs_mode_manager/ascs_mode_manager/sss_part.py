"""SSS part of the ascs_mode_manager stepper: perigee automatic turn-on of the SSS ASCS (spec §8; seed 001).

Plumbing only: the logic is :class:`ascs_mode_manager.sss_ascs.SssAscs`.

Input (stage ``sss``): ``magnetometer/volts`` and ``magnetometer/bias_volts`` of step k
(lag 0). Of the triaxial fluxgate only body **y** is used: it is the ASCS's single spin-plane channel
(the core's wiring: y magnetometer → spin coil along x, attitude coil along z, spin axis z). The channel
is read as the flight hardware's polarity comparator sees it: the analog output referenced to the
telemetered bias, ``B_y = (V_y − V_bias,y) / k`` with k the sensor scale (2.5 V/G, ``sss`` section), so
everything the sensor model does (clipping at the rails, the 0.004 G resolution, nonlinearity, coupling,
faults: a stuck axis stops the commutation, a dead unit never turns on) reaches the logic. The x and z
axes are passed to the core only because its interface takes the body vector; it reads y alone.
(``magnetometer/field`` would be the same number after the sensor's own naive inversion about the
nominal 2.5 V bias; the bias-referenced reading is what a comparator against the bias reference does.)

Outputs of step k:

* ``controller/moment_command``: the coils' steady-state dipoles, body A·m² — spin coil ±2.65 on x,
  attitude coil ±9.08 or 0 on z, y always 0. The em_driver's ``constant_level`` axes take only the sign
  (−1/0/+1: the full bus across the coil, the resistance limiting the current).
* ``mode`` (DiagnosticArray, preamble contract): status 'ascs_mode_manager', message = mode name, keys
  ``mode``, ``cause``, ``captured`` ('false': no capture in SSS) and SSS telemetry (``pass_mode`` —
  spin | attitude | direct_attitude | off, what the per-pass report integrates —, ``enabled``,
  ``selected_mode``, ``spin_direction``, ``signal_gauss``, ``spin_coil``, ``attitude_coil``,
  ``power_w``).
* ``events``: every automatic turn-on/turn-off, every spin-mode turn-on the one-mode-per-perigee-pass rule
  inhibits, and every commanded mode change, with its sim time:
  ``t=1234.50 turn_on sss_spin_idle->sss_spin_torquing: <why>``.
* ``ground/ack``: every ground command accepted or refused, with the reason (the host's ``answer_due``).
* ``diagnostics``: every 20 steps, and at once (WARN) when an input or a ground command is rejected.

Mode names: ``sss_disabled`` (not enabled, Direct Attitude off), ``sss_spin_idle`` /
``sss_attitude_idle`` (enabled, that mode selected, below the polarity-sensing level),
``sss_spin_torquing`` / ``sss_attitude_torquing`` (a perigee pass is on), ``sss_direct_attitude``
(attitude coil straight from the bus, by command).

Ground commands (grammar in :mod:`ascs_mode_manager.sss_ascs`, e.g. ``sss enable``, ``sss despin``,
``sss mode attitude``) arrive on ``ground/command`` and are applied at the next step the node computes;
scheduled ones (``modes.ground_commands: ["0: sss enable"]``) at the first step with t_k ≥ T_S.

Mechanization (``sss.mechanization``): the flight selection, ``one_channel_constant`` (spec §8), is the
core's own spin-coil command. The other three of seed 001 are selectable too: during a spin-mode pass the
spin-plane dipoles (x, y) are then :func:`~ascs_mode_manager.spin_mechanizations.coil_moments` of that
mechanization (x coil from the y magnetometer, y coil from the x magnetometer inverted; sine drives
proportional, constant levels saturated), while the pass itself (turn-on/turn-off, hold) is still
detected on the y channel. The scenario must match: a coil on y for the two-channel ones, and
``bridge_switch`` (proportional current) em_driver axes for the sine drives, with the seed's coil.
"""

from __future__ import annotations

from typing import Any

import numpy as np
from acds_common.cdr import Status
from acds_common.messages import MODE_STATUS, WARN, diagnostic, vec, vector3
from acds_common.mode_report import ModeReport
from acds_common.units import GAUSS_T, tesla_to_gauss
from acds_common.validation import scenario_key

from ascs_mode_manager.spin_mechanizations import MECHANIZATIONS, AscsError, Mechanization, coil_moments
from ascs_mode_manager.sss_ascs import SssAscs, SssOutput, build_sss_ascs

NODE = MODE_STATUS
#: Body axis of the spin-plane magnetometer channel (fixed by the core's wiring).
CHANNEL_AXIS = 1
DIAGNOSTIC_EVERY = 20


def mode_name(ascs: SssAscs, out: SssOutput) -> str:
    """The published mode name for the core's state after a step (module docstring)."""
    if ascs.direct_attitude:
        return 'sss_direct_attitude'
    if out.torquing_active:
        return f'sss_{out.mode}_torquing'
    if not ascs.enabled:
        return 'sss_disabled'
    return f'sss_{ascs.mode}_idle'


def dipole_command(mech: Mechanization, ascs: SssAscs, out: SssOutput, b_sensed_t: np.ndarray) -> np.ndarray:
    """Commanded body dipoles, A·m², after a core step: the core's own, or during a spin-mode pass with a
    mechanization other than the flight one, that mechanization's spin-plane coils (x, y) from the sensed
    field (module docstring)."""
    dipole = out.dipole_body_am2.copy()
    if mech.key != 'one_channel_constant' and out.torquing_active and out.mode == 'spin':
        direction = 1 if ascs.spin_direction == 'spin_up' else -1
        dipole[:2] = coil_moments(mech, np.asarray(b_sensed_t)[:2], ascs.config.polarity_level_t, direction)
    return dipole


class SssPart:
    """The SSS ASCS logic of the mode-manager stepper (module docstring)."""

    def __init__(self, host: Any) -> None:
        self.host = host
        p = host.sss_params
        self.mech = MECHANIZATIONS[p['mechanization']]
        self.scale_v_per_t = p['magnetometer_scale_v_per_g'] / GAUSS_T
        with scenario_key('sss', AscsError):
            self.core = build_sss_ascs(p)
        self.mode = 'sss_disabled'
        self.last_signal_t = 0.0

    def sensed_field_t(self, k: int, inp: dict[str, Any], diagnostics: list[Status]) -> np.ndarray:
        """Bias-referenced field of the three axes, T; a non-finite or absent reading reads as zero."""
        if inp['volts'] is None or inp['bias'] is None:
            return np.zeros(3)
        volts, bias = vec(inp['volts']), vec(inp['bias'])
        if not (np.all(np.isfinite(volts)) and np.all(np.isfinite(bias))):
            diagnostics.extend(diagnostic(NODE, {'volts': volts.tolist(), 'bias_volts': bias.tolist(), 'step': k},
                                          'rejected non-finite magnetometer input: comparator reads zero field',
                                          WARN))
            return np.zeros(3)
        return (volts - bias) / self.scale_v_per_t

    def step(self, k: int, t_s: float, inp: dict[str, Any]) -> dict[str, Any]:
        """Step k: commands due, the core step, then mode, moment command, events and diagnostics."""
        diagnostics: list[Status] = []
        causes = [f'ground command {text!r}' for text, _result in self.host.answer_due(t_s, diagnostics)]
        b_t = self.sensed_field_t(k, inp, diagnostics)
        self.last_signal_t = float(b_t[CHANNEL_AXIS])
        out = self.core.step(t_s, self.host.control_period_s, b_t)
        name = mode_name(self.core, out)
        cause = ''
        events = []
        for event in out.events:
            cause = event.detail
            events.append(f't={event.t_s:.2f} {event.kind} {self.mode}->{name}: {event.detail}')
        if name != self.mode and not out.events:
            cause = '; '.join(c for c in causes if c) or 'on-board logic'
            events.append(f't={t_s:.2f} mode {self.mode}->{name}: {cause}')
        self.mode = name
        for text in events:
            self.host.log('info', text)
        result: dict[str, Any] = {
            'moment': vector3(dipole_command(self.mech, self.core, out, b_t)),
            'mode': self.mode_value(out, cause),
        }
        if events:
            result['events'] = events
        if k % DIAGNOSTIC_EVERY == 0:
            diagnostics.extend(diagnostic(NODE, self.telemetry(out)))
        if diagnostics:
            result['diagnostics'] = tuple(diagnostics)
        return result

    def telemetry(self, out: SssOutput) -> dict[str, str]:
        """SSS telemetry key/values (strings)."""
        return {
            'pass_mode': out.mode,
            'enabled': str(self.core.enabled).lower(),
            'selected_mode': self.core.mode,
            'spin_direction': self.core.spin_direction,
            'direct_attitude': str(self.core.direct_attitude).lower(),
            'signal_gauss': f'{tesla_to_gauss(self.last_signal_t):.5f}',
            'spin_coil': str(out.spin_coil),
            'attitude_coil': str(out.attitude_coil),
            'power_w': f'{out.power_w:.6g}',
        }

    def mode_value(self, out: SssOutput, cause: str) -> tuple[Status]:
        """The step's ``mode`` DiagnosticArray value (module docstring)."""
        return ModeReport(self.mode, cause, status=tuple(self.telemetry(out).items()), run_complete=None).encode()
