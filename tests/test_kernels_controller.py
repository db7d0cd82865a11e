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

import numpy as np
from acds_common.dpa_commands import LAW_CHOICES
from acds_common.modes import HEAO_MODES
from acds_common.vec3 import ZERO
from acds_controller.controller_step import NOT_FINITE, dpa_control
from acds_controller.dpa import (
    BAD_REFERENCE,
    DONE,
    FIELD_ZERO,
    NO_Q,
    NO_REFERENCE,
    SCAN_RATE_RANGE,
    Dpa,
    DpaConfig,
    dpa_step,
)
from acds_controller.transfer_assembly import FULL_SCALE_V, SCALE_V_PER_GAUSS, TransferAssembly, count_v, field_xyz
from acds_controller.wheel_laws import NORMAL_MODE, V_SAT_V, WheelLawGains, wheel_volts_xyz


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


# ---- the stage's step: dpa_control (wheel momentum, finiteness, TA field, DPA period: dpa_step) ----

def _config(rng: random.Random) -> DpaConfig:
    """A DPA configuration with every law pair, coupling on or off, random gains in their ranges."""
    u = rng.uniform
    a = [[u(-1, 1) for _ in range(3)] for _ in range(3)]
    inertia = (np.array(a) @ np.array(a).T + np.eye(3)) * u(1e2, 1e4)
    limits = tuple(rng.choice([None, u(1e-3, 0.5)]) for _ in range(3))
    gains = WheelLawGains(tuple(u(0.0, 1e3) for _ in range(3)), limits, tuple(u(0.0, 100.0) for _ in range(3)))
    return DpaConfig(
        inertia_kg_m2=inertia, acquisition_law=rng.choice(LAW_CHOICES['acquisition']),
        unloading_law=rng.choice(LAW_CHOICES['unloading']), acquisition_gain_study=u(0.0, 5.0),
        bdot_gain_study=u(0.0, 100.0), unloading_gain_mode_1b_study=u(0.0, 1.0), unloading_gain_scan_study=u(0.0, 1.0),
        unloading_gain_point_study=u(0.0, 1.0), max_moment_am2=rng.choice([2000.0, u(0.0, 5000.0)]),
        coupling_compensation=rng.random() < 0.5, coupling_delta_t_per_am2=np.array(a) * 1e-9,
        wheel_gains_acquisition=gains, wheel_gains_normal=rng.choice([NORMAL_MODE, gains]),
        scan_rate_rad_s=u(-0.1, 0.1), target_q_body_to_eci=_unit_q(rng), lead_time_s=u(0.0, 1e3),
        detumble_gain_kg_m2_s=u(0.0, 1.0), dump_gain_per_s=u(0.0, 1.0))


def _unit_q(rng: random.Random) -> tuple[float, float, float, float]:
    q = [rng.gauss(0.0, 1.0) for _ in range(4)]
    n = math.sqrt(sum(c * c for c in q))
    return q[0] / n, q[1] / n, q[2] / n, q[3] / n


def _vec(rng: random.Random, scale: float) -> tuple[float, float, float]:
    """A random float triple, now and then with a zero, a signed zero or a component far out of scale."""
    def one() -> float:
        kind = rng.random()
        if kind < 0.1:
            return rng.choice([0.0, -0.0])
        if kind < 0.15:
            return rng.choice([-1.0, 1.0]) * 10.0 ** rng.uniform(-300.0, 300.0)
        return rng.uniform(-scale, scale)
    return one(), one(), one()


def _state(rng: random.Random) -> tuple:
    return rng.random() < 0.8, _vec(rng, 5e-5), _vec(rng, 3000.0)


def _q(rng: random.Random) -> tuple[float, float, float, float]:
    """An attitude reference: unit, off unit by less or more than the 1e-3 tolerance, or not finite."""
    q = _unit_q(rng)
    kind = rng.random()
    if kind < 0.1:
        return q[0] * 1.01, q[1], q[2], q[3]
    if kind < 0.2:
        return q[0], rng.choice([math.nan, math.inf]), q[2], q[3]
    return tuple(c * (1.0 + rng.uniform(-5e-4, 5e-4)) for c in q)


