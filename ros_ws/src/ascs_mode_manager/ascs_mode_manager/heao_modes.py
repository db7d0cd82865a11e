"""HEAO ACDS mode sequencing: Mode 1A → 1B → capture → cruise, and ground commands (spec §8; seed 002 §4.1, §4.3.1).

Modes (the strings the DPA takes): ``'standby'``, ``'mode_1a'`` (magnetics only, rate
reduction), ``'mode_1b'`` (wheels on sun sensor and gyros, magnetics unloading),
``'celestial_scan'`` (HEAO-A/C cruise), ``'celestial_point'`` (HEAO-B cruise).

Acquisition capture is not a mode: the study's acquisition ends inside Mode 1B when the
body z axis is within 10° of the sun line with the rates nulled (§4.3.1). It is kept as a
latched flag (:attr:`HeaoModeManager.captured`) and reported once as a ``Transition`` with
``kind='capture'`` (from_mode = to_mode = 'mode_1b'). "Rates nulled" is taken as every
|ω_i| ≤ 0.01°/s, a tenth of the acquisition maneuver rate limit 0.1°/s (Table 4-2); the
seed gives no number.

Ground commands (:mod:`acds_common.commands`, one parser each; whitespace separated, keywords
case-insensitive)::

    mode <standby|mode_1a|mode_1b|celestial_scan|celestial_point>
    eea_select <x|y|z> <A|B>          → routed to em_driver (active driver/winding)
    magnetometer_select <A|B>         → routed to magnetometer_sim (active assembly)
    law <acquisition|unloading> <name> → routed to acds_controller (checked against ``law_choices``)
    gain <name> <value>               → routed to acds_controller (study units, checked against ``gain_limits``)

Mode transfers accepted by ground command (checked against the mode the manager will be in
once the commands already queued are applied):

* ``standby`` and ``mode_1a`` (restart of acquisition / reacquisition) from any other mode;
* ``mode_1b`` from standby or a cruise mode; from ``mode_1a`` it is refused, being the
  on-board transfer on rate thresholds and sun presence (§4.1);
* a cruise mode from the other cruise mode, or from ``mode_1b`` once captured.

A command accepted at sim time t is queued and applied at the start of the next
:meth:`HeaoModeManager.step` (the next step boundary); routed commands are returned at once
and the node layer forwards them so that their owner applies them at its next step.

The on-board transfers are one kernel (:mod:`acds_common.kernels`), :func:`heao_logic`, on the core's state as
a tuple (:meth:`HeaoModeManager.kernel_state`: the mode as its index in ``HEAO_MODES``, times NaN for None):
:meth:`HeaoModeManager.advance` runs it (after the queued commands) and formats the transitions' causes; the
direct engine's compiled step runs :func:`heao_advance`, which says whether the step is quiet (no transition, the
same status), and on any other step the Python core runs it again (:mod:`ascs_mode_manager.heao_part`).
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass

from acds_common import kernels
from acds_common.commands import (
    AXES,
    Command,
    EeaSelect,
    GainCommand,
    LawCommand,
    MagnetometerSelect,
    ModeCommand,
    decode,
)
from acds_common.modes import CELESTIAL_POINT, CELESTIAL_SCAN, HEAO_CRUISE_MODES, HEAO_MODE_INDEX, HEAO_MODES, MODE_1A, MODE_1B
from acds_common.units import deg, rad
from acds_common.validation import finite_xyz
from acds_common.vec3 import ZERO

from ascs_mode_manager.ground_commands import CommandResult, refuse
from ascs_mode_manager.spin_mechanizations import AscsError  # the package's one exception type

#: Baseline Mode 1A → 1B rate thresholds |ω_x|, |ω_y|, |ω_z|, deg/s (seed 002 §4.3.1).
BASELINE_RATE_THRESHOLDS_DEG_S = (0.573, 0.115, 0.115)
#: Table 4-7 case 5 thresholds ("higher rates for wheel transition"), deg/s.
CASE_5_RATE_THRESHOLDS_DEG_S = (1.3, 0.35, 0.36)
#: Capture cone: body z within 10° of the sun line (seed 002 §4.3.1).
CAPTURE_CONE_DEG = 10.0
#: "Rates nulled" for capture, deg/s: a tenth of the 0.1°/s maneuver rate limit (Table 4-2).
CAPTURE_RATE_DEG_S = 0.01



@dataclass(frozen=True)
class HeaoModeConfig:
    """Mode sequencing parameters (spec §8; seed 002 §4.1, §4.3.1, Table 4-7).

    ``rate_thresholds_rad_s``: Mode 1A → 1B thresholds on |ω_x|, |ω_y|, |ω_z| (rad/s).
    ``capture_cone_rad``: capture half-angle between body z and the sun line (rad).
    ``capture_rate_rad_s``: every |ω_i| at or below this counts as nulled (rad/s).
    ``capture_dwell_s``: time the capture condition must hold continuously (s; 0 = at once).
    ``cruise_target``: 'celestial_scan' (HEAO-A/C) or 'celestial_point' (HEAO-B).
    ``auto_cruise``: go to the cruise target by itself at capture; else wait for ground.
    ``wheels_on_from_separation``: Table 4-7 case 6, "initial wheel activation": the
    magnetics-only phase is skipped and the manager starts in Mode 1B (wheels on sun sensor
    and gyros from separation, magnetics unloading the wheels).
    ``initial_mode``: mode at separation when not starting with the wheels ('mode_1a' or 'standby').
    ``gain_limits`` / ``law_choices``: the controller's gain ranges and law names (the node
    passes ``acds_common.dpa_commands.GAIN_LIMITS`` / ``LAW_CHOICES``); when None only the syntax
    is checked here and the controller validates the rest.
    """

    rate_thresholds_rad_s: tuple[float, float, float] = (
        rad(BASELINE_RATE_THRESHOLDS_DEG_S[0]), rad(BASELINE_RATE_THRESHOLDS_DEG_S[1]),
        rad(BASELINE_RATE_THRESHOLDS_DEG_S[2]))
    capture_cone_rad: float = rad(CAPTURE_CONE_DEG)
    capture_rate_rad_s: float = rad(CAPTURE_RATE_DEG_S)
    capture_dwell_s: float = 0.0
    cruise_target: str = 'celestial_point'
    auto_cruise: bool = False
    wheels_on_from_separation: bool = False
    initial_mode: str = 'mode_1a'
    gain_limits: Mapping[str, tuple[float, float]] | None = None
    law_choices: Mapping[str, tuple[str, ...]] | None = None

    def __post_init__(self) -> None:
        thr = self.rate_thresholds_rad_s
        if len(thr) != 3 or not all(math.isfinite(x) and x > 0.0 for x in thr):
            raise AscsError(f'rate_thresholds_rad_s must be 3 positive rates, got {thr!r}')
        if not 0.0 < self.capture_cone_rad < math.pi:
            raise AscsError(f'capture_cone_rad = {self.capture_cone_rad!r} must be in (0, π)')
        if not 0.0 < self.capture_rate_rad_s < math.inf:
            raise AscsError(f'capture_rate_rad_s = {self.capture_rate_rad_s!r} must be > 0')
        if not 0.0 <= self.capture_dwell_s < math.inf:
            raise AscsError(f'capture_dwell_s = {self.capture_dwell_s!r} must be ≥ 0')
        if self.cruise_target not in HEAO_CRUISE_MODES:
            raise AscsError(f'cruise_target {self.cruise_target!r} must be one of {HEAO_CRUISE_MODES}')
        if self.initial_mode not in ('mode_1a', 'standby'):
            raise AscsError(f"initial_mode {self.initial_mode!r} must be 'mode_1a' or 'standby'")
        if self.wheels_on_from_separation and self.initial_mode != 'mode_1a':
            raise AscsError('wheels_on_from_separation starts in mode_1b; initial_mode must stay mode_1a')


@dataclass(frozen=True)
class Transition:
    """A mode change (``kind='mode'``) or the acquisition capture event (``kind='capture'``) at sim time ``t_s``."""

    t_s: float
    from_mode: str
    to_mode: str
    cause: str
    kind: str = 'mode'


#: :func:`heao_logic`'s configuration (:meth:`HeaoModeManager.kernel_params`) and state
#: (:meth:`HeaoModeManager.kernel_state`).
HeaoKernelParams = tuple[float, float, float, float, float, float, bool, int]
HeaoKernelState = tuple[int, bool, float, float, float, float, int]
#: The mode index of a mode the HEAO logic does not sequence (a variant's, e.g. the cold-gas modes): the kernel leaves
#: it alone (no Mode 1A transfer, no capture check) and only stamps the step's time.
OTHER_MODE = -1
#: :func:`heao_logic`'s events, bits: Mode 1A → 1B on the rates and the sun (a transition); a run started in Mode 1B
#: stamps its entry time (a status change, no transition); acquisition capture (a ``kind='capture'`` transition);
#: the automatic transfer to cruise at capture (a transition).
ENTERED_1B, ENTRY_STAMPED, CAPTURED, AUTO_CRUISE = 1, 2, 4, 8


@kernels.helper
def sun_norm(sun: Sequence[float]) -> float:
    """|sun| of the sun sensor's vector (0 when the sun is absent)."""
    return math.sqrt(sun[0] * sun[0] + sun[1] * sun[1] + sun[2] * sun[2])


