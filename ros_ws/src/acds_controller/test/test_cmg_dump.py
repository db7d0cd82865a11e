"""Tests of the AAP Workshop dump law, its minimum-energy solution and per-orbit bookkeeping (seed 000 §3, §5, App. B)."""

from __future__ import annotations

import math

import numpy as np
import pytest
from acds_common.units import FT_LB_S_NMS, ftlbs_to_nms, nms_to_ftlbs
from acds_controller.cmg_dump import (
    CmgDumpLaw,
    DumpLawConfig,
    OrbitAccumulator,
    OrbitClock,
    SampledMomentum,
    constant_magnitude,
    dump_report,
    field_gramian,
    hold_weights,
    k_to_si,
    khb_moment,
    limit_magnitude,
    loop_gain_k_seed,
    loop_gain_warning,
    loop_gains,
    min_energy_vector,
    orbit_stats,
    proper_initial_h_s_nms,
    trapezoid_weights,
)
from acds_controller.magnetic_laws import ControllerError
from hypothesis import given, settings
from hypothesis import strategies as st

T_ORB = 5562.77  # 220 nmi circular, s
N_ORB = 2.0 * math.pi / T_ORB
B0 = 0.26e-4  # Appendix A, T
H_B_POP = ftlbs_to_nms(np.array([0.0, 0.0, -255.0]))

_H = st.floats(-2000.0, 2000.0, allow_nan=False)
H_VEC = st.tuples(_H, _H, _H).map(np.array)


def field_history(seed: int, n: int = 400) -> tuple[np.ndarray, np.ndarray]:
    """An orbit of a field that turns twice per orbit about a tilted axis (Appendix A's shape), random tilt/phase."""
    rng = np.random.default_rng(seed)
    t = np.linspace(0.0, T_ORB, n + 1)
    a, c = rng.uniform(0.3, 0.9), rng.uniform(-0.5, 0.5)
    phase = rng.uniform(0.0, 2 * math.pi)
    b = B0 * np.column_stack([-a / 2 - 1.5 * a * np.cos(2 * N_ORB * t - phase),
                              c - 1.5 * a * np.sin(2 * N_ORB * t - phase), np.full_like(t, math.sqrt(1 - a * a))])
    return t, b


def test_k_in_si() -> None:
    """k = 4e6 amp-turn-m² per ft-lb-sec per Wb/m² is 2.950e6 A·m² per N·m·s per T."""
    assert k_to_si(4e6) == pytest.approx(4e6 / FT_LB_S_NMS, rel=1e-15)
    assert k_to_si(4e6) == pytest.approx(2.950e6, rel=1e-3)
    # |M| = k |H_s| |B| for H_s ⟂ B, in the seed's units:
    m = khb_moment(ftlbs_to_nms(np.array([0.0, 0.0, 20.0])), np.array([B0, 0.0, 0.0]))
    assert np.linalg.norm(m) == pytest.approx(4e6 * 20.0 * B0, rel=1e-12)


@settings(max_examples=60)
@given(H_VEC, H_VEC, st.integers(0, 10_000), st.sampled_from([3e6, 4e6, 5e6]))
def test_moment_perpendicular_to_b_and_orbit_torque_opposes_h_s(h_s: np.ndarray, h_0: np.ndarray, seed: int,
                                                                  k: float) -> None:
    """§3: M = k (H_s − H_0) × B is ⟂ B at every instant, and over an orbit ∫ M × B dt = −k W (H_s − H_0),
    which never has a component along H_s − H_0 (W is positive semi-definite)."""
    t, b = field_history(seed)
    w = trapezoid_weights(t)
    ms = np.array([khb_moment(h_s, bk, k, h_0) for bk in b])
    assert np.all(np.abs(np.einsum('ki,ki->k', ms, b)) <= 1e-9 * np.linalg.norm(ms, axis=1) * np.linalg.norm(b, axis=1)
                  + 1e-30)
    dump = (w[:, None] * np.cross(ms, b)).sum(axis=0)
    gram = field_gramian(b, w)
    assert np.allclose(dump, -k_to_si(k) * gram @ (h_s - h_0), rtol=1e-9, atol=1e-9)
    assert float(dump @ (h_s - h_0)) <= 1e-9 * np.linalg.norm(dump) * np.linalg.norm(h_s - h_0) + 1e-12


