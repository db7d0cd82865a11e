"""Which steps a recording holds, per per-step topic: the gaps between each topic's first and last step.

A recorder joining a running graph (``acds record``) is outside the lockstep handshake: under load
it can fall more than the history depth behind and miss steps in the middle of its bag (issue 18
item 6). :class:`StepCoverage` follows, as messages arrive, the steps seen on every per-step topic
as sorted runs of consecutive steps (one run when nothing is missing, so memory does not grow with
the run), and says which steps are missing between each topic's first and last. The recorder stores
them in the bag's metadata (custom data ``acds.gaps``: :func:`gaps_yaml`), ``acds info`` prints
them (:func:`describe`) and ``acds record`` fails unless told ``--allow-gaps``.
"""

from __future__ import annotations

import bisect
import itertools
from collections.abc import Iterable
from typing import Any

import yaml

#: Custom-data key (``acds.<key>`` in the bag) of the gaps, and its value when they could not be checked.
GAPS_KEY = 'gaps'
UNCHECKED = 'unchecked'


class StepCoverage:
    """The steps seen per topic of ``watched`` (absolute names) for stamps at ``dt_ns`` (module docstring)."""

    def __init__(self, dt_ns: int, watched: Iterable[str]) -> None:
        self.dt_ns = dt_ns
        self._runs: dict[str, list[list[int]]] = {t: [] for t in watched}

    def add(self, topic: str, stamp_ns: int) -> None:
        """A message of ``topic`` stamped ``stamp_ns`` arrived (a topic not watched is ignored)."""
        runs = self._runs.get(topic)
        if runs is None:
            return
        step = stamp_ns // self.dt_ns
        if runs and runs[-1][0] <= step <= runs[-1][1] + 1:  # in order (the usual case) or a repeat
            runs[-1][1] = max(runs[-1][1], step)
            return
        i = bisect.bisect_right(runs, [step, step])  # runs[i - 1] starts at or before step
        if i and runs[i - 1][1] + 1 >= step:
            runs[i - 1][1] = max(runs[i - 1][1], step)
            i -= 1
        else:
            runs.insert(i, [step, step])
        while i + 1 < len(runs) and runs[i + 1][0] <= runs[i][1] + 1:  # join the run after
            runs[i][1] = max(runs[i][1], runs.pop(i + 1)[1])

    def gaps(self) -> dict[str, list[tuple[int, int]]]:
        """Per topic with a hole: its missing steps as inclusive (first, last) ranges."""
        return {topic: [(a[1] + 1, b[0] - 1) for a, b in itertools.pairwise(runs)]
                for topic, runs in sorted(self._runs.items()) if len(runs) > 1}


def gaps_yaml(gaps: dict[str, list[tuple[int, int]]]) -> str:
    """The custom-data text of ``gaps`` (``{}``: checked, nothing missing)."""
    return yaml.safe_dump({t: [[a, b] for a, b in ranges] for t, ranges in gaps.items()}, sort_keys=True)


def missing_steps(ranges: Iterable[Any]) -> int:
    """The number of steps in inclusive (first, last) ranges."""
    return sum(b - a + 1 for a, b in ranges)


def describe(text: str | None) -> str | None:
    """One line about the stored gaps (custom data ``acds.gaps``); None when the bag has no such record."""
    if text is None:
        return None
    if text.strip() == UNCHECKED:
        return 'not checked (the recorder did not know the control period: record with --run-dir)'
    gaps = yaml.safe_load(text) or {}
    if not gaps:
        return 'none (every per-step topic holds every step from its first to its last)'
    parts = []
    for topic, ranges in gaps.items():
        shown = ', '.join(f'{a}' if a == b else f'{a}–{b}' for a, b in ranges[:3]) + (', …' if len(ranges) > 3 else '')
        parts.append(f'{topic} misses {missing_steps(ranges)} step(s) ({shown})')
    return f'{len(gaps)} topic(s) miss steps: ' + '; '.join(parts)
