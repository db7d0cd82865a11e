"""The rigid body's kernels give the plain functions' bits, and the circular-orbit path the general path's (issue 24).

:func:`dynamics.rigid_body_model.attitude_rk4_circular_dipole` evaluates the orbit and the field at the RK4
stage times itself (spec §3; :mod:`acds_common.kernels`). Checked on random and edge inputs, every returned
float as its IEEE bytes: compiled against plain, and plain against :func:`~dynamics.rigid_body_model.attitude_rk4`
given the stage environment the :class:`~acds_common.environment.Orbit` and
:class:`~acds_common.environment.TiltedDipoleField` methods compute (the model's path for other orbits and fields).
The model's one call per step (:func:`~dynamics.rigid_body_model.advance_circular_dipole`,
:func:`~dynamics.rigid_body_model.advance_stages`: the RK4, the mean torques and the truth values) and the reaction
wheels' (:func:`~dynamics.wheels_model.wheels_step`) likewise.
"""

from __future__ import annotations

import math
import random

from acds_common import units
from acds_common.environment import (
    EarthFieldConfig,
    Orbit,
    OrbitConfig,
    Sun,
    SunConfig,
    TiltedDipoleField,
    circular_dipole_environment,
    circular_dipole_parameters,
)
from dynamics.rigid_body_model import (
    advance_circular_dipole,
    advance_stages,
    attitude_rk4,
    attitude_rk4_circular_dipole,
    truth_values,
)
from dynamics.wheels_model import ReactionWheels, WheelsConfig, wheels_step


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


def _sun(rng: random.Random) -> tuple:
    """A :data:`~dynamics.rigid_body_model.SunAxes`: random unit directions, the sun line the same row or not,
    eclipse on or off."""
    def unit():
        v = tuple(rng.uniform(-1, 1) for _ in range(3))
        n = math.sqrt(sum(c * c for c in v))
        return tuple(c / n for c in v)
    line = unit()
    same = rng.random() < 0.5
    direction = line if same else unit()
    return direction, line, same, direction, rng.random() < 0.6


def _advance_cases(seed: int, count: int):
    """Arguments of both advance kernels from the RK4 cases: (circular dipole args, stage environment args)."""
    rng = random.Random(seed)
    for case, orbit, _field, args in _cases(seed, count):
        q, w, n, t0, dt, start, params, inertia, inverse, m, h0, hdot, td, gg, with_field = args
        p = (n, inertia, inverse, gg, _sun(rng))
        env = tuple((*orbit.position_xyz(t0 + dt * (j / (2 * n))), *(rng.uniform(-5e-5, 5e-5) for _ in range(3)))
                    for j in range(2 * n + 1))
        r_end, v_end = orbit.state_xyz(t0 + dt)
        end = (r_end if rng.random() < 0.8 else (-r_end[0], -r_end[1], -r_end[2]), v_end,
               tuple(rng.uniform(-5e-5, 5e-5) for _ in range(3)))
        yield case, ((p, params, q, w, t0, dt, start, m, h0, hdot, td, with_field),
                     (p, q, w, t0, dt, env, end, m, h0, hdot, td, with_field))


def test_advance_kernels_compiled_give_the_same_bits(compile_kernels, ieee_bits):
    """One rigid-body step, compiled against plain: the finiteness flag, B_eci and every truth value (B and the
    Sun in body axes, direction cosines, sun presence in and out of the shadow, mean torques)."""
    circular, stages = compile_kernels(advance_circular_dipole), compile_kernels(advance_stages)
    for case, (a, b) in _advance_cases(26, 1000):
        assert ieee_bits(circular(*a)) == ieee_bits(advance_circular_dipole(*a)), f'case {case}: {a}'
        assert ieee_bits(stages(*b)) == ieee_bits(advance_stages(*b)), f'case {case}: {b}'


