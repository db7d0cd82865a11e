"""AAP Workshop magnetic CMG dump, closed through the pure cores without ROS (seed 000 §3, §5).

Composition per control step k (what the graph will do once wired): field B_k in body axes → H_s sampled at
the first step of each orbit → dump law M_k → hold law ḣ_k (feedforward: the known external torque) → CMG
store integrates ḣ over the step. "Ideal hold" runs keep the attitude exactly (the CMGs take the step-mean
external torque, from the disturbance's closed-form integral); the last test closes the hold through the
rigid body instead. Steps of T/300 (18.5 s) put every orbit boundary on a step.

What the tests establish about the seed's k (reported, not tuned): the once-per-orbit sampled loop is
H_{n+1} = (I − k W_n) H_n + H_b with W_n = ∫ (|B|² I − B Bᵀ) dt over orbit n, which settles only if every
eigenvalue of k W_n lies in (0, 2). With the seed's k = 3e6…5e6 (ft-lb-sec, Wb/m², A·m²) and its field
(B_0 = 0.26e-4 T at 220 nmi) those eigenvalues are about 4 to 16, so from H_s = 0 the samples oscillate with
growing amplitude and the CMGs saturate within a few orbits.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from acds_common import units
from acds_common.attitude import dcm_to_quat
from acds_common.environment import EarthFieldConfig, Orbit, OrbitConfig, Sun, SunConfig, TiltedDipoleField
from acds_controller.cmg_dump import (
    CmgDumpLaw,
    DumpLawConfig,
    OrbitClock,
    SampledMomentum,
    field_gramian,
    hold_weights,
    k_to_si,
    loop_gains,
    orbit_stats,
)
from acds_controller.cmg_hold import HoldGains, cmg_hold_rate
from acds_controller.wheel_laws import inertial_hold_error
from dynamics.cmg_model import CmgConfig, ControlMomentGyros
from dynamics.disturbances import (
    MODE_GEOMETRY,
    SEED_BIAS_MOMENTUM_FTLBS,
    gravity_gradient_inertial_hold,
    seed_disturbance,
    workshop_inertia_kg_m2,
)
from dynamics.rigid_body_model import RigidBodyModel

INCLINATION = math.radians(35.0)
ORBIT = Orbit(OrbitConfig(kind='circular', inclination_rad=INCLINATION, altitude_m=220.0 * units.NMI_M))
T = ORBIT.period_s
N = ORBIT.mean_motion_rad_s
STEPS = 300  # per orbit
DT = T / STEPS
B0 = 0.26e-4  # Appendix A, T at the magnetic equator at 220 nmi
FIELD = TiltedDipoleField(EarthFieldConfig())
INERTIA = workshop_inertia_kg_m2()
H_B_POP = units.ftlbs_to_nms(np.array(SEED_BIAS_MOMENTUM_FTLBS['pop']))


def k_for_gain(g: float, b_t: float = B0) -> float:
    """The seed-unit k whose per-orbit gain k·B²·T is g for a constant field of magnitude b_t."""
    return g / (k_to_si(1.0) * b_t * b_t * T)


def ideal_hold(b_of_t, law: CmgDumpLaw | None, orbits: int, mode: str = 'pop') -> tuple[np.ndarray, ...]:
    """Per-step (t, M, B, H_s) and the per-orbit samples H_s,n of an ideal-hold run from H_s = 0."""
    disturbance = seed_disturbance(mode, N, rigid_body_gravity_gradient=False)
    cmg = ControlMomentGyros(CmgConfig())
    clock = OrbitClock(T)
    sampler = SampledMomentum(clock)
    rows = []
    for k in range(orbits * STEPS + 1):
        t = k * DT
        b = b_of_t(t)
        h_s = sampler.sample(t, cmg.momentum_body_nms())
        m = np.zeros(3) if law is None else law.step(t, h_s, b)
        t_ext = disturbance.momentum_nms(t, t + DT) / DT + np.cross(m, b)
        cmg.step(cmg_hold_rate(np.zeros(3), np.zeros(3), INERTIA, cmg.momentum_body_nms(), t_ext), DT)
        rows.append((t, m, b, h_s))
    t, m, b, h_s = (np.array(x) for x in zip(*rows, strict=True))
    return t, m, b, h_s, h_s[::STEPS]


def constant_field(t: float) -> np.ndarray:
    """B_0 along body x (the POP orbit normal): a constant direction, perpendicular to the POP bias."""
    return np.array([B0, 0.0, 0.0])


def test_without_the_law_h_s_grows_by_h_b_every_orbit() -> None:
    *_, samples = ideal_hold(constant_field, None, 16)
    assert np.allclose(np.diff(samples, axis=0), H_B_POP, rtol=1e-9, atol=1e-9)
    assert units.nms_to_ftlbs(samples[-1][2]) == pytest.approx(-16 * 255.0, rel=1e-9)


@pytest.mark.parametrize('g', [0.5, 1.0, 1.5, 1.9])
def test_constant_field_k_law_bounds_h_s_when_the_loop_gain_is_below_two(g: float) -> None:
    """Constant B ⟂ H_b: H_{n+1} = (1 − g) H_n + H_b with g = k B² T. For 0 < g < 2 the samples stay bounded over
    16 orbits and settle at H_b/g, where the orbit's dump equals the bias."""
    law = CmgDumpLaw(DumpLawConfig('khb', k_seed=k_for_gain(g)), OrbitClock(T))
    *_, samples = ideal_hold(constant_field, law, 16)
    expected = [np.zeros(3)]
    for _ in range(16):
        expected.append((1.0 - g) * expected[-1] + H_B_POP)
    assert np.allclose(samples, expected, rtol=1e-9, atol=1e-9)
    assert np.max(np.linalg.norm(samples, axis=1)) <= max(1.0, 1.0 / g) * np.linalg.norm(H_B_POP) * (1 + 1e-9)
    assert np.allclose(samples[-1], H_B_POP / g, rtol=0.02 if g != 1.9 else 0.6)


