"""acds_controller stepper: the HEAO transfer assembly + DPA (spec §7).

Stage ``dpa`` of step k takes the magnetometer volts and bias volts (k), gyro rates (k), sun
sensor (k), the ``mode`` of the mode manager (k, with any forwarded ``command/acds_controller``
law/gain commands, applied before the step is computed), the attitude reference
``truth/odometry`` (k; the ideal attitude of the cruise modes), the wheel momentum and rate of
step k−1 (lag 1, so h(t_k) = h_{k−1} + ḣ_{k−1}·Δt exactly) and the coil current of step k−1
(lag 1, TA telemetry only).

It returns ``moment`` (A·m²) and ``volts`` (wheel drive, V; with wheels in the graph) every step, and DPA +
TA telemetry on ``diagnostics`` every ``controller.telemetry_every`` steps and at once when something is
wrong (a refused command, a non-finite input).

Absent sources: no magnetometer → zero sensed field (the magnetic laws command nothing); no
mode manager → ``mode_1a`` (magnetics-only rate reduction); no wheels → zero wheel momentum.
A non-finite input is rejected with a diagnostic and the step commands zero moment and zero
wheel volts.

The stage's arithmetic and per-step decisions (the wheel momentum at t_k, the input checks, the TA's A/D
conversion and the DPA's period in the mode) are one kernel call a step, :func:`dpa_control`
(:mod:`acds_common.kernels`: compiled in the direct engine); the stepper keeps the mode and commands, the
messages of a refused step and the telemetry.

The node's other variants, chosen by the scenario (``acds_controller.nodes``): the AAP Workshop's
computer (``wheels.kind`` cmg, :mod:`acds_controller.workshop_step`), which uses :func:`warned` and
:func:`store_momentum`, and this DPA with the cold-gas acquisition law (node ``cold_gas`` in the graph,
:mod:`acds_controller.cold_gas_controller_step`).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from typing import Any

from acds_common import kernels
from acds_common.commands import GainCommand, LawCommand, decode
from acds_common.fused import FusedStage, Output
from acds_common.messages import WARN, diagnostic, xyz
from acds_common.mode_report import ModeStatusReader
from acds_common.modes import HEAO_MODE_INDEX, HEAO_MODES
from acds_common.stepper import Stepper
from acds_common.validation import all_finite

from acds_controller.configuration import build_dpa
from acds_controller.dpa import DONE, NO_FIGURES, NO_Q, Dpa, DpaFigures, DpaState, dpa_step
from acds_controller.magnetic_laws import ControllerError
from acds_controller.transfer_assembly import field_xyz

#: Excess-coil-current alarm: |I| above this multiple of the current of the maximum moment.
EXCESS_CURRENT_FACTOR = 1.1
ZERO = (0.0, 0.0, 0.0)
MID_SCALE_V = (2.5, 2.5, 2.5)
#: :func:`dpa_control`'s status for a non-finite input (the DPA's own statuses: :data:`acds_controller.dpa.DONE`…).
NOT_FINITE = -1


#: The commands the DPA applies (forwarded in the ``mode`` report, key ``command/acds_controller``).
GRAMMAR = (LawCommand, GainCommand)


def parse_command(text: str) -> LawCommand | GainCommand:
    """Parse a forwarded command; :class:`ControllerError` says what is wrong (the stepper makes it a diagnostic)."""
    return decode(text, GRAMMAR, 'acds_controller command', ControllerError)


def apply_command(dpa: Dpa, cmd: LawCommand | GainCommand) -> str:
    """Apply a parsed law/gain command to the DPA (which checks it against its tables); return what was done."""
    if isinstance(cmd, LawCommand):
        dpa.set_law(cmd.slot, cmd.name)
        return f'law {cmd.slot} set to {cmd.name}'
    dpa.set_gain(cmd.name, cmd.value)
    return f'gain {cmd.name} set to {cmd.value:g}'


def check_finite(inputs: tuple[tuple[str, Sequence[float]], ...]) -> None:
    """Raise :class:`ControllerError` naming the first input that is not finite."""
    for name, v in inputs:
        if not all_finite(v):
            raise ControllerError(f'{name} input is not finite: {[float(x) for x in v]}')


class DpaStep(Stepper):
    """Transfer assembly and digital processor of the HEAO ACDS."""

    node = 'acds_controller'

    def __init__(self, params: dict[str, Any], log: Any = None) -> None:
        super().__init__(params, log)
        c = self.section('controller')
        self.telemetry_period = c['telemetry_every']
        self.ta, self.dpa = build_dpa(self.section('spacecraft'), c, self.section('magnetometer'))
        self.excess_current_a = EXCESS_CURRENT_FACTOR * c['max_moment_am2'] / self.ta.moment_per_amp_am2_per_a
        #: Whether wheels read the DPA's wheel volts (output ``volts`` is declared only then).
        self.drives_wheels = self.present('reaction_wheels')
        self._mode_status = ModeStatusReader(self.node)
        #: The step kernel bound to the one signature :meth:`_dpa_step` calls it with (:func:`kernels.bound`), fixed
        #: by construction: the converter's and the DPA's parameters built by them (floats, ints, a bool, tuples of
        #: floats; a gain or law command rebuilds them alike), the DPA's state (a bool and float triples: its
        #: initial state, then this kernel's), the mode's index an ``int``, the inputs' Vector3Stamped values and
        #: the odometry's orientation (plain floats from :func:`acds_common.messages.vector3` or a kernel, the
        #: direct engine running only the built-in steppers) or the float defaults here, Δt ``_dt``.
        self._dt = float(self.control_period_s)
        self._control = kernels.bound(dpa_control, self.ta.params, self.dpa.params, self.dpa.state, 0, ZERO, ZERO,
                                      ZERO, ZERO, ZERO, ZERO, NO_Q, False, ZERO, self._dt)

    def control(self, k: int, t_s: float, inp: dict[str, Any]) -> dict[str, Any]:
        """Stage ``control``: one DPA control period (commands applied first, inputs checked)."""
        warnings: list[tuple[str, dict[str, str]]] = []
        mode, commands = self._mode_status(inp['mode'])
        if commands:
            self.apply_commands(k, commands, warnings)
        if mode not in HEAO_MODE_INDEX:  # before the mode manager speaks, or a mode the DPA does not know
            mode = resolve_mode(mode, 'mode_1a', HEAO_MODES, warnings, 'unknown mode {!r} from the mode manager')
        try:
            result = self._dpa_step(k, mode, inp)
        except ControllerError as exc:
            warnings.append((f'input rejected, zero commands this step: {exc}', {}))
            result = {'moment': ZERO, 'volts': ZERO}
        if not self.drives_wheels:
            del result['volts']
        return warned(self, k, result, warnings) if warnings else result

    def fused(self, stage: str, held: dict[str, Any]) -> FusedStage | None:
        """Stage ``control`` as :func:`control_fused` (:mod:`acds_common.fused`) with every source in the graph and the
        wheels driven; None with telemetry wanted, or when the block's ``mode`` forwards commands or is not a mode
        the DPA knows."""
        mode, commands = self._mode_status(held.get('mode'))
        if (stage != 'control' or self.telemetry_wanted or commands or mode not in HEAO_MODE_INDEX
                or not self.drives_wheels
                or not all(self.present(n) for n in ('magnetometer_sim', 'rigid_body', 'em_driver'))):
            return None
        return FusedStage(control_fused, (self.ta.params, self.dpa.params, HEAO_MODE_INDEX[mode], self._dt),
                          (self.dpa.state,), FUSED_INPUTS, (Output('moment', 3), Output('volts', 3)), self._restore)

    def _restore(self, s: tuple) -> None:
        self.dpa.state = s[0]

    def apply_commands(self, k: int, commands: list[str], warnings: list[tuple[str, dict[str, str]]]) -> None:
        """Apply the forwarded law/gain commands to the DPA; a refusal becomes a warning."""
        for text in commands:
            try:
                self.log('info', f'step {k}: {apply_command(self.dpa, parse_command(text))}')
            except ControllerError as exc:
                warnings.append((f'command refused: {text!r}: {exc}', {'command': text, 'reason': str(exc)}))

    def _dpa_step(self, k: int, mode: str, inp: dict[str, Any]) -> dict[str, Any]:
        # An absent input is its default (acds_common.messages.xyz's, written out: this runs every step).
        volts, bias, gyro, sun = inp['mag_volts'], inp['mag_bias'], inp['gyro'], inp['sun']
        wheel_h, wheel_hdot, odometry, coil = inp['wheel_h'], inp['wheel_hdot'], inp['odometry'], inp['coil_current']
        volts = MID_SCALE_V if volts is None else volts
        bias = MID_SCALE_V if bias is None else bias
        omega = ZERO if gyro is None else gyro[0]
        sun = ZERO if sun is None else sun
        wheel_h = ZERO if wheel_h is None else wheel_h
        wheel_hdot = ZERO if wheel_hdot is None else wheel_hdot
        coil = ZERO if coil is None else coil
        q = None if odometry is None else odometry.orientation
        dpa = self.dpa
        status, state, figures = self._control(self.ta.params, dpa.params, dpa.state, HEAO_MODE_INDEX[mode], volts, bias,
                                               omega, sun, wheel_h, wheel_hdot, NO_Q if q is None else q,
                                               q is not None, coil, self._dt)
        if status != DONE:
            if status == NOT_FINITE:
                check_finite((('magnetometer volts', volts), ('bias volts', bias), ('gyro', omega), ('sun sensor', sun),
                              ('wheel momentum', store_momentum(inp, self.control_period_s)), ('coil current', coil)))
            raise dpa.refusal(status, mode, omega, q)
        dpa.state = state
        result: dict[str, Any] = {'moment': figures[0], 'volts': figures[1]}
        if self.telemetry_wanted and k % self.telemetry_period == 0:
            out = dpa.output(mode, figures)
            alarms = [abs(i) > self.excess_current_a for i in coil]
            telemetry = {**out.telemetry, **self.ta.telemetry(figures[2], out.moment_xyz, bias, coil, alarms)}
            result['diagnostics'] = diagnostic(self.instance, telemetry)
        return result


def resolve_mode(mode: str | None, default: str, known: Any, warnings: list[tuple[str, dict[str, str]]],
                  unknown: str) -> str:
    """The mode to run: ``default`` before the mode manager speaks, standby (with a warning) for one not ``known``.

    ``unknown``: the warning's text, a :meth:`str.format` template of the mode (formatted only when it is sent).
    """
    if mode is None:
        return default
    if mode not in known:
        warnings.append((f'{unknown.format(mode)}: standby', {'mode': mode}))
        return 'standby'
    return mode


def warned(stepper: Stepper, k: int, result: dict[str, Any], warnings: list[tuple[str, dict[str, str]]]) -> dict[str, Any]:
    """The step's outputs with its warnings logged (by ``stepper``) and put first on ``diagnostics``."""
    if warnings:
        for message, _values in warnings:
            stepper.log('warn', f'step {k}: {message}')
        result['diagnostics'] = tuple(s for message, values in warnings
                                      for s in diagnostic(stepper.node, values, message, WARN)) \
            + result.get('diagnostics', ())
    return result


