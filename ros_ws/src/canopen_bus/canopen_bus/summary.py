"""The bus section of a run's summary: what the flight computer wrote and the timing of the wall-clock edge (spec §13).

Declared in the entry-point group ``acds.summaries``. Per step k, from ``cards/timing`` (the sensors' wall
lateness against the step's schedule t_wall(0) + t_k / R, the step's largest SDO request→reply time, the
largest age of a setpoint frame when the step sampled it) and ``cards/current_setpoint`` (the held setpoints
applied at k): p50/p99/max of each in ms (:class:`acds_common.timing.StepTimes`: quantiles to one log bin,
≤ 6 % high; the maximum exact), the steps whose sensors went out more than one step (Δt / R) late, counted and
the first ones named, the steps at which the applied setpoints changed, and the largest |setpoint|.
"""

from __future__ import annotations

import math
from typing import Any

from acds_common import topics
from acds_common.timing import StepTimes

from canopen_bus.nodes import SETPOINT, TIMING

TIMING_TOPIC, SETPOINT_TOPIC = topics.resolve(TIMING), topics.resolve(SETPOINT)
#: Late steps named in the summary (the count covers them all).
NAMED_LATE_STEPS = 20
KEYS = ('can_sensor_lateness_ms', 'can_sdo_latency_ms', 'can_setpoint_age_ms', 'can_late_steps', 'can_late_step_list',
        'can_setpoint_changes', 'can_first_setpoint_step', 'can_peak_setpoint_ma')
#: The summary keys this module contributes (:data:`acds_common.plugins.KEYS_ATTRIBUTE`).
SUMMARY_KEYS = KEYS


def applies(scenario: Any) -> bool:
    return 'canopen_cards' in scenario.get('', 'nodes')


def null_keys(summary: dict[str, Any]) -> None:
    """Only runs with CAN cards have these keys."""


class Accumulator:
    topics = (TIMING_TOPIC, SETPOINT_TOPIC)

    def __init__(self, scenario: Any) -> None:
        self.step_wall_s = scenario.control_period_s / scenario.get('can_bus', 'rtf')
        self.series = (StepTimes(), StepTimes(), StepTimes())
        self.late: list[int] = []
        self.late_count = 0
        self.changes = 0
        self.first_k: int | None = None
        self.last: tuple | None = None
        self.peak_a = 0.0

    def step(self, k: int, values: dict[str, Any]) -> None:
        timing = values.get(TIMING_TOPIC)
        if timing is not None:
            for series, v in zip(self.series, timing, strict=True):
                if not math.isnan(v):
                    series.add(k, v)
            if not math.isnan(timing[0]) and timing[0] > self.step_wall_s:
                self.late_count += 1
                if len(self.late) < NAMED_LATE_STEPS:
                    self.late.append(k)
        sp = values.get(SETPOINT_TOPIC)
        if sp is not None:
            sp = tuple(sp)
            if self.last is not None and sp != self.last:
                self.changes += 1
                if self.first_k is None:
                    self.first_k = k
            self.last = sp
            self.peak_a = max(self.peak_a, *(abs(v) for v in sp))

    def contribute(self, summary: dict[str, Any]) -> None:
        ms = [{q: t.report()[f'{q}_ms'] for q in ('p50', 'p99', 'max')} if t.count else None for t in self.series]
        summary.update(dict(zip(KEYS, (*ms, self.late_count, self.late, self.changes, self.first_k,
                                       self.peak_a * 1e3), strict=True)))


def print_tables(summary: dict[str, Any]) -> None:
    if 'can_late_steps' not in summary:
        return

    def pct(p: dict | None) -> str:
        return 'none' if not p else f'p50 {p["p50"]:.3f}, p99 {p["p99"]:.3f}, max {p["max"]:.3f} ms'

    s = summary
    rows = [
        ('sensor frames late vs the wall schedule', pct(s['can_sensor_lateness_ms'])),
        ('steps with sensors late by more than a step', f'{s["can_late_steps"]}'
         + (f' (first: {", ".join(map(str, s["can_late_step_list"]))})' if s['can_late_step_list'] else '')),
        ('SDO request → reply (largest per step)', pct(s['can_sdo_latency_ms'])),
        ('setpoint age when applied (largest per step)', pct(s['can_setpoint_age_ms'])),
        ('applied setpoint changes', f'{s["can_setpoint_changes"]}' + (
            f' (first at step {s["can_first_setpoint_step"]})' if s['can_first_setpoint_step'] is not None else '')),
        ('largest |setpoint|', f'{s["can_peak_setpoint_ma"]:.3f} mA'),
    ]
    width = max(len(k) for k, _ in rows)
    print('\n  Flight software on the bus (CANopen cards):')
    for key, value in rows:
        print(f'    {key:<{width}}  {value}')
