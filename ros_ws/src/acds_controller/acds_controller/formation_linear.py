"""Linearised spinning EMFF array: stability, controllability, LQR (spec §10; seed 004 slides 36–44).

The review's "Multi-Vehicle EMFF Analysis" linearises the two-vehicle cluster about its steady spin
(slide 40: nominal rate φ̇0 about the array normal, vehicles facing each other, "EM pointing toward the
other spacecraft carries bulk of centripetal load", the wheels holding the cluster's angular momentum:
I_zz,w Ω_zw + (I_zz,s + m r0²) φ̇0 = 0), finds its 18 poles (slide 42), its controllability (slide 43)
and an LQR (slide 44). Here, for N ≥ 2 vehicles with any coils and wheels:

* Nominal (``SpinNominal``): the array's places p_i about its centre of mass turn about the frame z
  axis at Ω; every vehicle turns with it (body axes = the rotating frame's axes), its wheels holding
  h_i = −(I_zz,i + m_i |p_i|²) Ω ẑ (slide 40, per vehicle, so the cluster's total angular momentum is
  zero); the dipoles are the least-Σ|μ|² solution (``formation_array.least_dipole_solution``) for the
  centripetal forces −m_i Ω² p_i (a vehicle without coils has none, and can only sit at the centre),
  and each vehicle's wheels take its nominal electromagnetic torque (zero for a linear array, whose
  dipoles lie on the baseline).
* Model: the same equations the graph flies in the ``free_space`` frame (``dynamics.formation``; the
  test suite checks the accelerations against it): far-field dipole–dipole wrench of every pair
  (``acds_common.dipole_field``), m_i r̈_i = F_i, I ω̇ = τ_EM − ḣ − ω × (I ω + h). Written in the rotating
  frame: position σ_i, velocity relative to the rotating frame u_i (u̇ = a − 2Ω×u − Ω×(Ω×σ)), attitude
  error δθ_i (body → inertial = R_z(Ωt) exp([δθ×])) and rate relative to the rotating frame δω_i =
  ω_i − exp(−[δθ×]) Ω ẑ (δθ̇ = δω to first order, δω̇ = ω̇ + δω × exp(−[δθ×]) Ω ẑ). The wheel momentum is
  held at its nominal (the wheels are torque actuators, as the review's 18-state model, whose state
  has no wheel speeds): the 3N wheel-momentum integrators are left out.
* Linearisation: numerical Jacobian by central differences (``JACOBIAN_STEP`` relative to each state's
  and input's scale) at the nominal (t = 0; the system is time-invariant in the rotating frame).
* The centre of mass (6 states, moved by no internal force) is taken out: the state is the relative
  positions ρ_i = σ_i − σ_1 (i = 2..N), the attitude errors δθ_i, then their rates: 12N − 6 states
  (18 for two vehicles, as the review's r, φ, ψ, α1–3, β1–3 and rates; 30 for three).
* Inputs: every vehicle's coil moments (A·m², per coil) then its wheel torques (N·m, per wheel).

Stability: the eigenvalues of A, grouped as slide 42 groups them (``group_eigenvalues``: at the origin,
real ± pairs, imaginary pairs, complex). Controllability (slide 43): the rank of [B AB … A^(n−1)B]
(``controllability_rank``, by orthogonal Krylov iteration). LQR (slide 44):
u = −K x with K = R⁻¹BᵀP, P the stabilising solution of AᵀP + PA − PBR⁻¹BᵀP + Q = 0 (``lqr_gain``;
numpy has no Riccati solver and scipy is not a dependency: the matrix sign function of the
Hamiltonian, Newton's iteration with determinant scaling (Byers 1987), then the residual is checked).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
from acds_common.dipole_field import cross3, dipole_pair_wrench

from acds_controller.formation_array import least_dipole_solution
from acds_controller.magnetic_laws import ControllerError

#: Central-difference step of the Jacobian, relative to each state's or input's scale.
JACOBIAN_STEP = 1e-5
#: Eigenvalues within this fraction of the largest |λ| count as zero / real / imaginary.
EIGEN_TOLERANCE = 1e-4
#: Singular values below this fraction of the largest count as zero in the controllability ranks.
RANK_TOLERANCE = 1e-9
#: Sign-function iterations allowed, and the ARE residual accepted (relative to |Q|).
SIGN_ITERATIONS = 100
RICCATI_TOLERANCE = 1e-8

_Z = np.array([0.0, 0.0, 1.0])


@dataclass(frozen=True)
class LinearVehicle:
    """A vehicle as the linear model sees it: ``name``, ``mass_kg``, ``inertia_kg_m2`` (3×3 body),
    ``coil_axes_body`` (3, n_coils) and ``wheel_axes_body`` (3, n_wheels), columns (either may be empty)."""

    name: str
    mass_kg: float
    inertia_kg_m2: np.ndarray
    coil_axes_body: np.ndarray
    wheel_axes_body: np.ndarray


@dataclass(frozen=True)
class SpinNominal:
    """The steady spin: ``places_m`` (N, 3) about the centre of mass, ``rate_rad_s`` about z, the body
    dipoles ``dipoles_am2`` (N, 3), wheel momenta ``wheel_h_nms`` (N, 3) and rates ``wheel_hdot_nm`` (N, 3)."""

    places_m: np.ndarray
    rate_rad_s: float
    dipoles_am2: np.ndarray
    wheel_h_nms: np.ndarray
    wheel_hdot_nm: np.ndarray


def rotation_from_vector(theta: np.ndarray) -> np.ndarray:
    """exp([θ×]): the rotation matrix of rotation vector θ (Rodrigues); ``formation_lqr.rotation_vector`` inverts it."""
    angle = float(np.linalg.norm(theta))
    k = np.array([[0.0, -theta[2], theta[1]], [theta[2], 0.0, -theta[0]], [-theta[1], theta[0], 0.0]])
    if angle < 1e-300:
        return np.eye(3) + k
    return np.eye(3) + math.sin(angle) / angle * k + (1.0 - math.cos(angle)) / angle ** 2 * k @ k


def em_wrench(positions_m: np.ndarray, dipoles_frame_am2: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Far-field force (N) and torque (N·m) on every vehicle, frame axes, from every pair."""
    n = len(positions_m)
    force, torque = np.zeros((n, 3)), np.zeros((n, 3))
    for i in range(n):
        for j in range(i + 1, n):
            f_i, t_i, f_j, t_j = dipole_pair_wrench(dipoles_frame_am2[i], dipoles_frame_am2[j],
                                                    positions_m[j] - positions_m[i])
            force[i] += f_i
            force[j] += f_j
            torque[i] += t_i
            torque[j] += t_j
    return force, torque


