"""One electromagnet winding and its pulsed transistor bridge-switch driver (spec §6).

Seed: 002_heao_acds_study.txt §4.2.4 (Table 4-3, the electromagnet) and §4.2.5
(Figs. 4-6 to 4-10, eqs. 4-27/4-28, the driver).

Circuit model (all currents in A, voltages in V, times in s):

* The absolute-value detector splits the command current into a magnitude I_c
  and a sign s. The comparator holds the coil current x = s·i (current measured
  along the commanded polarity) inside the band [lo, hi] with
  lo = I_c − h, hi = I_c + h, h = max(ε·I_c, band_floor_a).
* Bridge pair on, current along the commanded polarity (transistor path): the
  coil sees E − 2·V_ces, so x → I_on = (E − 2·V_ces)/R with τ = L/R.
* Bridge off with current flowing (freewheel path): the current returns to the
  supply through two diodes, the coil sees −(E + 2·ED) against the current, so
  |i| → −I_off = −(E + 2·ED)/R with τ = L/R until it reaches lo (bridge on again)
  or zero (the diodes block: the current cannot reverse and stays at zero).
* Bridge pair on while the current still flows against the new polarity (a
  command reversal): the turned-on transistors cannot carry reverse current;
  the current flows through the opposite pair's diodes back into the supply
  (same −(E + 2·ED) path) down to zero, then the transistors take over. The
  current therefore passes through zero monotonically, without a jump.

Between switching events the RL circuit is integrated exactly
(``em_driver.rl_circuit``): i(t) = i_∞ + (i_0 − i_∞)·exp(−t/τ); each next event
time is solved with a log.

Conventions:
* ``duty`` is the fraction of the period the comparator commands the bridge
  pair on (this includes a reversal's diode interval, during which the pair is
  commanded on but the diodes conduct).
* ``energy_drawn_j`` = ∫ E·|i| dt over the transistor-path intervals (the bus
  current equals the coil current); ``energy_returned_j`` = ∫ E·|i| dt over the
  diode-path intervals (energy pushed back into the bus);
  ``energy_from_bus_j`` = drawn − returned (net); ``power_w`` = drawn/duration.
* Moment = moment_per_amp_am2 · current (linear core; Table 4-3 keeps the core
  below 20,000 G so the study treats it as linear).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from enum import StrEnum
from typing import Any, NamedTuple

import numpy as np
from acds_common import kernels

from em_driver import rl_circuit

__all__ = [
    'EmDriverError',
    'CoilParams',
    'DriverParams',
    'Waveform',
    'PeriodResult',
    'CoilFault',
    'BridgeSwitchCoil',
    'duty_cycle_closed_form',
    'band_limits_a',
]


class EmDriverError(ValueError):
    """Invalid input to the electromagnet driver models (the one exception of the em_driver package)."""


@dataclass(frozen=True)
class CoilParams:
    """Electromagnet winding (seed 002 Table 4-3).

    resistance_ohm: winding resistance, Ω (30.3).
    inductance_h: winding inductance, H (20.3).
    moment_per_amp_am2: dipole per ampere, A·m²/A (2062 A·m² / 0.727 A ≈ 2836).
    max_moment_am2: maximum moment, A·m² (2062); commands are saturated here
        by the drive assembly.
    """

    resistance_ohm: float = 30.3
    inductance_h: float = 20.3
    moment_per_amp_am2: float = 2062.0 / 0.727
    max_moment_am2: float = 2062.0

    def __post_init__(self) -> None:
        for name in ('resistance_ohm', 'inductance_h', 'moment_per_amp_am2', 'max_moment_am2'):
            value = getattr(self, name)
            if not (math.isfinite(value) and value > 0.0):
                raise EmDriverError(f'CoilParams.{name} must be a finite positive number, got {value!r}')

    @property
    def tau_s(self) -> float:
        """Coil time constant τ = L/R, s."""
        return self.inductance_h / self.resistance_ohm

    @property
    def max_current_a(self) -> float:
        """Current at the maximum moment, A (0.727 A for Table 4-3)."""
        return self.max_moment_am2 / self.moment_per_amp_am2


@dataclass(frozen=True)
class DriverParams:
    """Bridge-switch driver (seed 002 §4.2.5, Fig. 4-10 constants).

    supply_v: bridge supply E, V (28 V bus).
    v_ces_v: transistor saturation voltage V_ces, V (0.35; two in the on path).
    diode_drop_v: diode forward drop ED, V (0.6; two in the freewheel path).
    epsilon: relative half-width ε of the hysteresis current band (0.01).
    band_floor_a: absolute floor on the band half-width, A (a real comparator
        has an offset). Default 4e-4 A: the switching period is about
        2·h·L·(1/(E − 2V_ces) + 1/(E + 2ED)) ≈ 2.9 s/A · h, so a 0.4 mA floor caps
        the switching frequency near 0.87 kHz (≤ 1 kHz), and it lies below
        ε·I_c over the whole Fig. 4-10 sweep (ε·0.05 A = 0.5 mA), so eq. 4-28
        holds unchanged there. Commands below the floor are treated as zero
        (the comparator cannot resolve them).
    current_sense_gain_v_per_a: current-sensor scale for e_f / e_ft, V/A. The
        seed gives no value; 5 V/A is chosen so e_ft spans ±5 V over the
        ±1 A the bridge can reach (I_on ≈ 0.9 A).
    """

    supply_v: float = 28.0
    v_ces_v: float = 0.35
    diode_drop_v: float = 0.6
    epsilon: float = 0.01
    band_floor_a: float = 4e-4
    current_sense_gain_v_per_a: float = 5.0

    def __post_init__(self) -> None:
        for name in ('supply_v', 'current_sense_gain_v_per_a'):
            value = getattr(self, name)
            if not (math.isfinite(value) and value > 0.0):
                raise EmDriverError(f'DriverParams.{name} must be a finite positive number, got {value!r}')
        for name in ('v_ces_v', 'diode_drop_v', 'band_floor_a'):
            value = getattr(self, name)
            if not (math.isfinite(value) and value >= 0.0):
                raise EmDriverError(f'DriverParams.{name} must be finite and >= 0, got {value!r}')
        if not (math.isfinite(self.epsilon) and 0.0 <= self.epsilon < 1.0):
            raise EmDriverError(f'DriverParams.epsilon must be in [0, 1), got {self.epsilon!r}')
        if 2.0 * self.v_ces_v >= self.supply_v:
            raise EmDriverError('DriverParams: 2·v_ces_v must be below supply_v or the bridge cannot drive')


def _on_current_a(coil: CoilParams, driver: DriverParams) -> float:
    """I_on = (E − 2·V_ces)/R, A: the current the on path tends to."""
    return (driver.supply_v - 2.0 * driver.v_ces_v) / coil.resistance_ohm


def _off_current_a(coil: CoilParams, driver: DriverParams) -> float:
    """I_off = (E + 2·ED)/R, A: magnitude of the freewheel path's asymptote."""
    return (driver.supply_v + 2.0 * driver.diode_drop_v) / coil.resistance_ohm


