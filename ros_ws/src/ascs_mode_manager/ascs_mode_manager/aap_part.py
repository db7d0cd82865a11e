"""AAP Workshop part of the ascs_mode_manager stepper (``modes.system: aap``; seed 000).

Plumbing only: the logic is :class:`ascs_mode_manager.workshop_modes.WorkshopModeManager`.

Stage ``aap`` of step k has no lockstep input (it is paced by ``/clock``): the Workshop's modes change only
by ground command. Per step, in this order: the due ground commands (scheduled, then live) are validated
and answered on ``ground/ack``; the accepted mode transfers are applied; ``mode`` (DiagnosticArray, every
step) carries status ``ascs_mode_manager`` with message = mode and keys ``mode``, ``cause`` (this step's
transition causes), ``captured`` ('false': no acquisition here), ``run_complete`` ('false');
``events`` one line per transfer, "t=<s> <from>-><to>: <cause>"; a refused command also goes on
``diagnostics`` (WARN) with the reason.
"""

from __future__ import annotations

from typing import Any

from acds_common.cdr import Status
from acds_common.mode_report import ModeReport
from acds_common.validation import scenario_key

from ascs_mode_manager.heao_part import event_text
from ascs_mode_manager.spin_mechanizations import AscsError
from ascs_mode_manager.workshop_modes import WorkshopModeManager


class AapPart:
    """The Workshop mode logic of the mode-manager stepper (module docstring)."""

    def __init__(self, host: Any) -> None:
        self.host = host
        with scenario_key('modes', AscsError):
            self.core = WorkshopModeManager(host.modes['initial_mode'])

    def step(self, k: int, t: float, _inp: dict[str, Any]) -> dict[str, Any]:
        """One step: ground commands, mode transfers, ``mode`` (always), ``events``, ``diagnostics``."""
        diagnostics: list[Status] = []
        self.host.answer_due(t, diagnostics)
        transitions = self.core.step(t)
        events = [event_text(tr) for tr in transitions]
        for text in events:
            self.host.log('info', text)
        report = ModeReport(self.core.mode, '; '.join(tr.cause for tr in transitions))
        out: dict[str, Any] = {'mode': report.encode()}
        if events:
            out['events'] = events
        if diagnostics:
            out['diagnostics'] = tuple(diagnostics)
        return out
