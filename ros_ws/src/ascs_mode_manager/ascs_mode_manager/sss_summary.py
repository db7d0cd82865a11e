"""SSS per-perigee-pass report (spec §8; seed 001): ``perigee_passes`` in the summary, and its table.

Built from what the run monitor recorded, one sample per control step k over [t_k, t_k+1):

* pass mode: the ``pass_mode`` key of the mode manager's step-k ``mode`` status
  (spin | attitude | direct_attitude | off);
* torque: ``truth/torque_magnetic`` of step k+1 (rigid_body's average of M × B_true over [t_k, t_k+1]);
* spin rate: body z rate of ``truth/odometry`` step k; spin axis: the direction of the angular
  momentum I·ω in ECI (so nutation does not read as precession);
* power: bus voltage × the step-average coil currents, the currents being the em_driver's step-average
  achieved dipole (``em_driver/dipole_avg`` step k) divided by each coil's moment per ampere
  (``em_driver.coil_moment_per_amp``), bus = ``em_driver.supply_v``: P = E·Σ|I_i|, what a saturated
  constant-level drive draws from the bus.

The statistics are :class:`ascs_mode_manager.sss_ascs.PassAccumulator`'s. A pass still on when the run
ends is closed at the last step and flagged ``complete: false``. The pass ripple is over the whole pass,
so it includes the field's rise and fall through perigee (the variable pulse width of seed 001 Fig. 9).

Beside the pass averages, each spin-mode pass reports its peak spin-plane field (|B| in the body x-y
plane, ``truth/b_body`` of its samples) and the one-revolution average torque and rms ripple of the
scenario's mechanization at that field, the quantity seed 001 quotes for the SSS-A system in a 0.3 G
perigee field: a constant field rotating in the spin plane at the pass's starting spin rate, the
mechanization's comparator at the scenario's polarity-sensing level, one revolution
(:func:`ascs_mode_manager.spin_mechanizations.simulate_rotating_field`).
"""

from __future__ import annotations

import dataclasses
import math
from typing import Any

import numpy as np
from acds_common import topics
from acds_common.attitude import quat_to_dcm
from acds_common.inertia import inertia_tensor
from acds_common.units import nm_to_dyne_cm, rad_s_to_rpm, tesla_to_gauss

from ascs_mode_manager.spin_mechanizations import MECHANIZATIONS, Mechanization, ripple_pct, simulate_rotating_field
from ascs_mode_manager.sss_ascs import PassAccumulator

KEYS = ('on_time_min', 'avg_torque_dyne_cm', 'peak_torque_dyne_cm', 'ripple_pct', 'spin_rate_change_rpm',
        'precession_deg', 'energy_j', 'mode')
#: Keys of the one-revolution quantities at the pass's peak field (None for attitude passes).
REVOLUTION_KEYS = ('peak_spin_plane_field_gauss', 'one_rev_avg_torque_dyne_cm', 'one_rev_ripple_pct')


def one_revolution(mech: Mechanization, field_t: float, spin_rate_rad_s: float, polarity_level_t: float,
                   direction: int) -> tuple[float, float]:
    """(average spin torque N·m, rms ripple % of it) of ``mech`` over one revolution in a constant field of
    ``field_t`` (T) rotating in the spin plane at ``spin_rate_rad_s``, comparator level ``polarity_level_t``
    (T), ``direction`` +1 spin-up / −1 despin; ripple NaN where the average is zero (field below the level)."""
    rpm = rad_s_to_rpm(spin_rate_rad_s)
    history = simulate_rotating_field(mech, tesla_to_gauss(field_t), rpm, duration_s=60.0 / rpm, direction=direction,
                                      polarity_level_t=polarity_level_t)
    return float(np.mean(history.torque_nm)), ripple_pct(history.torque_nm)


#: The summary keys this module contributes (:data:`acds_common.plugins.KEYS_ATTRIBUTE`).
SUMMARY_KEYS = ('perigee_passes', 'sss_events')


def applies(scenario: Any) -> bool:
    """The per-pass report comes from runs of the SSS mode manager."""
    return scenario.get('modes', 'system') == 'sss' and 'ascs_mode_manager' in scenario.get('', 'nodes')


def null_keys(_summary: dict[str, Any]) -> None:
    """No keys of this module appear outside SSS runs."""


