"""CubeSat torque-rod detumble summary (seed 003): time to rest, the rods' energy, peak current and duty.

Contributed when the graph drives torque rods (``em_driver.driver_kind: torque_rod``, node
``em_driver`` present). Per step k, from what the nodes publish:

* body rate: ``truth/odometry`` of step k (the state at t_k);
* electrical: ``em_driver/power`` and ``em_driver/duty`` of step k (net bus power of both
  windings and |PWM duty| of the active winding per axis, over [t_k, t_k+1]) and
  ``em_driver/coil_current`` (active winding current at t_k+1), counted once the truth of step
  k + 1 is in (the rigid body integrated that step; the drive of the step the run ends at is not).

Detumbled: |ω| < ``dynamics.detumbled_rate`` (default 0.1°/s), the norm of the body rate (issue 14); the
same key ends the run at detumble with ``dynamics.stop_when_detumbled`` (``dynamics.detumbled``).
``detumble_time_min`` is the first t_k from which |ω| stays below it to the end of the run
(``None`` when the run ends above it; a run ended by that rule ends ``detumbled_hold`` after it);
``first_below_threshold_min`` the first t_k below it at all.
``detumble_energy_j`` is the bus energy of the three rods over [0, detumble time];
``energy_j`` over the whole run (energy a decaying winding returns to the bus counts negative).
``peak_current_ma``: largest |active winding current| at a step end (the rods settle within
milliseconds, so the end value is the step's plateau; the PWM ripple is < 1 % of full scale).
``mean_duty``: mean |duty| per axis; ``full_duty_fraction``: share of steps with some axis at
full duty (the law saturated at the rods' maximum moment).
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np
from acds_common import topics

ODOMETRY, POWER, DUTY, CURRENT = (topics.resolve(t) for t in (
    topics.TRUTH_ODOMETRY, topics.COIL_POWER, topics.COIL_DUTY, topics.COIL_CURRENT))


#: The summary keys this module contributes (:data:`acds_common.plugins.KEYS_ATTRIBUTE`).
SUMMARY_KEYS = ('detumble_threshold_deg_s', 'initial_rate_deg_s', 'final_rate_deg_s', 'detumble_time_min',
                'first_below_threshold_min', 'detumble_energy_j', 'energy_j', 'mean_power_w', 'peak_current_ma', 'mean_duty',
                'mean_duty_to_detumble', 'full_duty_fraction')


def applies(scenario: Any) -> bool:
    """The detumble summary comes from runs whose em_driver drives torque rods."""
    return scenario.get('em_driver', 'driver_kind') == 'torque_rod' and 'em_driver' in scenario.get('', 'nodes')


def null_keys(_summary: dict[str, Any]) -> None:
    """No keys of this module appear outside torque-rod runs."""


class Accumulator:
    """Streaming detumble summary: the last step above the threshold, running energy, peaks and duty sums."""

    topics = (ODOMETRY, POWER, DUTY, CURRENT)

    def __init__(self, scenario: Any) -> None:
        self.dt_s = scenario.control_period_s
        self.threshold_rad_s = scenario.get('dynamics', 'detumbled_rate')
        self.initial_rate: float | None = None
        self.final_rate: float | None = None
        self.last_k: int | None = None
        self.last_above_k: int | None = None
        self.first_below_k: int | None = None
        self.energy_j = 0.0
        self.energy_to_last_above_j = 0.0
        self.peak_current_a = 0.0
        self.duty_sum = np.zeros(3)
        self.duty_sum_to_last_above = np.zeros(3)
        self.full_duty_steps = 0
        self.electrical_steps = 0
        self._pending: tuple[int, Any, Any, Any] | None = None  # step k's electrical values, until truth k + 1

    def step(self, k: int, values: dict[str, Any]) -> None:
        """Step k's rate (t_k); counts the rods' electrical values of step k − 1, which brought the body here."""
        odom = values.get(ODOMETRY)
        if odom is not None and self._pending is not None and self._pending[0] == k - 1:
            self._count(*self._pending)
        self._pending = None
        if odom is not None:
            rate = math.sqrt(sum(w * w for w in odom.angular))
            if self.initial_rate is None:
                self.initial_rate = rate
            self.final_rate, self.last_k = rate, k
            if rate >= self.threshold_rad_s:
                self.last_above_k = k
            elif self.first_below_k is None:
                self.first_below_k = k
        power, duty, current = values.get(POWER), values.get(DUTY), values.get(CURRENT)
        if power is not None and duty is not None and current is not None:
            self._pending = (k, power, duty, current)

    def _count(self, k: int, power: Any, duty: Any, current: Any) -> None:
        """The electrical values of integrated step k (over [t_k, t_k+1])."""
        self.energy_j += float(sum(power)) * self.dt_s
        self.duty_sum += duty
        self.electrical_steps += 1
        self.full_duty_steps += bool(max(duty) >= 1.0 - 1e-12)
        self.peak_current_a = max(self.peak_current_a, float(np.max(np.abs(current))))
        if k == self.last_above_k:  # not yet detumbled at t_k: this step's energy was spent to get there
            self.energy_to_last_above_j = self.energy_j
            self.duty_sum_to_last_above = self.duty_sum.copy()

    def contribute(self, summary: dict[str, Any]) -> None:
        """Add the ``detumble_*`` keys and the rods' electrical totals."""
        settled_k = None
        if self.last_k is not None:
            settled_k = 0 if self.last_above_k is None else self.last_above_k + 1
            if settled_k > self.last_k:
                settled_k = None
        n = max(self.electrical_steps, 1)
        summary.update({
            'detumble_threshold_deg_s': math.degrees(self.threshold_rad_s),
            'initial_rate_deg_s': None if self.initial_rate is None else math.degrees(self.initial_rate),
            'final_rate_deg_s': None if self.final_rate is None else math.degrees(self.final_rate),
            'detumble_time_min': None if settled_k is None else settled_k * self.dt_s / 60,
            'first_below_threshold_min': None if self.first_below_k is None else self.first_below_k * self.dt_s / 60,
            'detumble_energy_j': None if settled_k is None else (
                0.0 if self.last_above_k is None else self.energy_to_last_above_j),
            'energy_j': self.energy_j,
            'mean_power_w': self.energy_j / (n * self.dt_s),
            'peak_current_ma': self.peak_current_a * 1e3,
            'mean_duty': (self.duty_sum / n).tolist(),
            'mean_duty_to_detumble': None if settled_k is None or self.last_above_k is None else (
                self.duty_sum_to_last_above / (self.last_above_k + 1)).tolist(),
            'full_duty_fraction': self.full_duty_steps / n,
        })