def test_constant_field_with_the_seed_k_the_sampled_loop_diverges() -> None:
    """k = 4e6 at |B| = B_0: g = 11.1, so H_s,n = 0, H_b, (2 − g) H_b, … grows ×10 per orbit; the CMG envelope
    (12,000 ft-lb-sec) is hit in the third orbit."""
    law = CmgDumpLaw(DumpLawConfig('khb', k_seed=4e6), OrbitClock(T))
    g = 4e6 * k_to_si(1.0) * B0 ** 2 * T
    *_, samples = ideal_hold(constant_field, law, 4)
    assert g == pytest.approx(11.09, abs=0.01)
    assert np.allclose(samples[:3], [np.zeros(3), H_B_POP, (2.0 - g) * H_B_POP], rtol=1e-9, atol=1e-9)
    assert units.nms_to_ftlbs(np.linalg.norm(samples[3])) == pytest.approx(12000.0, rel=1e-9)


def pop_field_body(t: float) -> np.ndarray:
    """Tilted-dipole field along the 220 nmi, 35° orbit in POP body axes (attitude held inertially)."""
    dcm = MODE_GEOMETRY['pop'].body_to_eci_dcm(INCLINATION, 0.0)
    return dcm.T @ FIELD.b_eci(ORBIT.position_velocity_eci(t)[0], t)


def per_orbit_gramians(t: np.ndarray, b: np.ndarray, orbits: int) -> list[np.ndarray]:
    w = hold_weights(t)
    return [field_gramian(b[STEPS * n:STEPS * (n + 1)], w[STEPS * n:STEPS * (n + 1)]) for n in range(orbits)]


@pytest.mark.parametrize('k', [3e6, 4e6, 5e6])
def test_realistic_field_seed_k_range_from_zero_follows_the_map_and_does_not_converge(k: float) -> None:
    """Tilted dipole, 220 nmi, 35°, POP, H_s = 0 at the start: the samples follow H_{n+1} = (I − k W_n) H_n + H_b
    exactly, every orbit's loop gains exceed 2 (≈ 4–16 over 16 orbits), and |H_s| grows until the CMGs saturate."""
    law = CmgDumpLaw(DumpLawConfig('khb', k_seed=k), OrbitClock(T))
    t, _, b, _, samples = ideal_hold(pop_field_body, law, 4)
    grams = per_orbit_gramians(t, b, 4)
    for n in range(3):
        assert min(loop_gains(grams[n], k)) > 2.0
        if units.nms_to_ftlbs(np.linalg.norm(samples[n + 1])) < 12000.0 * (1 - 1e-9):
            predicted = samples[n] + H_B_POP - k_to_si(k) * grams[n] @ samples[n]
            assert np.allclose(samples[n + 1], predicted, rtol=1e-9, atol=1e-6)
    sizes = units.nms_to_ftlbs(np.linalg.norm(samples, axis=1))
    assert sizes[2] > 5 * sizes[1] and sizes[-1] == pytest.approx(12000.0, rel=1e-9)