def _clean(value: Any) -> Any:
    return None if isinstance(value, float) and not math.isfinite(value) else value


MODE, TORQUE, DIPOLE, ODOMETRY, B_BODY, EVENTS = (topics.resolve(t) for t in (
    topics.MODE, topics.TRUTH_TORQUE_MAG, topics.DIPOLE_AVG, topics.TRUTH_ODOMETRY, topics.TRUTH_B_BODY, topics.EVENTS))


class Accumulator:
    """Streaming per-pass report: each step k is added once the torque of step k + 1 is in."""

    topics = (MODE, TORQUE, DIPOLE, ODOMETRY, B_BODY)
    event_topics = (EVENTS,)

    def __init__(self, scenario: Any) -> None:
        sc = scenario
        self.dt_s = sc.control_period_s
        self.inertia = inertia_tensor(*sc.get('spacecraft', 'inertia')) * sc.get('spacecraft', 'inertia_scale')
        self.per_amp = np.array(sc.get('em_driver', 'coil_moment_per_amp_am2'))
        self.bus_v = sc.get('em_driver', 'supply_v')
        self.acc = PassAccumulator()
        self.mech = dataclasses.replace(MECHANIZATIONS[sc.get('sss', 'mechanization')], bus_v=sc.get('sss', 'bus_v'))
        self.level_t = sc.get('sss', 'polarity_level')
        #: The open pass's peak spin-plane field (T) and starting spin rate (rad/s); one entry per closed pass.
        self._open: tuple[float, float] | None = None
        self.pass_fields: list[tuple[float, float]] = []
        self._prev: tuple[int, str, float, float, np.ndarray] | None = None  # step k waiting for torque k+1
        self._last_state: tuple[int, float, np.ndarray] | None = None
        self.open_at_end = False
        self.events: list[dict[str, Any]] = []

    def step(self, k: int, values: dict[str, Any]) -> None:
        """Step k's pass mode, dipole and state; closes step k − 1 with this step's torque."""
        odom = values.get(ODOMETRY)
        state = None
        if odom is not None:
            omega = np.array(odom.angular)
            h_eci = quat_to_dcm(np.array(odom.orientation)) @ (self.inertia @ omega)
            state = (float(omega[2]), h_eci)
            self._last_state = (k, *state)
        torque = values.get(TORQUE)
        if self._prev is not None and torque is not None and self._prev[0] == k - 1:
            _, mode, power, rate, axis, field_t = self._prev
            self._add((k - 1) * self.dt_s, np.array(torque), rate, axis, power, mode, field_t)
            self.open_at_end = mode != 'off'
        self._prev = None
        mode_value = values.get(MODE)
        if mode_value and state is not None:
            pass_mode = dict(mode_value[0].values).get('pass_mode', 'off')
            dipole = np.array(values.get(DIPOLE) or (0.0, 0.0, 0.0))
            power = self.bus_v * float(np.sum(np.abs(dipole / self.per_amp)))
            b = values.get(B_BODY)
            field_t = 0.0 if b is None else float(np.hypot(b[0][0], b[0][1]))
            self._prev = (k, pass_mode, power, *state, field_t)

    def _add(self, t_s: float, torque: np.ndarray, rate: float, axis: np.ndarray, power: float, mode: str,
             field_t: float) -> None:
        """One sample to the pass statistics; the open pass's peak field and starting rate kept beside them."""
        if self.acc.add(t_s, torque, rate, axis, power, mode) is not None and self._open is not None:
            self.pass_fields.append(self._open)
            self._open = None
        if mode != 'off':
            peak, rate0 = self._open or (0.0, rate)
            self._open = (max(peak, field_t), rate0)

    def _revolution(self, report: dict[str, Any], peak_t: float, rate0: float) -> dict[str, Any]:
        """The one-revolution quantities of a pass at its peak spin-plane field (module docstring)."""
        out: dict[str, Any] = dict.fromkeys(REVOLUTION_KEYS)
        out['peak_spin_plane_field_gauss'] = float(tesla_to_gauss(peak_t))
        if report['mode'] == 'spin' and rate0 > 0.0:
            avg, ripple = one_revolution(self.mech, peak_t, rate0, self.level_t,
                                         -1 if report['avg_torque_nm'] < 0.0 else 1)
            out['one_rev_avg_torque_dyne_cm'] = float(nm_to_dyne_cm(avg))
            out['one_rev_ripple_pct'] = _clean(ripple)
        return out

    def event(self, _topic: str, text: str) -> None:
        """An ``events`` line."""
        head = text.split(' ', 2)
        try:
            t_s = float(head[0].removeprefix('t='))
        except ValueError:
            t_s = math.nan
        self.events.append({'t_s': _clean(t_s), 'kind': head[1] if len(head) > 1 else '', 'text': text})

    def contribute(self, summary: dict[str, Any]) -> None:
        """Add ``perigee_passes`` and ``sss_events``."""
        if self.open_at_end and self._last_state is not None:  # close with the state after the last torquing step
            k, rate, axis = self._last_state
            self._add(k * self.dt_s, np.zeros(3), rate, axis, 0.0, 'off', 0.0)
        passes = []
        for i, rep in enumerate(self.acc.reports):
            complete = not (self.open_at_end and i == len(self.acc.reports) - 1)
            passes.append({**{key: _clean(rep[key]) for key in KEYS},
                           'avg_torque_nm': rep['avg_torque_nm'], 'peak_torque_nm': rep['peak_torque_nm'],
                           't_start_s': rep['t_start_s'], 't_end_s': rep['t_end_s'], 'complete': complete,
                           **self._revolution(rep, *self.pass_fields[i])})
        summary['perigee_passes'] = passes
        summary['sss_events'] = self.events


