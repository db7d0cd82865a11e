"""Ground-command intake of the mode manager (spec §8: "transfers happen on board or by ground command").

Two sources feed one queue: the scenario's schedule (``modes.ground_commands``,
entries "T_S: command", applied at the first step with t_k ≥ T_S — deterministic)
and live commands received on ``ground/command`` (applied at the next step the
mode manager computes). The text is parsed where it enters, by the mode logic's
``parse`` (its grammar of :mod:`acds_common.commands` objects): the logic then
validates the command object (``apply``) and answers with a :class:`CommandResult`.
A text that does not parse is refused with the parser's reason. Every mode logic
(HEAO, cold-gas, SSS, AAP) takes its commands here.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass
from typing import Protocol

from acds_common.commands import Command, CommandError

from ascs_mode_manager.spin_mechanizations import AscsError


@dataclass(frozen=True)
class CommandResult:
    """Answer to a ground command: accepted or refused with a reason.

    ``route``: the node that must apply it ('em_driver', 'magnetometer_sim', 'acds_controller', 'cold_gas'),
    None for commands the mode logic applies itself. ``command``: the command's normalised text.
    """

    accepted: bool
    reason: str
    route: str | None = None
    command: str | None = None


def refuse(reason: str) -> CommandResult:
    """A refusal with its reason."""
    return CommandResult(False, reason)


class ModeLogic(Protocol):
    """What a mode logic offers the intake: its parser and its validation of a parsed command."""

    def parse(self, text: str) -> Command: ...

    def apply(self, cmd: Command, t_s: float) -> CommandResult: ...


#: A parsed command, or why its text does not parse.
Parsed = Command | CommandError


def parse(logic: ModeLogic, text: str) -> Parsed:
    """``text`` parsed by the logic's grammar; the :class:`CommandError` itself when it does not parse."""
    try:
        return logic.parse(text)
    except CommandError as exc:
        return exc


def answer(logic: ModeLogic, parsed: Parsed, t_s: float) -> CommandResult:
    """The logic's answer to a parsed command received at sim time ``t_s`` (s) (a parse error: refused)."""
    return refuse(str(parsed)) if isinstance(parsed, CommandError) else logic.apply(parsed, t_s)


def submit(logic: ModeLogic, text: str, t_s: float) -> CommandResult:
    """Parse and answer one command text at sim time ``t_s`` (s): tools (the SSS test stand) and tests."""
    return answer(logic, parse(logic, text), t_s)


def ack_line(t_s: float | None, source: str, text: str, result: CommandResult) -> str:
    """The one answer line on ``ground/ack``, for every mode logic: ``t=<s> accepted|refused (scheduled|live)
    '<text as received>': <reason>``; ``t_s`` None for a live command refused before any step took it."""
    when = '' if t_s is None else f't={t_s:.2f} '
    return f"{when}{'accepted' if result.accepted else 'refused'} ({source}) {text!r}: {result.reason}"


def parse_schedule(entries: list[str]) -> list[tuple[float, str]]:
    """``["T_S: command", ...]`` → [(T_S, command)] sorted by time (stable); AscsError naming a bad entry."""
    out = []
    for entry in entries:
        head, sep, text = str(entry).partition(':')
        try:
            t_s = float(head)
        except ValueError:
            t_s = math.nan
        if not sep or not math.isfinite(t_s) or t_s < 0.0 or not text.strip():
            raise AscsError(f'modes.ground_commands entry {entry!r} is not "T_S: command" (T_S seconds ≥ 0)')
        out.append((t_s, text.strip()))
    return sorted(out, key=lambda e: e[0])


#: Live commands that may wait for the next step; more are refused at once (never dropped silently).
MAX_PENDING = 5000
#: A scheduled command is due at the first step with T_S ≤ t_k + DUE_SLACK_S (s): a step clock's rounding.
DUE_SLACK_S = 1e-9


class GroundCommandQueue:
    """Scheduled and live ground commands, parsed on entry, handed out step by step."""

    def __init__(self, schedule: list[str], parser: Callable[[str], Parsed]) -> None:
        self._parse = parser
        self._scheduled = [(t_s, text, parser(text)) for t_s, text in parse_schedule(schedule)]
        self._live: list[tuple[str, Parsed]] = []
        #: Sim time (s) of the first waiting command: the next scheduled one's T_S, -inf while live ones wait, inf
        #: when none waits. Commands are due at the step at t_s when ``next_s <= t_s + DUE_SLACK_S`` (the
        #: per-step test that spares most steps the call of :meth:`due`).
        self.next_s = self._next_s()

    def _next_s(self) -> float:
        return -math.inf if self._live else self._scheduled[0][0] if self._scheduled else math.inf

    def receive(self, text: str) -> bool:
        """A live command: parsed and queued for the next step; False when the queue is full (the caller
        refuses it)."""
        if len(self._live) >= MAX_PENDING:
            return False
        self._live.append((text, self._parse(text)))
        self.next_s = -math.inf
        return True

    def due(self, t_s: float) -> list[tuple[str, Parsed, str]]:
        """Commands to apply at the step at ``t_s``: (text, parsed, 'scheduled'|'live'), scheduled first."""
        out = []
        while self._scheduled and self._scheduled[0][0] <= t_s + DUE_SLACK_S:
            _, text, parsed = self._scheduled.pop(0)
            out.append((text, parsed, 'scheduled'))
        if self._live:
            out.extend((text, parsed, 'live') for text, parsed in self._live)
            self._live = []
        self.next_s = self._next_s()
        return out
