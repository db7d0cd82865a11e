"""The magnetometer's compiled sample kernel gives the plain function's bits (issue 24; :mod:`acds_common.kernels`).

:func:`~magnetometer_sim.fluxgate.magnetometer_sample` (the field at the sensor B_true + residual + Δ·M, each
assembly's scale and offset errors and noise, curve, rails and quantisation, stuck axes, dead unit and the active
unit's field to a naive reader, spec §5) runs compiled in the direct engine and plain in the magnetometer node; it is
compared here bit for bit on random fields, dipoles, couplings, unit errors and faults, fields on and beyond the rails,
and exact quantisation ties (round-half-even both ways), with the Table 4-5 curve and perturbed ones, among them steps
so fine (1e-16 G) that quantisation keeps the curve's last bits. A field in gauss reaches the curve exactly through
the noise (no field, residual, coupling or unit error: the measured field is the noise itself).
"""

from __future__ import annotations

import random

import pytest
from acds_common.units import GAUSS_T
from magnetometer_sim.fluxgate import FluxgateAssembly, FluxgateAxisParams, magnetometer_sample

ZERO = (0.0, 0.0, 0.0)


@pytest.fixture(scope='module')
def fast(compile_kernels):
    out = compile_kernels(magnetometer_sample)
    assert out is not magnetometer_sample and out.py_func is magnetometer_sample
    return out


def _field_g(rng: random.Random, curve: tuple[float, ...]) -> float:
    """A field, G: in range, near or beyond the rails, zero, or one that lands exactly on a half step (a tie)."""
    c, _range2, bias, scale, _low, _high, step = curve
    kind = rng.random()
    if kind < 0.5:
        return rng.uniform(-1.0, 1.0)
    if kind < 0.7:
        return rng.choice([-1.0, 1.0]) * rng.uniform(0.95, 3.0)
    if kind < 0.75:
        return rng.choice([0.0, -0.0, 1e-300, -1e-300])
    if kind < 0.85:  # linear curve: b = (n + ½)·step/scale puts v/step on a tie for most n
        return ((rng.randint(-250, 249) + 0.5) * step) / scale if c == 0.0 else rng.uniform(-0.01, 0.01)
    return rng.choice([-1.0, 1.0]) * rng.uniform(1e3, 1e30)


def _curves(rng: random.Random) -> list[tuple[float, ...]]:
    nominal = FluxgateAssembly().curve
    linear = FluxgateAssembly(FluxgateAxisParams(nonlinearity_frac=0.0, resolution_g=0.004)).curve
    out = [nominal, linear]
    for _ in range(12):
        p = FluxgateAxisParams(nonlinearity_frac=rng.uniform(-0.4, 0.4), scale_v_per_g=rng.uniform(1.0, 4.0),
                               resolution_g=rng.choice([0.004, 1e-3, 1e-9, 1e-16, rng.uniform(1e-4, 0.05)]),
                               range_g=rng.uniform(0.5, 2.0), bias_v=2.5, rail_low_v=0.0, rail_high_v=5.0)
        out.append(FluxgateAssembly(p).curve)
    return out


def _xyz(rng: random.Random, draw) -> tuple[float, float, float]:
    return draw(), draw(), draw()


def _unit(rng: random.Random, exact: bool) -> tuple:
    """(scale errors, offsets G, noisy): none and noisy when ``exact`` (the noise is the field), else random."""
    if exact:
        return ZERO, ZERO, True
    return (_xyz(rng, lambda: rng.choice([0.0, rng.uniform(-5e-4, 5e-4)])),
            _xyz(rng, lambda: rng.choice([0.0, rng.uniform(-5e-4, 5e-4)])), rng.random() < 0.5)


def _faults(rng: random.Random) -> tuple:
    """(axis biases V, bias outputs V, stuck axes, dead) as :meth:`FluxgateAssembly._faults_changed` builds them."""
    bias = _xyz(rng, lambda: rng.choice([2.5, 2.5, rng.uniform(-1.0, 6.0), 2.5 + rng.randint(-50, 50) * 0.01]))
    out = tuple(min(max(e, 0.0), 5.0) for e in bias)
    return bias, out, tuple(rng.random() < 0.2 for _ in range(3)), rng.random() < 0.1