def band_limits_a(i_c_a: float, driver: DriverParams) -> tuple[float, float]:
    """Comparator thresholds (lo, hi), A, for a command magnitude i_c_a ≥ 0 (spec §6 band with floor).

    h = max(ε·I_c, band_floor_a); (lo, hi) = (I_c − h, I_c + h). A command below
    the floor (the comparator offset) gives (0, 0): treated as zero.
    """
    return comparator_band(i_c_a, driver.epsilon, driver.band_floor_a)


@kernels.helper
def comparator_band(i_c_a: float, epsilon: float, band_floor_a: float) -> tuple[float, float]:
    """:func:`band_limits_a` on the driver's ε and band floor (the form kernels call)."""
    if i_c_a < band_floor_a or i_c_a == 0.0:
        return 0.0, 0.0
    half = max(epsilon * i_c_a, band_floor_a)
    return i_c_a - half, i_c_a + half


@kernels.helper
def bridge_drive(command_a: float, epsilon: float, band_floor_a: float) -> tuple[float, bool, float, float]:
    """What a current command (A, signed) asks of the bridge (seed 002 §4.2.5 absolute-value detector and
    comparator): (polarity ±1, or 0 to keep the last one for a zero command; drive; lo; hi)."""
    lo, hi = comparator_band(abs(command_a), epsilon, band_floor_a)
    polarity = 1.0 if command_a > 0.0 else -1.0 if command_a < 0.0 else 0.0
    return polarity, hi > 0.0, lo, hi