def test_advance_kernel_is_the_rk4_and_the_truth_values(ieee_bits):
    """:func:`advance_circular_dipole` is :func:`attitude_rk4_circular_dipole` followed by the mean torques and
    :func:`truth_values` at its end (what the model gave in Python before the kernel did it)."""
    for case, (a, _b) in _advance_cases(27, 200):
        p, params, q, w, t0, dt, start, *body = a
        n, inertia, inverse, gg, sun = p
        q1, w1, smag, sgg, (r, v, b) = attitude_rk4_circular_dipole(q, w, n, t0, dt, start, params, inertia, inverse,
                                                                    *body[:4], gg, body[4])
        w6 = 6.0 * n
        want = (math.isfinite(sum(q1) + sum(w1)), b,
                truth_values(q1, w1, r, v, b, tuple(x / w6 for x in smag), tuple(x / w6 for x in sgg), sun))
        assert ieee_bits(advance_circular_dipole(*a)) == ieee_bits(want), f'case {case}'


def test_truth_values_compiled_give_the_same_bits_in_and_out_of_the_shadow(compile_kernels, ieee_bits):
    """The truth values alone, with the Sun's shadow edge cases: a position along the sun line (sunward and
    anti-sunward), on the shadow cylinder's axis and just outside its radius; and the Sun's presence as
    :meth:`Sun.present_xyz` gives it."""
    fast = compile_kernels(truth_values)
    rng = random.Random(28)
    sun_cfg = Sun(SunConfig(right_ascension_rad=0.3, declination_rad=-0.2, eclipse=True))
    d = sun_cfg.direction_xyz
    edge = [tuple(-7e6 * c for c in d), tuple(7e6 * c for c in d), (0.0, 0.0, 0.0), (-0.0, -0.0, -0.0),
            (-7e6 * d[0], -7e6 * d[1] + units.EARTH_RADIUS_M * 1.0000001, -7e6 * d[2])]
    for case in range(400):
        q = tuple(rng.uniform(-1, 1) for _ in range(4))
        w, v, b, tmag, tgg = (tuple(rng.uniform(-1, 1) for _ in range(3)) for _ in range(5))
        r = edge[case] if case < len(edge) else tuple(rng.uniform(-8e6, 8e6) for _ in range(3))
        sun = _sun(rng) if case >= len(edge) else (d, d, True, d, True)
        got = fast(q, w, r, v, b, tmag, tgg, sun)
        assert ieee_bits(got) == ieee_bits(truth_values(q, w, r, v, b, tmag, tgg, sun)), f'case {case}'
        if sun[4] and sun[3] is d:
            assert got[-1] == sun_cfg.present_xyz(r)


WHEEL_SETS = [{}, {'orthogonal_equivalent_active_wheels': 3}, {'layout': 'four_cant20'},
              {'layout': 'four_cant20', 'failed_wheel': 1}]


def test_wheels_step_compiled_gives_the_same_bits(compile_kernels, ieee_bits):
    """The wheels' step, compiled against plain, for each wheel set as :class:`ReactionWheels` builds its parameters:
    volts within, at (±V_sat) and beyond saturation, signed zeros, momenta near and at capacity (limited mid-step,
    driven back out), short and long steps; every returned float (momenta, torques, body h and ḣ)."""
    fast = compile_kernels(wheels_step)
    rng = random.Random(29)
    for kw in WHEEL_SETS:
        p = ReactionWheels(WheelsConfig(**kw))._params
        caps = p[5]
        for case in range(1500):
            volts = tuple(rng.choice([0.0, -0.0, 17.1, -17.1, rng.uniform(-40.0, 40.0), rng.uniform(-2.0, 2.0)])
                          for _ in range(3))
            h = tuple(rng.choice([0.0, -0.0, c, -c, rng.uniform(-1.0, 1.0) * c, c - rng.uniform(0.0, 0.1)])
                      if c else 0.0 for c in caps)
            dt = rng.choice([0.5, 1.0, rng.uniform(1e-3, 30.0)])
            args = (p, h, volts, dt)
            assert ieee_bits(fast(*args)) == ieee_bits(wheels_step(*args)), f'{kw} case {case}: {args}'
