"""Far-field dipole–dipole force and torque (spec §10; seed 004 slides 12, 13, 19, 20, 30)."""

from __future__ import annotations

import math

import numpy as np
import pytest
from acds_common.dipole_field import (
    MU0_OVER_4PI,
    coaxial_force_n,
    dipole_field_t,
    dipole_force_n,
    dipole_pair_wrench,
    dipole_torque_nm,
    force_matrix,
    side_by_side_force_n,
    torque_scale_nm,
)
from acds_common.units import MU0
from hypothesis import given
from hypothesis import strategies as st

_C = st.integers(-5_000_000, 5_000_000).map(lambda i: i / 1000.0)  # A·m², no subnormals
VEC = st.tuples(_C, _C, _C).map(np.array)
_P = st.integers(-20_000, 20_000).map(lambda i: i / 1000.0)  # m
POS = st.tuples(_P, _P, _P).map(np.array).filter(lambda r: np.linalg.norm(r) > 0.5)


def _f_scale(mu_a: np.ndarray, mu_b: np.ndarray, r: np.ndarray) -> float:
    """Force unit 3μ0|μ_A||μ_B|/(4π r⁴), N (absolute tolerances are fractions of it)."""
    return 3 * MU0_OVER_4PI * np.linalg.norm(mu_a) * np.linalg.norm(mu_b) / np.linalg.norm(r) ** 4


def _t_scale(mu_a: np.ndarray, mu_b: np.ndarray, r: np.ndarray) -> float:
    """Torque unit μ0|μ_A||μ_B|/(4π r³), N·m."""
    return MU0_OVER_4PI * np.linalg.norm(mu_a) * np.linalg.norm(mu_b) / np.linalg.norm(r) ** 3


def _numeric_gradient(mu_a: np.ndarray, mu_b: np.ndarray, r: np.ndarray, h: float = 1e-5) -> np.ndarray:
    """∇_r (μ_B·B_A(r)) by central differences (slide 13: F = −∇U, U = −μ_B·B_A)."""
    g = np.zeros(3)
    for i in range(3):
        e = np.zeros(3)
        e[i] = h
        g[i] = (mu_b @ dipole_field_t(mu_a, r + e) - mu_b @ dipole_field_t(mu_a, r - e)) / (2 * h)
    return g


@given(VEC, VEC, POS)
def test_force_is_the_gradient_of_the_potential(mu_a: np.ndarray, mu_b: np.ndarray, r: np.ndarray) -> None:
    f = dipole_force_n(mu_a, mu_b, r)
    assert np.allclose(f, _numeric_gradient(mu_a, mu_b, r), rtol=0, atol=1e-6 * _f_scale(mu_a, mu_b, r))


@given(VEC, VEC, POS)
def test_newtons_third_law_and_angular_momentum(mu_a: np.ndarray, mu_b: np.ndarray, r: np.ndarray) -> None:
    """F_A = −F_B and τ_A + τ_B + r × F_B = 0 (r from A to B): internal wrenches conserve momentum."""
    f_a, t_a, f_b, t_b = dipole_pair_wrench(mu_a, mu_b, r)
    assert np.array_equal(f_a, -f_b)
    # the same pair seen from B: A's force from B's formula with r reversed
    assert np.allclose(dipole_force_n(mu_b, mu_a, -r), f_a, rtol=0, atol=1e-12 * _f_scale(mu_a, mu_b, r))
    t_scale = _t_scale(mu_a, mu_b, r)
    assert np.allclose(t_a + t_b + np.cross(r, f_b), 0.0, rtol=0, atol=1e-12 * t_scale)
    # the torque on B is μ_B × B_A
    assert np.allclose(t_b, np.cross(mu_b, dipole_field_t(mu_a, r)), rtol=0, atol=1e-12 * t_scale)


@given(VEC, VEC, POS)
def test_force_is_linear_in_mu_b(mu_a: np.ndarray, mu_b: np.ndarray, r: np.ndarray) -> None:
    assert np.allclose(force_matrix(mu_a, r) @ mu_b, dipole_force_n(mu_a, mu_b, r), rtol=0,
                       atol=1e-12 * _f_scale(mu_a, mu_b, r))


