"""Ground-command intake of the mode manager (spec §8: "transfers happen on board or by ground command").

Two sources feed one queue: the scenario's schedule (``modes.ground_commands``,
entries "T_S: command", applied at the first step with t_k ≥ T_S — deterministic)
and live commands received on ``ground/command`` (applied at the next step the
mode manager computes). The HEAO and the SSS logic both take their commands here.
"""

from __future__ import annotations

import math

from ascs_mode_manager.spin_mechanizations import AscsError


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


class GroundCommandQueue:
    """Scheduled and live ground commands, handed out step by step."""

    def __init__(self, schedule: list[str]) -> None:
        self._scheduled = parse_schedule(schedule)
        self._live: list[str] = []

    def receive(self, text: str) -> bool:
        """A live command: queued for the next step; False when the queue is full (the caller refuses it)."""
        if len(self._live) >= MAX_PENDING:
            return False
        self._live.append(text)
        return True

    def due(self, t_s: float) -> list[tuple[str, str]]:
        """Commands to apply at the step at ``t_s``: (text, 'scheduled'|'live'), scheduled first."""
        out = []
        while self._scheduled and self._scheduled[0][0] <= t_s + 1e-9:
            out.append((self._scheduled.pop(0)[1], 'scheduled'))
        if self._live:
            out.extend((text, 'live') for text in self._live)
            self._live = []
        return out
