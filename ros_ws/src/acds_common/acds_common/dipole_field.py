"""Far field of magnetic dipoles and the exact dipole–dipole force and torque (spec §10).

Seed 004 (MIT SSL / Lockheed Martin EMFF review, 2003), re-derived because the extraction damaged
the equations:

* slide 12 "Magnetic Dipole Approximation": the field of dipole μ_A at displacement r from it,

      B_A(r) = μ0/(4π r³) · (3 (μ_A·r̂) r̂ − μ_A);

* slide 13 "Dipole-Dipole Interaction": potential U = −μ_B·B_A, force F_B = −∇U = ∇(μ_B·B_A),
  torque τ_B = μ_B × B_A. Carrying out the gradient (r from A to B, r̂ = r/r, a = μ_A, b = μ_B):

      F_B = 3μ0/(4π r⁴) · [ (a·r̂) b + (b·r̂) a + (a·b) r̂ − 5 (a·r̂)(b·r̂) r̂ ],

  odd in r̂ and symmetric in (a, b), so F_A = −F_B (Newton's third law). The torque on A is
  τ_A = μ_A × B_B(−r) = μ_A × B_B(r) (the field is even in r). Total angular momentum is conserved:
  τ_A + τ_B + r × F_B = 0 (about any point, with r from A to B);

* the slides' scaling laws (slide 13): F ~ 3μ0 μ_A μ_B/(2π s⁴), T ~ μ0 μ_A μ_B/(4π s³) (spec §10).
  The force law is exact for the coaxial geometry (both dipoles along the baseline), which is also
  the largest force magnitude any orientation gives; side by side (both perpendicular to the
  baseline, parallel) the force is half of it, 3μ0 μ_A μ_B/(4π s⁴), repulsive. The torque law is
  the unit of slide 19's planar torque (T_z = −μ0 μ_A μ_B/(4π d³)(cos α sin β + 2 sin α cos β));
  the largest torque on one dipole is twice it, μ0 μ_A μ_B/(2π s³) (that dipole perpendicular to
  the baseline, the other along it).

SI throughout: A·m² in, m, T, N, N·m out. Every function broadcasts over leading axes (…, 3), so a
formation evaluates all its pairs in one call. Inputs are not validated here (hot path); the
callers' cores validate their own inputs with their own exception types.
"""

from __future__ import annotations

import math

import numpy as np

from acds_common.units import MU0

#: μ0/(4π), T·m/A.
MU0_OVER_4PI = MU0 / (4.0 * math.pi)