def spin_nominal(vehicles: Sequence[LinearVehicle], places_m: np.ndarray, rate_rad_s: float,
                 planar: bool = False) -> SpinNominal:
    """The steady spin of ``vehicles`` at ``places_m`` (re-centred on their centre of mass) at ``rate_rad_s``
    (module docstring); ControllerError if the coils cannot make the least-dipole solution."""
    mass = np.array([v.mass_kg for v in vehicles])
    places = np.asarray(places_m, dtype=float)
    places = places - mass @ places / mass.sum()
    forces = -mass[:, None] * rate_rad_s ** 2 * places * np.array([1.0, 1.0, 0.0])
    active = [k for k, v in enumerate(vehicles) if v.coil_axes_body.shape[1] > 0]
    for k, v in enumerate(vehicles):
        if k not in active and np.linalg.norm(forces[k]) > 0.0:
            raise ControllerError(f"{v.name} has no coils, so no force holds it at {places[k].tolist()} m off the spin "
                                  "axis (a coil-less vehicle can only sit at the centre of mass)")
    if len(active) < 2:
        raise ControllerError(f"a spinning array needs at least two vehicles with coils, got {len(active)}")
    dip = np.zeros((len(vehicles), 3))
    dip[active] = least_dipole_solution(places[active], forces[active], planar=planar).dipoles_am2
    for v, mu in zip(vehicles, dip, strict=True):
        axes = v.coil_axes_body
        if np.linalg.norm(mu - axes @ (axes.T @ mu)) > 1e-9 * max(float(np.linalg.norm(mu)), 1.0):
            raise ControllerError(f"{v.name}: its coils {axes.T.tolist()} cannot make the steady spin's dipole "
                                  f"{mu.tolist()} A·m²")
    _, torque = em_wrench(places, dip)
    h = np.array([-(v.inertia_kg_m2[2, 2] + v.mass_kg * float(p[:2] @ p[:2])) * rate_rad_s * _Z
                  for v, p in zip(vehicles, places, strict=True)])
    return SpinNominal(places, float(rate_rad_s), dip, h, torque)


