"""The printed run summary: one aligned row per key, in the study's units (seed units at this edge).

Keys carry their unit in the name (``_min``, ``_ftlbs``, ``_deg_s``, ``_gauss``, ``_am2``,
``_dyne_cm``, ``_rel``); each row is ``label  value  unit``, a per-axis value as ``x / y / z``
(and ``/ rss``), a missing value as ``—``. Tables (lists of records: transitions, passes,
events; reports holding records: a formation's vehicles, the dump report's orbits) are printed by
their summary modules (:func:`acds_runtime.summary.print_tables`). The
integration health (the largest RK4 step angle and its verdict) is always printed; the
momentum and energy drift rows appear only for torque-free runs, where they are integration error.
"""

from __future__ import annotations

import math
from typing import Any

#: Unit suffix of a key → (printed unit, number format).
UNITS: tuple[tuple[str, str, str], ...] = (
    ('_min', 'min', '.2f'),
    ('_ftlbs', 'ft-lb-sec', '.3f'),
    ('_deg_s', 'deg/s', '.4g'),
    ('_gauss', 'G', '.4f'),
    ('_am2', 'A·m²', '.1f'),
    ('_dyne_cm', 'dyne-cm', '.1f'),
    ('_rel', '(relative)', '.3e'),
    ('_rad', 'rad', '.3g'),
)
#: Keys of the headline, not rows.
HEADLINE = ('scenario', 'steps', 'sim_minutes', 'wall_seconds')
#: Rows that only mean something for a torque-free run (integration error), and the flag that says so.
DRIFT_KEYS = ('momentum_drift_rel', 'energy_drift_rel')
TORQUE_FREE = 'torque_free'
MISSING = '—'
#: Labels clearer than the key's words.
LABELS = {'b_min_gauss': '|B| min seen', 'b_max_gauss': '|B| max seen',
          'final_momentum_ftlbs': 'final |H| (body + wheels)', 'final_rates_deg_s': 'final body rates',
          'step_angle_max_rad': 'RK4 step angle max (|ω| + 2 ω_orbit)·h'}


def _unit(key: str) -> tuple[str, str, str]:
    """(label, unit, format) of a summary key."""
    for suffix, unit, fmt in UNITS:
        if key.endswith(suffix):
            return key[:-len(suffix)].replace('_', ' '), unit, fmt
    return key.replace('_', ' '), '', '.6g'


def _number(value: Any, fmt: str) -> str:
    if value is None or (isinstance(value, float) and not math.isfinite(value)):
        return MISSING
    if isinstance(value, bool):
        return 'yes' if value else 'no'
    if isinstance(value, float):
        return format(value, fmt)
    return str(value)


def summary_rows(summary: dict[str, Any]) -> list[tuple[str, str, str]]:
    """(label, value, unit) of every printable key, in the summary's order (module docstring)."""
    rows = []
    for key, value in summary.items():
        if key in HEADLINE or key == TORQUE_FREE:
            continue
        if key in DRIFT_KEYS and not summary.get(TORQUE_FREE):
            continue
        if isinstance(value, list) and value and isinstance(value[0], dict):
            continue  # a table: its module prints it
        if isinstance(value, dict) and any(isinstance(v, dict) or (isinstance(v, list) and v and isinstance(v[0], dict))
                                           for v in value.values()):
            continue  # a report with its own tables (the formation's vehicles, the dump report's orbits)
        label, unit, fmt = _unit(key)
        label = LABELS.get(key, label)
        if isinstance(value, dict):
            label += f' ({" / ".join(value)})'
            text = ' / '.join(_number(v, fmt) for v in value.values())
        elif isinstance(value, (list, tuple)):
            if len(value) == 3:
                label += ' (x / y / z)'
            text = ' / '.join(_number(v, fmt) for v in value) if value else MISSING
        else:
            text = _number(value, fmt)
        rows.append((label, text, unit))
    return rows


def format_summary(summary: dict[str, Any]) -> str:
    """The headline and the aligned rows."""
    head = (f'== {summary["scenario"]}: {summary["steps"]} steps, {summary["sim_minutes"]:.1f} min sim '
            f'in {summary["wall_seconds"]:.1f} s wall ==')
    rows = summary_rows(summary)
    width = max((len(label) for label, _, _ in rows), default=0)
    value_width = max((len(text) for _, text, _ in rows if len(text) <= 40), default=0)
    lines = [head]
    for label, text, unit in rows:
        lines.append(f'  {label:<{width}}  {text:>{value_width}}  {unit}'.rstrip())
    return '\n'.join(lines)
