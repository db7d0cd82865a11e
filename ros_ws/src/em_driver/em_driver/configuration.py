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

Commands forwarded by ascs_mode_manager in the ``mode`` array (key ``command/em_driver``),
whitespace separated, keywords case-insensitive::

    eea_select <x|y|z> <A|B>                                          active driver + winding
    eea_failure <x|y|z> <A|B> <open_winding|stuck_on_bridge|dead_driver|none>

(the HEAO mode manager's ground grammar forwards ``eea_select``; ``eea_failure`` is for
tools and tests that talk to the node directly).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

from acds_common.torque_rod_record import TorqueRodRecordError, read_torque_rod_record
from acds_common.validation import scenario_key

from em_driver.bridge_switch import CoilFault, CoilParams, DriverParams, EmDriverError
from em_driver.drive_assembly import UNITS, AxisConfig, DriveAssembly
from em_driver.torque_rod import PwmDriverParams, TorqueRodAssembly
from em_driver.torque_rod_design import load_rod

__all__ = ['DriverCommand', 'axis_configs', 'build_assembly', 'build_torque_rods', 'parse_command']

_AXES = {'x': 0, 'y': 1, 'z': 2}
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
class DriverCommand:
    """A parsed command: verb 'select' or 'failure', axis 0…2, unit 'A'/'B', failure kind (None clears)."""

    verb: str
    axis: int
    unit: str
    failure: str | None = None

    def apply(self, assembly: DriveAssembly | TorqueRodAssembly) -> str:
        """Apply to the assembly; return the event text for telemetry."""
        name = 'xyz'[self.axis]
        if self.verb == 'select':
            assembly.select_eea(self.axis, self.unit)
            return f'eea_select: axis {name} unit {self.unit} active'
        assembly.inject_failure(self.axis, self.unit, self.failure)
        return f'axis {name} unit {self.unit}: failure {self.failure or "cleared"}'


def parse_command(text: str) -> DriverCommand:
    """Parse one forwarded command (grammar in the module docstring); EmDriverError says what is wrong."""
    words = str(text).split()
    verb = words[0].lower() if words else ''
    if verb == 'eea_select':
        if len(words) != 3 or words[1].lower() not in _AXES or words[2].upper() not in UNITS:
            raise EmDriverError(f'usage: eea_select <x|y|z> <A|B>, got {text!r}')
        return DriverCommand('select', _AXES[words[1].lower()], words[2].upper())
    if verb == 'eea_failure':
        if (len(words) != 4 or words[1].lower() not in _AXES or words[2].upper() not in UNITS
                or words[3].lower() not in (*_FAILURES, 'none')):
            raise EmDriverError(f'usage: eea_failure <x|y|z> <A|B> <{"|".join(_FAILURES)}|none>, got {text!r}')
        kind = words[3].lower()
        return DriverCommand('failure', _AXES[words[1].lower()], words[2].upper(), None if kind == 'none' else kind)
    raise EmDriverError(f'unknown em_driver command {text!r}; known: eea_select, eea_failure')
