"""Scenario section → drive assembly, and the forwarded-command grammar (pure, no rclpy).

The node (``em_driver_node``) receives the ``em_driver`` scenario section as SI values
({field: value}, see ``acds_common.scenario.SCHEMA['em_driver']``) and builds its coils here,
by ``driver_kind``:

* ``electromagnet``: the :class:`~em_driver.drive_assembly.DriveAssembly` of the HEAO/SSS coils
  (``drive_types``, ``coil_*``, ``supply_v``, ``epsilon``, ``band_floor_a``);
* ``torque_rod``: the :class:`~em_driver.torque_rod.TorqueRodAssembly` of seed 003, the rod of
  ``torque_rod_design`` (a ``design-torque-rod --json`` record) on every body axis, each winding
  on its PWM H-bridge (20 kHz, 10 bits) from ``supply_v`` with the record's bridge resistance
  (the design's R = V²/P − R_bridge assumes it). Both assemblies have the same interface
  (``step(moment_command_am2, dt_s) -> AssemblyResult``, ``select_eea``, ``inject_failure``), so
  the node, its topics and the commands below are the same; ``mismatch_settle`` applies to the
  electromagnets only (a rod settles within milliseconds, one control period decides).

Commands forwarded by ascs_mode_manager in the ``mode`` report (key ``command/em_driver``),
whitespace separated, keywords case-insensitive (:class:`acds_common.commands.EeaSelect`, :class:`EeaFailure`)::

    eea_select <x|y|z> <A|B>                                          active driver + winding
    eea_failure <x|y|z> <A|B> <open_winding|stuck_on_bridge|dead_driver|none>

(the HEAO mode manager's ground grammar forwards ``eea_select``; ``eea_failure`` is for
tools and tests that talk to the node directly).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any, ClassVar

from acds_common.commands import AXES, UNITS, CommandError, EeaSelect, decode
from acds_common.torque_rod_record import TorqueRodRecordError, read_torque_rod_record
from acds_common.validation import scenario_key

from em_driver.bridge_switch import CoilFault, CoilParams, DriverParams, EmDriverError
from em_driver.drive_assembly import AxisConfig, DriveAssembly
from em_driver.torque_rod import PwmDriverParams, TorqueRodAssembly
from em_driver.torque_rod_design import load_rod

__all__ = ['EeaFailure', 'apply_command', 'axis_configs', 'build_assembly', 'build_torque_rods', 'parse_command']

_FAILURES = tuple(f.value for f in CoilFault)


def axis_configs(section: dict[str, Any]) -> list[AxisConfig]:
    """Per-axis coil, driver and drive type from the section.

    Bridge-switch axes use the Fig. 4-10 drops (V_ces 0.35 V, ED 0.6 V) with the section's
    supply, ε and band floor; constant-level (SSS) axes switch the supply straight on
    (V_ces = 0), so their current tends to supply_v / R (seed 001).
    """
    out = []
    for i in range(3):
        coil = CoilParams(resistance_ohm=section['coil_resistance_ohm'][i],
                          inductance_h=section['coil_inductance_h'][i],
                          moment_per_amp_am2=section['coil_moment_per_amp_am2'][i],
                          max_moment_am2=section['coil_max_moment_am2'][i])
        drive_type = section['drive_types'][i]
        driver = DriverParams(supply_v=section['supply_v'], epsilon=section['epsilon'],
                              band_floor_a=section['band_floor_a'],
                              **({'v_ces_v': 0.0} if drive_type == 'constant_level' else {}))
        out.append(AxisConfig(drive_type, coil, driver))
    return out


def build_assembly(section: dict[str, Any]) -> DriveAssembly | TorqueRodAssembly:
    """The three-axis redundant drive assembly the section describes (failures come at failure_time)."""
    if section['driver_kind'] == 'torque_rod':
        return build_torque_rods(section)
    return DriveAssembly(axis_configs(section), auto_switch_to_standby=section['auto_switch_to_standby'],
                         mismatch_tolerance_frac=section['mismatch_tolerance_frac'],
                         mismatch_settle_s=section['mismatch_settle'])


def build_torque_rods(section: dict[str, Any]) -> TorqueRodAssembly:
    """Three rods of the ``torque_rod_design`` record, PWM from ``supply_v`` (module docstring)."""
    with scenario_key('torque_rod_design', EmDriverError):
        try:
            record = read_torque_rod_record(section['torque_rod_design'])
        except TorqueRodRecordError as exc:
            raise EmDriverError(str(exc)) from None
        rod = load_rod(record)
        driver = PwmDriverParams(supply_v=section['supply_v'], bridge_resistance_ohm=record['bridge_resistance_ohm'])
    return TorqueRodAssembly([rod] * 3, driver, auto_switch_to_standby=section['auto_switch_to_standby'],
                             mismatch_tolerance_frac=section['mismatch_tolerance_frac'])


@dataclass(frozen=True)
class EeaFailure:
    """``eea_failure <x|y|z> <A|B> <kind|none>``: a failure of one axis's unit injected (``failure`` None:
    cleared); for tools and tests that talk to the node directly (the ground grammar has no such command)."""

    axis: int
    unit: str
    failure: str | None
    verb: ClassVar[str] = 'eea_failure'
    route: ClassVar[str] = 'em_driver'

    @classmethod
    def parse(cls, args: Sequence[str]) -> EeaFailure:
        """The words after the verb → the command."""
        if (len(args) != 3 or args[0].lower() not in AXES or args[1].upper() not in UNITS
                or args[2].lower() not in (*_FAILURES, 'none')):
            raise CommandError(f'usage: eea_failure <x|y|z> <A|B> <{"|".join(_FAILURES)}|none>')
        kind = args[2].lower()
        return cls(AXES.index(args[0].lower()), args[1].upper(), None if kind == 'none' else kind)

    @property
    def text(self) -> str:
        """The normalised command."""
        return f'eea_failure {AXES[self.axis]} {self.unit} {self.failure or "none"}'


#: The commands the node applies (forwarded in the ``mode`` report, key ``command/em_driver``).
GRAMMAR = (EeaSelect, EeaFailure)


def parse_command(text: str) -> EeaSelect | EeaFailure:
    """Parse one forwarded command (grammar in the module docstring); EmDriverError says what is wrong."""
    return decode(text, GRAMMAR, 'em_driver command', EmDriverError)


def apply_command(cmd: EeaSelect | EeaFailure, assembly: DriveAssembly | TorqueRodAssembly) -> str:
    """Apply a parsed command to the assembly; return the event text for telemetry."""
    name = AXES[cmd.axis]
    if isinstance(cmd, EeaSelect):
        assembly.select_eea(cmd.axis, cmd.unit)
        return f'eea_select: axis {name} unit {cmd.unit} active'
    assembly.inject_failure(cmd.axis, cmd.unit, cmd.failure)
    return f'axis {name} unit {cmd.unit}: failure {cmd.failure or "cleared"}'
