"""HEAO part of the ascs_mode_manager stepper: Mode 1A → 1B → capture → cruise and ground commands (spec §8).

Stage ``heao`` of step k (inputs: gyro and sun sensor of step k from rigid_body):

1. ground commands: the scheduled ones (``modes.ground_commands``, "T_S: text") whose
   time has come (first step with t_k ≥ T_S), then the live ones received on
   ``ground/command`` since the previous step, in arrival order, are validated by the
   core; each is answered on ``ground/ack`` (the host's ``answer_due``: one line, accepted or refused with the
   reason, a refusal also a WARN diagnostic);
   accepted mode transfers are applied in this step, commands for other nodes are
   forwarded in this step's ``mode`` (key ``command/<node>``);
2. the on-board logic of :class:`~ascs_mode_manager.heao_modes.HeaoModeManager`;
3. ``mode`` (DiagnosticArray, every step): the step's
   :class:`~acds_common.mode_report.ModeReport` (encoded when it differs from the last step's): the mode,
   this step's transition causes ('' if none), the capture flag, the core's status keys, ``run_complete`` (from the
   capture step on when ``modes.stop_at_capture``: the time owner then ends the run after
   this step) and the forwarded commands;
4. ``events``: one line per transition, "t=<s> <from>-><to>: <cause>" (capture:
   "t=<s> capture in mode_1b: <cause>").

A live command received while step k is being computed is applied at step k+1 (the host
is single-threaded). Only the scheduled commands are tied to a sim time: they are the
deterministic way to command a run.

Compiled steps. The on-board logic is the kernel :func:`~ascs_mode_manager.heao_modes.heao_advance`; a
compiled caller stepping this part runs a step in the kernel only when the step would be *quiet* (outputs
``{'mode': <the last step's encoded report, the same object>}`` and nothing else, logs nothing), and
otherwise runs :meth:`HeaoPart.step` from the states at the start of the step. A step at t is NOT quiet when:

* a ground command is due: ``host.commands.next_s <= t + DUE_SLACK_S`` (a scheduled one whose time has come,
  or a live one received: ``next_s`` is then −inf); it is answered (``ack``), maybe forwarded or applied;
* the kernel says so: a transfer, a capture (and with ``modes.stop_at_capture`` the run's end), the Mode 1B
  entry stamp, a queued command, or a non-finite input (held here with a WARN diagnostic);
* the last step's report carried a cause or forwarded commands (this step's report, without them, differs),
  or there was no last step;
* the core is a variant's (the cold-gas logic adds its gas phases to the HEAO ``advance``).

:meth:`HeaoPart.fused_inputs` gives the caller what it needs (None when no step can be quiet now) and
:meth:`HeaoPart.fused_quiet` takes back the state after quiet steps and gives a quiet step's output. Across quiet
steps the caller carries the kernel's state from one step to the next; ``next_s`` changes only at a step that is
not quiet (the due commands are taken) or when a live command arrives (−inf). An absent gyro or sun sensor is the
zero vector, as :meth:`HeaoPart.step` reads it.
"""

from __future__ import annotations

import math
from typing import Any

from acds_common.cdr import Status
from acds_common.dpa_commands import GAIN_LIMITS, LAW_CHOICES
from acds_common.messages import MODE_STATUS, WARN, diagnostic
from acds_common.mode_report import ModeReport
from acds_common.modes import HEAO_CRUISE_MODES
from acds_common.validation import all_finite, scenario_key

from ascs_mode_manager.ground_commands import DUE_SLACK_S
from ascs_mode_manager.heao_modes import HeaoKernelParams, HeaoKernelState, HeaoModeConfig, HeaoModeManager, Transition
from ascs_mode_manager.spin_mechanizations import AscsError

#: An absent gyro or sun sensor input: the zero vector (the sun then reads as absent).
_ABSENT = (0.0, 0.0, 0.0)


def event_text(tr: Transition) -> str:
    """The ``events`` line of a transition."""
    if tr.kind == 'capture':
        return f't={tr.t_s:.1f} capture in {tr.to_mode}: {tr.cause}'
    return f't={tr.t_s:.1f} {tr.from_mode}->{tr.to_mode}: {tr.cause}'


def heao_config(m: dict[str, Any]) -> HeaoModeConfig:
    """The HEAO mode logic's configuration from the scenario's ``modes`` section (SI values)."""
    initial = m['initial_mode']
    return HeaoModeConfig(
        rate_thresholds_rad_s=tuple(m['rate_thresholds']),
        capture_cone_rad=m['capture_cone'], capture_rate_rad_s=m['capture_rate'],
        cruise_target=m['cruise_target'], auto_cruise=m['auto_cruise'],
        wheels_on_from_separation=initial == 'mode_1b',
        initial_mode='standby' if initial == 'standby' else 'mode_1a',
        gain_limits=GAIN_LIMITS, law_choices=LAW_CHOICES)


