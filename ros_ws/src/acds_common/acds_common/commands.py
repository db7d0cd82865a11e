"""Typed ground commands: one object and one parser per command (spec §8; seed 002 §4.3, Table 5-2).

A ground command is text where it enters the graph (the scenario's ``modes.ground_commands`` and the live
``ground/command`` topic) and where the mode manager forwards it to the node that applies it (the
``command/<node>`` pairs of the ``mode`` report, :mod:`acds_common.mode_report`). Each end decodes the
text once, with the parser of its command here, and works on the typed object; :attr:`text` is the
object's one encoding (what is forwarded, normalised: keywords lower case, units upper case).
:class:`CommandError` carries the reason a text does not parse (the refusal the ground sees).

Grammar (whitespace separated, keywords case-insensitive)::

    mode <name>                              ModeCommand        applied by the mode manager
    eea_select <x|y|z> <A|B>                 EeaSelect          → em_driver (active driver + winding)
    magnetometer_select <A|B>                MagnetometerSelect → magnetometer_sim (active assembly)
    law <slot> <name>                        LawCommand         → acds_controller (slots, names: dpa_commands)
    gain <name> <value>                      GainCommand        → acds_controller (study units, dpa_commands)
    gas isolation <1|2> <open|close>         GasCommand         → cold_gas (Table 5-2), forwarded without 'gas'
    gas bank <on|off> | gas transducer <on|off>

Which commands a mode logic takes is its grammar (a tuple of these classes, :func:`decode`); whether a
command is allowed now (mode, gain range) is its logic's decision, not the parser's. A command only one
package knows has the same shape (``verb``, ``route``, ``parse``, ``text``) in that package: the em_driver's
``eea_failure``, the magnetometer's ``magnetometer_fault`` (for tools that talk to the node directly), the
SSS ASCS's ``sss …`` (:class:`ascs_mode_manager.sss_ascs.SssCommand`).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass
from typing import ClassVar, Protocol

AXES = ('x', 'y', 'z')
#: The redundant units of an assembly (EEA driver + winding, magnetometer).
UNITS = ('A', 'B')


class CommandError(ValueError):
    """A command text that does not parse; the message is the reason (a usage line)."""


class Command(Protocol):
    """What every command object has: its verb, the node that applies it ('' = the mode manager), its text."""

    verb: ClassVar[str]
    route: ClassVar[str]

    @property
    def text(self) -> str: ...


@dataclass(frozen=True)
class ModeCommand:
    """``mode <name>``: a mode transfer; the mode logic checks the name against its mode set."""

    target: str
    verb: ClassVar[str] = 'mode'
    route: ClassVar[str] = ''

    @classmethod
    def parse(cls, args: Sequence[str]) -> ModeCommand:
        """The words after the verb → the command."""
        if len(args) != 1:
            raise CommandError('usage: mode <name>')
        return cls(args[0].lower())

    @property
    def text(self) -> str:
        """The normalised command."""
        return f'mode {self.target}'


@dataclass(frozen=True)
class EeaSelect:
    """``eea_select <x|y|z> <A|B>``: the active electromagnet driver + winding of one axis (seed 002 §4.4)."""

    axis: int
    unit: str
    verb: ClassVar[str] = 'eea_select'
    route: ClassVar[str] = 'em_driver'

    @classmethod
    def parse(cls, args: Sequence[str]) -> EeaSelect:
        """The words after the verb → the command."""
        if len(args) != 2 or args[0].lower() not in AXES or args[1].upper() not in UNITS:
            raise CommandError('usage: eea_select <x|y|z> <A|B>')
        return cls(AXES.index(args[0].lower()), args[1].upper())

    @property
    def text(self) -> str:
        """The normalised command."""
        return f'eea_select {AXES[self.axis]} {self.unit}'


@dataclass(frozen=True)
class MagnetometerSelect:
    """``magnetometer_select <A|B>``: the active magnetometer assembly."""

    unit: str
    verb: ClassVar[str] = 'magnetometer_select'
    route: ClassVar[str] = 'magnetometer_sim'

    @classmethod
    def parse(cls, args: Sequence[str]) -> MagnetometerSelect:
        """The words after the verb → the command."""
        if len(args) != 1 or args[0].upper() not in UNITS:
            raise CommandError('usage: magnetometer_select <A|B>')
        return cls(args[0].upper())

    @property
    def text(self) -> str:
        """The normalised command."""
        return f'magnetometer_select {self.unit}'


@dataclass(frozen=True)
class LawCommand:
    """``law <slot> <name>``: the DPA's magnetic law of a slot (:data:`acds_common.dpa_commands.LAW_CHOICES`)."""

    slot: str
    name: str
    verb: ClassVar[str] = 'law'
    route: ClassVar[str] = 'acds_controller'

    @classmethod
    def parse(cls, args: Sequence[str]) -> LawCommand:
        """The words after the verb → the command."""
        if len(args) != 2:
            raise CommandError('usage: law <acquisition|unloading> <name>')
        return cls(args[0].lower(), args[1].lower())

    @property
    def text(self) -> str:
        """The normalised command."""
        return f'law {self.slot} {self.name}'


