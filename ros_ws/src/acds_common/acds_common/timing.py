"""Flight-software timing: a node's wall time per step, in bounded memory (issue 20 §4; no rclpy).

The lockstep host (:mod:`acds_common.lockstep`) measures, for every step k, the wall time from the
moment each stage of k became ready (its last needed input arrived, or the stage before it fired) to
after the stage's outputs were published, summed over the node's stages: the node's own time for the
step, whatever the rest of the graph does. The samples go into a :class:`StepTimes`: a fixed-bin
logarithmic histogram (:data:`BINS_PER_DECADE` bins per decade from :data:`LO_S` up), so p50 and p99
are read to one bin (≤ 6 % high) and memory does not grow with the run; the maximum is exact.
Wall times describe the machine, not the data: they never enter a message the truth digest hashes,
and on ``/diagnostics`` their keys start with :data:`~acds_common.messages.WALL_CLOCK_PREFIX`.
"""

from __future__ import annotations

import json
import math
from typing import Any

from acds_common.messages import WALL_CLOCK_PREFIX

#: The histogram's lower edge (1 µs; anything faster counts in the first bin), bins per decade, decades.
LO_S, BINS_PER_DECADE, DECADES = 1e-6, 40, 8
#: What a node process prints as it leaves, followed by its timing as one JSON object (the launcher reads it).
TIMING_PREFIX = 'STEP TIMING '
#: The words of a node's failure at a step over its deadline with ``deadline_strict`` (the launcher blames no other node).
DEADLINE_FAILURE = 'over the deadline of'


class StepTimes:
    """Per-step wall times of one node: count, exact maximum, log-binned quantiles, steps over a deadline."""

    __slots__ = ('bins', 'count', 'deadline_s', 'first_over', 'max_s', 'over')

    def __init__(self, deadline_s: float = 0.0) -> None:
        self.bins = [0] * (BINS_PER_DECADE * DECADES + 1)
        self.count = 0
        self.max_s = 0.0
        self.deadline_s = deadline_s
        self.over = 0
        self.first_over: int | None = None

    def add(self, k: int, seconds: float) -> bool:
        """Record step k's wall time; True when it is over the deadline (if any)."""
        i = 0 if seconds <= LO_S else int(math.log10(seconds / LO_S) * BINS_PER_DECADE) + 1
        self.bins[min(i, len(self.bins) - 1)] += 1
        self.count += 1
        if seconds > self.max_s:
            self.max_s = seconds
        if 0.0 < self.deadline_s < seconds:
            self.over += 1
            if self.first_over is None:
                self.first_over = k
            return True
        return False

    def quantile(self, q: float) -> float:
        """The q-quantile, seconds: the upper edge of the bin it falls in, never above the maximum (0 if empty)."""
        if not self.count:
            return 0.0
        rank, seen = q * self.count, 0
        for i, n in enumerate(self.bins):
            seen += n
            if seen >= rank and n:
                return min(LO_S * 10 ** (i / BINS_PER_DECADE), self.max_s)
        return self.max_s

    def report(self) -> dict[str, Any]:
        """p50, p99, max in ms, the step count, and the deadline and steps over it (when one is set)."""
        out: dict[str, Any] = {'steps': self.count, 'p50_ms': self.quantile(0.5) * 1e3,
                               'p99_ms': self.quantile(0.99) * 1e3, 'max_ms': self.max_s * 1e3}
        if self.deadline_s > 0:
            out.update(deadline_ms=self.deadline_s * 1e3, over_deadline=self.over, first_over_step=self.first_over)
        return out

    def diagnostic_values(self) -> tuple[tuple[str, str], ...]:
        """The report as /diagnostics key/values, every key wall-clock prefixed (digests leave them out)."""
        return tuple((f'{WALL_CLOCK_PREFIX}step_{k}', f'{v:.3f}' if isinstance(v, float) else str(v))
                     for k, v in self.report().items())

    def line(self) -> str:
        """The line a node prints as it leaves (:data:`TIMING_PREFIX` + JSON)."""
        return TIMING_PREFIX + json.dumps(self.report())


def overrun(k: int, wall_s: float, deadline_ms: float) -> str:
    """The failure of step k over its deadline with ``--deadline-strict`` (one line, naming the step)."""
    return (f'step {k} took {wall_s * 1e3:.3f} ms from its last input to its outputs, {DEADLINE_FAILURE} '
            f'{deadline_ms:g} ms (--deadline-strict)')


def parse_line(line: str) -> dict[str, Any] | None:
    """The timing a node's output line announces (:meth:`StepTimes.line`), or None."""
    _, mark, rest = line.partition(TIMING_PREFIX)
    if not mark:
        return None
    try:
        value = json.loads(rest)
    except ValueError:
        return None
    return value if isinstance(value, dict) else None


def table(timing: dict[str, dict[str, Any] | None]) -> list[str]:
    """The run's timing table, one line per node (a node that left no report: a dash)."""
    lines = [f'{"node":28s} {"steps":>7s} {"p50 ms":>9s} {"p99 ms":>9s} {"max ms":>9s}  deadline']
    for node, t in timing.items():
        if t is None:
            lines.append(f'{node:28s} {"—":>7s}  (no timing report: the process did not leave cleanly)')
            continue
        budget = (f'{t["over_deadline"]} over {t["deadline_ms"]:g} ms' + (
            f' (first at step {t["first_over_step"]})' if t['over_deadline'] else '')) if 'deadline_ms' in t else '—'
        lines.append(f'{node:28s} {t["steps"]:7d} {t["p50_ms"]:9.3f} {t["p99_ms"]:9.3f} {t["max_ms"]:9.3f}  {budget}')
    return lines


def deadline_warnings(timing: dict[str, dict[str, Any] | None]) -> list[str]:
    """One line per node with steps over its deadline."""
    return [f'{node}: {t["over_deadline"]} of {t["steps"]} steps over the {t["deadline_ms"]:g} ms deadline '
            f'(first at step {t["first_over_step"]}; max {t["max_ms"]:.3f} ms)'
            for node, t in timing.items() if t and t.get('over_deadline')]