def test_scalings_force_inverse_fourth_torque_inverse_cube() -> None:
    rng = np.random.default_rng(4)
    mu_a, mu_b, u = rng.normal(size=(3, 3)) * 1000.0
    u /= np.linalg.norm(u)
    for s in (0.5, 2.0, 7.0):
        for k in (2.0, 10.0):
            f1, f2 = dipole_force_n(mu_a, mu_b, s * u), dipole_force_n(mu_a, mu_b, k * s * u)
            t1, t2 = dipole_torque_nm(mu_a, mu_b, s * u), dipole_torque_nm(mu_a, mu_b, k * s * u)
            assert np.allclose(f2, f1 / k ** 4, rtol=1e-12)
            assert np.allclose(t2, t1 / k ** 3, rtol=1e-12)


def test_coaxial_and_side_by_side_closed_forms() -> None:
    """Coaxial: attraction 3μ0 μ_A μ_B/(2π s⁴) (slide 13's F scaling); side by side: repulsion, half."""
    mu_a, mu_b, s = 4418.0, 3739.0, 2.5
    x = np.array([1.0, 0.0, 0.0])
    z = np.array([0.0, 0.0, 1.0])
    f_coax = dipole_force_n(mu_a * x, mu_b * x, s * x)
    assert coaxial_force_n(mu_a, mu_b, s) == pytest.approx(3 * MU0 * mu_a * mu_b / (2 * math.pi * s ** 4),
                                                           rel=1e-14)
    assert np.allclose(f_coax, -coaxial_force_n(mu_a, mu_b, s) * x, rtol=1e-13)  # B pulled toward A
    f_side = dipole_force_n(mu_a * z, mu_b * z, s * x)
    assert np.allclose(f_side, side_by_side_force_n(mu_a, mu_b, s) * x, rtol=1e-13)  # B pushed away
    assert side_by_side_force_n(mu_a, mu_b, s) == pytest.approx(0.5 * coaxial_force_n(mu_a, mu_b, s), rel=1e-14)
    # both geometries are torque-free
    for a, b in ((x, x), (z, z)):
        _, t_a, _, t_b = dipole_pair_wrench(mu_a * a, mu_b * b, s * x)
        assert np.allclose(t_a, 0.0, atol=1e-15) and np.allclose(t_b, 0.0, atol=1e-15)


def test_slide_scalings_are_the_extremes_over_orientation() -> None:
    """Slide 13 scalings: max |F| over orientations = coaxial value; max |τ| = 2 × μ0 μ_A μ_B/(4π s³)."""
    rng = np.random.default_rng(13)
    a = rng.normal(size=(20000, 3))
    b = rng.normal(size=(20000, 3))
    a /= np.linalg.norm(a, axis=1, keepdims=True)
    b /= np.linalg.norm(b, axis=1, keepdims=True)
    r = np.array([3.0, 0.0, 0.0])
    f = np.linalg.norm(dipole_force_n(a, b, r), axis=1)
    t = np.linalg.norm(dipole_torque_nm(a, b, r), axis=1)
    f_max, t_max = coaxial_force_n(1.0, 1.0, 3.0), 2.0 * torque_scale_nm(1.0, 1.0, 3.0)
    assert f.max() <= f_max * (1 + 1e-12) and f.max() > 0.99 * f_max
    assert t.max() <= t_max * (1 + 1e-12) and t.max() > 0.99 * t_max
    # the torque maximum: A along the baseline, B perpendicular
    t_perp = dipole_torque_nm(np.array([1.0, 0, 0]), np.array([0, 1.0, 0]), r)
    assert np.linalg.norm(t_perp) == pytest.approx(t_max, rel=1e-13)


