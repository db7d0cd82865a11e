"""CubeSat magnetic detumble law M = −(k_ω/|B|)(B̂ × ω) and its momentum-dumping form (spec §9; seed 003).

Seed: 003_oresat_magnetorquers.md, "Mission Requirements" (the law and gain are from its
ref. [2], Avanzini & Giulietti, "Magnetic Detumbling of a Rigid Spacecraft", JGCD 35(4), 2012,
doi 10.2514/1.53074):

    M = −(k_ω/|B|)(B̂ × ω),     k_ω = (4π/T_orb)(sin ξ + 1) J_min

T_orb the orbit period (s), ξ the inclination of the orbit to the geomagnetic equator (rad),
J_min the smallest principal moment of inertia (kg·m²). k_ω is in kg·m²/s (the seed prints
"kg m² s"; N·m·s per rad/s is what makes M come out in A·m²: k_ω·ω/|B| is N·m/T = A·m²).
With the seed's T_orb = 5560.8 s, ξ = 0.90129 rad, J_min = 5,094,047.43 g·mm² = 5.094e-3 kg·m²
this gives k_ω = 2.054e-5 kg·m²/s and, at |B| = 20 µT with 5°/s per axis and B ⟂ ω,
|M| = k_ω|ω|/|B| = 0.1552 A·m² (the rods' required dipole).

Why it detumbles: the torque T = M × B = −k_ω (B̂ × ω) × B̂ = −k_ω ω⊥ (ω⊥ the part of ω
normal to B), so the rate of change of the rotational kinetic energy E = ½ωᵀJω is
dE/dt = ω·T = −k_ω |B̂ × ω|² ≤ 0 at every instant (the gyroscopic term does no work).
Per-axis saturation keeps it: with M_sat = clip(M), ω·(M_sat × B) = −(|B|²/k_ω)·M_sat·M ≤ 0
because clipping keeps each component's sign. Along an inclined orbit the field direction
sweeps, so the component of ω along B is removed too, on average.

Momentum dumping (the seed: "the angular velocity of the body is replaced by the total
angular momentum of the wheels, and the control gain is selected based on mission
requirements"): M = −(k_h/|B|)(B̂ × h), h the wheels' momentum (N·m·s, body axes), k_h in
s⁻¹; the torque is −k_h h⊥. Gain rule used here (:func:`dump_gain_per_s`): the wheels hold
the body inertially fixed, so h is constant in body and inertial axes while the field
direction sweeps along the orbit; averaged over an orbit, ḣ = −k_h ⟨I − B̂B̂ᵀ⟩ h, whose
slowest mode decays as exp(−k_h λ_min t) with λ_min the smallest eigenvalue of
⟨I − B̂B̂ᵀ⟩ for a dipole field seen along a circular orbit inclined ξ to the magnetic
equator (:func:`orbit_average_projection`; λ_min = 0 at ξ = 0, where momentum along the
dipole axis cannot be dumped; 0.605 at the seed's ξ; 0.5 for a polar orbit). The requirement
"dump to ``residual_fraction`` of the initial momentum within ``dump_time_s``" then gives
k_h = ln(1/residual_fraction)/(λ_min·dump_time_s). The dipole this asks for is
k_h|h|/|B| (:func:`dump_peak_moment_am2`); a rod that cannot give it saturates (per axis),
which only slows the dump.

Units: field in T, rates in rad/s, momentum in N·m·s, moments in A·m², body axes.
"""

from __future__ import annotations

import math

import numpy as np
from acds_common import kernels
from acds_common.units import G_MM2_KG_M2
from acds_common.vec3 import Vec3, cross

from acds_controller.magnetic_laws import ControllerError, as_vector3, check_gain

__all__ = [
    'T_ORB_SEED_S',
    'XI_SEED_RAD',
    'J_MIN_SEED_KG_M2',
    'K_OMEGA_SEED',
    'detumble_gain',
    'detumble_moment',
    'dump_moment',
    'orbit_average_projection',
    'dump_gain_per_s',
    'dump_peak_moment_am2',
]