@pytest.mark.parametrize('seed', [4, 5])
def test_gramian_is_minus_the_integral_of_b_tilde_squared(seed: int) -> None:
    """W = −∫ B̃² dt with B̃ the matrix of B × (eq. 3), symmetric and positive definite off the magnetic equator (B-4)."""
    t, b = field_history(seed)
    w = trapezoid_weights(t)

    def tilde(v: np.ndarray) -> np.ndarray:
        return np.array([[0.0, -v[2], v[1]], [v[2], 0.0, -v[0]], [-v[1], v[0], 0.0]])

    expected = -sum(wk * tilde(bk) @ tilde(bk) for wk, bk in zip(w, b, strict=True))
    gram = field_gramian(b, w)
    assert np.allclose(gram, expected, rtol=1e-12, atol=1e-24)
    assert np.allclose(gram, gram.T) and np.linalg.eigvalsh(gram)[0] > 0.0


def test_constant_field_direction_min_energy_dumps_exactly_h_b_closed_form() -> None:
    """B(t) = B0 (1 + ½ sin 2nt) x̂, H_b ⟂ x̂: W = ∫b² dt (I − x̂x̂ᵀ), c = H_b / ∫b² dt with ∫b² dt = (9/8) B0² T,
    and ∫ (c × B) × B dt = −H_b. A bias component along B cannot be dumped (§2) and is returned as such."""
    t = np.linspace(0.0, T_ORB, 4001)
    mag = B0 * (1.0 + 0.5 * np.sin(2 * N_ORB * t))
    b = np.column_stack([mag, np.zeros_like(t), np.zeros_like(t)])
    w = trapezoid_weights(t)
    c, undumpable = min_energy_vector(field_gramian(b, w), H_B_POP)
    assert np.allclose(c, H_B_POP / (9.0 / 8.0 * B0 ** 2 * T_ORB), rtol=1e-6)
    assert np.allclose(undumpable, 0.0, atol=1e-9)
    dump = (w[:, None] * np.cross(np.cross(c, b), b)).sum(axis=0)
    assert np.allclose(dump, -H_B_POP, rtol=1e-12, atol=1e-9)
    h_b = H_B_POP + np.array([40.0, 0.0, 0.0])
    c2, undumpable2 = min_energy_vector(field_gramian(b, w), h_b)
    assert np.allclose(c2, c, rtol=1e-9) and np.allclose(undumpable2, [40.0, 0.0, 0.0], rtol=1e-9)


@pytest.mark.parametrize('seed', [1, 2, 3])
def test_min_energy_solution_is_the_least_energy_dump(seed: int) -> None:
    """Appendix B: M = (W⁻¹ H_b) × B dumps H_b exactly, and any other M + δ that dumps H_b costs more ∫|M|² dt."""
    t, b = field_history(seed)
    w = trapezoid_weights(t)
    gram = field_gramian(b, w)
    c, undumpable = min_energy_vector(gram, H_B_POP)
    assert np.allclose(undumpable, 0.0, atol=1e-9)
    m = np.cross(c, b)
    assert np.allclose((w[:, None] * np.cross(m, b)).sum(axis=0), -H_B_POP, rtol=1e-9, atol=1e-9)
    rng = np.random.default_rng(seed)
    delta = rng.normal(0.0, 500.0, b.shape)
    err = (w[:, None] * np.cross(delta, b)).sum(axis=0)
    delta = delta + np.cross(np.linalg.solve(gram, err), b)  # now ∫ δ × B dt = 0
    assert np.allclose((w[:, None] * np.cross(delta, b)).sum(axis=0), 0.0, atol=1e-9)

    def energy(x: np.ndarray) -> float:
        return float((w * np.einsum('ki,ki->k', x, x)).sum())

    assert energy(m + delta) > energy(m)
    assert float((w * np.einsum('ki,ki->k', m, delta)).sum()) == pytest.approx(0.0, abs=1e-9 * energy(m))