def build_core(m: dict[str, Any]) -> HeaoModeManager:
    """The HEAO mode manager core from the scenario's ``modes`` section (SI values).

    ``initial_mode`` mode_1b is Table 4-7 case 6 (wheels on from separation); a cruise mode
    starts a normal-mode run (§4.3.2) in cruise, already captured (the acquisition is not
    simulated).
    """
    initial = m['initial_mode']
    core = HeaoModeManager(heao_config(m))
    if initial in HEAO_CRUISE_MODES:
        core.mode = initial
        core.captured = True
    return core


class HeaoPart:
    """The HEAO mode logic of the mode-manager stepper (module docstring)."""

    #: The core from the ``modes`` section (a variant's part, e.g. the cold-gas acquisition's, builds its own).
    build_core = staticmethod(build_core)

    def __init__(self, host: Any) -> None:
        self.host = host
        m = host.modes
        with scenario_key('modes', AscsError):
            self.core = self.build_core(m)
        self.stop_at_capture = m['stop_at_capture']
        self.run_complete = False
        #: The last step's report fields (the core's status as its values) and its encoded ``mode`` value (reused
        #: while the fields stay the same).
        self._report: tuple[Any, ...] = ()
        self._mode_value: tuple[Status, ...] = ()

    def step(self, k: int, t: float, inp: dict[str, Any]) -> dict[str, Any]:
        """One step of the mode logic: ``mode`` (always), ``events`` (on transitions), ``diagnostics``."""
        diagnostics: list[Status] = []
        host = self.host
        accepted = host.answer_due(t, diagnostics) if host.commands.next_s <= t + DUE_SLACK_S else ()
        forwarded = tuple((result.route, result.command or text)
                          for text, result in accepted if result.route is not None) if accepted else ()
        gyro, sun = inp['gyro'], inp['sun']
        omega = _ABSENT if gyro is None else gyro[0]
        if sun is None:
            sun = _ABSENT
        # all_finite's one sum, written out on the per-step path; all_finite decides when the sum is not finite.
        if (math.isfinite(omega[0] + omega[1] + omega[2] + sun[0] + sun[1] + sun[2])
                or all_finite((*omega, *sun))):
            # Checked here, t_k from the host's step clock: the core's unchecked path. The sun sensor sends a zero
            # vector when the sun is absent, which the core reads as absent.
            transitions = self.core.advance(t, omega, sun, True)
        else:
            transitions = []
            message = f'non-finite gyro/sun input rejected at step {k}: mode logic held'
            host.log('warn', message)
            diagnostics.extend(diagnostic(MODE_STATUS, {}, message, WARN))
        events = []
        for tr in transitions:
            if tr.kind == 'capture' and self.stop_at_capture:
                self.run_complete = True
            text = event_text(tr)
            host.log('info', text)
            events.append(text)
        core = self.core
        cause = '; '.join(tr.cause for tr in transitions) if transitions else ''
        report = (core.mode, cause, core.captured, core.status_state(), self.run_complete, forwarded)
        if report != self._report:  # most steps report what the last one did: its encoding is reused
            self._report = report
            self._mode_value = ModeReport(core.mode, cause, core.captured, tuple(core.status().items()),
                                          self.run_complete, forwarded).encode()
        out: dict[str, Any] = {'mode': self._mode_value}
        if events:
            out['events'] = events
        if diagnostics:
            out['diagnostics'] = tuple(diagnostics)
        return out

    def fused_inputs(self) -> tuple[HeaoKernelParams, HeaoKernelState, float] | None:
        """For a compiled caller (module docstring, "Compiled steps"): the core's kernel parameters and state and
        the time the next ground command is due (``host.commands.next_s``: a step at t with ``next_s <= t +
        DUE_SLACK_S`` is not quiet); None when no step can be quiet now (a variant's core, or the last step's report
        has a cause or forwarded commands, or there was none)."""
        report = self._report
        if type(self.core).advance is not HeaoModeManager.advance or not report or report[1] or report[5]:
            return None
        return self.core.kernel_params(), self.core.kernel_state(), self.host.commands.next_s

    def fused_quiet(self, state: HeaoKernelState) -> dict[str, Any]:
        """After quiet steps of :func:`~ascs_mode_manager.heao_modes.heao_advance` from :meth:`fused_inputs`: the
        core takes the last one's ``state``; returns a quiet step's output (the last report, the same object)."""
        self.core.set_kernel_state(state)
        return {'mode': self._mode_value}
