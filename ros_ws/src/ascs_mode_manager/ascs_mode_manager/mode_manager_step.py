"""ascs_mode_manager steppers: the on-board mode logic (spec §8), one stepper per system.

The scenario's ``modes.system`` picks the variant (``ascs_mode_manager.nodes``): HEAO (Mode 1A → 1B →
cruise, :mod:`ascs_mode_manager.heao_part`; with the cold-gas acquisition in front,
:mod:`ascs_mode_manager.cold_gas_part`), SSS (perigee automatic turn-on,
:mod:`ascs_mode_manager.sss_part`) or AAP (the Workshop's CMG hold and magnetic dump,
:mod:`ascs_mode_manager.aap_part`). Each runs its part in stage ``mode_logic``; what they share is
:class:`ModeManagerStep`: the ground-command intake (:mod:`ascs_mode_manager.ground_commands`: the
scenario's schedule and the live commands the host receives on ``ground/command``) and the answers on
``ground/ack`` (output ``ack``: every command is answered, accepted or refused with the reason).
"""

from __future__ import annotations

from typing import Any, ClassVar

from acds_common import kernels
from acds_common.cdr import Status
from acds_common.fused import FusedStage
from acds_common.messages import MODE_STATUS, WARN, diagnostic
from acds_common.stepper import Stepper

from ascs_mode_manager.aap_part import AapPart
from ascs_mode_manager.cold_gas_part import ColdGasPart
from ascs_mode_manager.ground_commands import (
    DUE_SLACK_S,
    MAX_PENDING,
    CommandResult,
    GroundCommandQueue,
    ack_line,
    answer,
    parse,
    refuse,
)
from ascs_mode_manager.heao_modes import heao_advance
from ascs_mode_manager.heao_part import HeaoPart
from ascs_mode_manager.sss_part import SssPart


@kernels.helper
def heao_logic_fused(p: tuple, s: tuple, _k: int, t_s: float, gyro: Any, sun: Any) -> tuple:
    """Stage ``mode_logic`` of the HEAO part as a kernel (:mod:`acds_common.fused`;
    :mod:`ascs_mode_manager.heao_part`, "Compiled steps"): quiet when no ground command is due and
    :func:`~ascs_mode_manager.heao_modes.heao_advance` is quiet. ``p``: (the core's kernel parameters, the time the
    next ground command is due); ``s``: the core's kernel state."""
    params, next_s = p
    quiet, new = heao_advance(params, s, t_s, gyro[0], sun)
    quiet = quiet and next_s > t_s + DUE_SLACK_S
    return quiet, (new if quiet else s)


class ModeManagerStep(Stepper):
    """What every mode logic shares: ground commands in, answers out; ``part`` is the variant's logic."""

    node = 'ascs_mode_manager'
    #: The mode logic this variant runs, built with the stepper as its host.
    part: ClassVar[type]

    def __init__(self, params: dict[str, Any], log: Any = None) -> None:
        super().__init__(params, log)
        self.modes = self.section('modes')
        self.sss_params = self.section('sss')
        self._acks: list[str] = []
        self.logic = self.part(self)
        self.commands = GroundCommandQueue(self.modes['ground_commands'], lambda text: parse(self.logic.core, text))

    def receive_command(self, text: str) -> None:
        """A live ground command: applied at the next step this node computes (refused if the queue is full)."""
        if not self.commands.receive(text):
            self._acknowledge(ack_line(None, 'live', text, refuse(
                f'dropped, {MAX_PENDING} commands already wait for the next step')), False)

    def answer_due(self, t_s: float, diagnostics: list[Status]) -> list[tuple[str, CommandResult]]:
        """Answer every ground command due at the step at ``t_s`` (s) with the part's mode logic: each answered
        on ``ground/ack`` (:func:`~ascs_mode_manager.ground_commands.ack_line`), a refusal also as a WARN
        diagnostic; returns the accepted ones as (text as received, result), in order."""
        accepted = []
        for text, parsed, source in self.commands.due(t_s):
            result = answer(self.logic.core, parsed, t_s)
            self._acknowledge(ack_line(t_s, source, text, result), result.accepted)
            if result.accepted:
                accepted.append((text, result))
            else:
                diagnostics.extend(diagnostic(MODE_STATUS, {'command': text, 'reason': result.reason},
                                              'ground command refused', WARN))
        return accepted

    def _acknowledge(self, line: str, accepted: bool) -> None:
        """Answer a ground command on ``ground/ack`` (refusals carry the reason) and log it."""
        self._acks.append(line)
        self.log('info' if accepted else 'warn', f'ground command {line}')

    def fused(self, stage: str, _held: dict[str, Any]) -> FusedStage | None:
        """Stage ``mode_logic`` as :func:`heao_logic_fused` (:mod:`acds_common.fused`) for the HEAO part (its
        ``fused_inputs``), or None: another part, answers waiting, or no gyro and sun sensor in the graph."""
        inputs = getattr(self.logic, 'fused_inputs', None)
        if stage != 'mode_logic' or inputs is None or self._acks or not self.present('rigid_body'):
            return None
        parts = inputs()
        if parts is None:
            return None
        params, state, next_s = parts
        held = self.logic.fused_quiet(state)  # the state as it is; a quiet step's output
        return FusedStage(heao_logic_fused, (params, float(next_s)), state, ('gyro', 'sun'), (),
                          self.logic.fused_quiet, held)

    def mode_logic(self, k: int, t_s: float, inp: dict[str, Any]) -> dict[str, Any]:
        """Stage ``mode_logic``: one step of the mode logic, with the answers to the commands it took."""
        out = self.logic.step(k, t_s, inp)
        if self._acks:
            out['ack'], self._acks = self._acks, []
        return out


class HeaoModeManagerStep(ModeManagerStep):
    """The HEAO mode logic (``modes.system: heao``)."""

    part = HeaoPart


class ColdGasModeManagerStep(ModeManagerStep):
    """The HEAO mode logic with the cold-gas acquisition (``modes.system: heao_cold_gas``, seed 002 §3.1)."""

    part = ColdGasPart


class SssModeManagerStep(ModeManagerStep):
    """The SSS ASCS logic (``modes.system: sss``)."""

    part = SssPart


class AapModeManagerStep(ModeManagerStep):
    """The AAP Workshop mode logic (``modes.system: aap``)."""

    part = AapPart