def test_proper_initialisation_makes_the_k_law_the_min_energy_solution() -> None:
    """§3/§5: with k H_s = eq. (3)'s bracket the k·H_s × B law is identical to the minimum-energy M, for any k."""
    t, b = field_history(7)
    c, _ = min_energy_vector(field_gramian(b, trapezoid_weights(t)), H_B_POP)
    for k in (3e6, 4e6, 5e6):
        h_s = proper_initial_h_s_nms(c, k)
        assert np.allclose(np.array([khb_moment(h_s, bk, k) for bk in b]), np.cross(c, b), rtol=1e-12, atol=1e-9)
        h_0 = np.array([10.0, -20.0, 5.0])
        h_s0 = proper_initial_h_s_nms(c, k, h_0)
        assert np.allclose(khb_moment(h_s0, b[3], k, h_0), np.cross(c, b[3]), rtol=1e-12)


def test_loop_gains_for_a_constant_field_direction() -> None:
    """Constant B = B0 x̂: W = B0² T (I − x̂x̂ᵀ), so k W has gains 0 (along B) and g = k B0² T twice.
    With the seed's k and B0 this g is 11.1: outside the (0, 2) range in which the sampled loop converges."""
    t = np.linspace(0.0, T_ORB, 201)
    b = np.tile([B0, 0.0, 0.0], (t.size, 1))
    gains = loop_gains(field_gramian(b, trapezoid_weights(t)), 4e6)
    g = k_to_si(4e6) * B0 ** 2 * T_ORB
    assert gains == pytest.approx([0.0, g, g], rel=1e-9, abs=1e-9)
    assert g == pytest.approx(11.09, abs=0.01)


def test_loop_gains_of_a_field_rotating_in_a_plane_match_the_closed_form() -> None:
    """B = B0 (cos ωt, sin ωt, 0) over whole turns: W = B0² T (I − ⟨B̂B̂ᵀ⟩) = B0² T diag(½, ½, 1), so k·W has the
    gains g/2, g/2, g with g = k B0² T (issue 21's closed form); the loop-gain rule puts the largest at its target."""
    t = np.linspace(0.0, T_ORB, 2001)
    w_rot = 3 * 2 * math.pi / T_ORB  # three turns in the orbit
    b = B0 * np.column_stack([np.cos(w_rot * t), np.sin(w_rot * t), np.zeros_like(t)])
    w = field_gramian(b, trapezoid_weights(t))
    g = k_to_si(4e6) * B0 ** 2 * T_ORB
    assert loop_gains(w, 4e6) == pytest.approx([g / 2, g / 2, g], rel=1e-5)
    assert np.allclose(w, B0 ** 2 * T_ORB * np.diag([0.5, 0.5, 1.0]), rtol=1e-5, atol=1e-9 * B0 ** 2 * T_ORB)
    k = loop_gain_k_seed([w], 1.0)
    assert k == pytest.approx(1.0 / (k_to_si(1.0) * B0 ** 2 * T_ORB), rel=1e-5)
    assert loop_gains(w, k) == pytest.approx([0.5, 0.5, 1.0], rel=1e-5)
    assert loop_gain_k_seed([w, 0.5 * w], 1.5) == pytest.approx(1.5 * k, rel=1e-12)  # the largest W sets k
    with pytest.raises(ControllerError, match='largest loop gain'):
        loop_gain_k_seed([w], 2.5)


@settings(max_examples=40, deadline=None)
@given(H_VEC, st.floats(1.0, 1e5))
def test_the_magnitude_limit_keeps_the_direction(m: np.ndarray, limit: float) -> None:
    """§9: the limit is on |M|, not per axis: M is scaled, its direction kept; below the limit M is untouched."""
    out = limit_magnitude(m, limit)
    size = float(np.linalg.norm(m))
    assert float(np.linalg.norm(out)) <= limit * (1 + 1e-12)
    if size > limit:
        assert np.allclose(out, m * (limit / size), rtol=1e-12)
        assert float(np.linalg.norm(np.cross(out, m))) <= 1e-9 * size * limit
    else:
        assert np.array_equal(out, m)


def test_day_only_dumping_is_zero_at_night_and_constant_in_daylight() -> None:
    """§10: the moment has the constant |M| in daylight along k H_s × B, and is zero at night; the §9 limit caps
    the day and night law's |M| with its direction."""
    clock = OrbitClock(T_ORB)
    h, b = np.array([100.0, -50.0, 300.0]), np.array([2e-5, -1e-5, 3e-5])
    law = CmgDumpLaw(DumpLawConfig('khb', day_moment_am2=5000.0), clock)
    day, night = law.step(0.0, h, b, day=True), law.step(10.0, h, b, day=False)
    assert np.array_equal(night, np.zeros(3))
    assert float(np.linalg.norm(day)) == pytest.approx(5000.0, rel=1e-12)
    assert np.allclose(day / 5000.0, khb_moment(h, b) / np.linalg.norm(khb_moment(h, b)))
    assert np.array_equal(constant_magnitude(np.zeros(3), 5000.0), np.zeros(3))
    plain = khb_moment(h, b)
    capped = CmgDumpLaw(DumpLawConfig('khb', moment_limit_am2=0.5 * float(np.linalg.norm(plain))), clock)
    assert np.allclose(capped.step(0.0, h, b, day=False), 0.5 * plain)  # day and night: night is dumped too