def _split(r_m: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(r̂, |r|) with |r| keeping a trailing axis for broadcasting."""
    r = np.asarray(r_m, dtype=float)
    rn = np.sqrt(_dot(r, r))
    return r / rn, rn


def _dot(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    return np.einsum("...i,...i->...", a, b)[..., None]


#: ``cross3``'s components of a and of b: (i+1, i+2 mod 3) then (i+2, i+1 mod 3) for i = 0, 1, 2.
_CROSS_A = np.array([1, 2, 0, 2, 0, 1])
_CROSS_B = np.array([2, 0, 1, 1, 2, 0])


def cross3(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """a × b over the last axis of (…, 3) arrays (broadcasting): component i is
    a[i+1] b[i+2] − a[i+2] b[i+1], the six products in one multiplication; numpy.cross without its
    per-call axis handling, which dominates on the few-vector arrays of a formation step."""
    p = np.asarray(a, dtype=float).take(_CROSS_A, -1) * np.asarray(b, dtype=float).take(_CROSS_B, -1)
    return p[..., :3] - p[..., 3:]


def unit_perpendicular(v: np.ndarray) -> np.ndarray:
    """A deterministic unit vector perpendicular to the non-zero 3-vector ``v`` (v × the axis least
    aligned with it), for building a basis across a baseline or a coil axis."""
    v = np.asarray(v, dtype=float)
    seed = np.zeros(3)
    seed[int(np.argmin(np.abs(v)))] = 1.0
    u = cross3(v, seed)
    return u / np.linalg.norm(u)


def _field(mu: np.ndarray, mu_r: np.ndarray, rhat: np.ndarray, k3: np.ndarray) -> np.ndarray:
    """Slide 12's field k3 (3 (μ·r̂) r̂ − μ) from its pieces: ``mu_r`` = μ·r̂, ``k3`` = μ0/(4π r³)."""
    return k3 * (3.0 * mu_r * rhat - mu)


def _force(a: np.ndarray, b: np.ndarray, ar: np.ndarray, br: np.ndarray, rhat: np.ndarray,
           rn: np.ndarray) -> np.ndarray:
    """Slide 13's force on B from its pieces (``ar`` = a·r̂, ``br`` = b·r̂; see the module docstring)."""
    return 3.0 * MU0_OVER_4PI / rn ** 4 * (ar * b + br * a + _dot(a, b) * rhat - 5.0 * ar * br * rhat)


def dipole_field_t(mu_am2: np.ndarray, r_m: np.ndarray) -> np.ndarray:
    """Field B (T) of dipole ``mu_am2`` (A·m²) at displacement ``r_m`` (m) from it (slide 12)."""
    mu = np.asarray(mu_am2, dtype=float)
    rhat, rn = _split(r_m)
    return _field(mu, _dot(mu, rhat), rhat, MU0_OVER_4PI / rn ** 3)


def force_matrix(mu_a_am2: np.ndarray, r_ab_m: np.ndarray) -> np.ndarray:
    """3×3 matrix K (N per A·m²) with F_B = K μ_B: the force on B is linear in μ_B for a fixed μ_A.

    K = 3μ0/(4π r⁴) · [ (a·r̂) I + a r̂ᵀ + r̂ aᵀ − 5 (a·r̂) r̂ r̂ᵀ ] (see the module docstring). It is
    what the formation controller inverts to "pick one vehicle's dipole, solve the rest" (slide 23).
    Broadcasts to (…, 3, 3).
    """
    a = np.asarray(mu_a_am2, dtype=float)
    rhat, rn = _split(r_ab_m)
    ar = _dot(a, rhat)[..., None]
    eye = np.eye(3)
    outer = rhat[..., :, None] * rhat[..., None, :]
    k = (3.0 * MU0_OVER_4PI / rn ** 4)[..., None]
    return k * (ar * eye + a[..., :, None] * rhat[..., None, :] + rhat[..., :, None] * a[..., None, :]
                - 5.0 * ar * outer)


def dipole_force_n(mu_a_am2: np.ndarray, mu_b_am2: np.ndarray, r_ab_m: np.ndarray) -> np.ndarray:
    """Exact far-field force (N) on dipole B from dipole A, ``r_ab_m`` from A to B: F_B = ∇(μ_B·B_A)."""
    a = np.asarray(mu_a_am2, dtype=float)
    b = np.asarray(mu_b_am2, dtype=float)
    rhat, rn = _split(r_ab_m)
    return _force(a, b, _dot(a, rhat), _dot(b, rhat), rhat, rn)


def dipole_torque_nm(mu_a_am2: np.ndarray, mu_b_am2: np.ndarray, r_ab_m: np.ndarray) -> np.ndarray:
    """Torque (N·m) on dipole B from dipole A's field, about B's centre: τ_B = μ_B × B_A(r_AB)."""
    return cross3(mu_b_am2, dipole_field_t(mu_a_am2, r_ab_m))


def dipole_pair_wrench(mu_a_am2: np.ndarray, mu_b_am2: np.ndarray,
                       r_ab_m: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """(F_A, τ_A, F_B, τ_B): forces (N) and torques about each dipole's own centre (N·m) of a pair.

    Each torque is computed from the other dipole's field (τ_A = μ_A × B_B(r), τ_B = μ_B × B_A(r));
    F_A = −F_B is exact (the same floating-point numbers negated). The same numbers as
    ``dipole_force_n`` and ``dipole_torque_nm``, with r̂, |r|, a·r̂, b·r̂ and μ0/(4π r³) computed once
    for the three (the formation's hot path).
    """
    a = np.asarray(mu_a_am2, dtype=float)
    b = np.asarray(mu_b_am2, dtype=float)
    rhat, rn = _split(r_ab_m)
    ar, br = _dot(a, rhat), _dot(b, rhat)
    f_b = _force(a, b, ar, br, rhat, rn)
    k3 = MU0_OVER_4PI / rn ** 3
    return -f_b, cross3(a, _field(b, br, rhat, k3)), f_b, cross3(b, _field(a, ar, rhat, k3))


def coaxial_force_n(mu_a_am2: float, mu_b_am2: float, separation_m: float) -> float:
    """Attraction (N) of two coaxial dipoles pointing the same way along their baseline (slide 13).

    F = 3μ0 μ_A μ_B/(2π s⁴) — the slides' force scaling law, exact in this geometry.
    """
    return 6.0 * MU0_OVER_4PI * mu_a_am2 * mu_b_am2 / separation_m ** 4


def side_by_side_force_n(mu_a_am2: float, mu_b_am2: float, separation_m: float) -> float:
    """Repulsion (N) of two parallel dipoles both perpendicular to their baseline.

    F = 3μ0 μ_A μ_B/(4π s⁴), half the coaxial force (slide 9, "side by side" arrangement).
    """
    return 3.0 * MU0_OVER_4PI * mu_a_am2 * mu_b_am2 / separation_m ** 4


def torque_scale_nm(mu_a_am2: float, mu_b_am2: float, separation_m: float) -> float:
    """The slides' torque scaling μ0 μ_A μ_B/(4π s³), N·m (slide 13, spec §10); the largest torque
    on one dipole is twice this (one dipole along the baseline, the other perpendicular)."""
    return MU0_OVER_4PI * mu_a_am2 * mu_b_am2 / separation_m ** 3
