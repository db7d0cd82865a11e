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
from acds_common import kernels
from acds_common.commands import UNITS  # redundant unit names per axis (driver + winding)

from em_driver.bridge_switch import (
    CURRENT,
    POWERED,
    BridgeSwitchCoil,
    CoilFault,
    CoilParams,
    DriverParams,
    EmDriverError,
    bridge_drive,
    level_drive,
    period_figures,
    state_table,
    unit_period,
)

__all__ = ['DRIVE_TYPES', 'FIGURES', 'UNITS', 'AxisConfig', 'AssemblyResult', 'DriveAssembly']

#: Drive types selectable per axis.
DRIVE_TYPES = ('bridge_switch', 'constant_level', 'none')


def axis_of(axes: Sequence[Any], axis: int) -> Any:
    """``axes[axis]`` of a three-axis assembly (0, 1, 2 = x, y, z); anything else is refused by name."""
    if axis not in (0, 1, 2):
        raise EmDriverError(f'axis must be 0, 1 or 2 (x, y, z), got {axis!r}')
    return axes[axis]


def standby_unit(unit: str) -> str:
    """The other unit of an axis ('A' <-> 'B')."""
    return UNITS[1] if unit == UNITS[0] else UNITS[0]


def alarm_events(k: int, unit: str, was: bool, alarm: bool, readings: Callable[[], tuple[str, str]],
                 switch: bool) -> list[str]:
    """The mismatch alarm's edges on axis ``k`` (spec §6 failure detection: ``was`` before, ``alarm`` now, on
    the active ``unit``) and, with ``switch``, the automatic switch from ``unit`` to the standby unit; returns
    the events (the caller keeps the alarm and the active unit). ``readings()`` gives the (measured, expected)
    texts of an alarm that trips: formatted only then."""
    events: list[str] = []
    if alarm and not was:
        measured, expected = readings()
        events.append(f'axis {k}: excess coil current / mismatch alarm on unit {unit} '
                      f'(measured {measured}, expected {expected})')
    elif was and not alarm:
        events.append(f'axis {k}: mismatch alarm cleared')
    if switch:
        events.append(f'axis {k}: auto switch from unit {unit} to standby unit {standby_unit(unit)}')
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


#: The per-axis figures of a period, in the order of :func:`axis_period`'s (a kernel row's) figures.
FIGURES = ('avg_dipole_am2', 'end_dipole_am2', 'coil_current_a', 'commanded_current_a', 'e_ft_v', 'duty', 'power_w',
           'switch_count')
_COLUMN = {name: i for i, name in enumerate(FIGURES)}