class SpinningArrayModel:
    """The rotating-frame equations of the array about ``nominal`` (module docstring)."""

    def __init__(self, vehicles: Sequence[LinearVehicle], nominal: SpinNominal) -> None:
        self.vehicles = tuple(vehicles)
        self.nominal = nominal
        self.n = len(vehicles)
        self.mass = np.array([v.mass_kg for v in vehicles])
        self.inertia = np.stack([np.asarray(v.inertia_kg_m2, dtype=float) for v in vehicles])
        self.inertia_inv = np.linalg.inv(self.inertia)
        self.input_sizes = [(v.coil_axes_body.shape[1], v.wheel_axes_body.shape[1]) for v in vehicles]
        self.n_inputs = sum(a + b for a, b in self.input_sizes)

    def full_derivative(self, state: np.ndarray, inputs: np.ndarray) -> np.ndarray:
        """d/dt of (σ, u, δθ, δω) (each (N, 3), flattened in that order) for input deviations
        (coil moments, wheel torques per vehicle)."""
        n = self.n
        sigma, u, dtheta, domega = state.reshape(4, n, 3)
        nom = self.nominal
        omega_vec = nom.rate_rad_s * _Z
        rot = np.stack([rotation_from_vector(dtheta[k]) for k in range(n)])  # body → inertial at t = 0
        dip_body, hdot = nom.dipoles_am2.copy(), nom.wheel_hdot_nm.copy()
        at = 0
        for k, (v, (nc, nw)) in enumerate(zip(self.vehicles, self.input_sizes, strict=True)):
            dip_body[k] += v.coil_axes_body @ inputs[at:at + nc]
            hdot[k] += v.wheel_axes_body @ inputs[at + nc:at + nc + nw]
            at += nc + nw
        dip_frame = np.einsum("nij,nj->ni", rot, dip_body)
        force, torque_frame = em_wrench(sigma, dip_frame)
        torque = np.einsum("nji,nj->ni", rot, torque_frame)
        acc = force / self.mass[:, None]
        omega_ref_body = np.einsum("nji,j->ni", rot, omega_vec)
        w = omega_ref_body + domega
        iw = np.einsum("nij,nj->ni", self.inertia, w)
        wdot = np.einsum("nij,nj->ni", self.inertia_inv, torque - hdot - cross3(w, iw + nom.wheel_h_nms))
        u_dot = acc - 2.0 * cross3(omega_vec, u) - cross3(omega_vec, cross3(omega_vec, sigma))
        return np.concatenate([u, u_dot, domega, wdot + cross3(domega, omega_ref_body)]).ravel()

    def nominal_state(self) -> np.ndarray:
        n = self.n
        return np.concatenate([self.nominal.places_m, np.zeros((3 * n, 3))]).ravel()

    def state_scales(self) -> np.ndarray:
        n = self.n
        d = float(np.max(np.linalg.norm(self.nominal.places_m, axis=1)))
        rate = abs(self.nominal.rate_rad_s)
        return np.concatenate([np.full(3 * n, d), np.full(3 * n, d * rate), np.ones(3 * n), np.full(3 * n, rate)])

    def input_scales(self) -> np.ndarray:
        out = []
        for k, (nc, nw) in enumerate(self.input_sizes):
            out += [max(float(np.linalg.norm(self.nominal.dipoles_am2[k])), 1.0)] * nc
            out += [max(float(np.linalg.norm(self.nominal.wheel_h_nms[k])) * abs(self.nominal.rate_rad_s), 1e-6)] * nw
        return np.array(out)

    def full_jacobians(self) -> tuple[np.ndarray, np.ndarray]:
        """(A, B) of the 12N-state rotating-frame model (central differences)."""
        x0 = self.nominal_state()
        u0 = np.zeros(self.n_inputs)
        hx = JACOBIAN_STEP * self.state_scales()
        hu = JACOBIAN_STEP * self.input_scales()
        a = np.stack([(self.full_derivative(x0 + e, u0) - self.full_derivative(x0 - e, u0)) / (2.0 * e[i])
                      for i, e in enumerate(np.diag(hx))], axis=1)
        b = np.stack([(self.full_derivative(x0, u0 + e) - self.full_derivative(x0, u0 - e)) / (2.0 * e[i])
                      for i, e in enumerate(np.diag(hu))], axis=1) if self.n_inputs else np.zeros((len(x0), 0))
        return a, b

    def relative_transform(self) -> np.ndarray:
        """T (12N × 12N): full state → (centre of mass (6), reduced state (12N − 6)), module docstring order."""
        n = self.n
        mass = self.mass / self.mass.sum()
        pos = np.zeros((3 * n, 3 * n))
        pos[0:3] = np.kron(mass[None, :], np.eye(3))
        for i in range(1, n):
            pos[3 * i:3 * i + 3, 3 * i:3 * i + 3] = np.eye(3)
            pos[3 * i:3 * i + 3, 0:3] = -np.eye(3)
        eye = np.eye(3 * n)
        t = np.zeros((12 * n, 12 * n))  # full order σ, u, δθ, δω → σ_cm, u_cm, then ρ, δθ, ρ̇, δω
        t[0:3, 0:3 * n] = pos[0:3]
        t[3:6, 3 * n:6 * n] = pos[0:3]
        m = 3 * (n - 1)
        t[6:6 + m, 0:3 * n] = pos[3:]
        t[6 + m:6 + m + 3 * n, 6 * n:9 * n] = eye
        t[6 + m + 3 * n:6 + 2 * m + 3 * n, 3 * n:6 * n] = pos[3:]
        t[6 + 2 * m + 3 * n:, 9 * n:] = eye
        return t

    def reduced(self) -> tuple[np.ndarray, np.ndarray]:
        """(A, B) of the (12N − 6)-state model without the centre of mass (module docstring)."""
        a, b = self.full_jacobians()
        t = self.relative_transform()
        a_t = t @ a @ np.linalg.inv(t)
        b_t = t @ b
        coupling = float(np.abs(a_t[6:, :6]).max())
        if coupling > 1e-6 * max(float(np.abs(a_t).max()), 1e-300):
            raise ControllerError(f"the centre of mass does not decouple (|∂ẋ_rel/∂x_cm| = {coupling:.3e}): the "
                                  "forces are not internal")
        return a_t[6:, 6:], b_t[6:]