@kernels.helper
def level_drive(level: int) -> tuple[float, bool, float, float]:
    """What a constant-level command −1/0/+1 asks of the switch (seed 001 SSS; the form of
    :func:`bridge_drive`): the level's polarity (0 keeps the last), the supply switched straight on."""
    return float(level), level != 0, math.inf, math.inf


def duty_cycle_closed_form(i_c_a: float, coil: CoilParams, driver: DriverParams) -> tuple[float, float]:
    """Duty cycle (0…1) and switching frequency (Hz) from the corrected eq. 4-27/4-28 (spec §6).

    t_on = τ·ln((I_on − lo)/(I_on − hi)), t_off = τ·ln((hi + I_off)/(lo + I_off)),
    duty = t_on/(t_on + t_off), f = 1/(t_on + t_off), τ = L/R, with (lo, hi) the
    comparator band (= (1∓ε)·I_c whenever ε·I_c exceeds the floor). A command
    whose upper threshold the supply cannot reach (hi ≥ I_on) saturates: (1.0, 0.0).
    A zero command gives (0.0, 0.0).
    """
    if not (math.isfinite(i_c_a) and i_c_a >= 0.0):
        raise EmDriverError(f'i_c_a must be a finite current >= 0 A, got {i_c_a!r}')
    lo, hi = band_limits_a(i_c_a, driver)
    if hi == 0.0:
        return 0.0, 0.0
    i_on = _on_current_a(coil, driver)
    i_off = _off_current_a(coil, driver)
    if hi >= i_on:
        return 1.0, 0.0
    tau = coil.tau_s
    t_on = tau * math.log((i_on - lo) / (i_on - hi))
    t_off = tau * math.log((hi + i_off) / (lo + i_off))
    period = t_on + t_off
    return t_on / period, 1.0 / period


class CoilFault(StrEnum):
    """Failures a winding + driver unit can suffer (spec §6 failure detection)."""

    OPEN_WINDING = 'open_winding'  # no current can flow
    STUCK_ON_BRIDGE = 'stuck_on_bridge'  # bridge pair always on: current → I_on
    DEAD_DRIVER = 'dead_driver'  # no drive at all: current decays through the diodes

    @classmethod
    def parse(cls, fault: CoilFault | str | None, what: str) -> CoilFault | None:
        """``fault`` as a CoilFault (None clears it); an unknown kind is refused naming ``what`` failed."""
        if fault is None:
            return None
        try:
            return cls(fault)
        except ValueError:
            kinds = ', '.join(f.value for f in cls)
            raise EmDriverError(f'unknown {what} fault {fault!r}; expected one of: {kinds}') from None


@dataclass(frozen=True)
class Waveform:
    """Recorded coil current: every switching edge plus intermediate points for plotting.

    times_s: sample times from the start of the period, s.
    currents_a: coil current at those times, A (signed).
    bridge_on: comparator state (pair commanded on) on the interval starting at each sample.
    """

    times_s: np.ndarray
    currents_a: np.ndarray
    bridge_on: np.ndarray