class AssemblyResult:
    """Per-axis outputs of one control period (x, y, z).

    avg_dipole_am2 / end_dipole_am2: time-averaged and end dipole, A·m².
    coil_current_a: active winding current at the end, A.
    commanded_current_a: current command per axis, A (TA "torquer current cmd").
    e_ft_v: active unit's current telemetry, V.
    duty: active unit's duty cycle (0…1).
    power_w: electrical power drawn by both units of the axis, W.
    switch_count: active unit's bridge transitions.
    alarms: excess-coil-current / mismatch alarm per axis.
    active_units: 'A' or 'B' per axis.
    events: unit switch-overs and alarm transitions this period.
    diagnostics: rejected commands (NaN/inf) this period.

    ``figures``: one (x, y, z) triple per name of :data:`FIGURES`, in that order, floats (ints for
    ``switch_count``), kept as given (what :func:`drive_step` returns; the stepper unpacks them): :meth:`xyz` and
    :meth:`per_axis` read them; the attributes are the figures as numpy arrays, built when read. ``alarms``: a
    triple of bools.
    """

    __slots__ = ('figures', 'alarm_flags', 'active_units', 'events', 'diagnostics')

    def __init__(self, figures: Sequence[tuple[Any, Any, Any]], alarms: tuple[bool, bool, bool],
                 active_units: tuple[str, str, str], events: tuple[str, ...], diagnostics: tuple[str, ...]) -> None:
        self.figures = figures
        #: The alarms as a tuple of bools (what the stepper compares step to step).
        self.alarm_flags = alarms
        self.active_units = active_units
        self.events = events
        self.diagnostics = diagnostics

    def xyz(self, name: str) -> tuple[float, float, float]:
        """One figure (by its name in :data:`FIGURES`) per axis (x, y, z): a float triple (ints for
        ``switch_count``)."""
        return self.figures[_COLUMN[name]]

    def per_axis(self, name: str) -> Sequence[Any]:
        """One figure (by its name in :data:`FIGURES`) or ``alarms``, per axis (the telemetry's path: no array
        built)."""
        return self.alarm_flags if name == 'alarms' else self.figures[_COLUMN[name]]

    @property
    def avg_dipole_am2(self) -> np.ndarray:
        """Time-averaged dipole, A·m²."""
        return np.asarray(self.per_axis('avg_dipole_am2'))

    @property
    def end_dipole_am2(self) -> np.ndarray:
        """Dipole at the end, A·m²."""
        return np.asarray(self.per_axis('end_dipole_am2'))

    @property
    def coil_current_a(self) -> np.ndarray:
        """Active winding current at the end, A."""
        return np.asarray(self.per_axis('coil_current_a'))

    @property
    def commanded_current_a(self) -> np.ndarray:
        """Current command, A."""
        return np.asarray(self.per_axis('commanded_current_a'))

    @property
    def e_ft_v(self) -> np.ndarray:
        """Active unit's current telemetry, V."""
        return np.asarray(self.per_axis('e_ft_v'))

    @property
    def duty(self) -> np.ndarray:
        """Active unit's duty cycle."""
        return np.asarray(self.per_axis('duty'))

    @property
    def switch_count(self) -> np.ndarray:
        """Active unit's bridge transitions."""
        return np.asarray(self.per_axis('switch_count'))

    @property
    def power_w(self) -> np.ndarray:
        """Electrical power of both units, W."""
        return np.asarray(self.per_axis('power_w'))

    @property
    def alarms(self) -> np.ndarray:
        """Excess-coil-current / mismatch alarm."""
        return np.asarray(self.alarm_flags)


#: An axis's drive type as the kernels read it (its index in DRIVE_TYPES).
_BRIDGE_SWITCH, _CONSTANT_LEVEL, _NO_COIL = (float(DRIVE_TYPES.index(t)) for t in DRIVE_TYPES)


@kernels.helper
def unit_share(row, powered: bool, drive: tuple[float, bool, float, float], idle: tuple[float, bool, float, float],
               duration_s: float, p) -> tuple[float, float, float, float, float, float, int]:
    """One unit of an axis over the period (:func:`~em_driver.bridge_switch.unit_period`): powered, it gets the
    axis's ``drive``, unpowered (the standby unit) ``idle``; returns its average and end moment (A·m²), end
    current (A), e_ft (V), duty, power (W) and switch count. ``p``: the axis's parameter row (:func:`axis_period`)."""
    row[POWERED] = 1.0 if powered else 0.0
    polarity, on, lo, hi = drive if powered else idle
    integral_i, on_time, drawn, _, switches = unit_period(row, polarity, on, lo, hi, duration_s, p[1], p[2], p[3],
                                                          p[4], None)
    current_a = row[CURRENT]
    _, avg_moment, end_moment, duty, power, e_ft = period_figures(integral_i, on_time, drawn, duration_s,
                                                                  current_a, p[7], p[8])
    return avg_moment, end_moment, current_a, e_ft, duty, power, switches


@kernels.helper
def axis_period(state, k: int, p, command: float, active: int, duration_s: float
                ) -> tuple[float, float, float, float, float, float, float, int]:
    """Axis ``k`` over one period (spec §6; seed 002 §4.2.5: the TA powers the ``active`` unit, 0 = A, 1 = B):
    the held moment command (A·m²) saturated at the coil's maximum and turned into a current command
    (bridge switch), or its sign switching the supply (constant level). Parameter row ``p``: drive type, τ, E,
    I_on, I_off, ε, band floor, moment per amp, sense gain, max moment, then :func:`axis_monitor`'s tolerance
    (A), settle time (s) and automatic switch (1.0 on). Returns the axis's average and end dipole (A·m², both
    windings), and the commanded current (A) and the active unit's end current (A), e_ft (V), duty, both units'
    power (W) and the active unit's switch count, in :data:`FIGURES` order."""
    drive_type = p[0]
    if drive_type == _NO_COIL:
        return 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0
    if drive_type == _CONSTANT_LEVEL:
        level = 1 if command > 0.0 else -1 if command < 0.0 else 0
        command_a = level * p[3]
        drive, idle = level_drive(level), level_drive(0)
    else:
        limit = p[9]
        command_a = (-limit if command < -limit else limit if command > limit else command) / p[7]
        drive, idle = bridge_drive(command_a, p[5], p[6]), bridge_drive(0.0, p[5], p[6])
    a = unit_share(state[2 * k], active == 0, drive, idle, duration_s, p)
    b = unit_share(state[2 * k + 1], active == 1, drive, idle, duration_s, p)
    on = a if active == 0 else b
    return a[0] + b[0], a[1] + b[1], on[2], command_a, on[3], on[4], a[5] + b[5], on[6]


