"""The em_driver drive kernel compiled gives the plain function's bits (issue 24; :mod:`acds_common.kernels`).

The direct engine drives the whole electromagnet assembly (spec §6; seed 002 §4.2.5: two bridge-switch drivers
and windings per axis, e_ft against the command) with one compiled call a step
(:func:`em_driver.drive_assembly.drive_step`); a node process runs the same source as plain Python. Here two
assemblies, one built before and one after :func:`acds_common.kernels.enable`, are driven through the same
random commands (reversals, zero, saturation, NaN/inf components), EEA switches, failures of every kind, all
drive types and the monitor's settle times and automatic switch, and every reported float, the units' state and
the axes' monitor rows are compared bit for bit; so is a lone
:class:`~em_driver.bridge_switch.BridgeSwitchCoil`.
"""

from __future__ import annotations

import math
import random

import numpy as np
import pytest
from acds_common import kernels
from em_driver.bridge_switch import BridgeSwitchCoil, CoilParams, DriverParams
from em_driver.drive_assembly import AxisConfig, DriveAssembly, drive_step

FAULTS = (None, 'open_winding', 'stuck_on_bridge', 'dead_driver')
PER_AXIS = ('avg_dipole_am2', 'end_dipole_am2', 'coil_current_a', 'commanded_current_a', 'e_ft_v', 'duty',
            'switch_count', 'power_w', 'alarms')


def _units(assembly: DriveAssembly) -> list:
    return [(u.current_a, u.bridge_on, u.fault, u.powered) for ax in assembly._axes for u in ax.units.values()]


def _monitor(assembly: DriveAssembly) -> list:
    """The axes' monitor rows (held command, mismatch time, alarm, active unit, measured and expected currents)."""
    return [[float(v) for v in row] for row in assembly._monitor]


def _command(rng: random.Random) -> list[float]:
    special = (0.0, -0.0, 3000.0, -3000.0, 2062.0, 1e-3, -0.5, math.nan, math.inf, -math.inf)
    return [rng.choice(special) if rng.random() < 0.25 else rng.uniform(-2200.0, 2200.0) for _ in range(3)]


def _plain(factory):
    """``factory()`` built on the plain kernels, whether or not this process enabled compilation already."""
    with pytest.MonkeyPatch.context() as patch:
        patch.setattr(kernels, '_enabled', False)
        return factory()


def _configs(rng: random.Random, variant: int) -> list[AxisConfig]:
    coil = CoilParams() if variant == 0 else CoilParams(resistance_ohm=30.3 * rng.uniform(0.8, 1.2),
                                                        inductance_h=20.3 * rng.uniform(0.5, 1.5))
    types = ('bridge_switch', 'bridge_switch', 'constant_level') if variant % 2 else ('bridge_switch',) * 3
    if variant % 5 == 4:
        types = ('constant_level', 'none', 'bridge_switch')
    return [AxisConfig.constant_level(coil) if t == 'constant_level' else AxisConfig(t, coil) for t in types]


def test_drive_assembly_compiled_gives_the_same_bits(ieee_bits):
    """Twenty assemblies, 300 steps each, plain and compiled side by side."""
    plans = []
    for variant in range(20):
        rng = random.Random(100 + variant)
        plans.append((variant, _configs(rng, variant), rng))
    plain = _plain(lambda: [DriveAssembly(c, auto_switch_to_standby=v % 2 == 0,
                                          mismatch_settle_s=(0.0, 1.0, 3.0)[v % 3]) for v, c, _ in plans])
    assert all(a._step is drive_step for a in plain)  # noqa: SLF001 - the plain path really is plain
    kernels.enable()
    assert kernels.compiled(drive_step) is not drive_step
    fast = [DriveAssembly(c, auto_switch_to_standby=v % 2 == 0, mismatch_settle_s=(0.0, 1.0, 3.0)[v % 3])
            for v, c, _ in plans]
    for (variant, _, rng), slow, quick in zip(plans, plain, fast, strict=True):
        for step in range(300):
            r = rng.random()
            if r < 0.03:
                axis, unit = rng.randrange(3), rng.choice('AB')
                slow.select_eea(axis, unit)
                quick.select_eea(axis, unit)
            elif r < 0.07:
                axis, unit, kind = rng.randrange(3), rng.choice('AB'), rng.choice(FAULTS)
                slow.inject_failure(axis, unit, kind)
                quick.inject_failure(axis, unit, kind)
            command = _command(rng)
            dt = rng.choice([0.5, 0.5, 0.1, 2.0, rng.uniform(1e-3, 5.0)])
            want = slow.step(command, dt)
            got = quick.step(np.array(command), dt)
            where = f'variant {variant} step {step}: {command}'
            for name in PER_AXIS:
                assert ieee_bits(got.per_axis(name)) == ieee_bits(want.per_axis(name)), f'{where}: {name}'
            assert (got.active_units, got.events, got.diagnostics) == (want.active_units, want.events,
                                                                       want.diagnostics), where
            assert ieee_bits(_units(quick)) == ieee_bits(_units(slow)), where
            assert ieee_bits(_monitor(quick)) == ieee_bits(_monitor(slow)), where


def test_bridge_switch_coil_compiled_gives_the_same_bits(ieee_bits):
    """A lone unit: bridge-switch and constant-level periods, faults, driver power, recorded waveforms."""
    rng = random.Random(2402)
    starts = [rng.uniform(-0.9, 0.9) for _ in range(8)]
    plain = _plain(lambda: [BridgeSwitchCoil(CoilParams(), DriverParams(), i0) for i0 in starts])
    kernels.enable()
    fast = [BridgeSwitchCoil(CoilParams(), DriverParams(), i0) for i0 in starts]
    for slow, quick in zip(plain, fast, strict=True):
        for step in range(200):
            if rng.random() < 0.05:
                kind = rng.choice(FAULTS)
                slow.set_fault(kind)
                quick.set_fault(kind)
            if rng.random() < 0.05:
                slow.powered = quick.powered = not slow.powered
            record = rng.random() < 0.05
            duration = rng.choice([0.5, 3.0, 1e-3, rng.uniform(1e-3, 5.0)])
            if rng.random() < 0.2:
                level = rng.choice([-1, 0, 1])
                want, got = (u.run_constant_level(level, duration, record=record) for u in (slow, quick))
            else:
                current = rng.choice([0.0, rng.uniform(-1.0, 1.0), rng.uniform(-1e-3, 1e-3), 2.0])
                want, got = (u.run(current, duration, record=record) for u in (slow, quick))
            where = f'step {step}'
            assert ieee_bits(tuple(map(float, got[:11]))) == ieee_bits(tuple(map(float, want[:11]))), where
            assert ieee_bits((quick.current_a, quick.bridge_on)) == ieee_bits((slow.current_a, slow.bridge_on)), where
            if record:
                for field in ('times_s', 'currents_a', 'bridge_on'):
                    assert np.array_equal(getattr(got.waveform, field), getattr(want.waveform, field)), where