def finite_number(word: str, what: str) -> float:
    """A command's numeric word as a finite float; :class:`CommandError` naming ``what`` otherwise."""
    try:
        value = float(word)
    except ValueError:
        raise CommandError(f'{what} {word!r} is not a number') from None
    if not math.isfinite(value):
        raise CommandError(f'{what} {word!r} is not finite')
    return value


@dataclass(frozen=True)
class GainCommand:
    """``gain <name> <value>``: a DPA run-time gain, study units (:data:`acds_common.dpa_commands.GAIN_TABLE`)."""

    name: str
    value: float
    verb: ClassVar[str] = 'gain'
    route: ClassVar[str] = 'acds_controller'

    @classmethod
    def parse(cls, args: Sequence[str]) -> GainCommand:
        """The words after the verb → the command (a finite number)."""
        if len(args) != 2:
            raise CommandError('usage: gain <name> <value>')
        return cls(args[0].lower(), finite_number(args[1], 'gain value'))

    @property
    def text(self) -> str:
        """The normalised command (the value's repr: the receiver reads back the same float)."""
        return f'gain {self.name} {self.value!r}'


@dataclass(frozen=True)
class GasCommand:
    """``gas isolation <1|2> <open|close>`` | ``gas bank <on|off>`` | ``gas transducer <on|off>`` (Table 5-2).

    ``device``: 'isolation', 'bank' or 'transducer'; ``valve``: 1 or 2 for an isolation valve, else None;
    ``on``: open / power on. Forwarded to cold_gas without the verb (:attr:`text`: 'isolation 1 open').
    """

    device: str
    on: bool
    valve: int | None = None
    verb: ClassVar[str] = 'gas'
    route: ClassVar[str] = 'cold_gas'
    usage: ClassVar[str] = 'usage: gas isolation <1|2> <open|close> | gas bank <on|off> | gas transducer <on|off>'

    @classmethod
    def parse(cls, args: Sequence[str]) -> GasCommand:
        """The words after the verb (the forwarded text's words) → the command."""
        a = [w.lower() for w in args]
        if len(a) == 3 and a[0] == 'isolation' and a[1] in ('1', '2') and a[2] in ('open', 'close'):
            return cls('isolation', a[2] == 'open', int(a[1]))
        if len(a) == 2 and a[0] in ('bank', 'transducer') and a[1] in ('on', 'off'):
            return cls(a[0], a[1] == 'on')
        raise CommandError(cls.usage)

    @property
    def text(self) -> str:
        """The forwarded text (without the verb)."""
        if self.device == 'isolation':
            return f'isolation {self.valve} {"open" if self.on else "close"}'
        return f'{self.device} {"on" if self.on else "off"}'


def decode(text: str, grammar: Sequence[type], what: str = 'command',
           error: type[Exception] = CommandError) -> Command:
    """``text`` as one of the ``grammar``'s commands (chosen by its verb); ``error`` (a node's own error type,
    :class:`CommandError` by default) says why not.

    ``what`` names the grammar in the refusal of an unknown verb ("unknown <what> '<verb>'; known: …").
    """
    words = str(text).split()
    try:
        if not words:
            raise CommandError('empty command')
        verb = words[0].lower()
        for family in grammar:
            if family.verb == verb:
                return family.parse(words[1:])
        raise CommandError(f"unknown {what} '{verb}'; known: {', '.join(f.verb for f in grammar)}")
    except CommandError as exc:
        if error is CommandError:
            raise
        raise error(str(exc)) from None