#: An axis's row of the monitor table (:func:`drive_step`; a drive assembly keeps its three axes' rows in one
#: table, updated in place like its units' :func:`~em_driver.bridge_switch.state_table`): the held moment command
#: (A·m²), the mismatch time (s), the alarm (1.0 on), the active unit (0.0 = A, 1.0 = B), and the last period's
#: measured and expected currents (A).
HELD, MISMATCH, ALARM, ACTIVE, MEASURED, EXPECTED = range(6)


@kernels.helper
def axis_monitor(axis, figures, p, duration_s: float) -> bool:
    """The mismatch / excess-coil-current alarm of one axis after its period (spec §6 failure detection; seed
    002 §4.2.5: e_ft compared with the command), its monitor row ``axis`` (see :data:`HELD`) updated in place: the
    active unit's measured current (its e_ft over the sense gain) against the current a healthy driver holds (the
    commanded current limited to ±I_on), apart by more than the tolerance (A) for longer than the settle time
    raises the alarm, and with the automatic switch makes the standby unit active (its mismatch time then 0).
    ``figures``: the axis's :func:`axis_period` figures; ``p`` its parameter row. Returns whether the alarm
    changed or switched the unit."""
    if p[0] == _NO_COIL:
        return False
    measured_a = figures[4] / p[8]
    command_a = figures[3]
    on_a = p[3]
    expected_a = -on_a if command_a < -on_a else on_a if command_a > on_a else command_a  # min(max(…))
    axis[MEASURED] = measured_a
    axis[EXPECTED] = expected_a
    mismatch_s = axis[MISMATCH] + duration_s if abs(measured_a - expected_a) > p[10] else 0.0
    alarm = mismatch_s > p[11]
    was = axis[ALARM] != 0.0
    axis[ALARM] = 1.0 if alarm else 0.0
    if alarm and p[12] != 0.0:
        axis[ACTIVE] = 1.0 - axis[ACTIVE]
        axis[MISMATCH] = 0.0
        return True
    axis[MISMATCH] = mismatch_s
    return alarm != was


@kernels.helper
def axis_step(units, k: int, p, axis, command: float, duration_s: float
              ) -> tuple[tuple[float, float, float, float, float, float, float, int], bool]:
    """Axis ``k`` over one period: its moment command (A·m²) held unless non-finite (then the last valid one
    stays), :func:`axis_period` on the active unit, :func:`axis_monitor`; returns both's results."""
    if math.isfinite(command):
        axis[HELD] = command
    figures = axis_period(units, k, p, axis[HELD], int(axis[ACTIVE]), duration_s)
    return figures, axis_monitor(axis, figures, p, duration_s)


@kernels.helper
def drive_step(units, params, axes, command: tuple[float, float, float], duration_s: float) -> tuple:
    """One control period of the assembly (spec §6): each axis's :func:`axis_step`. ``units`` the six units'
    rows (axis k's units A and B at 2k, 2k + 1), ``axes`` the three axes' monitor rows (both tables updated in
    place), ``params`` the axes' parameter rows. Returns whether an alarm changed or switched a unit, and the
    figures, one (x, y, z) triple per name of :data:`FIGURES`.

    A kernel (:mod:`acds_common.kernels`): one call a step drives the assembly.
    """
    x, y, z = command
    a, changed_x = axis_step(units, 0, params[0], axes[0], x, duration_s)
    b, changed_y = axis_step(units, 1, params[1], axes[1], y, duration_s)
    c, changed_z = axis_step(units, 2, params[2], axes[2], z, duration_s)
    return changed_x or changed_y or changed_z, (
        (a[0], b[0], c[0]), (a[1], b[1], c[1]), (a[2], b[2], c[2]), (a[3], b[3], c[3]), (a[4], b[4], c[4]),
        (a[5], b[5], c[5]), (a[6], b[6], c[6]), (a[7], b[7], c[7]))