def _control_case(rng: random.Random, ta: tuple[float, float, float], params: tuple) -> tuple:
    """dpa_control's arguments: every mode, inputs finite or not, field volts equal to the bias (zero field)."""
    volts = tuple(rng.uniform(-0.5, 5.5) for _ in range(3))
    bias = volts if rng.random() < 0.1 else tuple(rng.uniform(2.4, 2.6) for _ in range(3))
    omega = _vec(rng, rng.choice([0.02, 20.0]))  # beyond ±10 rad/s the scan law refuses
    sun = rng.choice([ZERO, _vec(rng, 0.4), _vec(rng, 1.0)])
    inputs = [volts, bias, omega, sun, _vec(rng, 30.0), _vec(rng, 0.1), _vec(rng, 1.0)]
    if rng.random() < 0.05:
        i, j = rng.randrange(len(inputs)), rng.randrange(3)
        inputs[i] = tuple(rng.choice([math.nan, math.inf, -math.inf]) if n == j else c for n, c in enumerate(inputs[i]))
    volts, bias, omega, sun, h, hdot, coil = inputs
    q_given = rng.random() < 0.9
    return (ta, params, _state(rng), rng.randrange(len(HEAO_MODES)), volts, bias, omega, sun, h, hdot,
            _q(rng) if q_given else NO_Q, q_given, coil, rng.choice([0.5, rng.uniform(1e-3, 60.0)]))


def test_dpa_control_compiled_gives_the_same_bits(compile_kernels, ieee_bits):
    """The stage's one call a step, compiled against plain: random configurations (every law pair, coupling on and
    off, limiters on and off), every mode, refused steps (non-finite inputs, no or a bad attitude reference, a scan
    rate out of range) and the zero field among random inputs; status, state and figures bit for bit."""
    fast = compile_kernels(dpa_control)
    rng = random.Random(2407)
    statuses = set()
    for case in range(400):
        dpa = Dpa(_config(rng))
        ta = TransferAssembly(adc_bits=rng.choice([10, rng.randint(8, 24)])).params
        for _ in range(25):
            args = _control_case(rng, ta, dpa.params)
            plain = dpa_control(*args)
            statuses.add(plain[0])
            assert ieee_bits(fast(*args)) == ieee_bits(plain), f'case {case}: {args}'
    assert statuses == {NOT_FINITE, DONE, NO_REFERENCE, BAD_REFERENCE, SCAN_RATE_RANGE}  # a TA field never underflows


def test_dpa_step_compiled_gives_the_same_bits(compile_kernels, ieee_bits):
    """The DPA's period on any field (the public path :meth:`Dpa.step_xyz`): zero and signed-zero components,
    fields whose |B|² underflows (the seed-003 laws refuse them), huge ones, in every mode and configuration."""
    fast = compile_kernels(dpa_step)
    rng = random.Random(2408)
    statuses = set()
    for case in range(400):
        dpa = Dpa(_config(rng))
        for _ in range(25):
            b = rng.choice([_vec(rng, 5e-5), _vec(rng, 1e-160), (0.0, -0.0, 0.0)])
            args = (dpa.params, _state(rng), rng.randrange(len(HEAO_MODES)), b, _vec(rng, 0.05), _vec(rng, 1.0),
                    _vec(rng, 30.0), _unit_q(rng), True, rng.uniform(1e-3, 60.0))
            plain = dpa_step(*args)
            statuses.add(plain[0])
            assert ieee_bits(fast(*args)) == ieee_bits(plain), f'case {case}: {args}'
    assert FIELD_ZERO in statuses


def test_wheel_volts_compiled_gives_the_same_bits(compile_kernels, ieee_bits):
    """The wheel law's min/max on limits, rails and signed zeros, and no limiter (+∞), as Python's (finite inputs:
    the stage refuses any other, and a NaN's sign is not kept alike)."""
    fast = compile_kernels(wheel_volts_xyz)
    rng = random.Random(2409)
    edges = [0.0, -0.0, 1e-300, -1e-300, 1e300, -1e300]
    for case in range(20000):
        theta = tuple(rng.choice(edges) if rng.random() < 0.3 else rng.uniform(-1.0, 1.0) for _ in range(3))
        omega = tuple(rng.choice(edges) if rng.random() < 0.3 else rng.uniform(-0.1, 0.1) for _ in range(3))
        limit = tuple(rng.choice([math.inf, 0.0, rng.uniform(0.0, 0.5)]) for _ in range(3))
        row = (tuple(rng.choice([0.0, rng.uniform(0.0, 1e5)]) for _ in range(3)), limit,
               tuple(rng.choice([0.0, rng.uniform(0.0, 100.0)]) for _ in range(3)))
        args = (theta, omega, row, rng.choice([0.0, V_SAT_V, rng.uniform(0.0, 1e3)]))
        assert ieee_bits(fast(*args)) == ieee_bits(wheel_volts_xyz(*args)), f'case {case}: {args}'