def store_momentum(inp: dict[str, Any], dt: float) -> tuple[float, float, float]:
    """h(t_k) of the wheels or CMGs from their step k−1 outputs (lag 1): :func:`momentum_xyz`."""
    return momentum_xyz(xyz(inp['wheel_h']), xyz(inp['wheel_hdot']), dt)


@kernels.helper
def momentum_xyz(h: Sequence[float], hdot: Sequence[float], dt: float) -> tuple[float, float, float]:
    """h_{k−1} + ḣ_{k−1}·Δt, exactly (the wheels' or CMGs' momentum at t_k from their step k−1 outputs)."""
    return h[0] + hdot[0] * dt, h[1] + hdot[1] * dt, h[2] + hdot[2] * dt


@kernels.helper
def finite_xyz(v: Sequence[float]) -> bool:
    """Whether the three components are finite."""
    return math.isfinite(v[0]) and math.isfinite(v[1]) and math.isfinite(v[2])


@kernels.helper
def dpa_control(ta: tuple[float, float, float], params: tuple, state: DpaState, mode: int, volts: Sequence[float],
                bias: Sequence[float], omega: Sequence[float], sun: Sequence[float], wheel_h: Sequence[float],
                wheel_hdot: Sequence[float], q: Sequence[float], q_given: bool, coil: Sequence[float], dt: float
                ) -> tuple[int, DpaState, DpaFigures]:
    """Stage ``control``'s arithmetic (spec §7): the wheel momentum at t_k (:func:`momentum_xyz`), every input
    checked finite (else :data:`NOT_FINITE`), the TA's field (:func:`~acds_controller.transfer_assembly.field_xyz`,
    ``ta`` its :attr:`~acds_controller.transfer_assembly.TransferAssembly.params`) and the DPA's period
    (:func:`~acds_controller.dpa.dpa_step`, with ``params`` and ``state``). Returns its status, state and figures.

    A kernel (:mod:`acds_common.kernels`): the stage's one compiled call a step in the direct engine.
    """
    h = momentum_xyz(wheel_h, wheel_hdot, dt)
    if not (finite_xyz(volts) and finite_xyz(bias) and finite_xyz(omega) and finite_xyz(sun) and finite_xyz(h)
            and finite_xyz(coil)):
        return NOT_FINITE, state, NO_FIGURES
    b = field_xyz(volts, bias, ta[0], ta[1], ta[2])
    return dpa_step(params, state, mode, b, omega, sun, h, q, q_given, dt)


#: The inputs :func:`control_fused` takes, in order.
FUSED_INPUTS = ('mag_volts', 'mag_bias', 'gyro', 'sun', 'odometry', 'wheel_h', 'wheel_hdot', 'coil_current')


@kernels.helper
def control_fused(p: tuple, s: tuple, _k: int, _t: float, volts: Any, bias: Any, gyro: Any, sun: Any, odometry: Any,
                  wheel_h: Any, wheel_hdot: Any, coil: Any) -> tuple:
    """Stage ``control`` as a kernel (:mod:`acds_common.fused`): :func:`dpa_control` in the block's mode, quiet when
    it is done (a non-finite input or a refusal is the Python stage's). ``p``: (the TA's and the DPA's parameters,
    the mode's index, Δt); ``s``: (the DPA's state,)."""
    ta, params, mode, dt = p
    status, state, figures = dpa_control(ta, params, s[0], mode, volts, bias, gyro[0], sun, wheel_h, wheel_hdot,
                                         odometry[1], True, coil, dt)
    quiet = status == DONE
    return quiet, ((state,) if quiet else s), figures[0], figures[1]