@kernels.helper
def sun_angle(sun: Sequence[float], norm: float) -> float:
    """Angle between body z and the sun line (rad) from the sun vector and its ``norm``; π when the sun is absent
    (``norm`` not > 0)."""
    if not norm > 0.0:
        return math.pi
    return math.acos(max(-1.0, min(1.0, sun[2] / norm)))


@kernels.helper
def rates_within(omega: Sequence[float], x: float, y: float, z: float) -> bool:
    """|ω_x| ≤ x, |ω_y| ≤ y and |ω_z| ≤ z."""
    return abs(omega[0]) <= x and abs(omega[1]) <= y and abs(omega[2]) <= z


@kernels.helper
def heao_enter(state: HeaoKernelState, t: float, to: int) -> HeaoKernelState:
    """The state after entering mode index ``to`` at ``t`` (:data:`OTHER_MODE`: a variant's mode): capture is
    latched in Mode 1B and kept in cruise only (the captured flag and the capture condition's start are cleared
    entering any other mode); entering Mode 1B stamps its entry time."""
    _mode, captured, entry, capture, since, last, pending = state
    if to != CELESTIAL_SCAN and to != CELESTIAL_POINT:
        captured = False
        since = math.nan
    if to == MODE_1B:
        entry = t
    return to, captured, entry, capture, since, last, pending


