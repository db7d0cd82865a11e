"""The magnetometer's compiled volts kernel gives the plain function's bits (issue 24; :mod:`acds_common.kernels`).

:func:`~magnetometer_sim.fluxgate.pair_volts` (both assemblies' curve, rails and quantisation, spec §5) runs compiled
in the direct engine and plain in the magnetometer node; it is compared here bit for bit on random fields about
random biases, fields on and beyond the rails, and exact quantisation ties (round-half-even both ways), with the
Table 4-5 curve and perturbed ones, among them steps so fine (1e-16 G) that quantisation keeps the curve's
last bits.
"""

from __future__ import annotations

import random

import pytest
from magnetometer_sim.fluxgate import FluxgateAssembly, FluxgateAxisParams, pair_volts


@pytest.fixture(scope='module')
def fast(compile_kernels):
    out = compile_kernels(pair_volts)
    assert out is not pair_volts and out.py_func is pair_volts
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


def test_pair_volts_compiled_gives_the_same_bits(fast, ieee_bits):
    rng = random.Random(5)
    for curve in _curves(rng):
        for case in range(3000):
            args = []
            for _unit in range(2):
                args.append(tuple(_field_g(rng, curve) for _ in range(3)))
                args.append(tuple(rng.choice([2.5, 2.5, rng.uniform(-1.0, 6.0), 2.5 + rng.randint(-50, 50) * 0.01])
                                  for _ in range(3)))
            got, want = fast(*args, curve), pair_volts(*args, curve)
            assert ieee_bits(got) == ieee_bits(want), f'curve {curve}, case {case}: {args}'


def test_exact_ties_round_half_even(fast, ieee_bits):
    """v/step exactly n + ½ (step 0.5 V: every tie representable): both forms round to the even neighbour."""
    curve = (0.0, 1.0, 2.5, 1.0, 0.0, 5.0, 0.5)
    fields = tuple((n + 0.5) * 0.5 - 2.5 for n in range(10))
    for i in range(0, 9, 3):
        b, bias = fields[i:i + 3], (2.5, 2.5, 2.5)
        got, want = fast(b, bias, b, bias, curve), pair_volts(b, bias, b, bias, curve)
        assert ieee_bits(got) == ieee_bits(want)
        assert all(round(v / 0.5) % 2 == 0 for v in want[0])  # the ties went to even