class PeriodResult(NamedTuple):
    """What one driver reports per control period (spec §6).

    Currents in A, moments in A·m², energies in J, power in W, e_ft in V.
    duty: fraction of the period the bridge pair was commanded on.
    switch_count: number of bridge on↔off transitions in the period.
    energy_drawn_j: ∫E·|i| dt over transistor-path intervals.
    energy_returned_j: ∫E·|i| dt over diode-path intervals (back into the bus).
    energy_from_bus_j: drawn − returned (net).
    power_w: energy_drawn_j / duration.
    e_ft_v: current-sensor telemetry voltage at the end (signed).
    waveform: recorded current if ``record`` was set, else None.
    """

    avg_current_a: float
    end_current_a: float
    avg_moment_am2: float
    end_moment_am2: float
    duty: float
    switch_count: int
    energy_drawn_j: float
    energy_returned_j: float
    energy_from_bus_j: float
    power_w: float
    e_ft_v: float
    waveform: Waveform | None = None


class _Recorder:
    """Collects waveform samples: every segment start plus interior points at most ``step_s`` apart."""

    def __init__(self, step_s: float) -> None:
        self.step_s = step_s
        self.times: list[float] = []
        self.currents: list[float] = []
        self.states: list[bool] = []

    def segment(self, t0: float, dt: float, i0: float, i_inf: float, tau: float, on: bool) -> None:
        n = max(1, math.ceil(dt / self.step_s))
        for k in range(n):
            s = dt * k / n
            self.times.append(t0 + s)
            self.currents.append(i_inf + (i0 - i_inf) * math.exp(-s / tau))
            self.states.append(on)

    def finish(self, t_end: float, i_end: float, on: bool) -> Waveform:
        self.times.append(t_end)
        self.currents.append(i_end)
        self.states.append(on)
        return Waveform(np.array(self.times), np.array(self.currents), np.array(self.states, dtype=bool))


@kernels.helper
def coil_period(s: float, i: float, on: bool, active: bool, lo: float, hi: float, duration_s: float, tau: float,
                supply: float, i_on: float, i_off: float, recorder: _Recorder | None
                ) -> tuple[float, bool, float, float, float, float, int]:
    """Event-driven exact integration of one winding over one period (module docstring): polarity ``s``, start
    current ``i`` (A) and comparator state ``on``; ``active`` drives the band [lo, hi] (A along the polarity;
    inf, inf: the switch held on); τ (s), supply E (V), I_on and I_off (A). Returns the end current and
    comparator state, ∫ i dt (A·s), the on time (s), the energy drawn and returned (J) and the switch count.

    A kernel (:mod:`acds_common.kernels`), called through :func:`unit_period`; ``recorder`` (a waveform) only on
    the plain function.
    """
    band = recorder is None and 0.0 < lo < hi < i_on  # a band the bridge can hold: whole cycles in closed form
    t = 0.0
    integral_i = 0.0
    on_time = 0.0
    drawn = 0.0
    returned = 0.0
    switches = 0
    while True:
        # Comparator: switch at the thresholds (decided on the present current).
        x = s * i
        new_on = active and (x <= lo or (on and x < hi))
        if new_on != on:
            switches += 1
            on = new_on
        # The path and the event that ends this segment.
        if on and x >= 0.0:  # transistor path along the polarity
            i_inf, target, transistor = s * i_on, s * hi, True
        elif on:  # reversal: opposite pair's diodes carry the current down to zero
            i_inf, target, transistor = s * i_off, 0.0, False
        elif i != 0.0:  # freewheel through the diodes
            i_inf = -math.copysign(i_off, i)
            target = s * lo if (active and s * i > lo) else 0.0
            transistor = False
        else:  # off at zero current: the diodes block, nothing happens
            i_inf, target, transistor = 0.0, 0.0, False
        if transistor and x == lo and band:
            # Settled in the band at the turn-on edge: the waveform is exactly periodic until the
            # period ends, so the whole on/off cycles that end before it are added in closed form.
            n, t_on, t_off, area_on, area_off = whole_cycles(lo, hi, t, duration_s, tau, i_on, i_off)
            if n > 0:
                t += n * (t_on + t_off)
                integral_i += n * s * (area_on + area_off)
                on_time += n * t_on
                drawn += n * supply * area_on
                returned += n * supply * area_off
                switches += 2 * n
        remaining = duration_s - t
        reach = rl_circuit.time_to_reach_s(i, i_inf, target, tau)
        hit = reach < remaining
        dt = reach if hit else remaining
        i_free, area = rl_circuit.segment(i, i_inf, tau, dt)  # area = ∫ i dt over the segment
        i_end = target if hit else i_free
        if recorder is not None:
            recorder.segment(t, dt, i, i_inf, tau, on)
        integral_i += area
        if on:
            on_time += dt
        if transistor:
            drawn += supply * abs(area)
        else:
            returned += supply * abs(area)
        t += dt
        i = i_end
        if not hit:
            break
    return i, on, integral_i, on_time, drawn, returned, switches