# ------------------------------------------------------------------------ stability, controllability


def review_two_vehicle_eigenvalues(mass_kg: float, r0_m: float, rate_rad_s: float, i_rr_kg_m2: float,
                                   i_zz_kg_m2: float) -> dict[str, float]:
    """Slide 42's closed forms for two identical vehicles at r0 from the centre spinning at φ̇0 (the
    extraction is garbled; read as): λ1–6 = 0, λ7,8 = ±φ̇0, λ9,10 = ±iφ̇0,
    λ11,12 = ±i (r0φ̇0/I_rr) √(m(m r0² + I_rr/3)), λ13,14 = ±i (r0φ̇0/I_rr) √(m(m r0² + I_rr)),
    λ15,16 = ±i r0φ̇0 √(m/(3 I_zz)), λ17,18 = ±i r0φ̇0 √(m/I_zz); I_rr = I_rr,s + I_rr,w (the model's I_xx)."""
    m, r, w, i_rr, i_zz = mass_kg, r0_m, abs(rate_rad_s), i_rr_kg_m2, i_zz_kg_m2
    return {'zero (count)': 6.0, 'lambda7,8 (real)': w, 'lambda9,10 (imag)': w,
            'lambda11,12 (imag)': r * w / i_rr * math.sqrt(m * (m * r * r + i_rr / 3.0)),
            'lambda13,14 (imag)': r * w / i_rr * math.sqrt(m * (m * r * r + i_rr)),
            'lambda15,16 (imag)': r * w * math.sqrt(m / (3.0 * i_zz)),
            'lambda17,18 (imag)': r * w * math.sqrt(m / i_zz)}


@dataclass(frozen=True)
class EigenGroups:
    """Eigenvalues grouped as slide 42: ``zero`` (count), ``real_pairs`` (+σ values), ``imaginary_pairs``
    (+ω values), ``complex`` (remaining, with their conjugates), all sorted."""

    zero: int
    real_pairs: tuple[float, ...]
    imaginary_pairs: tuple[float, ...]
    complex: tuple[complex, ...]
    real_unpaired: tuple[float, ...]