def test_the_report_says_whether_the_loop_converges() -> None:
    """``loop_gain_max`` / ``loop_converges`` in the report and the one warning line: the seed's k on Appendix A's
    field shape has gains above 2; a k with the largest gain 1 converges and warns nothing."""
    clock = OrbitClock(T_ORB)
    t = np.linspace(0.0, T_ORB, 557)
    k_ok = loop_gain_k_seed([field_gramian(np.array([_rotating_field(x) for x in t]), trapezoid_weights(t))], 1.0)
    for k, converges in ((4e6, False), (k_ok, True)):
        law = CmgDumpLaw(DumpLawConfig('khb', k_seed=k), clock)
        tt, m, bb, h_s = _ideal_hold_run(law, _rotating_field, H_B_POP, 2, 20.0)
        rep = {'k_seed': k, **dump_report(orbit_stats(tt, m, bb, np.ones(tt.size, dtype=bool), h_s, clock, H_B_POP,
                                                      k_seed=k))}
        assert rep['loop_converges'] is converges
        assert rep['loop_gain_max'] == max(r['loop_gains'][-1] for r in rep['per_orbit'])
        warning = loop_gain_warning(rep)
        assert (warning is None) is converges
        if warning is not None:
            assert 'cannot converge' in warning and '\n' not in warning
    no_gains = dump_report(orbit_stats(tt, m, bb, np.ones(tt.size, dtype=bool), h_s, clock, H_B_POP))
    assert no_gains['loop_converges'] is None and loop_gain_warning(no_gains) is None


def _ideal_hold_run(law: CmgDumpLaw, b_of_t, h_b: np.ndarray, orbits: int, dt: float, h0: np.ndarray | None = None):
    """CMG momentum under ideal attitude hold: ḣ = H_b/T + M × B, M held over each step (test-only integrator)."""
    clock = law.clock
    sampler = SampledMomentum(clock)
    steps = math.ceil(orbits * clock.period_s / dt) + 1  # the last step opens orbit `orbits`
    h = np.zeros(3) if h0 is None else h0.copy()
    rows = []
    for k in range(steps):
        t = k * dt
        b = b_of_t(t)
        h_s = sampler.sample(t, h)
        m = law.step(t, h_s, b)
        rows.append((t, m, b, h_s))
        h = h + (h_b / clock.period_s + np.cross(m, b)) * dt
    t, m, b, h_s = (np.array(x) for x in zip(*rows, strict=True))
    return t, m, b, h_s


def _rotating_field(t: float) -> np.ndarray:
    """Appendix A's shape, fixed tilt: turns twice per orbit, ~1.5 B0 peak."""
    a = 0.6
    return B0 * np.array([-a / 2 - 1.5 * a * math.cos(2 * N_ORB * t), -1.5 * a * math.sin(2 * N_ORB * t),
                          math.sqrt(1 - a * a)])


def test_sampled_momentum_changes_only_at_orbit_boundaries_and_obeys_the_bookkeeping() -> None:
    """§5: H_s is held within each orbit and ΔH_s = H_b + ∫ M × B dt over the orbit; the per-orbit samples follow
    H_{n+1} = (I − k W_n) H_n + H_b exactly. A small k (inside the converging range) is used on purpose."""
    dt = 20.0
    clock = OrbitClock(T_ORB)
    law = CmgDumpLaw(DumpLawConfig('khb', k_seed=1e5), clock)
    t, m, b, h_s = _ideal_hold_run(law, _rotating_field, H_B_POP, 4, dt)
    orbit_of = np.array([clock.index(x) for x in t])
    for n in range(4):
        held = h_s[orbit_of == n]
        assert np.all(held == held[0])
    stats = orbit_stats(t, m, b, np.ones(t.size, dtype=bool), h_s, clock, H_B_POP, k_seed=1e5)
    assert [s.orbit for s in stats] == [0, 1, 2, 3]
    for s in stats:
        assert np.allclose(s.delta_h_s_nms, H_B_POP * s.duration_s / T_ORB + s.magnetic_momentum_nms, atol=1e-9)
        sel = orbit_of == s.orbit
        gram = field_gramian(b[sel], hold_weights(t)[sel])
        expected = s.h_s_nms + H_B_POP * s.duration_s / T_ORB - k_to_si(1e5) * gram @ s.h_s_nms
        assert np.allclose(s.h_s_nms + s.delta_h_s_nms, expected, atol=1e-9)
        assert 0.0 < min(s.loop_gains) and max(s.loop_gains) < 2.0