def _case(rng: random.Random, curve: tuple[float, ...]) -> tuple:
    """One call's arguments: with probability ½ the field reaches the curve exactly through the noise."""
    exact = rng.random() < 0.5
    if exact:
        residual, delta, b_true, dipole = ZERO, (ZERO, ZERO, ZERO), ZERO, ZERO
    else:
        residual = _xyz(rng, lambda: rng.choice([0.0, rng.uniform(-1e-6, 1e-6)]))
        delta = tuple(_xyz(rng, lambda: rng.choice([0.0, rng.uniform(-1e-8, 1e-8)])) for _ in range(3))
        b_true = _xyz(rng, lambda: _field_g(rng, curve) * GAUSS_T)
        dipole = _xyz(rng, lambda: rng.choice([0.0, -0.0, rng.uniform(-2500.0, 2500.0)]))
    units = (_unit(rng, exact), _unit(rng, exact))
    noise = tuple(_xyz(rng, lambda: _field_g(rng, curve) if exact else rng.gauss(0.0, 1e-3)) for _ in range(2))
    last = tuple(_xyz(rng, lambda: rng.uniform(0.0, 5.0)) for _ in range(2))
    return ((residual, delta, curve, units), (_faults(rng), _faults(rng)), last, b_true, dipole, noise,
            rng.randint(0, 1))


def test_magnetometer_sample_compiled_gives_the_same_bits(fast, ieee_bits):
    rng = random.Random(5)
    for curve in _curves(rng):
        for case in range(2000):
            args = _case(rng, curve)
            got, want = fast(*args), magnetometer_sample(*args)
            assert ieee_bits(got) == ieee_bits(want), f'curve {curve}, case {case}: {args}'


def test_exact_ties_round_half_even(fast, ieee_bits):
    """v/step exactly n + ½ (step 0.5 V: every tie representable): both forms round to the even neighbour."""
    curve = (0.0, 1.0, 2.5, 1.0, 0.0, 5.0, 0.5)
    fields = tuple((n + 0.5) * 0.5 - 2.5 for n in range(10))
    unit, faults = (ZERO, ZERO, True), ((2.5, 2.5, 2.5), (2.5, 2.5, 2.5), (False, False, False), False)
    for i in range(0, 9, 3):
        b = fields[i:i + 3]
        args = ((ZERO, (ZERO, ZERO, ZERO), curve, (unit, unit)), (faults, faults), (ZERO, ZERO), ZERO, ZERO, (b, b), 0)
        got, want = fast(*args), magnetometer_sample(*args)
        assert ieee_bits(got) == ieee_bits(want)
        volts = want[1][0]
        assert all(round(v / 0.5) % 2 == 0 for v in volts)  # the ties went to even


def test_bound_call_site_gives_the_plain_bits_through_faults_and_input_types(ieee_bits):
    """:meth:`Magnetometer.sample_xyz` bound (argument types checked, ``ACDS_KERNEL_CHECK``) against plain: through
    a stuck axis, a dead unit, a switch to the standby unit, cleared faults, and fields and dipoles given as ints,
    numpy scalars and lists (made float tuples before the kernel, as the plain sums make them floats)."""
    import numpy as np
    from acds_common import kernels
    from magnetometer_sim.fluxgate import Magnetometer

    def build():
        return Magnetometer(FluxgateAxisParams(accuracy_error_enabled=True), seed=11,
                            residual_field_t=(2e-7, -1e-7, 0.0), coupling_t_per_am2=np.full((3, 3), 3e-9))

    with pytest.MonkeyPatch.context() as patch:
        patch.setattr(kernels, '_enabled', False)
        plain = build()
    kernels.enable()
    with pytest.MonkeyPatch.context() as patch:
        patch.setenv('ACDS_KERNEL_CHECK', '1')
        fast = build()
    assert plain._sample is magnetometer_sample and fast._sample is not magnetometer_sample
    rng = random.Random(3)
    events = {50: ('inject_fault', 'A', 'stuck_axis', 1), 100: ('inject_fault', 'B', 'dead_unit'),
              150: ('select_unit', 'B'), 200: ('clear_faults', 'B'), 250: ('inject_fault', 'B', 'bias_shift', None, -6.0),
              300: ('clear_faults',)}
    for k in range(400):
        if k in events:
            name, *args = events[k]
            for mag in (plain, fast):
                getattr(mag, name)(*args)
        b = [rng.uniform(-6e-5, 6e-5) for _ in range(3)]
        d = [rng.choice([0, 1500, rng.uniform(-2000.0, 2000.0)]) for _ in range(3)]
        kind = k % 3
        b, d = (tuple(b), tuple(d)) if kind == 0 else (np.array(b), tuple(np.float64(x) for x in d)) if kind == 1 \
            else (b, d)
        got, want = fast.sample_xyz(b, d), plain.sample_xyz(b, d)
        assert ieee_bits(got) == ieee_bits(want), k