@kernels.helper
def heao_logic(params: HeaoKernelParams, state: HeaoKernelState, t: float, omega: Sequence[float],
               sun: Sequence[float]) -> tuple[int, HeaoKernelState]:
    """The on-board transfers of one step at ``t`` (s) with gyro rates ``omega`` (rad/s, body) and the sun sensor's
    ``sun`` (the zero vector when absent), on a state with no command queued (seed 002 Figure 4-3, §4.3.1):

    * Mode 1A → 1B when the sun is present and |ω_i| ≤ threshold_i on all three axes (baseline 0.573, 0.115,
      0.115 deg/s);
    * in Mode 1B (entered now or before; a run started in it stamps its entry time) and not yet captured, the
      capture check: z within the capture cone (10°) of the sun line and every |ω_i| ≤ the capture rate
      (0.01 deg/s, "rates nulled"), held for the dwell; at capture with ``auto_cruise`` the transfer to the cruise
      target.

    Returns the events (:data:`ENTERED_1B` … bits, 0 when the step only stamped its time and the capture
    condition's start) and the state. A kernel helper (:mod:`acds_common.kernels`), the logic of
    :meth:`HeaoModeManager.advance` and of the compiled :func:`heao_advance`.
    """
    thr_x, thr_y, thr_z, cone, rate, dwell, auto_cruise, cruise = params
    mode, captured, entry, capture, since, _last, pending = state
    state = (mode, captured, entry, capture, since, t, pending)
    events = 0
    norm = sun_norm(sun)
    if mode == MODE_1A and norm > 0.0 and rates_within(omega, thr_x, thr_y, thr_z):
        state = heao_enter(state, t, MODE_1B)
        events |= ENTERED_1B
    mode, captured, entry, capture, since, last, pending = state
    if mode != MODE_1B:
        return events, state
    if math.isnan(entry):
        entry = t
        events |= ENTRY_STAMPED
    if not captured:
        if sun_angle(sun, norm) > cone or not rates_within(omega, rate, rate, rate):
            since = math.nan
        else:
            if math.isnan(since):
                since = t
            if not t - since < dwell:
                captured = True
                capture = t
                events |= CAPTURED
    state = (mode, captured, entry, capture, since, last, pending)
    if events & CAPTURED and auto_cruise:
        state = heao_enter(state, t, cruise)
        events |= AUTO_CRUISE
    return events, state