def print_tables(summary: dict[str, Any]) -> None:
    """The detumble report, SI (the seed's units)."""
    if 'detumble_threshold_deg_s' not in summary:
        return

    def show(value: Any, fmt: str, unit: str) -> str:
        return 'not reached in this run' if value is None else f'{value:{fmt}} {unit}'

    def minutes(value: float | None) -> str:
        return 'not reached in this run' if value is None else f'{value * 60:.0f} s ({value:.1f} min)'

    s = summary
    rows = [
        ('|ω| at t0', show(s['initial_rate_deg_s'], '.4f', '°/s')),
        (f'time to |ω| < {s["detumble_threshold_deg_s"]:g}°/s (stays below)', minutes(s['detumble_time_min'])),
        ('first time below', minutes(s['first_below_threshold_min'])),
        ('rods energy to detumble', show(s['detumble_energy_j'], '.1f', 'J')),
        ('rods energy, whole run', show(s['energy_j'], '.1f', f'J (mean {s["mean_power_w"]:.4f} W)')),
        ('peak rod current', show(s['peak_current_ma'], '.2f', 'mA')),
        ('mean |duty| x, y, z', ', '.join(f'{d:.3f}' for d in s['mean_duty'])),
        ('steps at full duty', show(100 * s['full_duty_fraction'], '.1f', '%')),
        ('|ω| at the end', show(s['final_rate_deg_s'], '.4f', '°/s')),
    ]
    width = max(len(k) for k, _ in rows)
    print('\n  CubeSat detumble (torque rods):')
    for key, value in rows:
        print(f'    {key:<{width}}  {value}')