#: Samples per orbit for the orbit average (uniform in argument of latitude; the integrand is smooth
#: and periodic, so the trapezoid rule converges geometrically: 360 points give ~1e-15).
_ORBIT_SAMPLES = 360
#: Why the two laws refuse a zero field.
B_ZERO_MESSAGE = 'b_t is zero: the field direction B̂ is undefined'


def detumble_gain(orbit_period_s: float, xi_rad: float, j_min_kg_m2: float) -> float:
    """k_ω = (4π/T_orb)(sin ξ + 1) J_min, kg·m²/s (seed 003 "Mission Requirements", ref. [2]).

    ``orbit_period_s``: T_orb, s; ``xi_rad``: inclination of the orbit to the geomagnetic
    equator, rad (0…π/2); ``j_min_kg_m2``: smallest principal moment of inertia, kg·m².
    """
    t = check_gain(orbit_period_s, 'orbit_period_s', 0.0, math.inf)
    xi = check_gain(xi_rad, 'xi_rad', 0.0, math.pi / 2)
    j = check_gain(j_min_kg_m2, 'j_min_kg_m2', 0.0, math.inf)
    if t == 0.0 or j == 0.0:
        raise ControllerError('orbit_period_s and j_min_kg_m2 must be > 0')
    return 4.0 * math.pi / t * (math.sin(xi) + 1.0) * j


#: Seed 003 "Mission Requirements": the ISS orbit period, s, its inclination taken as ξ, rad, and OreSat's
#: J_min from its CAD model (the seed's 5,094,047.43 "g/mm²" is g·mm²), kg·m²; k_ω from them, kg·m²/s.
T_ORB_SEED_S = 5560.8
XI_SEED_RAD = 0.90129
J_MIN_SEED_KG_M2 = 5_094_047.43 * G_MM2_KG_M2
K_OMEGA_SEED = detumble_gain(T_ORB_SEED_S, XI_SEED_RAD, J_MIN_SEED_KG_M2)


@kernels.helper
def cross_law_xyz(b_t: Vec3, x: Vec3, gain: float) -> tuple[bool, Vec3]:
    """Kernel of the two laws: (True, −(gain/|B|²)(B × x)) on float triples, (False, 0) when |B|² is not > 0
    (B̂ undefined; a field small enough that |B|² underflows too). The DPA's compiled step calls it."""
    b2 = b_t[0] * b_t[0] + b_t[1] * b_t[1] + b_t[2] * b_t[2]
    if not b2 > 0.0:
        return False, (0.0, 0.0, 0.0)
    c = -(gain / b2)
    v = cross(b_t, x)
    return True, (c * v[0], c * v[1], c * v[2])


def _cross_law(b_t: np.ndarray, x: np.ndarray, gain: float, name: str) -> np.ndarray:
    """−(gain/|B|)(B̂ × x) = −(gain/|B|²)(B × x), A·m² when gain·x/|B| is N·m/T."""
    bx, by, bz = as_vector3(b_t, 'b_t').tolist()
    vx, vy, vz = as_vector3(x, name).tolist()
    defined, m = cross_law_xyz((bx, by, bz), (vx, vy, vz), gain)
    if not defined:
        raise ControllerError(B_ZERO_MESSAGE)
    return np.array(m)


def detumble_moment(b_body_t: np.ndarray, omega_body_rad_s: np.ndarray, k_omega: float) -> np.ndarray:
    """M = −(k_ω/|B|)(B̂ × ω), A·m², unsaturated (seed 003; saturate per axis with ``magnetic_laws.saturate``).

    ``b_body_t``: field, T (body); ``omega_body_rad_s``: body rate, rad/s; ``k_omega``: kg·m²/s
    (:func:`detumble_gain`). M is normal to B; |M| = k_ω|ω|/|B| when B ⟂ ω.
    """
    k = check_gain(k_omega, 'k_omega (kg·m²/s)', 0.0, math.inf)
    return _cross_law(b_body_t, omega_body_rad_s, k, 'omega_body_rad_s')