def test_min_energy_law_steps_with_its_prediction() -> None:
    """'min_energy': c fixed per orbit from the predicted field; with a perfect prediction each orbit dumps H_b
    (up to the step partition of the orbit), so ΔH_s ≈ 0 from H_s = 0."""
    clock = OrbitClock(T_ORB)
    law = CmgDumpLaw(DumpLawConfig('min_energy', h_b_nms=tuple(H_B_POP)), clock, _rotating_field)
    t, m, b, h_s = _ideal_hold_run(law, _rotating_field, H_B_POP, 3, 10.0)
    stats = orbit_stats(t, m, b, np.ones(t.size, dtype=bool), h_s, clock, H_B_POP)
    for s in stats:
        assert nms_to_ftlbs(np.linalg.norm(s.delta_h_s_nms)) < 2.0  # of 255 ft-lb-sec
        # the report's comparison solves eq. (3) on the orbit's own steps (556 or 557 of 10 s for T = 5562.8 s)
        assert s.m_o_am2 == pytest.approx(s.min_energy_m_o_am2, rel=2 * 10.0 / T_ORB)
    assert np.allclose(np.cross(law.min_energy_vector, b[-1]), m[-1])
    assert np.allclose(law.undumpable_nms, 0.0, atol=1e-9)


def test_law_selector_and_per_axis_limit() -> None:
    clock = OrbitClock(T_ORB)
    b = np.array([2e-5, -1e-5, 3e-5])
    h = np.array([100.0, -50.0, 300.0])
    h_0 = (20.0, 0.0, -10.0)
    plain = CmgDumpLaw(DumpLawConfig('khb'), clock).step(0.0, h, b)
    shifted = CmgDumpLaw(DumpLawConfig('khb_shifted', h_0_nms=h_0), clock).step(0.0, h, b)
    assert np.allclose(plain, khb_moment(h, b))
    assert np.allclose(shifted, khb_moment(h - np.array(h_0), b))
    limited_law = CmgDumpLaw(DumpLawConfig('khb', max_moment_am2=1000.0), clock)
    limited = limited_law.step(0.0, h, b)
    assert np.all(np.abs(limited) <= 1000.0) and np.allclose(limited_law.unsaturated_am2, plain)
    assert np.all(np.sign(limited) == np.sign(plain))


def test_dump_report_takes_the_largest_over_orbits_in_seed_units() -> None:
    dt = 20.0
    clock = OrbitClock(T_ORB)
    law = CmgDumpLaw(DumpLawConfig('khb', k_seed=1e5), clock)
    t, m, b, h_s = _ideal_hold_run(law, _rotating_field, H_B_POP, 3, dt)
    day = ((t % T_ORB) / T_ORB) < 220.0 / 360.0
    stats = orbit_stats(t, m, b, day, h_s, clock, H_B_POP)
    rep = dump_report(stats)
    assert rep['orbits'] == 3 and len(rep['per_orbit']) == 3
    for key in ('M_n_am2', 'M_d_am2', 'M_o_am2', 'M_m_am2', 'min_energy_M_o_am2', 'delta_H_s_ftlbs'):
        assert rep[key] == max(r[key] for r in rep['per_orbit'])
    row = rep['per_orbit'][1]
    assert row['day_s'] == pytest.approx(220.0 / 360.0 * T_ORB, abs=dt) and row['night_s'] > 0.0
    assert row['delta_H_s_ftlbs'] == pytest.approx(float(np.linalg.norm(nms_to_ftlbs(stats[1].delta_h_s_nms))))
    assert row['bias_observed_ftlbs'] == pytest.approx([0.0, 0.0, -255.0 * row['duration_s'] / T_ORB], abs=1e-6)
    assert row['M_m_am2'] >= row['M_o_am2'] >= min(row['M_n_am2'], row['M_d_am2'])
    no_night = dump_report(orbit_stats(t, m, b, np.ones(t.size, dtype=bool), h_s, clock, H_B_POP))
    assert no_night['M_n_am2'] is None and no_night['per_orbit'][0]['night_s'] == 0.0