@kernels.helper
def whole_cycles(lo: float, hi: float, t_s: float, duration_s: float, tau: float, i_on: float,
                 i_off: float) -> tuple[int, float, float, float, float]:
    """Number of whole band cycles from ``t_s`` that end strictly before ``duration_s`` (the rest is
    integrated edge by edge) and one cycle's t_on, t_off, ∫|i| dt on, ∫|i| dt off, from the same
    exponentials as eq. 4-27."""
    t_on = tau * math.log((i_on - lo) / (i_on - hi))
    t_off = tau * math.log((hi + i_off) / (lo + i_off))
    area_on = i_on * t_on + (lo - i_on) * tau * (1.0 - math.exp(-t_on / tau))
    area_off = -i_off * t_off + (hi + i_off) * tau * (1.0 - math.exp(-t_off / tau))
    period = t_on + t_off
    n = int((duration_s - t_s) / period)
    if n > 0 and t_s + n * period >= duration_s:  # rounding: keep the period's end for the edges
        n -= 1
    return n, t_on, t_off, area_on, area_off


#: A unit's state row (:class:`BridgeSwitchCoil`; a drive assembly keeps its six units' rows in one table):
#: coil current (A), comparator state and polarity (1.0 on / ±1.0), fault code, driver power (1.0 powered).
CURRENT, BRIDGE_ON, POLARITY, FAULT, POWERED = range(5)
#: The fault codes of the state row, indexed by code (0.0: healthy).
FAULT_CODES = (None, CoilFault.OPEN_WINDING, CoilFault.STUCK_ON_BRIDGE, CoilFault.DEAD_DRIVER)
_OPEN, _STUCK, _DEAD = (float(FAULT_CODES.index(f)) for f in CoilFault)


def state_table(rows: int, compiled: bool) -> Any:
    """``rows`` unit state rows (healthy, powered, no current, positive polarity): a numpy table for the
    compiled kernels (which update it in place; a unit holds a view of its row), lists for the plain
    functions (faster there)."""
    table = [[0.0, 0.0, 1.0, 0.0, 1.0] for _ in range(rows)]
    return np.array(table) if compiled else table


