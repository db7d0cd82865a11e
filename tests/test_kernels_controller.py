"""The controller's compiled kernel gives the plain function's bits (issue 24; :mod:`acds_common.kernels`).

The direct engine runs the transfer assembly's A/D conversion of all axes (:func:`field_xyz`, seed 002 §4.2.7)
compiled by numba; the per-process graph runs the same source as plain Python. It is compared here on random
voltages, on every kind of count edge (half-count boundaries and their neighbouring doubles, both rails, far
beyond the rails, ±0) and on every ADC width, each returned float bit for bit; the A/D helper is also compared with
the converter's definition, the nearest count clipped to 0…2ⁿ−1. The engines
test and the truth digests compare whole runs.
"""

from __future__ import annotations

import math
import random

from acds_controller.transfer_assembly import FULL_SCALE_V, SCALE_V_PER_GAUSS, count_v, field_xyz


def test_compiled_form_is_compiled(compile_kernels):
    """Once enabled, the kernel resolves to numba's compiled dispatcher (not the plain function)."""
    out = compile_kernels(field_xyz)
    assert out is not field_xyz and out.py_func is field_xyz


def _edge_volts(rng: random.Random, lsb: float, top: int) -> float:
    """A voltage on or next to a count edge: a half-count boundary, a rail, far beyond one, or a signed zero."""
    kind = rng.random()
    if kind < 0.4:  # a half-count boundary inside the span, or the double on either side of it
        v = (rng.randint(0, top + 1) - 0.5) * lsb
        return rng.choice([v, math.nextafter(v, math.inf), math.nextafter(v, -math.inf)])
    if kind < 0.6:  # the rails: just under 0 and around the top count's upper boundary
        v = rng.choice([-0.5 * lsb, 0.0, (top + 0.5) * lsb, top * lsb, (top + 1) * lsb])
        return rng.choice([v, math.nextafter(v, math.inf), math.nextafter(v, -math.inf)])
    if kind < 0.8:  # far beyond the rails (a converter saturates; the count would not fit an integer)
        return rng.choice([-1.0, 1.0]) * 10.0 ** rng.uniform(1.0, 308.0)
    return rng.choice([0.0, -0.0, 5e-324, -5e-324])


def test_field_xyz_compiled_gives_the_same_bits(compile_kernels, ieee_bits):
    """Random and edge field and bias voltages, every ADC width of the TA (8…24 bits), the Table 4-5 span and
    scale and perturbed ones."""
    fast = compile_kernels(field_xyz)
    rng = random.Random(2424)
    for case in range(20000):
        bits = rng.randint(8, 24)
        full_scale = FULL_SCALE_V if case % 2 else FULL_SCALE_V * rng.uniform(0.5, 2.0)
        scale = SCALE_V_PER_GAUSS if case % 3 else SCALE_V_PER_GAUSS * rng.uniform(0.5, 2.0)
        lsb, top = full_scale / (1 << bits), (1 << bits) - 1
        volts = [_edge_volts(rng, lsb, top) if rng.random() < 0.5 else rng.uniform(-0.5, 1.1 * full_scale)
                 for _ in range(6)]
        args = (tuple(volts[:3]), tuple(volts[3:]), lsb, float(top), scale)
        assert ieee_bits(fast(*args)) == ieee_bits(field_xyz(*args)), f'case {case}: {args}'


def test_count_v_is_the_nearest_count_clipped(ieee_bits):
    """The A/D helper, plain, on the same edges against the converter's definition: the count ⌊v/LSB + ½⌋
    (Python's unbounded integer) clipped to 0…2ⁿ−1, times the LSB."""
    rng = random.Random(7)
    for _ in range(20000):
        bits = rng.randint(8, 24)
        lsb, top = FULL_SCALE_V / (1 << bits), (1 << bits) - 1
        v = _edge_volts(rng, lsb, top)
        if math.isfinite(v / lsb):  # a count exists (far enough beyond the rails v/LSB overflows)
            count = math.floor(v / lsb + 0.5)
            assert ieee_bits(count_v(v, lsb, float(top))) == ieee_bits(min(max(count, 0), top) * lsb), (v, bits)