@kernels.helper
def heao_advance(params: HeaoKernelParams, state: HeaoKernelState, t: float, omega: Sequence[float],
                 sun: Sequence[float]) -> tuple[bool, HeaoKernelState]:
    """One step of the HEAO mode logic (spec §8; seed 002 Figure 4-3, §4.3.1: Mode 1A → 1B, capture in Mode 1B,
    cruise) for a compiled caller (:mod:`acds_common.kernels`, :func:`heao_logic`): ``(quiet, state)``.

    ``quiet`` means :meth:`HeaoModeManager.advance` ``(t, omega, sun, True)`` from ``state`` returns no transition
    and leaves :meth:`HeaoModeManager.status_state`, the mode and the captured flag as they were, and the returned
    state, taken by :meth:`HeaoModeManager.set_kernel_state`, is then exactly the core advance leaves (only the
    step time and the capture condition's start change). Not quiet, the state is to be thrown away and the step run
    in Python: a ground command waits (applied at this step: a transition and a status change), a non-finite
    input or time (the stepper holds the logic and warns), a transfer, a capture or the Mode 1B entry stamp.
    """
    if state[6] != 0 or not math.isfinite(t + omega[0] + omega[1] + omega[2] + sun[0] + sun[1] + sun[2]):
        return False, state
    events, new = heao_logic(params, state, t, omega, sun)
    return events == 0, new


