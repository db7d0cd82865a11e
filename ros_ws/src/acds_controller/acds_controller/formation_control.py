"""Formation control for electromagnetic formation flight (spec §10; seed 004, MIT SSL / LM 2003).

Dipole solutions (far field, ``acds_common.dipole_field``):

* Slide 23 "Solving the EOM": for N vehicles there are 3N − 3 force constraints and 3N dipole
  components, "this allows us to arbitrarily specify one vehicle's dipole ... pick the magnetic dipole
  strengths for one vehicle ... and solve for the remaining". ``solve_remaining_dipoles`` does that
  for any N by Newton's method on the bilinear force equations (exact Jacobian; for N = 2 the force
  on B is linear in μ_B, F_B = K(μ_A, r) μ_B, and one step solves it). Of the multiple solutions
  (slide 24) it returns the one reached from the initial guess (the previous step's, for continuity).
* The free choice for a pair (slide 27 "Choosing the free dipole ... such that a cost function is
  optimized – dipole strength distribution"): ``min_norm_dipoles`` picks μ_A to minimise
  |μ_A|² + |μ_B|² for the commanded force, i.e. the total coil current squared (the H-bridge and
  battery losses of slides 73, 81 go as I²). By scaling, the optimum has |μ_A| = |μ_B|; the optimal
  directions lie in the plane of the baseline r̂ and the force (checked against a search over the
  sphere in the tests), where the problem is one angle, solved by a grid plus golden-section search.
  For a pure attraction it is the coaxial pair; for the steady spin below, it is the slides' geometry.
* Earth as a momentum dump (slides 31–33, ``DumpLaw``): "pick a satellite to dump momentum, turn up
  its dipole strength to maximum, align the dipole to optimize momentum exchange, solve the remaining
  dipoles for the required instantaneous forces; once the required momentum has been dumped, pick
  another" — the dumping vehicle is the one with the most stored wheel momentum (slide 33), its
  dipole is μ = −μ_max (B × h)/|B × h| (the Earth torque μ × B = −μ_max B² h⊥/|B × h| opposes h),
  and the partner's dipole is solved by ``solve_remaining_dipoles``. The maximum is capped at the
  dipole that removes h⊥ in one control period (a sampled law's deadbeat bound: held longer it
  overshoots and chatters; the slides' continuous-time simulation has no such limit), but not below
  the min-norm pair's |μ| for the step's force (so dumping never asks more dipole of the partner).

Two-vehicle steady spin (slides 19, 48, 49), derived: masses m_A, m_B at separation d spinning at ω
about their centre of mass; each vehicle's centripetal force is μ_red ω² d (μ_red = m_A m_B /(m_A +
m_B); m r ω² with r = d/2 for equal masses). Slide 48's geometry ("N S N S" along the baseline, "EM
pointing toward the other spacecraft carries the bulk of the centripetal load", slide 37) is coaxial,
F = 3μ0 μ_A μ_B/(2π d⁴), so

    μ_A μ_B = 2π μ_red ω² d⁵ / (3 μ0)      (equal masses m: π m ω² d⁵/(3 μ0) = 32π m r⁵ ω²/(3 μ0)),

which is slide 49's μ_avg² = 16 m x0⁵ ω²/c with c = 3μ0/(2π), x0 = d/2. During spin-up (ω̇ ≠ 0) with
B's dipole on the baseline (β = 0, slide 19's parametrisation), the tangential force μ_red d ω̇ needs A's
dipole at α from the baseline with tan α = 2ω̇/ω² and μ_A μ_B = 2π μ_red d⁵ √(ω⁴ + 4ω̇²)/(3 μ0), the
extracted slide's "32π m r⁵ √(ω⁴ + 4ω̇²)/(3μ0)" and "α = cos⁻¹(ω²/√(ω⁴ + 4ω̇²))"
(``spin_dipole_product_am4``).

Control laws (``FormationController``, two vehicles A, B; ρ = r_B − r_A in the formation frame):

* relative acceleration ρ̈ = F_B/m_B − F_A/m_A = F_B/μ_red (internal forces, F_A = −F_B), plus in the
  Hill frame the free CW terms (3n²x + 2nẏ, −2nẋ, −n²z) (slide 63), fed forward;
* ``HoldLaw``: PD on the relative position, ρ̈_des = −ω_n²(ρ − ρ*) − 2ζω_n ρ̇;
* ``SpinUpLaw`` (about the frame z axis): radial PD on the separation, rate loop on θ̇ with a ramped
  rate reference, centripetal and Coriolis terms fed forward:
  F_B = μ_red[(d̈_des − d θ̇²) r̂ + (d θ̈_des + 2 ḋ θ̇) θ̂];
* the force is limited to ``max_force_n`` (direction kept); since the dipoles are held over the
  control period while the baseline turns, the dipoles are solved for the baseline and the force
  rotated half a period ahead at the baseline's present angular rate;
* dipoles beyond a coil's limit: all dipoles scaled together by s (the force keeps its direction and
  scales by s²). The formation force has priority over dumping: a step where the partner's solved
  dipole would exceed its coils (or the dumping dipole cannot make the force at all, e.g. lying
  across the baseline) is flown with the min-norm pair instead;
* ``AttitudeLaw``: each vehicle holds its attitude (captured at the first step) with its wheels,
  which take the predicted EM (and Earth) torque: ḣ = τ_pred − I α_des − ω × (I ω + h),
  α_des = −ω_n² θ_err − 2ζω_n ω (slide 18: "reaction wheels are used to counteract EM torques").
  Planar: the yaw channel only.

"A formation controller per vehicle": every vehicle's controller runs this same deterministic
computation on the shared measurements (the testbed's inter-vehicle RF link, slide 70) and applies
its own ``VehicleCommand``. SI throughout: m, m/s, kg, A·m², N, N·m, N·m·s, T, rad, s.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
from acds_common.dipole_field import (
    MU0_OVER_4PI,
    cross3,
    dipole_force_n,
    dipole_pair_wrench,
    force_matrix,
    unit_perpendicular,
)
from acds_common.units import MU0

from acds_controller.magnetic_laws import ControllerError, as_matrix3, as_vector3, check_gain

#: Frames the controller works in (as dynamics.formation).
FRAMES = ("planar", "free_space", "hill")
#: Grid points over the free dipole angle [0, π) before the golden-section refinement.
_ANGLE_GRID = 720
_GOLDEN = (math.sqrt(5.0) - 1.0) / 2.0


# ------------------------------------------------------------------------------ dipole solutions


def _plane_g(alpha: np.ndarray, f1: float, f2: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """For A's unit dipole at ``alpha`` from the baseline in the (r̂, ê2) plane: (b1, b2, |b|) with
    b = M(α)⁻¹ f, M(α) = [[−2c, s], [s, c]] the in-plane force matrix over 3μ0/(4π r⁴)."""
    c, s = np.cos(alpha), np.sin(alpha)
    den = 1.0 + c * c
    b1 = (-c * f1 + s * f2) / den
    b2 = (s * f1 + 2.0 * c * f2) / den
    return b1, b2, np.hypot(b1, b2)


def min_norm_dipoles(r_ab_m: np.ndarray, force_b_n: np.ndarray, plane_normal: np.ndarray | None = None,
                     previous_mu_a_am2: np.ndarray | None = None) -> tuple[np.ndarray, np.ndarray]:
    """(μ_A, μ_B), A·m², giving far-field force ``force_b_n`` (N) on B (``r_ab_m`` from A to B) with the
    least |μ_A|² + |μ_B|² (module docstring). ``plane_normal``: the dipoles' plane (planar testbed: the
    frame z; None: the plane of r̂ and F). ``previous_mu_a_am2`` breaks ties (equal minima, the ± sign)
    toward continuity."""
    r = as_vector3(r_ab_m, "r_ab_m")
    f = as_vector3(force_b_n, "force_b_n")
    dist = float(np.linalg.norm(r))
    if dist <= 0.0:
        raise ControllerError("r_ab_m must be non-zero (the two dipoles coincide)")
    e1 = r / dist
    prev = None if previous_mu_a_am2 is None else as_vector3(previous_mu_a_am2, "previous_mu_a_am2")
    if plane_normal is not None:
        n = as_vector3(plane_normal, "plane_normal")
        n = n - (n @ e1) * e1
        if np.linalg.norm(n) < 1e-12:
            raise ControllerError("plane_normal is parallel to the baseline")
        n /= np.linalg.norm(n)
        if abs(f @ n) > 1e-9 * max(float(np.linalg.norm(f)), 1e-300):
            raise ControllerError(f"force {f.tolist()} N leaves the dipoles' plane (normal {n.tolist()})")
    else:
        n = cross3(e1, f)
        if np.linalg.norm(n) <= 1e-12 * float(np.linalg.norm(f)):
            perp = None if prev is None else prev - (prev @ e1) * e1
            e2 = perp / np.linalg.norm(perp) if perp is not None and np.linalg.norm(perp) > 0 else unit_perpendicular(e1)
            n = cross3(e1, e2)
        n = n / np.linalg.norm(n)
    e2 = cross3(n, e1)
    k = 3.0 * MU0_OVER_4PI / dist ** 4
    f1, f2 = float(f @ e1) / k, float(f @ e2) / k
    if f1 == 0.0 and f2 == 0.0:
        return np.zeros(3), np.zeros(3)
    grid = np.pi * np.arange(_ANGLE_GRID) / _ANGLE_GRID
    g = _plane_g(grid, f1, f2)[2]
    step = np.pi / _ANGLE_GRID
    candidates = []
    for i in np.flatnonzero((g <= np.roll(g, 1)) & (g <= np.roll(g, -1))):
        lo, hi = grid[i] - step, grid[i] + step
        x1, x2 = hi - _GOLDEN * (hi - lo), lo + _GOLDEN * (hi - lo)
        g1, g2 = _plane_g(np.array([x1, x2]), f1, f2)[2]
        for _ in range(60):
            if g1 <= g2:
                hi, x2, g2 = x2, x1, g1
                x1 = hi - _GOLDEN * (hi - lo)
                g1 = float(_plane_g(np.array([x1]), f1, f2)[2][0])
            else:
                lo, x1, g1 = x1, x2, g2
                x2 = lo + _GOLDEN * (hi - lo)
                g2 = float(_plane_g(np.array([x2]), f1, f2)[2][0])
        a = 0.5 * (lo + hi)
        candidates.append((float(_plane_g(np.array([a]), f1, f2)[2][0]), a))
    best = min(c[0] for c in candidates)
    ties = [a for gv, a in candidates if gv <= best * (1.0 + 1e-9)]

    def closeness(a: float) -> float:
        u = math.cos(a) * e1 + math.sin(a) * e2
        return -abs(float(u @ prev)) if prev is not None else a

    alpha = min(ties, key=closeness)
    b1, b2, gv = (float(x[0]) for x in _plane_g(np.array([alpha]), f1, f2))
    scale = math.sqrt(gv)
    mu_a = scale * (math.cos(alpha) * e1 + math.sin(alpha) * e2)
    mu_b = (b1 * e1 + b2 * e2) / scale
    if prev is not None and float(mu_a @ prev) < 0.0:
        mu_a, mu_b = -mu_a, -mu_b
    return mu_a, mu_b


def em_forces_n(positions_m: np.ndarray, dipoles_am2: np.ndarray) -> np.ndarray:
    """Far-field force (N) on every vehicle from all the others, (N, 3)."""
    pos = np.asarray(positions_m, dtype=float)
    dip = np.asarray(dipoles_am2, dtype=float)
    out = np.zeros_like(pos)
    for i in range(len(pos)):
        for j in range(i + 1, len(pos)):
            f_j = dipole_force_n(dip[i], dip[j], pos[j] - pos[i])
            out[j] += f_j
            out[i] -= f_j
    return out


def solve_remaining_dipoles(positions_m: np.ndarray, free_index: int, free_dipole_am2: np.ndarray,
                            forces_n: np.ndarray, guess_am2: np.ndarray, planar: bool = False,
                            tol: float = 1e-10, max_iterations: int = 50) -> np.ndarray:
    """Slide 23: with vehicle ``free_index``'s dipole given, the dipoles (N, 3) of the others that make the
    far-field force on each of them equal ``forces_n`` (N, 3; the free vehicle's force follows, Σ F = 0).

    Newton's method from ``guess_am2`` (N, 3) with the exact Jacobian: ∂F_i/∂μ_i = Σ_j K(μ_j, r_ji),
    ∂F_i/∂μ_j = K(μ_i, r_ji) (F is a symmetric bilinear form of the two dipoles). ``planar``: dipoles
    and forces in the frame's x–y plane. Raises ControllerError if the Jacobian is singular or the
    iteration does not reach ``tol`` (relative to the largest commanded force)."""
    pos = np.asarray(positions_m, dtype=float)
    n = len(pos)
    if pos.shape != (n, 3) or n < 2:
        raise ControllerError(f"positions_m must be (N >= 2, 3), got shape {pos.shape}")
    if not 0 <= free_index < n:
        raise ControllerError(f"free_index must be in [0, {n}), got {free_index}")
    forces = np.asarray(forces_n, dtype=float)
    dip = np.array(guess_am2, dtype=float)
    if forces.shape != (n, 3) or dip.shape != (n, 3):
        raise ControllerError(f"forces_n and guess_am2 must be ({n}, 3)")
    dip[free_index] = as_vector3(free_dipole_am2, "free_dipole_am2")
    dims = 2 if planar else 3
    others = [i for i in range(n) if i != free_index]
    scale = max(float(np.abs(forces).max()), 1e-300)
    for _ in range(max_iterations):
        resid = (em_forces_n(pos, dip) - forces)[others][:, :dims].ravel()
        if np.abs(resid).max() <= tol * scale:
            return dip
        jac = np.zeros((len(others) * dims, len(others) * dims))
        for a, i in enumerate(others):
            for j in range(n):
                if j == i:
                    continue
                k_ij = force_matrix(dip[j], pos[i] - pos[j])[:dims, :dims]  # ∂F_i/∂μ_i part
                jac[a * dims:(a + 1) * dims, a * dims:(a + 1) * dims] += k_ij
                if j != free_index:
                    b = others.index(j)
                    jac[a * dims:(a + 1) * dims, b * dims:(b + 1) * dims] = force_matrix(
                        dip[i], pos[i] - pos[j])[:dims, :dims]
        try:
            delta = np.linalg.solve(jac, resid)
        except np.linalg.LinAlgError as exc:
            raise ControllerError("dipole solution is singular for this free dipole and geometry "
                                  "(e.g. a free dipole perpendicular to the baseline in 3-D)") from exc
        for a, i in enumerate(others):
            dip[i, :dims] -= delta[a * dims:(a + 1) * dims]
    raise ControllerError(f"dipole solution did not converge in {max_iterations} Newton iterations")


def steady_spin_dipole_product_am4(mass_a_kg: float, mass_b_kg: float, separation_m: float, rate_rad_s: float) -> float:
    """Slides 48–49 closed form μ_A μ_B = 2π μ_red ω² d⁵/(3μ0), (A·m²)², for a coaxial pair spinning at
    ω at separation d (module docstring)."""
    return spin_dipole_product_am4(mass_a_kg, mass_b_kg, separation_m, rate_rad_s, 0.0)[0]


def spin_dipole_product_am4(mass_a_kg: float, mass_b_kg: float, separation_m: float, rate_rad_s: float,
                            rate_dot_rad_s2: float) -> tuple[float, float]:
    """Slide 19, B's dipole on the baseline (β = 0): (μ_A μ_B in (A·m²)², α in rad) for rate ω and
    angular acceleration ω̇: μ_A μ_B = 2π μ_red d⁵ √(ω⁴ + 4ω̇²)/(3μ0), tan α = 2ω̇/ω² (α = 0 steady)."""
    for name, v in (("mass_a_kg", mass_a_kg), ("mass_b_kg", mass_b_kg), ("separation_m", separation_m)):
        check_gain(v, name, 1e-300, math.inf)
    mu_red = mass_a_kg * mass_b_kg / (mass_a_kg + mass_b_kg)
    w2 = rate_rad_s * rate_rad_s
    product = 2.0 * math.pi * mu_red * separation_m ** 5 * math.hypot(w2, 2.0 * rate_dot_rad_s2) / (3.0 * MU0)
    return product, math.atan2(2.0 * rate_dot_rad_s2, w2)


# ------------------------------------------------------------------------------------ controller


def _half_period_prediction(rho: np.ndarray, rho_dot: np.ndarray, tau_s: float) -> tuple[np.ndarray, np.ndarray]:
    """(R, ρ(t + τ)): the baseline's rotation over ``tau_s`` at its present angular rate Ω = ρ × ρ̇/|ρ|²
    (Rodrigues) and the baseline then, with its length changed at the present ḋ. Used to aim the held
    dipoles at the middle of the control period: exact for a steady spin, where a straight-line
    prediction would see a spurious radial velocity."""
    d2 = float(rho @ rho)
    d = math.sqrt(d2)
    omega = cross3(rho, rho_dot) / d2
    angle = float(np.linalg.norm(omega)) * tau_s
    rotation = np.eye(3)
    if angle > 0.0:
        axis = omega / np.linalg.norm(omega)
        kx = np.array([[0.0, -axis[2], axis[1]], [axis[2], 0.0, -axis[0]], [-axis[1], axis[0], 0.0]])
        rotation = rotation + math.sin(angle) * kx + (1.0 - math.cos(angle)) * kx @ kx
    d_dot = float(rho @ rho_dot) / d
    return rotation, rotation @ rho * ((d + d_dot * tau_s) / d)




@dataclass(frozen=True)
class ControlledVehicle:
    """What the controller knows of a vehicle: ``name``, ``mass_kg``, ``inertia_kg_m2`` (3×3 body),
    ``coil_axes_body`` (3, n) orthonormal columns, ``coil_max_dipole_am2`` (n,) per-coil limits."""

    name: str
    mass_kg: float
    inertia_kg_m2: np.ndarray
    coil_axes_body: np.ndarray
    coil_max_dipole_am2: np.ndarray

    def __post_init__(self) -> None:
        check_gain(self.mass_kg, f"{self.name}.mass_kg", 1e-300, math.inf)
        object.__setattr__(self, "inertia_kg_m2", as_matrix3(self.inertia_kg_m2, f"{self.name}.inertia_kg_m2"))
        axes = np.asarray(self.coil_axes_body, dtype=float)
        limits = np.asarray(self.coil_max_dipole_am2, dtype=float)
        if (axes.ndim != 2 or axes.shape[0] != 3 or limits.shape != (axes.shape[1],)
                or not np.allclose(axes.T @ axes, np.eye(axes.shape[1]), atol=1e-9) or not np.all(limits > 0)):
            raise ControllerError(f"{self.name}: coil_axes_body must be orthonormal columns (3, n) and "
                                  "coil_max_dipole_am2 n positive limits")
        object.__setattr__(self, "coil_axes_body", axes)
        object.__setattr__(self, "coil_max_dipole_am2", limits)


@dataclass(frozen=True)
class Measurement:
    """One vehicle's measured state: ``position_m``, ``velocity_m_s`` (formation frame), ``body_to_inertial``
    (3×3 DCM), ``omega_body_rad_s``, ``wheel_h_body_nms``, ``b_inertial_t`` (Earth field, T; None if none)."""

    position_m: np.ndarray
    velocity_m_s: np.ndarray
    body_to_inertial: np.ndarray
    omega_body_rad_s: np.ndarray
    wheel_h_body_nms: np.ndarray
    b_inertial_t: np.ndarray | None = None


@dataclass(frozen=True)
class HoldLaw:
    """Hold ρ = r_B − r_A at ``relative_position_m`` (formation frame) with a PD of natural frequency
    ``natural_frequency_rad_s`` and damping ratio ``damping_ratio``."""

    relative_position_m: Sequence[float]
    natural_frequency_rad_s: float = 0.1
    damping_ratio: float = 0.9


@dataclass(frozen=True)
class SpinUpLaw:
    """Spin the pair about the frame z axis to ``rate_rad_s`` (signed) at separation ``separation_m``: rate
    reference ramped at ``ramp_rad_s2`` from ``start_s``; radial PD (``radial_natural_frequency_rad_s``,
    ``radial_damping_ratio``); rate loop gain ``rate_gain_per_s``."""

    separation_m: float
    rate_rad_s: float
    ramp_rad_s2: float
    start_s: float = 0.0
    radial_natural_frequency_rad_s: float = 0.2
    radial_damping_ratio: float = 0.9
    rate_gain_per_s: float = 0.2

    def rate_reference(self, t_s: float) -> tuple[float, float]:
        """(ω_ref rad/s, ω̇_ref rad/s²) at ``t_s``."""
        if t_s <= self.start_s:
            return 0.0, 0.0
        w = math.copysign(min(abs(self.rate_rad_s), self.ramp_rad_s2 * (t_s - self.start_s)), self.rate_rad_s)
        return w, (0.0 if abs(w) >= abs(self.rate_rad_s) else math.copysign(self.ramp_rad_s2, self.rate_rad_s))


@dataclass(frozen=True)
class AttitudeLaw:
    """Attitude hold by the wheels: PD natural frequency and damping ratio (per body axis)."""

    natural_frequency_rad_s: float = 0.5
    damping_ratio: float = 0.8


@dataclass(frozen=True)
class DumpLaw:
    """Earth as a momentum dump (slides 31–33): start dumping the vehicle with the most wheel momentum when
    it exceeds ``start_nms``; stop (and pick again) when it is below ``done_nms``."""

    start_nms: float
    done_nms: float


@dataclass(frozen=True)
class VehicleCommand:
    """One vehicle's command for the step: ``dipole_body_am2`` (to its coil drivers), ``coil_moments_am2``
    (per coil, along its axis), ``wheel_torque_body_nm`` (wanted ḣ, to its wheels); and for telemetry
    ``force_command_n`` (frame), ``dipole_frame_am2``, ``dumping``."""

    dipole_body_am2: np.ndarray
    coil_moments_am2: np.ndarray
    wheel_torque_body_nm: np.ndarray
    force_command_n: np.ndarray
    dipole_frame_am2: np.ndarray
    dumping: bool


class FormationController:
    """Two-vehicle EMFF formation controller (module docstring).

    ``vehicles`` (A, B); ``frame`` (FRAMES); ``law`` (HoldLaw or SpinUpLaw); ``attitude`` (AttitudeLaw);
    ``control_period_s``; ``max_force_n`` on the commanded relative force; ``mean_motion_rad_s`` (Hill
    frame); ``dump`` (DumpLaw, Hill frame with an Earth field only). ``step(t_s, measurements,
    frame_to_inertial)`` returns both vehicles' commands.
    """

    def __init__(self, vehicles: Sequence[ControlledVehicle], frame: str, law: HoldLaw | SpinUpLaw,
                 attitude: AttitudeLaw, control_period_s: float, max_force_n: float,
                 mean_motion_rad_s: float = 0.0, dump: DumpLaw | None = None) -> None:
        if len(vehicles) != 2:
            raise ControllerError(f"FormationController controls a pair of vehicles, got {len(vehicles)}")
        if frame not in FRAMES:
            raise ControllerError(f"frame must be one of {FRAMES}, got {frame!r}")
        if dump is not None and frame != "hill":
            raise ControllerError("the Earth momentum dump needs frame 'hill' (an orbit in the Earth's field)")
        if isinstance(law, SpinUpLaw) and frame == "hill":
            raise ControllerError("SpinUpLaw is for frames 'planar' and 'free_space'")
        self.vehicles = tuple(vehicles)
        self.frame, self.law, self.attitude, self.dump = frame, law, attitude, dump
        self.dt = check_gain(control_period_s, "control_period_s", 1e-9, math.inf)
        self.max_force_n = check_gain(max_force_n, "max_force_n", 0.0, math.inf)
        self.n = check_gain(mean_motion_rad_s, "mean_motion_rad_s", 0.0, 1.0)
        m_a, m_b = (v.mass_kg for v in vehicles)
        self.mu_red_kg = m_a * m_b / (m_a + m_b)
        self._targets: list[np.ndarray] | None = None
        self._prev_mu_a: np.ndarray | None = None
        self._dumper: int | None = None
        self._dumping_now = False

    @property
    def dumping_vehicle(self) -> int | None:
        """Index of the vehicle selected to dump momentum (None when none is); it dumps on a step only
        when the partner's solved dipole fits its coils (``VehicleCommand.dumping``)."""
        return self._dumper

    def _force_command(self, t_s: float, rho: np.ndarray, rho_dot: np.ndarray) -> np.ndarray:
        """Commanded force on B (N, frame) for relative position/velocity ``rho``/``rho_dot``."""
        law = self.law
        if isinstance(law, HoldLaw):
            wn, zeta = law.natural_frequency_rad_s, law.damping_ratio
            acc = -wn * wn * (rho - np.asarray(law.relative_position_m, dtype=float)) - 2.0 * zeta * wn * rho_dot
            if self.frame == "hill":
                n = self.n
                acc = acc - np.array([3.0 * n * n * rho[0] + 2.0 * n * rho_dot[1], -2.0 * n * rho_dot[0],
                                      -n * n * rho[2]])
        else:
            d = math.hypot(rho[0], rho[1])
            r_hat = np.array([rho[0] / d, rho[1] / d, 0.0])
            t_hat = np.array([-r_hat[1], r_hat[0], 0.0])
            d_dot = float(rho_dot @ r_hat)
            theta_dot = float(rho_dot @ t_hat) / d
            w_ref, wdot_ref = law.rate_reference(t_s)
            wn, zeta = law.radial_natural_frequency_rad_s, law.radial_damping_ratio
            d_ddot = -wn * wn * (d - law.separation_m) - 2.0 * zeta * wn * d_dot
            theta_ddot = wdot_ref + law.rate_gain_per_s * (w_ref - theta_dot)
            acc = (d_ddot - d * theta_dot ** 2) * r_hat + (d * theta_ddot + 2.0 * d_dot * theta_dot) * t_hat
            acc[2] = -wn * wn * rho[2] - 2.0 * zeta * wn * rho_dot[2]
        if self.frame == "planar":
            acc[2] = 0.0
        force = self.mu_red_kg * acc
        norm = float(np.linalg.norm(force))
        return force * (self.max_force_n / norm) if norm > self.max_force_n else force

    def _coil_scale(self, k: int, dipole_frame: np.ndarray, body_to_frame: np.ndarray) -> float:
        """Largest |coil moment|/limit of vehicle k for a frame dipole (≤ 1 is feasible)."""
        v = self.vehicles[k]
        moments = v.coil_axes_body.T @ (body_to_frame.T @ dipole_frame)
        return float(np.max(np.abs(moments) / v.coil_max_dipole_am2))

    def _dump_dipole(self, k: int, b_frame: np.ndarray, h_frame: np.ndarray, body_to_frame: np.ndarray,
                     floor_am2: float) -> np.ndarray:
        """Full dipole of vehicle k along −(B × h), the direction whose Earth torque removes h fastest —
        but no more than removes the momentum across the field, |h⊥| = |B × h|/|B|, in one control period
        (|μ| ≤ |B × h|/(|B|² Δt): a larger dipole held for the period overshoots h⊥ and chatters), and no
        less than ``floor_am2`` (the min-norm pair's, so the partner needs no more dipole than without
        dumping)."""
        u = -cross3(b_frame, h_frame)
        norm = float(np.linalg.norm(u))
        if norm == 0.0:
            return np.zeros(3)
        deadbeat = norm / (float(b_frame @ b_frame) * self.dt)
        u /= norm
        return u * min(1.0 / self._coil_scale(k, u, body_to_frame), max(deadbeat, floor_am2))

    def step(self, t_s: float, measurements: Sequence[Measurement],
             frame_to_inertial: np.ndarray | None = None) -> tuple[VehicleCommand, VehicleCommand]:
        """Commands for both vehicles over [t_s, t_s + control period]; ``frame_to_inertial`` (3×3) is the
        formation frame's axes in the inertial frame (Hill → ECI; identity by default)."""
        if len(measurements) != 2:
            raise ControllerError(f"need the measurements of both vehicles, got {len(measurements)}")
        f2i = np.eye(3) if frame_to_inertial is None else as_matrix3(frame_to_inertial, "frame_to_inertial")
        pairs = list(zip(measurements, self.vehicles, strict=True))
        pos = np.array([as_vector3(m.position_m, f"{v.name} position_m") for m, v in pairs])
        vel = np.array([as_vector3(m.velocity_m_s, f"{v.name} velocity_m_s") for m, v in pairs])
        rot = [as_matrix3(m.body_to_inertial, f"{v.name} body_to_inertial") for m, v in pairs]
        b2f = [f2i.T @ r for r in rot]
        if self._targets is None:
            self._targets = [r.copy() for r in rot]
        rho_now, rho_dot = pos[1] - pos[0], vel[1] - vel[0]
        rotation, rho = _half_period_prediction(rho_now, rho_dot, 0.5 * self.dt)
        force_b = rotation @ self._force_command(t_s, rho_now, rho_dot)
        pos_mid = np.array([np.zeros(3), rho])
        b_frame = [None if m.b_inertial_t is None else f2i.T @ as_vector3(m.b_inertial_t, f"{v.name} b_inertial_t")
                   for m, v in pairs]
        h_frame = [b2f[k] @ as_vector3(measurements[k].wheel_h_body_nms, f"{v.name} wheel_h_body_nms")
                   for k, v in enumerate(self.vehicles)]
        dip = self._dipoles(rho, force_b, pos_mid, b_frame, h_frame, b2f)
        self._prev_mu_a = dip[0].copy()
        _, t_a, _, t_b = dipole_pair_wrench(dip[0], dip[1], rho)
        commands = []
        for k, (v, m, tau_em) in enumerate(zip(self.vehicles, measurements, (t_a, t_b), strict=True)):
            tau_frame = tau_em + (cross3(dip[k], b_frame[k]) if b_frame[k] is not None else 0.0)
            wheel = self._wheel_torque(k, m, rot[k], b2f[k].T @ tau_frame)
            dip_body = b2f[k].T @ dip[k]
            commands.append(VehicleCommand(dip_body, v.coil_axes_body.T @ dip_body, wheel,
                                           force_b if k == 1 else -force_b, dip[k], self._dumping_now and self._dumper == k))
        return commands[0], commands[1]

    def _dipoles(self, rho: np.ndarray, force_b: np.ndarray, pos: np.ndarray, b_frame: list[np.ndarray | None],
                 h_frame: list[np.ndarray], b2f: list[np.ndarray]) -> list[np.ndarray]:
        """Frame dipoles of A and B for the commanded force, within the coil limits."""
        have_field = self.dump is not None and all(b is not None for b in b_frame)
        if have_field:
            stored = [float(np.linalg.norm(h)) for h in h_frame]
            if self._dumper is not None and stored[self._dumper] < self.dump.done_nms:
                self._dumper = None
            if self._dumper is None and max(stored) > self.dump.start_nms:
                self._dumper = int(np.argmax(stored))
        self._dumping_now = False
        normal = np.array([0.0, 0.0, 1.0]) if self.frame == "planar" else None
        mu_a, mu_b = min_norm_dipoles(rho, force_b, normal, self._prev_mu_a)
        if have_field and self._dumper is not None:
            k = self._dumper
            free = self._dump_dipole(k, b_frame[k], h_frame[k], b2f[k], float(np.linalg.norm(mu_a)))
            forces = np.array([-force_b, force_b])
            try:
                sol = solve_remaining_dipoles(pos, k, free, forces, np.zeros((2, 3)))
            except ControllerError:
                sol = None  # the dumping dipole cannot make this force (e.g. it is across the baseline)
            if sol is not None and self._coil_scale(1 - k, sol[1 - k], b2f[1 - k]) <= 1.0:
                self._dumping_now = True
                return [sol[0], sol[1]]
        scale = max(self._coil_scale(0, mu_a, b2f[0]), self._coil_scale(1, mu_b, b2f[1]))
        if scale > 1.0:
            mu_a, mu_b = mu_a / scale, mu_b / scale
        return [mu_a, mu_b]

    def _wheel_torque(self, k: int, m: Measurement, rot: np.ndarray, tau_body: np.ndarray) -> np.ndarray:
        """Wanted ḣ (body, N·m) of vehicle k (``wheel_torque_command``)."""
        return wheel_torque_command(self.attitude, self.vehicles[k], self.frame == "planar", self._targets[k], m, rot,
                                    tau_body)


def wheel_torque_command(attitude: AttitudeLaw, v: ControlledVehicle, planar: bool, target: np.ndarray,
                         m: Measurement, rot: np.ndarray, tau_body: np.ndarray) -> np.ndarray:
    """Wanted ḣ (body, N·m) of vehicle ``v``: take the predicted external torque ``tau_body`` and add the
    attitude PD toward ``target`` (body → inertial DCM); ``planar``: the yaw channel only."""
    err = rot.T @ target  # target → body; skew part ≈ −[θ×], θ the body's rotation from target
    theta = 0.5 * np.array([err[1, 2] - err[2, 1], err[2, 0] - err[0, 2], err[0, 1] - err[1, 0]])
    w = as_vector3(m.omega_body_rad_s, f"{v.name} omega_body_rad_s")
    h = as_vector3(m.wheel_h_body_nms, f"{v.name} wheel_h_body_nms")
    wn, zeta = attitude.natural_frequency_rad_s, attitude.damping_ratio
    alpha = -wn * wn * theta - 2.0 * zeta * wn * w
    inertia = v.inertia_kg_m2
    if planar:
        return np.array([0.0, 0.0, tau_body[2] - inertia[2, 2] * alpha[2]])
    return tau_body - inertia @ alpha - cross3(w, inertia @ w + h)
