"""AAP Workshop mode logic: CMG attitude hold with or without the magnetic momentum dump (seed 000 §1, §4, §13).

Seed: ``000_aap_cmg_dump_levidow.txt``. The Workshop's CMGs hold its attitude ("the momentum exchange action of
the control moment gyros used for attitude control", §1) and the magnetic dump runs on top of it, automatically
("Operation is automatic and momentum dump attitude maneuvers are eliminated", abstract): the computer samples
H_s each orbit and commands the magnet. No on-board transfer is described, so the modes change only by ground
command. Modes (the strings the controller's Workshop computer takes):

* ``'cmg_dump'``: CMG hold and the magnetic dump (the seed's operating mode);
* ``'cmg_hold'``: CMG hold, magnets off (the bias momentum accumulates in the CMGs, §1);
* ``'standby'``: nothing commanded.

Ground command grammar: ``mode <cmg_dump|cmg_hold|standby>``, accepted from any other mode and applied at the
next step; anything else is refused with the reason.
"""

from __future__ import annotations

from acds_common.commands import CommandError, ModeCommand, decode
from acds_common.modes import WORKSHOP_INITIAL_MODES, WORKSHOP_MODES

from ascs_mode_manager.ground_commands import CommandResult, refuse
from ascs_mode_manager.heao_modes import Transition
from ascs_mode_manager.spin_mechanizations import AscsError


class WorkshopModeManager:
    """The Workshop's mode and its ground commands."""

    def __init__(self, initial_mode: str) -> None:
        if initial_mode not in WORKSHOP_INITIAL_MODES:
            raise AscsError(f'initial_mode {initial_mode!r} is not a Workshop mode to start in; choose one of '
                            f'{WORKSHOP_INITIAL_MODES}')
        self.mode = initial_mode
        self._pending: list[tuple[str, float]] = []

    #: The one command this logic takes.
    grammar = (ModeCommand,)

    def parse(self, text: str) -> ModeCommand:
        """A ground command's text → its command (:class:`CommandError`: the reason it does not parse)."""
        try:
            return decode(text, self.grammar)
        except CommandError:
            raise CommandError(f'the Workshop mode logic takes only "mode <{"|".join(WORKSHOP_MODES)}>"') from None

    def apply(self, cmd: ModeCommand, t_s: float) -> CommandResult:
        """Validate a parsed mode command received at sim time ``t_s`` (s); accepted, it applies at the next step."""
        target = cmd.target
        if target not in WORKSHOP_MODES:
            return refuse(f"unknown mode '{target}'; Workshop modes: {', '.join(WORKSHOP_MODES)}")
        current = self._pending[-1][0] if self._pending else self.mode
        if target == current:
            return refuse(f'wrong mode: already in {current}')
        self._pending.append((target, float(t_s)))
        return CommandResult(True, f'{current} → {target} at the next step', None, cmd.text)

    def step(self, t_s: float) -> list[Transition]:
        """Apply the mode transfers accepted before this step (at sim time ``t_s``); return them."""
        out = []
        for target, t_cmd in self._pending:
            out.append(Transition(float(t_s), self.mode, target, f'ground command at t={t_cmd:.1f}'))
            self.mode = target
        self._pending = []
        return out
