"""The torque-rod design record: the JSON file ``acds design-torque-rod --json`` writes (seed 003 "Design").

A scenario names one (``em_driver.torque_rod_design``) as the rod of every axis. Two nodes read
it: the em_driver builds its rods from it (``em_driver.torque_rod_design.load_rod``), and the
rigid body bounds the dipole it accepts with it (:func:`dipole_bound_am2`), so reading and
checking the file is shared here. Keys carry their unit (seed units: g, mm, A·m²).
"""

from __future__ import annotations

import json
import math
from pathlib import Path
from typing import Any

__all__ = ['TorqueRodRecordError', 'NUMBER_KEYS', 'read_torque_rod_record', 'dipole_bound_am2']


class TorqueRodRecordError(ValueError):
    """A torque-rod design record cannot be read or lacks what the rod needs (the message names the file and key)."""


#: Positive numbers a record must hold: what builds the rod and what bounds its dipole.
NUMBER_KEYS = ('core_length_mm', 'core_radius_mm', 'wire_insulation_build_mm', 'wire_length_per_winding_m',
               'resistance_ohm', 'bridge_resistance_ohm', 'voltage_v', 'current_a', 'moment_am2')
#: Whole numbers and text it must hold.
INTEGER_KEYS = ('awg', 'windings')
TEXT_KEYS = ('core',)
#: A design file larger than this is not a design record.
MAX_RECORD_BYTES = 1 << 16


def read_torque_rod_record(path: str | Path) -> dict[str, Any]:
    """The record in ``path`` (a JSON object), checked: every key of NUMBER_KEYS a finite number (> 0 except
    the bridge resistance, ≥ 0), awg and windings whole numbers, core a string."""
    if not str(path):
        raise TorqueRodRecordError('no design file given: torque rods need one (write it with '
                                   '`acds design-torque-rod --json PATH`)')
    p = Path(path)
    try:
        if p.stat().st_size > MAX_RECORD_BYTES:
            raise TorqueRodRecordError(f'{p}: {p.stat().st_size} bytes is too large for a torque-rod design record')
        data = json.loads(p.read_text(encoding='utf-8'))
    except OSError as exc:
        raise TorqueRodRecordError(f'{p}: cannot be read: {exc.strerror or exc}') from None
    except (UnicodeDecodeError, json.JSONDecodeError) as exc:
        raise TorqueRodRecordError(f'{p}: is not a JSON design record ({exc}); write one with '
                                   '`acds design-torque-rod --json PATH`') from None
    if not isinstance(data, dict):
        raise TorqueRodRecordError(f'{p}: a design record is one JSON object, got {type(data).__name__}')
    for key in (*NUMBER_KEYS, *INTEGER_KEYS, *TEXT_KEYS):
        if key not in data:
            raise TorqueRodRecordError(f'{p}: lacks key {key!r} (not a `acds design-torque-rod --json` record?)')
    for key in NUMBER_KEYS:
        value = data[key]
        number = not isinstance(value, bool) and isinstance(value, (int, float)) and math.isfinite(value)
        if not number or not (value >= 0.0 if key == 'bridge_resistance_ohm' else value > 0.0):
            raise TorqueRodRecordError(f'{p}: {key} must be a finite positive number, got {value!r}')
    for key in INTEGER_KEYS:
        if isinstance(data[key], bool) or not isinstance(data[key], int):
            raise TorqueRodRecordError(f'{p}: {key} must be a whole number, got {data[key]!r}')
    if not isinstance(data['core'], str):
        raise TorqueRodRecordError(f'{p}: core must be a material name, got {data["core"]!r}')
    return data


def dipole_bound_am2(record: dict[str, Any], supply_v: float) -> float:
    """An upper bound of the dipole one rod of ``record`` can produce on a ``supply_v`` bus, A·m².

    No winding current exceeds supply_v/R in magnitude (PWM on-phase: V/(R + R_bridge); a
    freewheeling or diode-decaying current only falls), so the windings together carry at most
    i_max = windings·supply_v/R. The rod's moment curve m(i) (linear, then the core saturates) has
    m(i)/i non-increasing, so with the record's full-duty point (current_a, moment_am2):
    m(i) ≤ moment_am2·max(i, current_a)/current_a.
    """
    i_max = record['windings'] * supply_v / record['resistance_ohm']
    return record['moment_am2'] * max(i_max, record['current_a']) / record['current_a']