def group_eigenvalues(eigenvalues: np.ndarray, tol: float = EIGEN_TOLERANCE) -> EigenGroups:
    """Slide 42's grouping of ``eigenvalues``: |λ|, |Re λ| or |Im λ| below ``tol`` × the largest |λ| count as
    zero (a repeated eigenvalue of a numerical Jacobian splits by ~√ of its error, hence the loose default)."""
    lam = np.asarray(eigenvalues, dtype=complex)
    eps = tol * max(float(np.abs(lam).max()), 1e-300)
    zero = int(np.sum(np.abs(lam) <= eps))
    rest = lam[np.abs(lam) > eps]
    real = sorted(float(x.real) for x in rest if abs(x.imag) <= eps)
    imag = sorted(float(abs(x.imag)) for x in rest if abs(x.real) <= eps and x.imag > 0)
    cplx = tuple(sorted((complex(x) for x in rest if abs(x.real) > eps and abs(x.imag) > eps),
                        key=lambda z: (abs(z), z.real, z.imag)))
    pos = [x for x in real if x > 0]
    neg = [-x for x in real if x < 0]
    pairs, unpaired = [], []
    for p in pos:
        match = next((q for q in neg if abs(q - p) <= eps), None)
        if match is None:
            unpaired.append(p)
        else:
            neg.remove(match)
            pairs.append(p)
    unpaired += [-q for q in neg]
    return EigenGroups(zero, tuple(pairs), tuple(imag), cplx, tuple(sorted(unpaired)))


def controllability_rank(a: np.ndarray, b: np.ndarray, tol: float = RANK_TOLERANCE) -> int:
    """Rank of [B AB … A^(n−1)B]: the dimension of the Krylov space span{B, AB, …}, built by orthogonal
    iteration (the powers A^k B themselves lose the slow modes to rounding when the eigenvalues spread
    over decades). A is scaled by its spectral radius and every new direction normalised before it is
    projected on the space so far; it is new if more than √tol of it is left."""
    n = a.shape[0]
    if b.shape[1] == 0:
        return 0
    rho = max(float(np.abs(np.linalg.eigvals(a)).max()), 1e-300)
    a_s = a / rho
    b_s = b / np.linalg.norm(b, axis=0, keepdims=True).clip(1e-300)
    basis = np.zeros((n, 0))
    new = b_s
    while basis.shape[1] < n:
        new = new / np.linalg.norm(new, axis=0, keepdims=True).clip(1e-300)  # each direction at unit size
        new = new - basis @ (basis.T @ new)
        u, s, _ = np.linalg.svd(new, full_matrices=False)
        keep = u[:, s > math.sqrt(tol)]
        if keep.shape[1] == 0:
            break
        keep = keep - basis @ (basis.T @ keep)
        keep, _ = np.linalg.qr(keep)
        basis = np.hstack([basis, keep])
        new = a_s @ keep
    return basis.shape[1]


# ---------------------------------------------------------------------------------------------- LQR


def lqr_gain(a: np.ndarray, b: np.ndarray, q: np.ndarray, r: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(K, P) of the continuous LQR (module docstring). ControllerError if the Riccati solution fails."""
    n = a.shape[0]
    r_inv = np.linalg.inv(r)
    g = b @ r_inv @ b.T
    ham = np.block([[a, -g], [-q, -a.T]])
    z = ham.copy()
    for it in range(SIGN_ITERATIONS):
        try:
            z_inv = np.linalg.inv(z)
        except np.linalg.LinAlgError:
            raise ControllerError(f"LQR: the Hamiltonian has eigenvalues on the imaginary axis (sign iteration {it} "
                                  "singular): the weighted system is not stabilisable/detectable") from None
        _, logdet = np.linalg.slogdet(z)
        c = math.exp(logdet / (2 * n))
        z_next = 0.5 * (z / c + c * z_inv)
        if np.linalg.norm(z_next - z, 1) <= 1e-13 * np.linalg.norm(z_next, 1):
            z = z_next
            break
        z = z_next
    w11, w12, w21, w22 = z[:n, :n], z[:n, n:], z[n:, :n], z[n:, n:]
    lhs = np.vstack([w12, w22 + np.eye(n)])
    rhs = -np.vstack([w11 + np.eye(n), w21])
    p = np.linalg.lstsq(lhs, rhs, rcond=None)[0]
    p = 0.5 * (p + p.T)
    resid = a.T @ p + p @ a - p @ g @ p + q
    scale = max(float(np.linalg.norm(q)), float(np.linalg.norm(a.T @ p)), 1e-300)
    if float(np.linalg.norm(resid)) > RICCATI_TOLERANCE * scale:
        raise ControllerError(f"LQR: the Riccati residual {np.linalg.norm(resid):.3e} exceeds "
                              f"{RICCATI_TOLERANCE:g} × {scale:.3e} (sign-function solve)")
    k = r_inv @ b.T @ p
    if np.max(np.linalg.eigvals(a - b @ k).real) >= 0.0:
        raise ControllerError("LQR: the closed loop A − BK is not stable")
    return k, p
