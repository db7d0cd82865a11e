"""Three-axis electromagnet driver assembly with redundancy, failures and alarms (spec §6).

Seed: 002_heao_acds_study.txt §4.2.5 (two complete drivers and windings per
axis, active/standby, selected by the TA; e_ft compared with the command to
detect a failure), §4.2.7 and Table 4-11 (EEA SELECT command, COIL CURRENT,
TORQUER CURRENT CMD and EXCESS COIL CURRENT ALARM telemetry); seed
001_sss_ascs_fulcher.txt (SSS saturated constant-level drive, the coil
resistance alone limiting the current).

Conventions:
* Axis index 0, 1, 2 = body x, y, z. Units per axis are 'A' (default active)
  and 'B' (standby). Both windings sit on the same core, so the axis dipole is
  the sum of the two windings' moments; the standby unit is unpowered (the TA
  removes its power), so its winding only carries a decaying current after a
  switch-over.
* 'bridge_switch' axes: the moment command (A·m²) is saturated at the coil's
  max_moment_am2 and divided by moment_per_amp_am2 to give the current command.
* 'constant_level' axes: only the sign of the command component matters
  (−1/0/+1); the full supply is switched onto the coil.
* 'none' axes: there is no coil on that axis (an EMFF vehicle's two coils, seed 004): zero dipole,
  zero current, no alarm; the command on it is ignored.
* Mismatch / excess-coil-current alarm: the active unit's measured current
  (e_ft / sense gain) differs from the current a healthy driver would hold
  (the command, limited to what the supply reaches) by more than
  ``mismatch_tolerance_frac`` × the axis full-scale current, continuously for
  longer than ``mismatch_settle_s``. Defaults 0.1 (0.0727 A for Table 4-3, ten
  times the ±1 % band) and 3.0 s (a full-scale step settles within about
  1.1 s = τ·ln(I_on/(I_on − 0.727 A)), so a healthy driver never trips it).
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np
from acds_common.commands import UNITS  # redundant unit names per axis (driver + winding)

from em_driver.bridge_switch import (
    BridgeSwitchCoil,
    CoilFault,
    CoilParams,
    DriverParams,
    EmDriverError,
    PeriodResult,
)

__all__ = ['DRIVE_TYPES', 'UNITS', 'AxisConfig', 'AssemblyResult', 'DriveAssembly']

#: Drive types selectable per axis.
DRIVE_TYPES = ('bridge_switch', 'constant_level', 'none')


def axis_of(axes: Sequence[Any], axis: int) -> Any:
    """``axes[axis]`` of a three-axis assembly (0, 1, 2 = x, y, z); anything else is refused by name."""
    if axis not in (0, 1, 2):
        raise EmDriverError(f'axis must be 0, 1 or 2 (x, y, z), got {axis!r}')
    return axes[axis]


def alarm_events(k: int, ax: Any, alarm: bool, readings: Callable[[], tuple[str, str]], switch: bool) -> list[str]:
    """The mismatch alarm's edges on axis ``k`` (spec §6 failure detection; ``ax`` has ``alarm`` and ``active``),
    and, when it trips with ``switch``, the automatic switch to the standby unit; returns the events.
    ``readings()`` gives the (measured, expected) texts of an event: formatted only when there is one."""
    if alarm == ax.alarm and not switch:  # no edge, no switch: the common case
        return []
    events: list[str] = []
    if alarm and not ax.alarm:
        measured, expected = readings()
        events.append(f'axis {k}: excess coil current / mismatch alarm on unit {ax.active} '
                      f'(measured {measured}, expected {expected})')
    elif ax.alarm and not alarm:
        events.append(f'axis {k}: mismatch alarm cleared')
    ax.alarm = alarm
    if alarm and switch:
        standby = UNITS[1] if ax.active == UNITS[0] else UNITS[0]
        events.append(f'axis {k}: auto switch from unit {ax.active} to standby unit {standby}')
        ax.active = standby
    return events


def _default_constant_level_driver() -> DriverParams:
    """Saturated switch: no transistor drop, so the current tends to E/R exactly (seed 001)."""
    return DriverParams(v_ces_v=0.0)


@dataclass(frozen=True)
class AxisConfig:
    """One axis: drive type ('bridge_switch' or 'constant_level'), coil and driver parameters.

    coil: CoilParams (Table 4-3 by default); driver: DriverParams (Fig. 4-10
    constants by default; a constant-level axis built with
    ``AxisConfig.constant_level`` uses v_ces_v = 0 so it reaches 28 V / R).
    """

    drive_type: str = 'bridge_switch'
    coil: CoilParams = field(default_factory=CoilParams)
    driver: DriverParams = field(default_factory=DriverParams)

    def __post_init__(self) -> None:
        if self.drive_type not in DRIVE_TYPES:
            raise EmDriverError(f'drive_type must be one of {DRIVE_TYPES}, got {self.drive_type!r}')

    @classmethod
    def constant_level(cls, coil: CoilParams) -> AxisConfig:
        """A saturated constant-level axis (SSS) on the given coil, 28 V switched straight on."""
        return cls('constant_level', coil, _default_constant_level_driver())


class AssemblyResult:
    """Per-axis outputs of one control period (arrays indexed x, y, z).

    avg_dipole_am2 / end_dipole_am2: time-averaged and end dipole, A·m².
    coil_current_a: active winding current at the end, A.
    commanded_current_a: current command per axis, A (TA "torquer current cmd").
    e_ft_v: active unit's current telemetry, V.
    duty: active unit's duty cycle (0…1). switch_count: its bridge transitions.
    power_w: electrical power drawn by both units of the axis, W.
    alarms: excess-coil-current / mismatch alarm per axis.
    active_units: 'A' or 'B' per axis.
    events: unit switch-overs and alarm transitions this period.
    diagnostics: rejected commands (NaN/inf) this period.

    The per-axis values are kept as given (the assembly gives float tuples, what the stepper
    publishes through :meth:`xyz`); the attributes are them as numpy arrays, built when read.
    """

    def __init__(self, *, avg_dipole_am2: Sequence[float], end_dipole_am2: Sequence[float],
                 coil_current_a: Sequence[float], commanded_current_a: Sequence[float], e_ft_v: Sequence[float],
                 duty: Sequence[float], switch_count: Sequence[int], power_w: Sequence[float],
                 alarms: Sequence[bool], active_units: tuple[str, str, str], events: tuple[str, ...],
                 diagnostics: tuple[str, ...]) -> None:
        self._values = {'avg_dipole_am2': avg_dipole_am2, 'end_dipole_am2': end_dipole_am2,
                        'coil_current_a': coil_current_a, 'commanded_current_a': commanded_current_a,
                        'e_ft_v': e_ft_v, 'duty': duty, 'switch_count': switch_count, 'power_w': power_w,
                        'alarms': alarms}
        self.active_units = active_units
        self.events = events
        self.diagnostics = diagnostics
        #: The alarms as a tuple of bools (what the stepper compares step to step).
        self.alarm_flags = tuple(map(bool, alarms))

    def xyz(self, name: str) -> tuple[float, float, float]:
        """One per-axis quantity (by its attribute name) as a float triple."""
        x, y, z = self._values[name]
        return float(x), float(y), float(z)

    def per_axis(self, name: str) -> Sequence[Any]:
        """One per-axis quantity (by its attribute name) as given (the telemetry's path: no array built)."""
        return self._values[name]

    @property
    def avg_dipole_am2(self) -> np.ndarray:
        """Time-averaged dipole, A·m²."""
        return np.asarray(self._values['avg_dipole_am2'])

    @property
    def end_dipole_am2(self) -> np.ndarray:
        """Dipole at the end, A·m²."""
        return np.asarray(self._values['end_dipole_am2'])

    @property
    def coil_current_a(self) -> np.ndarray:
        """Active winding current at the end, A."""
        return np.asarray(self._values['coil_current_a'])

    @property
    def commanded_current_a(self) -> np.ndarray:
        """Current command, A."""
        return np.asarray(self._values['commanded_current_a'])

    @property
    def e_ft_v(self) -> np.ndarray:
        """Active unit's current telemetry, V."""
        return np.asarray(self._values['e_ft_v'])

    @property
    def duty(self) -> np.ndarray:
        """Active unit's duty cycle."""
        return np.asarray(self._values['duty'])

    @property
    def switch_count(self) -> np.ndarray:
        """Active unit's bridge transitions."""
        return np.asarray(self._values['switch_count'])

    @property
    def power_w(self) -> np.ndarray:
        """Electrical power of both units, W."""
        return np.asarray(self._values['power_w'])

    @property
    def alarms(self) -> np.ndarray:
        """Excess-coil-current / mismatch alarm."""
        return np.asarray(self._values['alarms'])


class _Axis:
    """One axis: two units (driver + winding) and the mismatch monitor."""

    def __init__(self, config: AxisConfig) -> None:
        self.config = config
        self.units = {name: BridgeSwitchCoil(config.coil, config.driver) for name in UNITS}
        self.active = UNITS[0]
        self.command = 0.0
        self.mismatch_time_s = 0.0
        self.alarm = False
        on_current_a = self.units[UNITS[0]].on_current_a  # both units: the same coil and driver
        #: Mismatch monitor: the current the bridge can hold and the axis full-scale current, A.
        self.on_current_a = on_current_a
        self.full_scale_a = on_current_a if config.drive_type == 'constant_level' else config.coil.max_current_a
        self.sense_gain_v_per_a = config.driver.current_sense_gain_v_per_a
        # What every step reads, looked up once.
        self.constant_level = config.drive_type == 'constant_level'
        self.max_moment_am2 = config.coil.max_moment_am2
        self.moment_per_amp_am2 = config.coil.moment_per_amp_am2

    def level(self) -> int:
        """Sign of the held command: −1, 0 or +1 (the constant-level drive's level)."""
        return (self.command > 0.0) - (self.command < 0.0)

    def current_command_a(self) -> float:
        """Current command for the held moment / level command, A (signed)."""
        if self.constant_level:
            return self.level() * self.units[self.active].on_current_a
        limit, command = self.max_moment_am2, self.command
        # min(max(command, −limit), limit), without the two calls
        return (-limit if command < -limit else limit if command > limit else command) / self.moment_per_amp_am2

    def run_unit(self, name: str, dt_s: float, command_a: float) -> PeriodResult:
        """Run one unit for the period; ``command_a`` is :meth:`current_command_a` (the active one's)."""
        unit = self.units[name]
        powered = name == self.active
        unit.powered = powered
        if self.constant_level:
            return unit.run_constant_level(self.level() if powered else 0, dt_s)
        return unit.run(command_a if powered else 0.0, dt_s)


class DriveAssembly:
    """Three axes of electromagnets with active/standby drivers and windings (spec §6).

    axes: three AxisConfig (default: three Table 4-3 bridge-switch axes).
    auto_switch_to_standby: when an axis' mismatch alarm trips, switch it to the
        other unit by itself and report it in the events.
    mismatch_tolerance_frac: alarm tolerance as a fraction of the axis full-scale
        current (max_current_a for bridge-switch axes, I_on for constant-level).
    mismatch_settle_s: how long, s, the mismatch must persist before the alarm.
    """

    def __init__(self, axes: Sequence[AxisConfig] | None = None, auto_switch_to_standby: bool = False,
                 mismatch_tolerance_frac: float = 0.1, mismatch_settle_s: float = 3.0) -> None:
        configs = [AxisConfig() for _ in range(3)] if axes is None else list(axes)
        if len(configs) != 3:
            raise EmDriverError(f'DriveAssembly needs exactly 3 axis configs, got {len(configs)}')
        if not (math.isfinite(mismatch_tolerance_frac) and mismatch_tolerance_frac > 0.0):
            raise EmDriverError(f'mismatch_tolerance_frac must be > 0, got {mismatch_tolerance_frac!r}')
        if not (math.isfinite(mismatch_settle_s) and mismatch_settle_s >= 0.0):
            raise EmDriverError(f'mismatch_settle_s must be >= 0 s, got {mismatch_settle_s!r}')
        self._axes = [_Axis(c) for c in configs]
        self.auto_switch_to_standby = auto_switch_to_standby
        self.mismatch_tolerance_frac = mismatch_tolerance_frac
        self.mismatch_settle_s = mismatch_settle_s
        self._pending_events: list[str] = []

    @property
    def active_units(self) -> tuple[str, str, str]:
        """Active unit per axis."""
        x, y, z = self._axes
        return x.active, y.active, z.active

    def select_eea(self, axis: int, unit: str) -> None:
        """EEA SELECT (Table 4-11): make ``unit`` ('A'/'B') the active driver + winding of ``axis`` (0…2)."""
        ax = self._axis(axis)
        self._check_unit(unit)
        if unit != ax.active:
            ax.active = unit
            ax.mismatch_time_s = 0.0
            self._pending_events.append(f'axis {axis}: EEA select -> unit {unit}')

    def inject_failure(self, axis: int, unit: str, kind: str | None) -> None:
        """Fail one unit: kind 'open_winding', 'stuck_on_bridge' or 'dead_driver'; None clears it."""
        self._check_unit(unit)
        self._axis(axis).units[unit].set_fault(kind)

    def unit_fault(self, axis: int, unit: str) -> CoilFault | None:
        """The failure injected into one unit, or None."""
        self._check_unit(unit)
        return self._axis(axis).units[unit].fault

    def step(self, moment_command_am2: np.ndarray, dt_s: float) -> AssemblyResult:
        """Drive the three axes for dt_s (s) toward moment_command_am2 (A·m², body axes).

        A NaN/inf component is rejected: that axis holds its last valid command and
        the result carries a diagnostic (no exception: the node keeps running).
        """
        try:
            command = [float(c) for c in moment_command_am2]
        except TypeError:
            command = []
        if len(command) != 3:
            raise EmDriverError(f'moment_command_am2 must have shape (3,), got {np.shape(moment_command_am2)}')
        if not (math.isfinite(dt_s) and dt_s > 0.0):
            raise EmDriverError(f'dt_s must be a finite positive time, got {dt_s!r}')
        diagnostics: list[str] = []
        events, self._pending_events = self._pending_events, []
        rows: list[tuple[float, float, float, float, float, float, float, int]] = []
        unit_a, unit_b = UNITS
        for k, ax in enumerate(self._axes):
            if ax.config.drive_type == 'none':  # no coil on this axis: nothing to drive, nothing to monitor
                rows.append((0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0))
                continue
            c = command[k]
            if math.isfinite(c):
                ax.command = c
            else:
                diagnostics.append(f'axis {k}: rejected non-finite moment command {c!r}; '
                                   f'holding last valid command {ax.command:g}')
            command_a = ax.current_command_a()
            a, b = ax.run_unit(unit_a, dt_s, command_a), ax.run_unit(unit_b, dt_s, command_a)
            active = a if ax.active == unit_a else b
            rows.append((a.avg_moment_am2 + b.avg_moment_am2, a.end_moment_am2 + b.end_moment_am2,
                         active.end_current_a, command_a, active.e_ft_v, active.duty,
                         a.power_w + b.power_w, active.switch_count))
            monitored = self._monitor(k, ax, active, command_a, dt_s)
            if monitored:
                events.extend(monitored)
        avg, end, cur, cmd, eft, duty, power, switches = zip(*rows, strict=True)
        x, y, z = self._axes
        return AssemblyResult(
            avg_dipole_am2=avg, end_dipole_am2=end, coil_current_a=cur, commanded_current_a=cmd, e_ft_v=eft, duty=duty,
            switch_count=switches, power_w=power, alarms=(x.alarm, y.alarm, z.alarm),
            active_units=(x.active, y.active, z.active), events=tuple(events), diagnostics=tuple(diagnostics))

    def _monitor(self, k: int, ax: _Axis, active: PeriodResult, command_a: float, dt_s: float) -> list[str]:
        """Mismatch alarm: e_ft against the expected current (``command_a`` limited to what the supply
        reaches); optional auto switch to standby."""
        measured_a = active.e_ft_v / ax.sense_gain_v_per_a
        on_a = ax.on_current_a
        expected_a = -on_a if command_a < -on_a else on_a if command_a > on_a else command_a  # min(max(…))
        if abs(measured_a - expected_a) > self.mismatch_tolerance_frac * ax.full_scale_a:
            ax.mismatch_time_s += dt_s
        else:
            ax.mismatch_time_s = 0.0
        alarm = ax.mismatch_time_s > self.mismatch_settle_s
        switch = alarm and self.auto_switch_to_standby
        events = alarm_events(k, ax, alarm, lambda: (f'{measured_a:.4f} A', f'{expected_a:.4f} A'), switch)
        if switch:
            ax.mismatch_time_s = 0.0
        return events

    def _axis(self, axis: int) -> _Axis:
        return axis_of(self._axes, axis)

    @staticmethod
    def _check_unit(unit: str) -> None:
        if unit not in UNITS:
            raise EmDriverError(f'unit must be one of {UNITS}, got {unit!r}')