class HeaoModeManager:
    """On-board HEAO mode logic with ground command handling (spec §8; seed 002 Figure 4-3, §4.3.1)."""

    def __init__(self, config: HeaoModeConfig) -> None:
        self.config = config
        self.mode: str = 'mode_1b' if config.wheels_on_from_separation else config.initial_mode
        self.captured = False
        #: Sim time of the latest Mode 1B entry and of acquisition capture (s), None until they happen.
        self.mode_1b_entry_t_s: float | None = None
        self.capture_t_s: float | None = None
        self._capture_since_t_s: float | None = None
        self._last_t_s: float | None = None
        self._pending: list[tuple[str, float, str]] = []
        self._kernel_params = self.kernel_params()
        #: :func:`heao_logic` bound to the one signature :meth:`advance` calls it with (:func:`kernels.bound`; compiled
        #: in the direct engine): the tuples of :meth:`kernel_params` and :meth:`kernel_state`, a float time and float
        #: triples (the stepper's step time and its gyro and sun sensor triples, :meth:`step`'s checked ones, ZERO).
        self._logic = kernels.bound(heao_logic, self._kernel_params, self.kernel_state(), 0.0, ZERO, ZERO)

    # ----------------------------------------------------------------- stepping
    def step(
        self, t_s: float, omega_rad_s: Sequence[float], sun_body_unit: Sequence[float], sun_present: bool
    ) -> list[Transition]:
        """Advance the mode logic to sim time ``t_s`` (s) with gyro rates (rad/s, body) and the sun sensor.

        Queued ground mode commands are applied first, then the on-board transfers:
        1A → 1B when |ω_i| ≤ threshold_i on all three axes and the sun is present; in 1B the
        capture check (z within the cone of the sun line, all |ω_i| ≤ capture rate, held for
        the dwell); at capture with ``auto_cruise`` the transfer to the cruise target.
        """
        t = float(t_s)
        if not math.isfinite(t):
            raise AscsError(f't_s must be finite, got {t_s!r}')
        if self._last_t_s is not None and t < self._last_t_s:
            raise AscsError(f't_s = {t} s goes back in time (last step at {self._last_t_s} s)')
        try:
            omega = finite_xyz('omega_rad_s', omega_rad_s, AscsError)
            sun = finite_xyz('sun_body_unit', sun_body_unit, AscsError)
        except AscsError:
            raise AscsError('omega_rad_s and sun_body_unit must be finite 3-vectors') from None
        return self.advance(t, omega, sun, bool(sun_present))

    def advance(self, t: float, omega: tuple[float, float, float], sun: tuple[float, float, float],
                sun_present: bool) -> list[Transition]:
        """:meth:`step` without its checks (the stepper's per-step path): ``t`` a finite float not before the last
        step's, ``omega`` and ``sun`` finite float triples.

        The queued ground commands are applied here (:meth:`_enter`), the on-board logic is the kernel
        :func:`heao_logic` on :meth:`kernel_state` (the one definition the compiled step runs too); its events
        become the transitions, their causes formatted from the inputs."""
        out: list[Transition] = []
        if self._pending:
            for to_mode, t_accepted, text in self._pending:
                out.append(self._enter(t, to_mode, f"ground command '{text}' accepted at t={t_accepted:.3f} s"))
            self._pending.clear()
        if not sun_present:
            sun = ZERO  # the kernel reads the zero vector as the sun absent
        events, state = self._logic(self._kernel_params, self.kernel_state(), t, omega, sun)
        self.set_kernel_state(state)
        if events:
            out.extend(self._transitions(events, t, omega, sun))
        return out

    def _transitions(self, events: int, t: float, omega: tuple[float, float, float],
                     sun: tuple[float, float, float]) -> list[Transition]:
        """The transitions of :func:`heao_logic`'s ``events`` at ``t``, with their causes (from the step's inputs)."""
        cfg = self.config
        out: list[Transition] = []
        if events & ENTERED_1B:
            thr = cfg.rate_thresholds_rad_s
            rates = ', '.join(f'|ω{a}|={deg(abs(omega[i])):.4f}≤{deg(thr[i]):.4f}' for i, a in enumerate(AXES))
            out.append(Transition(t, 'mode_1a', 'mode_1b', f'rates below thresholds ({rates} deg/s) and sun present'))
        if events & CAPTURED:
            angle = sun_angle(sun, sun_norm(sun))
            out.append(Transition(t, 'mode_1b', 'mode_1b',
                                  f'acquisition capture: z {deg(angle):.2f}° from the sun line, rates nulled '
                                  f'(max |ω| {deg(max(abs(w) for w in omega)):.4f} deg/s)', kind='capture'))
        if events & AUTO_CRUISE:
            out.append(Transition(t, 'mode_1b', cfg.cruise_target, 'automatic transfer to cruise at acquisition capture'))
        return out

    def _enter(self, t: float, to_mode: str, cause: str) -> Transition:
        """Enter ``to_mode`` at ``t`` (:func:`heao_enter`; a variant's mode is entered by name) and say so."""
        from_mode = self.mode
        self.set_kernel_state(heao_enter(self.kernel_state(), t, HEAO_MODE_INDEX.get(to_mode, OTHER_MODE)))
        self.mode = to_mode
        return Transition(t, from_mode, to_mode, cause)

    # ----------------------------------------------------------------- kernel
    def kernel_params(self) -> HeaoKernelParams:
        """The configuration as :func:`heao_logic` reads it: (rate thresholds x, y, z (rad/s), capture cone (rad),
        capture rate (rad/s), capture dwell (s), auto cruise, cruise target's mode index)."""
        cfg = self.config
        thr = cfg.rate_thresholds_rad_s
        return (float(thr[0]), float(thr[1]), float(thr[2]), float(cfg.capture_cone_rad), float(cfg.capture_rate_rad_s),
                float(cfg.capture_dwell_s), bool(cfg.auto_cruise), HEAO_MODE_INDEX[cfg.cruise_target])

    def kernel_state(self) -> HeaoKernelState:
        """Everything :meth:`advance` reads and writes, as :func:`heao_logic` reads it: (mode index, or
        :data:`OTHER_MODE` for a variant's mode; captured; Mode 1B entry, capture, capture-condition-since and last
        step times (s, NaN for None: every time the logic stores is a finite step time); queued commands)."""
        entry, capture, since, last = self.mode_1b_entry_t_s, self.capture_t_s, self._capture_since_t_s, self._last_t_s
        nan = math.nan  # written out: the per-step path
        return (HEAO_MODE_INDEX.get(self.mode, OTHER_MODE), self.captured, nan if entry is None else entry,
                nan if capture is None else capture, nan if since is None else since, nan if last is None else last,
                len(self._pending))

    def set_kernel_state(self, state: HeaoKernelState) -> None:
        """Take a state of :func:`heao_logic` / :func:`heao_advance` (a :meth:`kernel_state` stepped by the kernel):
        the mode by name (an :data:`OTHER_MODE` leaves the variant's mode as it is: the kernel never enters one or
        leaves one), the captured flag and the times (NaN → None). The queued commands are Python's (the kernel
        never applies them: :func:`heao_advance` is not quiet while any wait), so their count is not taken."""
        mode, captured, entry, capture, since, last, _pending = state
        if mode != OTHER_MODE:
            self.mode = HEAO_MODES[mode]
        self.captured = captured
        # x != x: x is NaN (written out: the per-step path)
        self.mode_1b_entry_t_s = None if entry != entry else entry
        self.capture_t_s = None if capture != capture else capture
        self._capture_since_t_s = None if since != since else since
        self._last_t_s = None if last != last else last

    # ----------------------------------------------------------- ground commands
    #: The commands this logic takes (:mod:`acds_common.commands`); a variant adds its own.
    grammar: tuple[type, ...] = (ModeCommand, EeaSelect, MagnetometerSelect, LawCommand, GainCommand)

    def parse(self, text: str) -> Command:
        """A ground command's text → its command object (:class:`CommandError`: the reason it does not parse)."""
        return decode(text, self.grammar)

    def apply(self, cmd: Command, t_s: float) -> CommandResult:
        """Validate a parsed ground command received at sim time ``t_s`` (s): a mode transfer is queued for the
        next step, the rest is routed to the node that applies it (module docstring)."""
        if isinstance(cmd, ModeCommand):
            return self._cmd_mode(cmd.target, float(t_s))
        if isinstance(cmd, LawCommand) and self.config.law_choices is not None:
            choices = self.config.law_choices
            if cmd.slot not in choices:
                return refuse(f"unknown law slot '{cmd.slot}'; slots: {', '.join(choices)}")
            if cmd.name not in choices[cmd.slot]:
                return refuse(f"unknown {cmd.slot} law '{cmd.name}'; choose one of {', '.join(choices[cmd.slot])}")
        if isinstance(cmd, GainCommand) and self.config.gain_limits is not None:
            limits = self.config.gain_limits
            if cmd.name not in limits:
                return refuse(f"unknown gain '{cmd.name}'; known: {', '.join(sorted(limits))}")
            lo, hi = limits[cmd.name]
            if not lo <= cmd.value <= hi:
                return refuse(f'gain {cmd.name} = {cmd.value:g} is out of range [{lo:g}, {hi:g}]')
        return CommandResult(True, f'routed to {cmd.route}', cmd.route, cmd.text)

    def _effective_mode(self) -> str:
        return self._pending[-1][0] if self._pending else self.mode

    def _cmd_mode(self, target: str, t_s: float) -> CommandResult:
        if target not in HEAO_MODES:
            return refuse(f"unknown mode '{target}'; modes: {', '.join(HEAO_MODES)}")
        current = self._effective_mode()
        captured = self.captured and not self._pending
        if target == current:
            return refuse(f'wrong mode: already in {current}')
        if target == 'mode_1b' and current == 'mode_1a':
            return refuse('wrong mode: mode_1a → mode_1b is the on-board transfer '
                           '(all rates below thresholds and sun present)')
        if target in HEAO_CRUISE_MODES and current not in HEAO_CRUISE_MODES:
            if current != 'mode_1b':
                return refuse(f'wrong mode: {current}; cruise is entered from mode_1b after acquisition capture')
            if not captured:
                return refuse('wrong mode: mode_1b has not reached acquisition capture '
                               '(z within the capture cone of the sun line with rates nulled)')
        normalised = f'mode {target}'
        self._pending.append((target, t_s, normalised))
        return CommandResult(True, f'{current} → {target} at the next step', None, normalised)

    def status_state(self) -> tuple[object, ...]:
        """The values :meth:`status` formats (equal states, equal status: the stepper formats it when this changes)."""
        return self.mode_1b_entry_t_s, self.capture_t_s, len(self._pending)

    def status(self) -> dict[str, str]:
        """The logic's status beyond :attr:`mode` and :attr:`captured`, as key/value strings for the ``mode``
        report (times in s, '' when not reached)."""
        entry, capture, pending = HeaoModeManager.status_state(self)  # this class's three (a variant adds its own)
        return {
            'mode_1b_entry_t_s': '' if entry is None else f'{entry:.3f}',
            'capture_t_s': '' if capture is None else f'{capture:.3f}',
            'pending_commands': str(pending),
        }
