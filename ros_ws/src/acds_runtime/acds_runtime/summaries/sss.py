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
ends is closed at the last step and flagged ``complete: false``.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np
from acds_common import topics
from acds_common.inertia import inertia_tensor
from ascs_mode_manager.sss_ascs import PassAccumulator
from dynamics.rigid_body_model import quat_to_dcm

KEYS = ('on_time_min', 'avg_torque_dyne_cm', 'peak_torque_dyne_cm', 'ripple_pct', 'spin_rate_change_rpm',
        'precession_deg', 'energy_j', 'mode')


def applies(scenario: Any) -> bool:
    """The per-pass report comes from runs of the SSS mode manager."""
    return scenario.get('modes', 'system') == 'sss' and 'ascs_mode_manager' in scenario.get('', 'nodes')


def null_keys(_summary: dict[str, Any]) -> None:
    """No keys of this module appear outside SSS runs."""


def _clean(value: Any) -> Any:
    return None if isinstance(value, float) and not math.isfinite(value) else value


MODE, TORQUE, DIPOLE, ODOMETRY, EVENTS = (topics.resolve(t) for t in (
    topics.MODE, topics.TRUTH_TORQUE_MAG, topics.DIPOLE_AVG, topics.TRUTH_ODOMETRY, topics.EVENTS))


class Accumulator:
    """Streaming per-pass report: each step k is added once the torque of step k + 1 is in."""

    topics = (MODE, TORQUE, DIPOLE, ODOMETRY)
    event_topics = (EVENTS,)

    def __init__(self, scenario: Any) -> None:
        sc = scenario
        self.dt_s = sc.control_period_s
        self.inertia = inertia_tensor(*sc.get('spacecraft', 'inertia')) * sc.get('spacecraft', 'inertia_scale')
        self.per_amp = np.array(sc.get('em_driver', 'coil_moment_per_amp_am2'))
        self.bus_v = sc.get('em_driver', 'supply_v')
        self.acc = PassAccumulator()
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
            _, mode, power, rate, axis = self._prev
            self.acc.add((k - 1) * self.dt_s, np.array(torque), rate, axis, power, mode)
            self.open_at_end = mode != 'off'
        self._prev = None
        mode_value = values.get(MODE)
        if mode_value and state is not None:
            pass_mode = dict(mode_value[0].values).get('pass_mode', 'off')
            dipole = np.array(values.get(DIPOLE) or (0.0, 0.0, 0.0))
            power = self.bus_v * float(np.sum(np.abs(dipole / self.per_amp)))
            self._prev = (k, pass_mode, power, *state)

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
            self.acc.add(k * self.dt_s, np.zeros(3), rate, axis, 0.0, 'off')
        passes = []
        for i, rep in enumerate(self.acc.reports):
            complete = not (self.open_at_end and i == len(self.acc.reports) - 1)
            passes.append({**{key: _clean(rep[key]) for key in KEYS},
                           'avg_torque_nm': rep['avg_torque_nm'], 'peak_torque_nm': rep['peak_torque_nm'],
                           't_start_s': rep['t_start_s'], 't_end_s': rep['t_end_s'], 'complete': complete})
        summary['perigee_passes'] = passes
        summary['sss_events'] = self.events


def print_tables(summary: dict[str, Any]) -> None:
    """The per-pass report, torques in dyne-cm and N·m."""
    if 'perigee_passes' not in summary:
        return
    events = summary.get('sss_events', [])
    print('\n  SSS events:')
    for e in events:
        print(f'    {e["text"]}')
    if not events:
        print('    (none)')
    passes = summary['perigee_passes']
    print(f'\n  SSS perigee passes ({len(passes)}):')
    header = (f'    {"#":>2} {"mode":<15} {"start":>8} {"on-time":>8} {"avg torque":>21} {"peak torque":>21} '
              f'{"ripple":>7} {"d spin":>9} {"precess":>8} {"energy":>8}')
    units = (f'    {"":>2} {"":<15} {"min":>8} {"min":>8} {"dyne-cm":>10} {"N·m":>10} {"dyne-cm":>10} '
             f'{"N·m":>10} {"% rms":>7} {"rpm":>9} {"deg":>8} {"J":>8}')
    print(header)
    print(units)
    for i, p in enumerate(passes, 1):
        ripple = f'{p["ripple_pct"]:7.1f}' if p['ripple_pct'] is not None else f'{"n/a":>7}'
        note = '' if p['complete'] else '  (still on at the end of the run)'
        print(f'    {i:>2} {p["mode"]:<15} {p["t_start_s"] / 60:8.2f} {p["on_time_min"]:8.2f} '
              f'{p["avg_torque_dyne_cm"]:10.1f} {p["avg_torque_nm"]:10.3e} '
              f'{p["peak_torque_dyne_cm"]:10.1f} {p["peak_torque_nm"]:10.3e} {ripple} '
              f'{p["spin_rate_change_rpm"]:+9.4f} {p["precession_deg"]:8.3f} {p["energy_j"]:8.1f}{note}')
    if not passes:
        print('    (no pass: the spin-plane field never reached the polarity-sensing level while enabled)')