@kernels.helper
def unit_period(row, polarity: float, drive: bool, lo: float, hi: float, duration_s: float, tau: float,
                supply: float, i_on: float, i_off: float, recorder: _Recorder | None
                ) -> tuple[float, float, float, float, int]:
    """One unit (driver + winding) over one period (spec §6, seed 002 §4.2.5), its state ``row`` (see
    :data:`CURRENT`) updated in place: the bridge routed to ``polarity`` (0 keeps the last; a stuck-on pair
    keeps its own), the drive (:func:`bridge_drive` / :func:`level_drive`) gated by the fault and the driver
    power, then :func:`coil_period`. Returns ∫ i dt (A·s), the on time (s), the energy drawn and returned (J)
    and the switch count. An open winding carries no current; the comparator, seeing none, holds the bridge on
    while driven.

    A kernel (:mod:`acds_common.kernels`): a row is a list (plain) or a numpy row (compiled).
    """
    fault = row[FAULT]
    if polarity != 0.0 and fault != _STUCK:
        row[POLARITY] = polarity
    on = row[BRIDGE_ON] != 0.0
    if fault == _OPEN:
        row[CURRENT] = 0.0
        row[BRIDGE_ON] = 1.0 if drive else 0.0
        if recorder is not None:
            recorder.segment(0.0, duration_s, 0.0, 0.0, tau, drive)
        return 0.0, duration_s if drive else 0.0, 0.0, 0.0, 1 if drive != on else 0
    if fault == _DEAD or row[POWERED] == 0.0:
        drive = False
    elif fault == _STUCK:
        drive, lo, hi = True, math.inf, math.inf
    i = row[CURRENT]
    if not (drive or on or i != 0.0) and recorder is None:
        # Off at zero current and nothing to drive (a standby unit): the diodes block, nothing happens.
        row[CURRENT] = 0.0
        return 0.0, 0.0, 0.0, 0.0, 0
    i, on, integral_i, on_time, drawn, returned, switches = coil_period(
        row[POLARITY], i, on, drive, lo, hi, duration_s, tau, supply, i_on, i_off, recorder)
    row[CURRENT] = i
    row[BRIDGE_ON] = 1.0 if on else 0.0
    return integral_i, on_time, drawn, returned, switches


@kernels.helper
def period_figures(integral_i: float, on_time: float, drawn: float, duration_s: float, current_a: float,
                   moment_per_amp_am2: float, sense_gain_v_per_a: float
                   ) -> tuple[float, float, float, float, float, float]:
    """A period's report (:class:`PeriodResult`) from :func:`unit_period`'s totals and the end current: average
    current (A), average and end moment (A·m²), duty, power (W) and e_ft (V)."""
    avg_current_a = integral_i / duration_s
    return (avg_current_a, moment_per_amp_am2 * avg_current_a, moment_per_amp_am2 * current_a,
            on_time / duration_s, drawn / duration_s, sense_gain_v_per_a * current_a)


