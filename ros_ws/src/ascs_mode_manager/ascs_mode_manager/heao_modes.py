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
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass

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
from acds_common.modes import HEAO_CRUISE_MODES, HEAO_MODES
from acds_common.units import deg, rad
from acds_common.validation import finite_xyz

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
        step's, ``omega`` and ``sun`` finite float triples."""
        self._last_t_s = t
        sun_norm = math.sqrt(sun[0] * sun[0] + sun[1] * sun[1] + sun[2] * sun[2])
        present = sun_present and sun_norm > 0.0

        out: list[Transition] = []
        if self._pending:
            for to_mode, t_accepted, text in self._pending:
                out.append(self._enter(t, to_mode, f"ground command '{text}' accepted at t={t_accepted:.3f} s"))
            self._pending.clear()

        mode = self.mode
        if mode == 'mode_1a':
            thr = self.config.rate_thresholds_rad_s
            if present and abs(omega[0]) <= thr[0] and abs(omega[1]) <= thr[1] and abs(omega[2]) <= thr[2]:
                rates = ', '.join(f'|ω{a}|={deg(abs(omega[i])):.4f}≤{deg(thr[i]):.4f}'
                                  for i, a in enumerate(AXES))
                out.append(self._enter(t, 'mode_1b', f'rates below thresholds ({rates} deg/s) and sun present'))
                mode = self.mode
        if mode == 'mode_1b':
            if self.mode_1b_entry_t_s is None:
                self.mode_1b_entry_t_s = t  # started in Mode 1B (wheels on from separation)
            if not self.captured:
                out.extend(self._check_capture(t, omega, sun[2] / sun_norm if present else None))
        return out

    def _check_capture(self, t: float, omega: tuple[float, float, float], sun_z: float | None) -> list[Transition]:
        """Capture check; ``sun_z`` is the z component of the sun unit vector (None: sun absent)."""
        cfg = self.config
        angle = math.pi if sun_z is None else math.acos(max(-1.0, min(1.0, sun_z)))
        rate = cfg.capture_rate_rad_s
        if angle > cfg.capture_cone_rad or not (abs(omega[0]) <= rate and abs(omega[1]) <= rate
                                                and abs(omega[2]) <= rate):
            self._capture_since_t_s = None
            return []
        if self._capture_since_t_s is None:
            self._capture_since_t_s = t
        if t - self._capture_since_t_s < cfg.capture_dwell_s:
            return []
        self.captured = True
        self.capture_t_s = t
        out = [Transition(t, 'mode_1b', 'mode_1b',
                          f'acquisition capture: z {deg(angle):.2f}° from the sun line, rates nulled '
                          f'(max |ω| {deg(max(abs(w) for w in omega)):.4f} deg/s)', kind='capture')]
        if cfg.auto_cruise:
            out.append(self._enter(t, cfg.cruise_target, 'automatic transfer to cruise at acquisition capture'))
        return out

    def _enter(self, t: float, to_mode: str, cause: str) -> Transition:
        from_mode = self.mode
        self.mode = to_mode
        if to_mode not in HEAO_CRUISE_MODES:  # capture is latched in Mode 1B and kept in cruise only
            self.captured = False
            self._capture_since_t_s = None
        if to_mode == 'mode_1b':
            self.mode_1b_entry_t_s = t
        return Transition(t, from_mode, to_mode, cause)

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
