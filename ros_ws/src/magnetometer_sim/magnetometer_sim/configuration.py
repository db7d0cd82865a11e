"""Scenario section → magnetometer model, and the forwarded-command grammar (pure, no rclpy).

The node (``magnetometer_node``) receives the ``magnetometer`` scenario section as
SI values ({field: value}, see ``acds_common.scenario.SCHEMA['magnetometer']``) and
builds the :class:`~magnetometer_sim.fluxgate.Magnetometer` here, so the mapping
from presets to the coupling matrix Δ is testable without ROS.

Commands forwarded by ascs_mode_manager in the ``mode`` array (key
``command/magnetometer_sim``), whitespace separated, keywords case-insensitive::

    magnetometer_select <A|B>                                    active assembly
    magnetometer_fault <A|B> <bias_shift|stuck_axis|dead_unit> [x|y|z|all] [volts]
    magnetometer_fault <A|B> clear                               remove that unit's faults

(the HEAO mode manager's ground grammar forwards ``magnetometer_select``; the
fault form is for tools and tests that talk to the node directly).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

from acds_common.coupling import CouplingError, coupling_from_section
from acds_common.units import GAUSS_T

from magnetometer_sim.fluxgate import (
    FAULT_KINDS,
    UNITS,
    FluxgateAxisParams,
    Magnetometer,
    MagnetometerError,
)

__all__ = ['MagnetometerCommand', 'build_magnetometer', 'parse_command']

_AXES = {'x': 0, 'y': 1, 'z': 2, 'all': None}


def build_magnetometer(section: dict[str, Any], seed: int) -> Magnetometer:
    """The two-assembly magnetometer the section describes (faults are injected later, at fault_time)."""
    params = FluxgateAxisParams(noise_std_g=float(section['noise_std']) / GAUSS_T,
                                accuracy_error_enabled=bool(section['accuracy_error']))
    try:
        delta = coupling_from_section(section)
    except CouplingError as exc:
        raise MagnetometerError(str(exc)) from None
    mag = Magnetometer(params, seed=int(seed), residual_field_t=section['residual_field'], coupling_t_per_am2=delta)
    mag.select_unit(section['active_unit'])
    return mag


@dataclass(frozen=True)
class MagnetometerCommand:
    """A parsed command: verb 'select' or 'fault'; unit; fault kind ('clear' clears), axis (None = all), volts."""

    verb: str
    unit: str
    kind: str | None = None
    axis: int | None = None
    value_v: float | None = None

    def apply(self, mag: Magnetometer) -> str:
        """Apply to the model; return the event text for telemetry."""
        if self.verb == 'select':
            mag.select_unit(self.unit)
            return f'magnetometer_select: unit {self.unit} active'
        if self.kind == 'clear':
            mag.clear_faults(self.unit)
            return f'unit {self.unit}: faults cleared'
        assert self.kind is not None
        mag.inject_fault(self.unit, self.kind, self.axis, self.value_v)
        where = 'all axes' if self.axis is None else f'axis {"xyz"[self.axis]}'
        size = f' {self.value_v:+g} V' if self.value_v is not None else ''
        return f'unit {self.unit}: {self.kind}{size} on {where}'


def parse_command(text: str) -> MagnetometerCommand:
    """Parse one forwarded command (grammar in the module docstring); MagnetometerError says what is wrong."""
    words = str(text).split()
    verb = words[0].lower() if words else ''
    if verb == 'magnetometer_select':
        if len(words) != 2 or words[1].upper() not in UNITS:
            raise MagnetometerError(f'usage: magnetometer_select <A|B>, got {text!r}')
        return MagnetometerCommand('select', words[1].upper())
    if verb == 'magnetometer_fault':
        usage = f'usage: magnetometer_fault <A|B> <{"|".join(FAULT_KINDS)}|clear> [x|y|z|all] [volts], got {text!r}'
        if not 3 <= len(words) <= 5 or words[1].upper() not in UNITS:
            raise MagnetometerError(usage)
        unit, kind = words[1].upper(), words[2].lower()
        if kind not in (*FAULT_KINDS, 'clear'):
            raise MagnetometerError(usage)
        axis_word = words[3].lower() if len(words) >= 4 else 'all'
        if axis_word not in _AXES:
            raise MagnetometerError(usage)
        value = None
        if kind == 'bias_shift':
            if len(words) != 5:
                raise MagnetometerError(f'bias_shift needs a size in volts: {usage}')
            try:
                value = float(words[4])
            except ValueError:
                raise MagnetometerError(f'bias_shift size {words[4]!r} is not a number') from None
            if not math.isfinite(value):
                raise MagnetometerError(f'bias_shift size {words[4]!r} is not finite')
        elif len(words) == 5:
            raise MagnetometerError(usage)
        return MagnetometerCommand('fault', unit, kind, _AXES[axis_word], value)
    raise MagnetometerError(f'unknown magnetometer command {text!r}; known: magnetometer_select, magnetometer_fault')
