"""Scenario section → magnetometer model, and the forwarded-command grammar (pure, no rclpy).

The node (``magnetometer_node``) receives the ``magnetometer`` scenario section as
SI values ({field: value}, see ``acds_common.scenario.SCHEMA['magnetometer']``) and
builds the :class:`~magnetometer_sim.fluxgate.Magnetometer` here, so the mapping
from presets to the coupling matrix Δ is testable without ROS.

Commands forwarded by ascs_mode_manager in the ``mode`` report (key
``command/magnetometer_sim``), whitespace separated, keywords case-insensitive
(:class:`acds_common.commands.MagnetometerSelect`, :class:`MagnetometerFault`)::

    magnetometer_select <A|B>                                    active assembly
    magnetometer_fault <A|B> <bias_shift|stuck_axis|dead_unit> [x|y|z|all] [volts]
    magnetometer_fault <A|B> clear                               remove that unit's faults

(the HEAO mode manager's ground grammar forwards ``magnetometer_select``; the
fault form is for tools and tests that talk to the node directly).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any, ClassVar

from acds_common import topics
from acds_common.commands import AXES, UNITS, CommandError, MagnetometerSelect, decode, finite_number
from acds_common.coupling import CouplingError, coupling_from_section
from acds_common.units import GAUSS_T

from magnetometer_sim.fluxgate import (
    FAULT_KINDS,
    FluxgateAxisParams,
    Magnetometer,
    MagnetometerError,
)

__all__ = ['MagnetometerFault', 'apply_command', 'build_magnetometer', 'parse_command']

def axis_params(section: dict[str, Any]) -> FluxgateAxisParams:
    """Every fluxgate axis of the section's magnetometer (Table 4-5, with the section's noise and accuracy)."""
    return FluxgateAxisParams(noise_std_g=float(section['noise_std']) / GAUSS_T,
                              accuracy_error_enabled=bool(section['accuracy_error']))


def volts_transfer(section: dict[str, Any]) -> list[str]:
    """The output volts' transfer to field, per axis, as the contract states it (fluxgate module docstring)."""
    a = axis_params(section)
    fs_v = (a.rail_low_v, a.rail_high_v)
    steps = round((fs_v[1] - fs_v[0]) / a.step_v)
    k_si = a.scale_v_per_g / GAUSS_T
    residual = ', '.join(f'{v:g}' for v in section['residual_field'])
    return [
        f'axes x, y, z (sensor frame = body axes), the same transfer each: zero field → V_bias = {a.bias_v:g} V; '
        f'scale k = {a.scale_v_per_g:g} V/G = {k_si:g} V/T; range ±{a.range_g:g} G = ±{a.range_g * GAUSS_T:g} T → '
        f'{fs_v[0]:g}…{fs_v[1]:g} V (clipped at the rails)',
        f'quantisation: steps of {a.step_v:g} V = {a.resolution_g:g} G ({steps} steps over {fs_v[0]:g}…{fs_v[1]:g} '
        f'V, about {math.log2(steps):.1f} bits); read it with an A/D of your own (the built-in controller: '
        'controller_adc_bits over 0…5 V)',
        f'to engineering units: B_i = (V_i − V_bias,i)/k T, with V_bias,i the same step\'s '
        f'{topics.NAMESPACE}/{topics.MAG_BIAS_VOLTS} (the bias channel: the assembly\'s zero-field reference voltage, nominally '
        f'{a.bias_v:g} V; a bias-shift fault moves it with the field channels, so subtracting it, not '
        f'{a.bias_v:g} V, removes that fault)',
        f'error budget: end-point nonlinearity, slope within ±{100 * abs(a.nonlinearity_frac):g} % of k over the '
        f'range (≤ 0.4 % of reading); accuracy ±{100 * a.accuracy_frac_fs:g} % of full scale '
        f'({"applied, seeded per unit" if a.accuracy_error_enabled else "not applied in this scenario"}); '
        f'noise σ = {a.noise_std_g * GAUSS_T:g} T',
        f'what the volts measure: B_true + residual body-fixed field [{residual}] T + coupling Δ·M of the '
        f'electromagnets\' previous-step dipole (coupling preset {section["coupling_preset"]}); assembly '
        f'{section["active_unit"]} active',
    ]