def test_streaming_accumulator_closes_the_last_orbit_at_the_end_and_takes_the_step_torques() -> None:
    """The streaming form (what the run summary uses): the same orbits as on arrays; ``finish`` closes the last
    orbit only when the data ran to its end (the CMG momentum then gives ΔH_s); a given step torque (the rigid
    body's exact step mean) replaces M × B in ∫ M × B dt."""
    dt = 20.0
    clock = OrbitClock(T_ORB)
    law = CmgDumpLaw(DumpLawConfig('khb', k_seed=1e5), clock)
    t, m, b, h_s = _ideal_hold_run(law, _rotating_field, H_B_POP, 3, dt)
    day = np.ones(t.size, dtype=bool)
    keep = t < 3 * T_ORB  # the data stop just before the third orbit's end: no next sample
    acc = OrbitAccumulator(clock, H_B_POP, k_seed=1e5)
    for row in zip(t[keep], hold_weights(t)[keep], m[keep], b[keep], day[keep], h_s[keep], strict=True):
        acc.add(*row, h_store_nms=row[5])
    arrays = orbit_stats(t, m, b, day, h_s, clock, H_B_POP, k_seed=1e5)
    assert [s.orbit for s in acc.stats] == [0, 1] and [s.orbit for s in arrays] == [0, 1, 2]
    for a, s in zip(acc.stats, arrays, strict=False):
        assert a.m_o_am2 == s.m_o_am2 and np.array_equal(a.delta_h_s_nms, s.delta_h_s_nms)
    h_end = h_s[~keep][0]
    acc.finish(float(t[keep][-1] + dt), h_end)
    assert [s.orbit for s in acc.stats] == [0, 1, 2]
    assert np.allclose(acc.stats[2].delta_h_s_nms, h_end - h_s[keep][-1])
    short = OrbitAccumulator(clock, H_B_POP)
    for x, w, mk, bk, hk in zip(t[:100], hold_weights(t)[:100], m[:100], b[:100], h_s[:100], strict=True):
        short.add(x, w, mk, bk, True, hk, torque_nm=np.array([0.0, 0.0, 1.0]), h_store_nms=hk)
    short.finish(float(t[99] + dt), h_s[100])
    assert short.stats == []  # a third of an orbit is not an orbit
    doubled = OrbitAccumulator(clock, H_B_POP)
    for x, w, mk, bk, hk in zip(t, hold_weights(t), m, b, h_s, strict=True):
        doubled.add(x, w, mk, bk, True, hk, torque_nm=2.0 * np.cross(mk, bk))
    assert np.allclose(doubled.stats[0].magnetic_momentum_nms, 2.0 * arrays[0].magnetic_momentum_nms)


def test_bad_inputs_are_named() -> None:
    clock = OrbitClock(T_ORB)
    with pytest.raises(ControllerError, match='law must be one of'):
        DumpLawConfig('bxh')
    with pytest.raises(ControllerError, match='needs h_b_nms'):
        DumpLawConfig('min_energy')
    with pytest.raises(ControllerError, match='needs predict_b_body_t'):
        CmgDumpLaw(DumpLawConfig('min_energy', h_b_nms=(0.0, 0.0, 1.0)), clock)
    with pytest.raises(ControllerError, match='h_s_nms'):
        khb_moment(np.array([np.nan, 0.0, 0.0]), np.ones(3))
    with pytest.raises(ControllerError, match='field gramian is zero'):
        min_energy_vector(np.zeros((3, 3)), H_B_POP)
    sampler = SampledMomentum(clock)
    sampler.sample(2 * T_ORB, np.zeros(3))
    with pytest.raises(ControllerError, match='time went back'):
        sampler.sample(0.0, np.zeros(3))
    with pytest.raises(ControllerError, match='no complete orbit'):
        dump_report([])