class BridgeSwitchCoil:
    """One winding with its bridge-switch driver, integrated exactly between switching events (spec §6).

    coil, driver: parameters; current0_a: initial coil current, A (signed).
    The object keeps the coil current, the bridge state and the last polarity
    between calls, so consecutive ``run`` calls form one continuous waveform; they,
    the fault and the driver power are its state row (:func:`unit_period`), its own
    or, given ``state``, a row of a drive assembly's table.
    """

    def __init__(self, coil: CoilParams, driver: DriverParams, current0_a: float = 0.0, state: Any = None) -> None:
        if not math.isfinite(current0_a):
            raise EmDriverError(f'current0_a must be finite, got {current0_a!r}')
        self.coil = coil
        self.driver = driver
        #: What :func:`unit_period` reads of the circuit: τ (s), supply E (V), I_on and I_off (A).
        self.circuit = (coil.tau_s, driver.supply_v, _on_current_a(coil, driver), _off_current_a(coil, driver))
        self._unit_period = kernels.compiled(unit_period)
        row = state_table(1, self._unit_period is not unit_period)[0] if state is None else state
        row[CURRENT] = float(current0_a)
        row[POLARITY] = 1.0 if current0_a >= 0.0 else -1.0
        self._row = row

    @property
    def current_a(self) -> float:
        """Present coil current, A (signed)."""
        return float(self._row[CURRENT])

    @property
    def bridge_on(self) -> bool:
        """Present comparator state: True while the bridge pair is commanded on."""
        return bool(self._row[BRIDGE_ON])

    @property
    def on_current_a(self) -> float:
        """I_on = (E − 2·V_ces)/R, A: the largest current the bridge can hold."""
        return self.circuit[2]

    @property
    def fault(self) -> CoilFault | None:
        """The injected failure, or None."""
        return FAULT_CODES[int(self._row[FAULT])]

    @property
    def powered(self) -> bool:
        """Driver power (the TA powers only the active unit): unpowered, nothing drives
        the winding, even a stuck-on bridge; its current decays through the diodes."""
        return bool(self._row[POWERED])

    @powered.setter
    def powered(self, on: bool) -> None:
        self._row[POWERED] = 1.0 if on else 0.0

    def e_ft_v(self) -> float:
        """Current-sensor telemetry voltage e_ft, V (signed; gain ``current_sense_gain_v_per_a``)."""
        return self.driver.current_sense_gain_v_per_a * self.current_a

    def set_fault(self, fault: CoilFault | str | None) -> None:
        """Inject a failure ('open_winding', 'stuck_on_bridge', 'dead_driver') or clear it with None."""
        self._row[FAULT] = float(FAULT_CODES.index(CoilFault.parse(fault, 'coil')))

    def run(self, command_current_a: float, duration_s: float, record: bool = False,
            record_step_s: float | None = None) -> PeriodResult:
        """Hold the hysteresis band about command_current_a (A, signed) for duration_s (s).

        The bridge drives the command's polarity; a command the supply cannot reach
        saturates (bridge stays on, current → I_on); a zero command turns the bridge
        off and the current decays to zero through the diodes. ``record`` keeps the
        waveform with points at most ``record_step_s`` apart (default τ/200).
        """
        if not math.isfinite(command_current_a):
            raise EmDriverError(f'command current must be finite, got {command_current_a!r}')
        drive = bridge_drive(float(command_current_a), self.driver.epsilon, self.driver.band_floor_a)
        return self._simulate(drive, duration_s, record, record_step_s)

    def run_constant_level(self, level: int, duration_s: float, record: bool = False,
                           record_step_s: float | None = None) -> PeriodResult:
        """Saturated constant-level drive (seed 001 SSS): level −1/0/+1 switches the full supply.

        The switch stays on (no current band), so the coil resistance alone limits
        the current: i → (E − 2·V_ces)/R with τ = L/R (E/R when v_ces_v = 0). Level 0
        turns it off; the current decays through the diodes.
        """
        if level not in (-1, 0, 1):
            raise EmDriverError(f'constant-level command must be -1, 0 or +1, got {level!r}')
        return self._simulate(level_drive(int(level)), duration_s, record, record_step_s)

    def _simulate(self, drive: tuple[float, bool, float, float], duration_s: float, record: bool,
                  record_step_s: float | None) -> PeriodResult:
        """Event-driven exact integration over one period (see the module docstring and :func:`unit_period`)."""
        if not (math.isfinite(duration_s) and duration_s > 0.0):
            raise EmDriverError(f'duration_s must be a finite positive time, got {duration_s!r}')
        recorder = None
        if record:
            step = self.circuit[0] / 200.0 if record_step_s is None else record_step_s
            if not (math.isfinite(step) and step > 0.0):
                raise EmDriverError(f'record_step_s must be a finite positive time, got {record_step_s!r}')
            recorder = _Recorder(step)
        period = self._unit_period if recorder is None else unit_period  # the recorder: the plain function
        integral_i, on_time, drawn, returned, switches = period(
            self._row, *drive, duration_s, *self.circuit, recorder)
        i = self.current_a
        waveform = recorder.finish(duration_s, i, self.bridge_on) if recorder is not None else None
        avg_current_a, avg_moment, end_moment, duty, power, e_ft = period_figures(
            integral_i, on_time, drawn, duration_s, i, self.coil.moment_per_amp_am2,
            self.driver.current_sense_gain_v_per_a)
        return PeriodResult(avg_current_a, i, avg_moment, end_moment, duty, switches, drawn, returned,
                            drawn - returned, power, e_ft, waveform)