def dump_moment(b_body_t: np.ndarray, h_wheel_nms: np.ndarray, k_h_per_s: float) -> np.ndarray:
    """Momentum-dumping form M = −(k_h/|B|)(B̂ × h), A·m², unsaturated (seed 003; module docstring).

    ``h_wheel_nms``: wheels' momentum, N·m·s (body); ``k_h_per_s``: s⁻¹ (:func:`dump_gain_per_s`).
    The torque M × B = −k_h h⊥ removes the part of h normal to the field.
    """
    k = check_gain(k_h_per_s, 'k_h_per_s (1/s)', 0.0, math.inf)
    return _cross_law(b_body_t, h_wheel_nms, k, 'h_wheel_nms')


def orbit_average_projection(xi_rad: float) -> np.ndarray:
    """⟨I − B̂B̂ᵀ⟩ over one circular orbit inclined ``xi_rad`` to the geomagnetic equator (3×3, dimensionless).

    Frame: z along the dipole axis, x to the ascending node on the magnetic equator. The
    direction of a centred dipole field, B ∝ 3(ẑ·r̂)r̂ − ẑ, does not depend on the altitude, and
    the argument of latitude of a circular orbit is uniform in time, so the average is over it.
    """
    xi = check_gain(xi_rad, 'xi_rad', 0.0, math.pi / 2)
    u = np.linspace(0.0, 2.0 * math.pi, _ORBIT_SAMPLES, endpoint=False)
    r = np.stack([np.cos(u), np.sin(u) * math.cos(xi), np.sin(u) * math.sin(xi)], axis=1)
    b = 3.0 * r[:, 2:3] * r - np.array([0.0, 0.0, 1.0])
    b /= np.linalg.norm(b, axis=1, keepdims=True)
    return np.eye(3) - np.einsum('ni,nj->ij', b, b) / len(u)


def dump_gain_per_s(dump_time_s: float, xi_rad: float, residual_fraction: float) -> float:
    """k_h = ln(1/residual_fraction)/(λ_min·dump_time_s), s⁻¹: the gain rule of the module docstring.

    ``dump_time_s``: time allowed to dump (the seed: "perform manoeuvres within a specified time
    frame (say, 1 orbit of 90 minutes)"), s; ``xi_rad``: orbit inclination to the geomagnetic
    equator, rad; ``residual_fraction``: momentum left of the slowest mode after that time (0…1).
    """
    t = check_gain(dump_time_s, 'dump_time_s', 0.0, math.inf)
    f = check_gain(residual_fraction, 'residual_fraction', 0.0, 1.0)
    if t == 0.0 or f in (0.0, 1.0):
        raise ControllerError('dump_time_s must be > 0 s and residual_fraction strictly between 0 and 1')
    lam_min = float(np.linalg.eigvalsh(orbit_average_projection(xi_rad))[0])
    if lam_min < 1e-9:
        raise ControllerError(f'xi_rad = {xi_rad!r}: in a magnetic-equatorial orbit the field keeps one '
                              'direction, so momentum along it cannot be dumped (λ_min = 0)')
    return math.log(1.0 / f) / (lam_min * t)


def dump_peak_moment_am2(k_h_per_s: float, h_max_nms: float, b_min_t: float) -> float:
    """Largest dipole the dumping law asks for, k_h·|h|/|B|, A·m² (B ⟂ h at the weakest field)."""
    k = check_gain(k_h_per_s, 'k_h_per_s (1/s)', 0.0, math.inf)
    h = check_gain(h_max_nms, 'h_max_nms', 0.0, math.inf)
    b = check_gain(b_min_t, 'b_min_t', 0.0, math.inf)
    if b == 0.0:
        raise ControllerError('b_min_t must be > 0 T')
    return k * h / b