def test_realistic_field_converges_for_a_k_inside_the_stability_range() -> None:
    """Same orbit with k = 1/λ_max(W) of the first orbit (gains ≈ 0.5–1): from H_s = 0 the samples settle within a
    few orbits at the moment that dumps H_b, so |ΔH_s| falls to a small fraction of |H_b|."""
    probe_t = np.linspace(0.0, T, STEPS + 1)
    w0 = field_gramian(np.array([pop_field_body(x) for x in probe_t]), hold_weights(probe_t))
    k = 1.0 / (k_to_si(1.0) * float(np.linalg.eigvalsh(w0)[-1]))
    law = CmgDumpLaw(DumpLawConfig('khb', k_seed=k), OrbitClock(T))
    t, m, b, h_s, samples = ideal_hold(pop_field_body, law, 8)
    stats = orbit_stats(t, m, b, np.ones(t.size, dtype=bool), h_s, OrbitClock(T), H_B_POP, k_seed=k)
    delta = [float(np.linalg.norm(s.delta_h_s_nms)) for s in stats]
    assert all(0.0 < min(s.loop_gains) and max(s.loop_gains) < 2.0 for s in stats)
    assert delta[0] == pytest.approx(np.linalg.norm(H_B_POP))
    assert max(delta[4:]) < 0.1 * np.linalg.norm(H_B_POP)
    for s in stats[4:]:
        assert s.m_o_am2 == pytest.approx(s.min_energy_m_o_am2, rel=0.1)


def test_hold_law_through_the_rigid_body_stores_the_gravity_gradient_bias_and_the_dump() -> None:
    """IOP attitude, gravity gradient computed by the rigid body, the k·H_s × B moment applied as the body's dipole:
    the hold law keeps the attitude within 0.1° and, over one orbit, the CMG momentum changes by the torques'
    integral — the gravity-gradient bias (573 ft-lb-sec along x, §5's 575) plus ∫ M × B dt."""
    geometry = MODE_GEOMETRY['iop']
    q0 = dcm_to_quat(geometry.body_to_eci_dcm(INCLINATION, 0.0))
    steps = 1500  # Δt = 3.7 s: ω_n Δt = 0.19 for the default 0.05 rad/s hold bandwidth
    dt = T / steps
    body = RigidBodyModel(INERTIA, ORBIT, FIELD, Sun(SunConfig()), gravity_gradient=True, substeps=1, q0_body_to_eci=q0)
    h0 = units.ftlbs_to_nms(np.array([0.0, 300.0, 0.0]))
    cmg = ControlMomentGyros(CmgConfig(), h0)
    clock = OrbitClock(T)
    sampler, law = SampledMomentum(clock), CmgDumpLaw(DumpLawConfig('khb'), clock)
    gains = HoldGains()
    gg_sum, mag_sum, err_max = np.zeros(3), np.zeros(3), 0.0
    for _ in range(steps):
        truth = body.truth(cmg.momentum_body_nms())
        err = inertial_hold_error(truth.q_body_to_eci, q0)
        err_max = max(err_max, float(np.linalg.norm(err)))
        m = law.step(truth.t_s, sampler.sample(truth.t_s, cmg.momentum_body_nms()), truth.b_body_t)
        hdot = cmg_hold_rate(err, truth.omega_body_rad_s, INERTIA, cmg.momentum_body_nms(), np.cross(m, truth.b_body_t),
                             gains)
        h_start, hdot_mean = cmg.step(hdot, dt)
        body.advance(dt, m, h_start, hdot_mean)
        after = body.truth(cmg.momentum_body_nms())
        gg_sum += after.torque_gravity_gradient_body_nm * dt
        mag_sum += after.torque_magnetic_body_nm * dt
    dh = cmg.momentum_body_nms() - h0
    body_dh = INERTIA @ body.omega_body_rad_s
    assert math.degrees(err_max) < 0.1
    assert np.allclose(dh + body_dh, gg_sum + mag_sum, rtol=0.0, atol=1e-3 * np.linalg.norm(gg_sum + mag_sum))
    assert np.allclose(units.nms_to_ftlbs(gg_sum), [573.0, 0.0, 0.0], atol=2.0)
    gg = gravity_gradient_inertial_hold(INERTIA, geometry, N)
    assert np.allclose(gg_sum, np.array(gg.constant_nm) * T, rtol=0.0, atol=0.005 * np.linalg.norm(gg_sum))
    assert float(mag_sum @ h0) < -0.1 * float(h0 @ h0)  # the dump acted against the held H_s