def build_magnetometer(section: dict[str, Any], seed: int) -> Magnetometer:
    """The two-assembly magnetometer the section describes (faults are injected later, at fault_time)."""
    params = axis_params(section)
    try:
        delta = coupling_from_section(section)
    except CouplingError as exc:
        raise MagnetometerError(str(exc)) from None
    mag = Magnetometer(params, seed=int(seed), residual_field_t=section['residual_field'], coupling_t_per_am2=delta)
    mag.select_unit(section['active_unit'])
    return mag


@dataclass(frozen=True)
class MagnetometerFault:
    """``magnetometer_fault <A|B> <kind|clear> [x|y|z|all] [volts]``: a fault of one unit injected (``kind``
    'clear' removes that unit's faults; ``axis`` None = all; ``value_v`` the bias shift); for tools and tests
    that talk to the node directly (the ground grammar has no such command)."""

    unit: str
    kind: str
    axis: int | None = None
    value_v: float | None = None
    verb: ClassVar[str] = 'magnetometer_fault'
    route: ClassVar[str] = 'magnetometer_sim'

    @classmethod
    def parse(cls, args: Sequence[str]) -> MagnetometerFault:
        """The words after the verb → the command."""
        usage = f'usage: magnetometer_fault <A|B> <{"|".join(FAULT_KINDS)}|clear> [x|y|z|all] [volts]'
        if not 2 <= len(args) <= 4 or args[0].upper() not in UNITS or args[1].lower() not in (*FAULT_KINDS, 'clear'):
            raise CommandError(usage)
        unit, kind = args[0].upper(), args[1].lower()
        axis_word = args[2].lower() if len(args) >= 3 else 'all'
        if axis_word not in (*AXES, 'all'):
            raise CommandError(usage)
        value = None
        if kind == 'bias_shift':
            if len(args) != 4:
                raise CommandError(f'bias_shift needs a size in volts: {usage}')
            value = finite_number(args[3], 'bias_shift size')
        elif len(args) == 4:
            raise CommandError(usage)
        return cls(unit, kind, None if axis_word == 'all' else AXES.index(axis_word), value)

    @property
    def text(self) -> str:
        """The normalised command."""
        axis = 'all' if self.axis is None else AXES[self.axis]
        return ' '.join(('magnetometer_fault', self.unit, self.kind, axis, *(() if self.value_v is None
                                                                                else (repr(self.value_v),))))


#: The commands the node applies (forwarded in the ``mode`` report, key ``command/magnetometer_sim``).
GRAMMAR = (MagnetometerSelect, MagnetometerFault)


def parse_command(text: str) -> MagnetometerSelect | MagnetometerFault:
    """Parse one forwarded command (grammar in the module docstring); MagnetometerError says what is wrong."""
    return decode(text, GRAMMAR, 'magnetometer command', MagnetometerError)


def apply_command(cmd: MagnetometerSelect | MagnetometerFault, mag: Magnetometer) -> str:
    """Apply a parsed command to the model; return the event text for telemetry."""
    if isinstance(cmd, MagnetometerSelect):
        mag.select_unit(cmd.unit)
        return f'magnetometer_select: unit {cmd.unit} active'
    if cmd.kind == 'clear':
        mag.clear_faults(cmd.unit)
        return f'unit {cmd.unit}: faults cleared'
    mag.inject_fault(cmd.unit, cmd.kind, cmd.axis, cmd.value_v)
    where = 'all axes' if cmd.axis is None else f'axis {AXES[cmd.axis]}'
    size = f' {cmd.value_v:+g} V' if cmd.value_v is not None else ''
    return f'unit {cmd.unit}: {cmd.kind}{size} on {where}'
