"""The rigid body's circular-orbit, tilted-dipole kernel gives the plain function's bits and the general path's (issue 24).

:func:`dynamics.rigid_body_model.attitude_rk4_circular_dipole` evaluates the orbit and the field at the RK4
stage times itself (spec §3; :mod:`acds_common.kernels`). Checked on random and edge inputs, every returned
float as its IEEE bytes: compiled against plain, and plain against :func:`~dynamics.rigid_body_model.attitude_rk4`
given the stage environment the :class:`~acds_common.environment.Orbit` and
:class:`~acds_common.environment.TiltedDipoleField` methods compute (the model's path for other orbits and fields).
"""

from __future__ import annotations

import math
import random

from acds_common.environment import (
    EarthFieldConfig,
    Orbit,
    OrbitConfig,
    TiltedDipoleField,
    circular_dipole_environment,
    circular_dipole_parameters,
)
from dynamics.rigid_body_model import attitude_rk4, attitude_rk4_circular_dipole


def _orbit_field(rng: random.Random) -> tuple[Orbit, TiltedDipoleField]:
    u = rng.uniform
    orbit = Orbit(OrbitConfig(kind='circular', altitude_m=u(2e5, 1.2e6), inclination_rad=u(0.0, math.pi),
                              raan_rad=u(-4.0, 4.0), arg_latitude0_rad=u(-4.0, 4.0)))
    field = TiltedDipoleField(EarthFieldConfig(tilt_rad=u(0.0, math.pi / 2), dipole_longitude_rad=u(-4.0, 4.0),
                                               greenwich_angle0_rad=u(-4.0, 4.0)))
    return orbit, field


def _case(rng: random.Random, orbit: Orbit, field: TiltedDipoleField) -> tuple:
    """Arguments of the circular-dipole kernel: edge times (0, −0, large) and flags among random ones."""
    u = rng.uniform
    n = rng.choice([1, 1, 2, 5, 10])
    dt = rng.choice([0.5, 2.0, u(1e-3, 1.0)])  # resolved steps (a diverging one stops the model)
    t0 = rng.choice([0.0, -0.0, u(0.0, 1e4), u(1e5, 1e7)])
    r, _v = orbit.state_xyz(t0)
    b = field.b_eci_xyz(r, t0)
    inertia = ((u(1e3, 3e3), u(-100, 100), u(-500, 500)), (0.0, u(5e3, 1.2e4), u(-20, 20)), (0.0, 0.0, u(5e3, 1.2e4)))
    inertia = tuple(tuple(inertia[min(i, j)][max(i, j)] for j in range(3)) for i in range(3))
    inverse = tuple(tuple(u(-1e-3, 1e-3) for _ in range(3)) for _ in range(3))
    m = rng.choice([(0.0, 0.0, 0.0), tuple(u(-500, 500) for _ in range(3))])
    return ((*(u(-1, 1) for _ in range(4)),), tuple(u(-0.05, 0.05) for _ in range(3)), n, t0, dt, (*r, *b),
            circular_dipole_parameters(orbit, field), inertia, inverse, m, tuple(u(-20, 20) for _ in range(3)),
            tuple(u(-0.2, 0.2) for _ in range(3)), tuple(u(-1e-3, 1e-3) for _ in range(3)),
            rng.random() < 0.7, any(m))


def _cases(seed: int, count: int):
    rng = random.Random(seed)
    for case in range(count):
        if case % 20 == 0:
            orbit, field = _orbit_field(rng)
        yield case, orbit, field, _case(rng, orbit, field)


def test_circular_dipole_parameters_only_for_a_circular_orbit_and_the_dipole():
    circular = Orbit(OrbitConfig())
    elliptical = Orbit(OrbitConfig(kind='elliptical', perigee_altitude_m=4e5, apogee_radius_m=8e6))
    assert circular_dipole_parameters(circular, TiltedDipoleField(EarthFieldConfig())) is not None
    assert circular_dipole_parameters(elliptical, TiltedDipoleField(EarthFieldConfig())) is None
    assert circular_dipole_parameters(circular, object()) is None


def test_circular_dipole_environment_compiled_gives_the_methods_bits(compile_kernels, ieee_bits):
    fast = compile_kernels(circular_dipole_environment)
    rng = random.Random(11)
    for _case_no in range(100):
        orbit, field = _orbit_field(rng)
        params = circular_dipole_parameters(orbit, field)
        for t in (0.0, -0.0, rng.uniform(0.0, 1e4), rng.uniform(1e5, 1e8)):
            r, v = orbit.state_xyz(t)
            want = (r, v, field.b_eci_xyz(r, t))
            assert ieee_bits(fast(params, t, True)) == ieee_bits(want) == ieee_bits(circular_dipole_environment(params, t, True))
            assert ieee_bits(fast(params, t, False)) == ieee_bits((r, v, (0.0, 0.0, 0.0)))


def test_attitude_rk4_circular_dipole_compiled_gives_the_same_bits(compile_kernels, ieee_bits):
    fast = compile_kernels(attitude_rk4_circular_dipole)
    for case, _orbit, _field, args in _cases(24, 2000):
        assert ieee_bits(fast(*args)) == ieee_bits(attitude_rk4_circular_dipole(*args)), f'case {case}: {args}'


def test_attitude_rk4_circular_dipole_gives_the_stage_environment_path_bits(ieee_bits):
    """The kernel's own orbit and field give what the model's stage environment gave :func:`attitude_rk4`
    (r and B from the Orbit and TiltedDipoleField methods at t0 + dt·j/(2n)), and the end's (r, v, B)."""
    for case, orbit, field, args in _cases(25, 500):
        q, w, n, t0, dt, _start, _params, *body = args
        gg, with_field = body[-2], body[-1]
        env = []
        for j in range(2 * n + 1):
            tj = t0 if j == 0 else t0 + dt * (j / (2 * n))
            r = orbit.position_xyz(tj)
            env.append((*r, *(field.b_eci_xyz(r, tj) if with_field else (0.0, 0.0, 0.0))) if gg or with_field
                       else (0.0,) * 6)
        r_end, v_end = orbit.state_xyz(t0 + dt)
        want = (*attitude_rk4(q, w, n, t0, dt, tuple(env), None, None, *body),
                (r_end, v_end, field.b_eci_xyz(r_end, t0 + dt)))
        assert ieee_bits(attitude_rk4_circular_dipole(*args)) == ieee_bits(want), f'case {case}: {args}'
