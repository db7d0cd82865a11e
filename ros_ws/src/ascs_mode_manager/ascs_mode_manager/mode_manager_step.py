"""ascs_mode_manager stepper: the on-board mode logic (spec §8).

One node; parameter ``modes_system`` selects the part that runs: ``heao`` (Mode 1A → 1B →
cruise, :mod:`ascs_mode_manager.heao_part`, stage ``heao``), ``sss`` (perigee automatic
turn-on, :mod:`ascs_mode_manager.sss_part`, stage ``sss``) or ``aap`` (the AAP Workshop's CMG
hold and magnetic dump, :mod:`ascs_mode_manager.aap_part`, stage ``aap``). The stepper owns what both
share: the ground-command intake (:mod:`ascs_mode_manager.ground_commands`: the scenario's
schedule and the live commands the host receives on ``ground/command``) and the answers on
``ground/ack`` (output ``ack``: every command is answered, accepted or refused with the
reason).
"""

from __future__ import annotations

from typing import Any

from acds_common.stepper import Stepper

from ascs_mode_manager.ground_commands import MAX_PENDING, GroundCommandQueue


class ModeManagerStep(Stepper):
    """Hosts the HEAO or the SSS mode logic."""

    node = 'ascs_mode_manager'

    def __init__(self, params: dict[str, Any], log: Any = None) -> None:
        super().__init__(params, log)
        self.modes = self.section('modes')
        self.sss_params = self.section('sss')
        self.commands = GroundCommandQueue(self.modes['ground_commands'])
        self._acks: list[str] = []
        if self.modes['system'] == 'sss':
            from ascs_mode_manager.sss_part import SssPart
            self.part: Any = SssPart(self)
        elif self.modes['system'] == 'aap':
            from ascs_mode_manager.aap_part import AapPart
            self.part = AapPart(self)
        else:
            from ascs_mode_manager.heao_part import HeaoPart
            self.part = HeaoPart(self)

    def receive_command(self, text: str) -> None:
        """A live ground command: applied at the next step this node computes (refused if the queue is full)."""
        if not self.commands.receive(text):
            self.acknowledge(f'refused {text!r}: dropped, {MAX_PENDING} commands already wait for the next step',
                             False)

    def acknowledge(self, line: str, accepted: bool) -> None:
        """Answer a ground command on ``ground/ack`` (refusals carry the reason) and log it."""
        self._acks.append(line)
        self.log('info' if accepted else 'warn', f'ground command {line}')

    def _stage(self, k: int, t_s: float, inp: dict[str, Any]) -> dict[str, Any]:
        out = self.part.step(k, t_s, inp)
        if self._acks:
            out['ack'], self._acks = self._acks, []
        return out

    def heao(self, k: int, t_s: float, inp: dict[str, Any]) -> dict[str, Any]:
        """Stage ``heao`` (HEAO mode logic)."""
        return self._stage(k, t_s, inp)

    def sss(self, k: int, t_s: float, inp: dict[str, Any]) -> dict[str, Any]:
        """Stage ``sss`` (SSS ASCS logic)."""
        return self._stage(k, t_s, inp)

    def aap(self, k: int, t_s: float, inp: dict[str, Any]) -> dict[str, Any]:
        """Stage ``aap`` (AAP Workshop mode logic)."""
        return self._stage(k, t_s, inp)
