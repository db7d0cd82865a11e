"""The mode manager's report of one step, typed: mode, run control and forwarded commands (spec §8).

On the wire it is the ``mode`` DiagnosticArray (standard ``diagnostic_msgs``): one status named
:data:`~acds_common.messages.MODE_STATUS` whose message is the mode and whose key/value pairs are, in this
order, ``mode``, ``cause`` (this step's transition causes, '' if none), ``captured`` ('true'/'false':
acquisition capture latched), the mode logic's own status keys, ``run_complete`` ('true'/'false'; absent
for a mode logic that never ends a run, the SSS ASCS) and one ``command/<node>`` pair per ground command
forwarded to ``node`` (in acceptance order). :meth:`ModeReport.encode` and :meth:`ModeReport.decode` are the
one place that layout is written and read: the mode manager encodes, every other node decodes, and no
one compares the text 'true' itself.
"""

from __future__ import annotations

from collections.abc import Callable, Iterable, Sequence
from dataclasses import dataclass
from typing import Generic, TypeVar

from acds_common.cdr import Status
from acds_common.messages import MODE_STATUS, OK

#: Key prefix of a forwarded ground command: ``command/<node>``.
COMMAND_PREFIX = 'command/'
_FLAG = {True: 'true', False: 'false'}
T = TypeVar('T')
_RESERVED = ('mode', 'cause', 'captured', 'run_complete')


@dataclass(frozen=True)
class ModeReport:
    """One step of the mode manager (module docstring).

    ``status``: the mode logic's own (key, text) telemetry. ``run_complete``: the time owner ends the run
    after this step; None for a mode logic that never asks it (the key is then not sent). ``forwarded``:
    (node, command text) pairs, the text as :mod:`acds_common.commands` encodes it.
    """

    mode: str
    cause: str = ''
    captured: bool = False
    status: tuple[tuple[str, str], ...] = ()
    run_complete: bool | None = False
    forwarded: tuple[tuple[str, str], ...] = ()

    def encode(self, level: int = OK) -> tuple[Status]:
        """The ``mode`` DiagnosticArray value."""
        values = [('mode', self.mode), ('cause', self.cause), ('captured', _FLAG[self.captured]), *self.status]
        if self.run_complete is not None:
            values.append(('run_complete', _FLAG[self.run_complete]))
        values.extend((COMMAND_PREFIX + node, text) for node, text in self.forwarded)
        return (Status(level, MODE_STATUS, self.mode, MODE_STATUS, tuple(values)),)

    @classmethod
    def from_values(cls, message: str, values: Iterable[tuple[str, str]]) -> ModeReport:
        """The report from the mode status's message and key/value pairs (a bag reader's view too)."""
        keyed: dict[str, str] = {}
        status, forwarded = [], []
        for key, value in values:
            if key.startswith(COMMAND_PREFIX):
                forwarded.append((key[len(COMMAND_PREFIX):], value))
            elif key in _RESERVED:
                keyed.setdefault(key, value)
            else:
                status.append((key, value))
        run_complete = keyed.get('run_complete')
        return cls(keyed.get('mode', message), keyed.get('cause', ''), keyed.get('captured') == _FLAG[True],
                   tuple(status), None if run_complete is None else run_complete == _FLAG[True], tuple(forwarded))

    @classmethod
    def decode(cls, value: Sequence[Status] | None) -> ModeReport | None:
        """The report in a ``mode`` DiagnosticArray value; None when absent (no mode manager, or before it speaks)."""
        status = _mode_status(value)
        return None if status is None else cls.from_values(status.message, status.values)

    def commands_for(self, node: str) -> list[str]:
        """The command texts forwarded to ``node`` this step, in order."""
        return [text for route, text in self.forwarded if route == node]


def _mode_status(value: Sequence[Status] | None) -> Status | None:
    for status in value or ():
        if status.name == MODE_STATUS:
            return status
    return None


def mode_status(value: Sequence[Status] | None, node: str) -> tuple[str | None, list[str]]:
    """(mode, commands forwarded to ``node`` in order) from the step's ``mode`` value; (None, []) if absent.

    What every node reads each step: the two fields alone, without building the whole :class:`ModeReport`.
    """
    status = _mode_status(value)
    if status is None:
        return None, []
    mode, key, commands = status.message, COMMAND_PREFIX + node, []
    for k, v in status.values:  # one pass: the last 'mode' pair (there is one), every command in order
        if k == 'mode':
            mode = v
        elif k == key:
            commands.append(v)
    return mode, commands


class ModeValueReader(Generic[T]):
    """``read(value)`` kept for the last ``mode`` value read: what a node or summary reads of the mode each step.

    The mode manager hands on the same value object while its report stays the same (it reuses its encoding),
    and the direct engine passes that object on in memory: most steps then read nothing. A value is an immutable
    tuple of :class:`Status`, so the same object means the same fields; a node process decodes a new object every
    step and reads it every step. The result returned is the one kept: the caller reads it, never changes it.
    """

    def __init__(self, read: Callable[[Sequence[Status] | None], T]) -> None:
        self._read = read
        self._value: Sequence[Status] | None = None
        self._result = read(None)

    def __call__(self, value: Sequence[Status] | None) -> T:
        """``read(value)``, computed only when ``value`` is another object than the last one."""
        if value is not self._value:
            self._value, self._result = value, self._read(value)
        return self._result


class ModeStatusReader(ModeValueReader[tuple[str | None, list[str]]]):
    """:func:`mode_status` for one node (mode, commands forwarded to it in order), kept for the last value read."""

    def __init__(self, node: str) -> None:
        self.node = node
        super().__init__(lambda value: mode_status(value, node))


def mode_state(value: Sequence[Status] | None) -> tuple[str, str, bool] | None:
    """(mode, cause, captured) of the step's ``mode`` value, as :meth:`ModeReport.decode` gives them; None if
    absent. What a run summary reads each step: the three keys alone, without building the whole report."""
    status = _mode_status(value)
    if status is None:
        return None
    mode = cause = captured = None
    for key, text in status.values:
        if key == 'mode':
            mode = text if mode is None else mode
        elif key == 'cause':
            cause = text if cause is None else cause
        elif key == 'captured':
            captured = text if captured is None else captured
    return (status.message if mode is None else mode), cause or '', captured == _FLAG[True]


def transitions(history: list[tuple[float, str, str, bool]]) -> list[dict[str, object]]:
    """Mode changes and the acquisition capture as [{t_min, from, to, cause}] (capture: to = 'capture') from the
    (t s, mode, cause, captured) of each step (:func:`mode_state`): a run summary's list and a plot's marks."""
    out: list[dict[str, object]] = []
    prev_mode, prev_captured = None, None
    for t, mode, cause, captured in history:
        if prev_mode is not None and mode != prev_mode:
            out.append({'t_min': t / 60, 'from': prev_mode, 'to': mode, 'cause': cause or None})
        if captured and prev_captured is False and (prev_mode == mode or prev_mode is None):
            out.append({'t_min': t / 60, 'from': mode, 'to': 'capture', 'cause': cause or None})
        prev_mode, prev_captured = mode, captured
    return out


def run_complete(value: Sequence[Status] | None) -> bool:
    """Whether the step's ``mode`` value asks the time owner to end the run (read each step: the one key alone)."""
    status = _mode_status(value)
    if status is not None:
        for key, text in status.values:
            if key == 'run_complete':
                return text == _FLAG[True]
    return False