def _cell(value: float | None, fmt: str, width: int) -> str:
    return f'{"—":>{width}}' if value is None else f'{value:{width}{fmt}}'


def print_tables(summary: dict[str, Any]) -> None:
    """The per-pass report (torques in dyne-cm and N·m) and, per spin pass, the one-revolution torque and
    ripple at its peak spin-plane field."""
    if 'perigee_passes' not in summary:
        return
    events = summary.get('sss_events', [])
    print('\n  SSS events:')
    for e in events:
        print(f'    {e["text"]}')
    if not events:
        print('    (none)')
    passes = summary['perigee_passes']
    print(f'\n  SSS perigee passes ({len(passes)}); pass ripple = rms about the pass average, including the '
          "field's rise and fall:")
    print(f'    {"#":>2} {"mode":<15} {"start":>8} {"on-time":>8} {"pass avg torque":>21} {"peak torque":>21} '
          f'{"pass":>8} {"d spin":>9} {"precess":>8} {"energy":>8}')
    print(f'    {"":>2} {"":<15} {"min":>8} {"min":>8} {"dyne-cm":>10} {"N·m":>10} {"dyne-cm":>10} '
          f'{"N·m":>10} {"ripple %":>8} {"rpm":>9} {"deg":>8} {"J":>8}')
    for i, p in enumerate(passes, 1):
        note = '' if p['complete'] else '  (still on at the end of the run)'
        print(f'    {i:>2} {p["mode"]:<15} {p["t_start_s"] / 60:8.2f} {p["on_time_min"]:8.2f} '
              f'{p["avg_torque_dyne_cm"]:10.1f} {p["avg_torque_nm"]:10.3e} '
              f'{p["peak_torque_dyne_cm"]:10.1f} {p["peak_torque_nm"]:10.3e} {_cell(p["ripple_pct"], ".1f", 8)} '
              f'{p["spin_rate_change_rpm"]:+9.4f} {p["precession_deg"]:8.3f} {p["energy_j"]:8.1f}{note}')
    if not passes:
        print('    (no pass: the spin-plane field never reached the polarity-sensing level while enabled)')
        return
    print('\n  At each pass\'s peak spin-plane field, one revolution of the mechanization (seed 001\'s quantity):')
    print(f'    {"#":>2} {"peak field":>10} {"1-rev avg torque":>16} {"1-rev ripple":>12}')
    print(f'    {"":>2} {"G":>10} {"dyne-cm":>16} {"% rms":>12}')
    for i, p in enumerate(passes, 1):
        print(f'    {i:>2} {_cell(p["peak_spin_plane_field_gauss"], ".4f", 10)} '
              f'{_cell(p["one_rev_avg_torque_dyne_cm"], ".1f", 16)} {_cell(p["one_rev_ripple_pct"], ".1f", 12)}')