@pytest.mark.parametrize('alpha_deg,beta_deg', [(0, 0), (30, -20), (90, 0), (45, 135), (-70, 10)])
def test_slide_19_planar_components(alpha_deg: float, beta_deg: float) -> None:
    """Slide 19 (2-satellite spin-up), dipoles in the plane at α (A) and β (B) from the baseline d:

    F_x = ∓3μ0 μ_A μ_B/(4π d⁴)(2 cos α cos β − sin α sin β),
    F_y = ∓3μ0 μ_A μ_B/(4π d⁴)(cos α sin β + sin α cos β),
    T_z = −μ0 μ_A μ_B/(4π d³)(cos α sin β + 2 sin α cos β).

    With B at +d x̂ from A: F_B = −(…)(2cαcβ − sαsβ) x̂ + (…)(cαsβ + sαcβ) ŷ, and the slide's T_z is
    the torque on A. (The extracted text carries a minus on F_y too; with our x̂ the sign of F_y is
    the opposite one — a sign lost or gained in the extraction or in the figure's angle sense.)
    """
    al, be = math.radians(alpha_deg), math.radians(beta_deg)
    mu_a, mu_b, d = 2000.0, 1500.0, 2.0
    a = mu_a * np.array([math.cos(al), math.sin(al), 0.0])
    b = mu_b * np.array([math.cos(be), math.sin(be), 0.0])
    f_a, t_a, f_b, t_b = dipole_pair_wrench(a, b, np.array([d, 0.0, 0.0]))
    kf = 3 * MU0 * mu_a * mu_b / (4 * math.pi * d ** 4)
    kt = MU0 * mu_a * mu_b / (4 * math.pi * d ** 3)
    ca, sa, cb, sb = math.cos(al), math.sin(al), math.cos(be), math.sin(be)
    assert f_b[0] == pytest.approx(-kf * (2 * ca * cb - sa * sb), abs=1e-12 * kf)
    assert f_b[1] == pytest.approx(kf * (ca * sb + sa * cb), abs=1e-12 * kf)
    assert t_a[2] == pytest.approx(-kt * (ca * sb + 2 * sa * cb), abs=1e-12 * kt)
    assert t_b[2] == pytest.approx(-kt * (sa * cb + 2 * ca * sb), abs=1e-12 * kt)
    assert f_b[2] == 0.0 and t_a[0] == t_a[1] == 0.0


@pytest.mark.parametrize('beta_deg', [0.0, 20.0, 45.0, 70.0])
def test_slide_20_pure_shear_torque_split(beta_deg: float) -> None:
    """Slide 20 "Torque Analysis": for a pure shear force (F_x = 0, i.e. tan α tan β = 2) the torques
    on the two dipoles are in the same direction and in the ratio τ_A/τ_B = (5 + 3 cos 2β)/4
    (2 when B lies along the baseline): the torques on each dipole are not usually equal."""
    be = math.radians(beta_deg)
    al = math.pi / 2 if beta_deg == 0.0 else math.atan(2.0 / math.tan(be))
    a = np.array([math.cos(al), math.sin(al), 0.0])
    b = np.array([math.cos(be), math.sin(be), 0.0])
    _, t_a, f_b, t_b = dipole_pair_wrench(a, b, np.array([1.0, 0.0, 0.0]))
    assert abs(f_b[0]) < 1e-12 * abs(f_b[1])
    assert t_a[2] * t_b[2] > 0.0
    assert t_a[2] / t_b[2] == pytest.approx((5 + 3 * math.cos(2 * be)) / 4, rel=1e-12)


def test_slide_30_earth_versus_another_satellite() -> None:
    """Slide 30: the Earth (8e22 A·m² at 6,378,000 m) on a 5e5 A·m² satellite gives an insignificant
    force (~1e-5 N) but a significant torque (~2e1 N·m); another satellite at 2–100 m gives ~1e4 to
    2e-3 N and ~3e4 to 3e-2 N·m. The exact extremes over orientation (coaxial force, perpendicular
    torque) agree with the slide's rounded figures within a factor 2, except the torque at 2 m:
    exactly 6.25e3 N·m at most, where the slide's 3e4 is the bare scaling μ0 μ²/s³ = 3.9e4."""
    mu_sat, mu_earth, r_earth = 5e5, 8e22, 6_378_000.0
    cases = [  # (μ_1, s, slide force N, slide torque N·m)
        (mu_earth, r_earth, 1e-5, 2e1), (mu_sat, 2.0, 1e4, None), (mu_sat, 100.0, 2e-3, 3e-2)]
    for mu_1, s, f_slide, t_slide in cases:
        f, t = coaxial_force_n(mu_1, mu_sat, s), 2.0 * torque_scale_nm(mu_1, mu_sat, s)
        assert 0.5 < f / f_slide < 2.0, (s, f)
        if t_slide is not None:
            assert 0.5 < t / t_slide < 2.0, (s, t)
    assert 2.0 * torque_scale_nm(mu_sat, mu_sat, 2.0) == pytest.approx(6250.0, rel=1e-12)
    assert MU0 * mu_sat ** 2 / 2.0 ** 3 == pytest.approx(3.93e4, rel=1e-2)
    # the slide's point: Earth force is negligible next to a neighbour's, the torque is not
    assert coaxial_force_n(mu_earth, mu_sat, r_earth) < 1e-2 * coaxial_force_n(mu_sat, mu_sat, 100.0)
    assert torque_scale_nm(mu_earth, mu_sat, r_earth) > 1e2 * torque_scale_nm(mu_sat, mu_sat, 100.0)