class _Axis:
    """One axis: two units (driver + winding; their state ``rows``) and its parameter row."""

    def __init__(self, config: AxisConfig, rows: Sequence[Any], monitor: tuple[float, float, bool]) -> None:
        self.config = config
        self.units = {name: BridgeSwitchCoil(config.coil, config.driver, state=row) for name, row in zip(UNITS, rows,
                                                                                                        strict=True)}
        unit = self.units[UNITS[0]]  # both units: the same coil and driver
        self.coil = config.drive_type != 'none'
        tolerance_frac, settle_s, auto_switch = monitor
        full_scale_a = unit.on_current_a if config.drive_type == 'constant_level' else config.coil.max_current_a
        #: The axis's parameter row (:func:`axis_period`, :func:`axis_monitor`): the mismatch monitor's tolerance
        #: (A: the fraction of the full-scale current), settle time (s) and automatic switch (1.0) last.
        self.params = (float(DRIVE_TYPES.index(config.drive_type)), *unit.circuit, config.driver.epsilon,
                       config.driver.band_floor_a, config.coil.moment_per_amp_am2,
                       config.driver.current_sense_gain_v_per_a, config.coil.max_moment_am2,
                       tolerance_frac * full_scale_a, float(settle_s), 1.0 if auto_switch else 0.0)


