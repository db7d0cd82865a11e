"""The compiled model kernels give the plain functions' bits (issue 24; :mod:`acds_common.kernels`).

The direct engine runs the attitude RK4 step and the coil's event-driven period compiled by numba; the
per-process graph runs the same source as plain Python. Each kernel is compared here on random and edge
inputs, every returned float bit for bit (a fused multiply-add, a reassociation or another ``exp`` than
the interpreter's would show as a last-bit difference); the engines test and the truth digests compare
whole runs.
"""

from __future__ import annotations

import math
import random

from dynamics.rigid_body_model import attitude_rk4
from em_driver.bridge_switch import CoilParams, DriverParams, band_limits_a, coil_period


def test_compiled_forms_are_compiled(compile_kernels):
    """Once enabled, a kernel resolves to numba's compiled dispatcher (not the plain function)."""
    for fn in (attitude_rk4, coil_period):
        out = compile_kernels(fn)
        assert out is not fn and out.py_func is fn


def _attitude_case(rng: random.Random) -> tuple:
    u = rng.uniform
    n = rng.choice([1, 1, 2, 5])
    r = 6.378e6 + u(2e5, 1.2e6)
    env = []
    for _ in range(2 * n + 1):
        d = [u(-1, 1) for _ in range(3)]
        s = math.sqrt(sum(x * x for x in d))
        env.append((*(r * x / s for x in d), *(u(-4e-5, 4e-5) for _ in range(3))))
    inertia = ((u(1e3, 3e3), u(-100, 100), u(-500, 500)), (0.0, u(5e3, 1.2e4), u(-20, 20)), (0.0, 0.0, u(5e3, 1.2e4)))
    inertia = tuple(tuple(inertia[min(i, j)][max(i, j)] for j in range(3)) for i in range(3))
    inverse = tuple(tuple(u(-1e-3, 1e-3) for _ in range(3)) for _ in range(3))
    q = tuple(u(-1, 1) for _ in range(4))
    return (q, tuple(u(-0.05, 0.05) for _ in range(3)), n, u(0.0, 1e5), 0.5, tuple(env), None, None, inertia, inverse,
            tuple(u(-2000, 2000) for _ in range(3)), tuple(u(-20, 20) for _ in range(3)),
            tuple(u(-0.2, 0.2) for _ in range(3)), tuple(u(-1e-3, 1e-3) for _ in range(3)),
            rng.random() < 0.7, rng.random() < 0.7)


def test_attitude_rk4_compiled_gives_the_same_bits(compile_kernels, ieee_bits):
    fast = compile_kernels(attitude_rk4)
    rng = random.Random(24)
    for case in range(3000):
        args = _attitude_case(rng)
        assert ieee_bits(fast(*args)) == ieee_bits(attitude_rk4(*args)), f'case {case}: {args}'


def test_coil_period_compiled_gives_the_same_bits(compile_kernels, ieee_bits):
    """Random commands held, switched, reversed, saturated and dropped, each period continuing the last one's end
    state (as a drive does), with the Table 4-3 winding and driver and with perturbed ones."""
    fast = compile_kernels(coil_period)
    rng = random.Random(2024)
    for variant in range(30):
        coil = CoilParams() if variant == 0 else CoilParams(resistance_ohm=30.3 * rng.uniform(0.8, 1.2),
                                                            inductance_h=20.3 * rng.uniform(0.5, 1.5))
        driver = DriverParams()
        tau = coil.inductance_h / coil.resistance_ohm
        i_on = (driver.supply_v - 2.0 * driver.v_ces_v) / coil.resistance_ohm
        i_off = (driver.supply_v + 2.0 * driver.diode_drop_v) / coil.resistance_ohm
        i, on, s = rng.uniform(-i_on, i_on), False, 1.0
        for _ in range(200):
            kind = rng.random()
            if kind < 0.1:  # the switch held on (constant level / stuck bridge)
                lo = hi = math.inf
                active = True
            elif kind < 0.2:  # zero command: decay
                lo = hi = 0.0
                active = False
            else:
                lo, hi = band_limits_a(rng.uniform(0.0, 1.1 * i_on), driver)
                active = hi > 0.0
            if rng.random() < 0.3:
                s = -s
            duration = rng.choice([0.5, 0.5, 2.0, rng.uniform(1e-3, 5.0)])
            args = (s, i, on, active, lo, hi, duration, tau, driver.supply_v, i_on, i_off, None)
            got, want = fast(*args), coil_period(*args)
            assert ieee_bits(got) == ieee_bits(want), f'variant {variant}: {args}'
            i, on = want[0], want[1]