class DriveAssembly:
    """Three axes of electromagnets with active/standby drivers and windings (spec §6).

    axes: three AxisConfig (default: three Table 4-3 bridge-switch axes).
    auto_switch_to_standby: when an axis' mismatch alarm trips, switch it to the
        other unit by itself and report it in the events.
    mismatch_tolerance_frac: alarm tolerance as a fraction of the axis full-scale
        current (max_current_a for bridge-switch axes, I_on for constant-level).
    mismatch_settle_s: how long, s, the mismatch must persist before the alarm.
    The three are fixed when the assembly is built (read-only).
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
        self._monitor_config = (mismatch_tolerance_frac, mismatch_settle_s, auto_switch_to_standby)
        compiled = kernels.compiled(drive_step) is not drive_step
        #: The six units' state rows (axis k's A and B at 2k, 2k + 1), the axes' monitor rows (:data:`HELD`; a
        #: numpy table for the compiled kernel, lists for the plain one, as :func:`state_table`) and parameter rows.
        self._state = state_table(6, compiled)
        monitor = [[0.0] * 6 for _ in range(3)]
        self._monitor = np.array(monitor) if compiled else monitor
        self._axes = [_Axis(c, self._state[2 * k:2 * k + 2], self._monitor_config) for k, c in enumerate(configs)]
        #: The axes with a coil: the ones whose commands are checked and alarms reported.
        self._coiled = tuple(k for k, ax in enumerate(self._axes) if ax.coil)
        params = [ax.params for ax in self._axes]
        self._params = np.array(params) if compiled else params
        #: The alarms and active units as the last step left them (read back from the monitor rows when the kernel
        #: says they changed, or set by :meth:`select_eea`).
        self._alarms = (False, False, False)
        self._active_units = (UNITS[0], UNITS[0], UNITS[0])
        #: The step kernel bound to the one signature :meth:`step_xyz` calls it with (:func:`kernels.bound`): the
        #: types are fixed by construction there: the unit, monitor and parameter tables are this object's float64
        #: C arrays (never replaced), the commands and period made floats by :meth:`step_xyz`.
        self._step = kernels.bound(drive_step, self._state, self._params, self._monitor, (0.0, 0.0, 0.0), 1.0)
        self._pending_events: list[str] = []

    @property
    def mismatch_tolerance_frac(self) -> float:
        """Alarm tolerance, fraction of the axis full-scale current."""
        return self._monitor_config[0]

    @property
    def mismatch_settle_s(self) -> float:
        """How long (s) the mismatch persists before the alarm."""
        return self._monitor_config[1]

    @property
    def auto_switch_to_standby(self) -> bool:
        """Whether an alarmed axis switches to its standby unit by itself."""
        return self._monitor_config[2]

    @property
    def active_units(self) -> tuple[str, str, str]:
        """Active unit per axis."""
        return self._active_units

    def select_eea(self, axis: int, unit: str) -> None:
        """EEA SELECT (Table 4-11): make ``unit`` ('A'/'B') the active driver + winding of ``axis`` (0…2)."""
        self._axis(axis)
        self._check_unit(unit)
        if unit != self._active_units[axis]:
            row = self._monitor[axis]
            row[ACTIVE] = float(UNITS.index(unit))
            row[MISMATCH] = 0.0
            units = list(self._active_units)
            units[axis] = unit
            x, y, z = units
            self._active_units = x, y, z
            self._pending_events.append(f'axis {axis}: EEA select -> unit {unit}')

    def inject_failure(self, axis: int, unit: str, kind: str | None) -> None:
        """Fail one unit: kind 'open_winding', 'stuck_on_bridge' or 'dead_driver'; None clears it."""
        self._check_unit(unit)
        self._axis(axis).units[unit].set_fault(kind)

    def unit_fault(self, axis: int, unit: str) -> CoilFault | None:
        """The failure injected into one unit, or None."""
        self._check_unit(unit)
        return self._axis(axis).units[unit].fault

    def kernel_parts(self) -> tuple[Any, Any, Any]:
        """:func:`drive_step`'s unit table, parameter rows and monitor table, for a compiled caller (the direct
        engine's fused loop, :mod:`acds_common.fused`); it hands the tables it stepped to :meth:`set_kernel_state`."""
        return self._state, self._params, self._monitor

    def set_kernel_state(self, units: Any, monitor: Any) -> None:
        """The unit and monitor tables a compiled caller stepped (copied into this assembly's own tables, which its
        units' rows view); alarms and active units are unchanged (the caller steps only while they are)."""
        self._state[:] = units
        self._monitor[:] = monitor

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
        return self.step_xyz(command, dt_s)

    def step_xyz(self, command: Sequence[float], dt_s: float) -> AssemblyResult:
        """:meth:`step` on a moment command that is already a float triple (a Vector3Stamped value) and a
        ``dt_s`` already checked (the scenario bounds the control period): the stepper's per-step path
        (spec §6), one :func:`drive_step` call. A non-finite component is still rejected per axis, as
        :meth:`step` does."""
        x, y, z = command
        diagnostics = () if math.isfinite(x + y + z) else self._rejected(command)
        changed, figures = self._step(self._state, self._params, self._monitor, (float(x), float(y), float(z)),
                                      float(dt_s))
        events, self._pending_events = self._pending_events, []
        if changed:
            events.extend(self._alarm_events())
        return AssemblyResult(figures, self._alarms, self._active_units, tuple(events), diagnostics)

    def _rejected(self, command: Sequence[float]) -> tuple[str, ...]:
        """The diagnostics of the non-finite command components :func:`drive_step` is about to reject (on the axes
        with a coil; an axis without one ignores its command), each with the command its axis holds."""
        return tuple(f'axis {k}: rejected non-finite moment command {command[k]!r}; '
                     f'holding last valid command {float(self._monitor[k][HELD]):g}'
                     for k in self._coiled if not math.isfinite(command[k]))

    def _alarm_events(self) -> list[str]:
        """The events of the alarm edges and automatic switches :func:`drive_step` made (its monitor rows against
        the alarms and active units the last step left); keeps the new ones."""
        events: list[str] = []
        alarms, units = list(self._alarms), list(self._active_units)
        for k in self._coiled:
            row = self._monitor[k]
            alarm, unit = bool(row[ALARM]), UNITS[int(row[ACTIVE])]
            measured_a, expected_a = float(row[MEASURED]), float(row[EXPECTED])
            events.extend(alarm_events(k, units[k], alarms[k], alarm,
                                       lambda m=measured_a, e=expected_a: (f'{m:.4f} A', f'{e:.4f} A'),
                                       unit != units[k]))
            alarms[k], units[k] = alarm, unit
        self._alarms = alarms[0], alarms[1], alarms[2]
        self._active_units = units[0], units[1], units[2]
        return events

    def _axis(self, axis: int) -> _Axis:
        return axis_of(self._axes, axis)

    @staticmethod
    def _check_unit(unit: str) -> None:
        if unit not in UNITS:
            raise EmDriverError(f'unit must be one of {UNITS}, got {unit!r}')
