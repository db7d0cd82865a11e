"""Arrays of N ≥ 2 EMFF vehicles: the least-dipole solve and the spinning-array law (spec §10; seed 004).

Dipole solve (slide 23 "Solving the EOM": "for a given instantaneous force profile there are (3N−3)
constraints and 3N variables (dipole strengths)"; slide 27 "choose the free dipole such that a cost
function is optimized – dipole strength distribution"). ``least_dipole_solution`` takes every
vehicle's commanded far-field force (they must sum to zero: internal forces) and returns the dipoles
that make them with the least Σ|μ_i|² (the total coil current squared, the I²R losses of slides 73,
81), as a constrained problem:

    minimise ½ Σ|μ_i|²   subject to   c(μ) = F_i(μ) − F_i* = 0   for every vehicle but the first,

(the first vehicle's force follows from Σ F = 0). Two Newton stages, each failing with a
ControllerError that names the stage and its residual:

1. *feasibility* (Gauss–Newton, minimum-norm steps μ ← μ − J⁺ c) from the initial guess;
2. *least dipole* (Newton on the Lagrange conditions μ + Jᵀλ = 0, c = 0). F is bilinear in the
   dipoles, so J(μ) is linear in μ and the Hessian of λ·c is exact: column k is J(e_k)ᵀλ. Where the
   Hessian of the Lagrangian has a negative curvature along the constraints, it is shifted so that the
   step descends (saddle-free Newton) instead of climbing to a saddle; a step is capped at half of
   |μ| and followed by a Gauss–Newton restoration of the forces (a projected SQP). The point
   reached is checked to be a minimum (reduced Hessian positive definite on the constraints' tangent
   space); from a saddle the solve steps along the negative curvature and runs both stages again.

In ``planar`` the dipoles and forces lie in the frame's x–y plane (2N unknowns, 2N − 2 constraints).
For N = 2 this reproduces ``formation_control.min_norm_dipoles`` (tested).

Spinning array (``ArraySpinLaw``, slides 21–22 "Spin-up of formations ... not restricted to linear
arrays ... configurations of any shape can be spun-up"): the vehicles' places in the array at t = 0
about its centre of mass, p_i (``array_position``), turn about the frame z axis at the reference rate
ω_ref(t) (ramped at ``ramp`` from ``start`` up to ``rate``), angle θ_ref = ∫ω_ref. Each vehicle tracks
r_i* = R(θ_ref) p_i about the measured centre of mass with a PD plus the reference's own acceleration
fed forward:

    a_i = −ω_ref² r_i* + ω̇_ref ẑ × r_i* − ω_n²(r_i − r_cm − r_i*) − 2ζω_n(v_i − v_cm − ω_ref ẑ × r_i*),

F_i = m_i a_i with the mass-weighted mean removed (Σ F_i = 0 exactly). As the two-vehicle law, the
dipoles are held over the control period while the array turns, so they are solved for the positions
and forces rotated half a period ahead at the array's measured rate Ω = Σ m_i (ρ_i × v_i)_z / Σ m_i
|ρ_i,xy|² (ρ_i, v_i about the centre of mass). Dipoles beyond a coil's limit: all scaled together.
Attitude: every vehicle holds its initial attitude with its wheels, which take the predicted
electromagnetic torque (``formation_control.wheel_torque_command``).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
from acds_common.dipole_field import MU0_OVER_4PI, dipole_pair_wrench, force_matrix

from acds_controller.formation_control import (
    AttitudeLaw,
    ControlledVehicle,
    Measurement,
    VehicleCommand,
    em_forces_n,
    wheel_torque_command,
)
from acds_controller.magnetic_laws import ControllerError, as_vector3, check_gain

#: Frames the array law flies in (it spins about the frame z axis).
ARRAY_FRAMES = ("planar", "free_space")
#: Relative tolerance of the dipole solve: the forces, of the largest commanded force; the Lagrange
#: (optimality) conditions, of |μ| (the total dipole is flat at its minimum: 1e-8 of |μ| is ~1e-16 of Σ|μ|²).
SOLVE_TOLERANCE = 1e-10
LAGRANGE_TOLERANCE = 1e-8
#: Newton iterations allowed per stage.
MAX_NEWTON_ITERATIONS = 60
#: A saddle is left along its negative curvature by this fraction of |μ|, at most this many times.
SADDLE_STEP = 0.25
MAX_SADDLE_ESCAPES = 8
#: Least curvature (of ½|μ|², whose Hessian is I) the saddle-free Newton step gives a turned-over direction.
CURVATURE_FLOOR = 0.01
#: A stage-2 step is at most this fraction of |μ|; after it, the forces are restored (Gauss–Newton) to
#: within this fraction of the largest commanded force before the next.
MAX_STEP_FRACTION = 0.5
RESTORE_FRACTION = 1e-3


# ------------------------------------------------------------------------------ the least-dipole solve


def _force_jacobian(pos: np.ndarray, dip: np.ndarray, dims: int) -> np.ndarray:
    """∂F_i/∂μ_k, rows the vehicles 1..N−1 (``dims`` components each), columns all N dipoles."""
    n = len(pos)
    jac = np.zeros(((n - 1) * dims, n * dims))
    for i in range(1, n):
        rows = slice((i - 1) * dims, i * dims)
        for j in range(n):
            if j == i:
                continue
            jac[rows, i * dims:(i + 1) * dims] += force_matrix(dip[j], pos[i] - pos[j])[:dims, :dims]
            jac[rows, j * dims:(j + 1) * dims] = force_matrix(dip[i], pos[i] - pos[j])[:dims, :dims]
    return jac


@dataclass(frozen=True)
class DipoleSolution:
    """``dipoles_am2`` (N, 3) and what the solve reached: ``force_residual_n`` (largest |F_i − F_i*|),
    ``iterations`` (feasibility, least dipole)."""

    dipoles_am2: np.ndarray
    force_residual_n: float
    iterations: tuple[int, int]


def least_dipole_solution(positions_m: np.ndarray, forces_n: np.ndarray, guess_am2: np.ndarray | None = None,
                          planar: bool = False, tol: float = SOLVE_TOLERANCE) -> DipoleSolution:
    """The dipoles (A·m², frame) making far-field forces ``forces_n`` (N, 3) on vehicles at ``positions_m``
    with the least Σ|μ_i|² (module docstring). Started from ``guess_am2`` (N, 3) if given (a warm start:
    the previous control step's); if it is None or ends on a saddle or fails, from every
    ``cold_guesses`` start, keeping the least minimum. ControllerError on bad input, or when no start
    converges to a minimum (the last failure: its stage and residual)."""
    pos = np.asarray(positions_m, dtype=float)
    n = len(pos)
    if pos.ndim != 2 or pos.shape != (n, 3) or n < 2:
        raise ControllerError(f"positions_m must be (N >= 2, 3), got shape {pos.shape}")
    forces = np.asarray(forces_n, dtype=float)
    if forces.shape != (n, 3) or not np.all(np.isfinite(forces)) or not np.all(np.isfinite(pos)):
        raise ControllerError(f"positions_m and forces_n must be finite ({n}, 3) arrays")
    for i in range(n):
        for j in range(i + 1, n):
            if np.linalg.norm(pos[i] - pos[j]) <= 0.0:
                raise ControllerError(f"vehicles {i} and {j} are at the same position {pos[i].tolist()} m")
    scale = max(float(np.abs(forces).max()), 1e-300)
    if np.abs(forces.sum(axis=0)).max() > 1e-9 * scale:
        raise ControllerError(f"commanded forces must sum to zero (internal forces), got Σ F = {forces.sum(axis=0).tolist()} N")
    if float(np.abs(forces).max()) == 0.0:
        return DipoleSolution(np.zeros((n, 3)), 0.0, (0, 0))
    if guess_am2 is not None:
        guess = np.asarray(guess_am2, dtype=float)
        if guess.shape != (n, 3) or not np.all(np.isfinite(guess)):
            raise ControllerError(f"guess_am2 must be a finite ({n}, 3) array")
        try:
            return _solve_from(pos, forces, guess, planar, tol)
        except ControllerError:
            pass  # the warm start failed: the cold starts below
    best: DipoleSolution | None = None
    error: ControllerError | None = None
    for guess in cold_guesses(pos, forces):
        try:
            sol = _solve_from(pos, forces, guess, planar, tol)
        except ControllerError as exc:
            error = exc
            continue
        if best is None or np.sum(sol.dipoles_am2 ** 2) < np.sum(best.dipoles_am2 ** 2) * (1.0 - 1e-12):
            best = sol
    if best is None:
        assert error is not None
        raise error
    return best


def cold_guesses(positions_m: np.ndarray, forces_n: np.ndarray) -> list[np.ndarray]:
    """Deterministic starts for the solve: every dipole along the frame x axis, the frame y axis, its
    direction from the centroid (radial) or across it (tangential, about z), each with all signs equal
    and alternating by vehicle; sized for the largest force between the nearest pair (3μ0μ²/(2πd⁴) = F)."""
    pos = np.asarray(positions_m, dtype=float)
    n = len(pos)
    rel = pos - pos.mean(axis=0)
    d = min(float(np.linalg.norm(pos[i] - pos[j])) for i in range(n) for j in range(i + 1, n))
    size = math.sqrt(max(float(np.abs(forces_n).max()), 1e-300) * d ** 4 / (6.0 * MU0_OVER_4PI))
    radial = np.array([r / np.linalg.norm(r) if np.linalg.norm(r) > 1e-9 * d else np.array([1.0, 0.0, 0.0])
                       for r in rel])
    tangential = np.cross(np.array([0.0, 0.0, 1.0]), radial)
    tangential[np.linalg.norm(tangential, axis=1) < 1e-12] = np.array([0.0, 1.0, 0.0])
    families = [np.tile([1.0, 0.0, 0.0], (n, 1)), np.tile([0.0, 1.0, 0.0], (n, 1)), radial, tangential]
    signs = (np.ones(n), np.array([(-1.0) ** i for i in range(n)]))
    return [size * s[:, None] * f for f in families for s in signs]


def _solve_from(positions_m: np.ndarray, forces_n: np.ndarray, guess_am2: np.ndarray, planar: bool,
                tol: float) -> DipoleSolution:
    """Newton's two stages from ``guess_am2`` (inputs checked by the caller). A Lagrange point that is a
    saddle (a negative curvature of Σ|μ|² along the constraints) is left along that direction, by
    ``SADDLE_STEP`` of |μ|, and both stages run again, at most ``MAX_SADDLE_ESCAPES`` times."""
    pos, forces = positions_m, forces_n
    n = len(pos)
    dims = 2 if planar else 3
    x = np.array(guess_am2, dtype=float)[:, :dims].ravel()
    scale = float(np.abs(forces).max())

    def unpack(v: np.ndarray) -> np.ndarray:
        out = np.zeros((n, 3))
        out[:, :dims] = v.reshape(n, dims)
        return out

    # F is bilinear in the dipoles: J(μ) = Σ_k μ_k J(e_k), c(μ) = ½ J(μ) μ − F*, Hessian of λ·c: Σ_i λ_i ∂J_i/∂μ.
    basis_jac = np.stack([_force_jacobian(pos, unpack(e), dims) for e in np.eye(n * dims)])  # (k, m, n·dims)
    target = forces[1:, :dims].ravel()

    def jacobian(v: np.ndarray) -> np.ndarray:
        return np.tensordot(v, basis_jac, axes=(0, 0))

    def constraint(v: np.ndarray) -> np.ndarray:
        return 0.5 * jacobian(v) @ v - target

    def hessian(lam: np.ndarray) -> np.ndarray:  # of ½|μ|² + λ·c
        return np.eye(n * dims) + np.einsum('kmj,m->jk', basis_jac, lam)

    iterations = [0, 0]
    for _escape in range(MAX_SADDLE_ESCAPES + 1):
        c = constraint(x)
        while np.abs(c).max() > tol * scale:
            if iterations[0] >= MAX_NEWTON_ITERATIONS * (_escape + 1):
                raise ControllerError(f"dipole solve, stage 1 (feasibility, Gauss–Newton): no convergence in "
                                      f"{iterations[0]} iterations, force residual {np.abs(c).max():.3e} N "
                                      f"(tolerance {tol * scale:.3e} N)")
            x = x - np.linalg.lstsq(jacobian(x), c, rcond=None)[0]
            c = constraint(x)
            iterations[0] += 1
        m = len(c)
        lam = -np.linalg.lstsq(jacobian(x).T, x, rcond=None)[0]
        for newton in range(MAX_NEWTON_ITERATIONS + 1):
            jac = jacobian(x)
            grad = x + jac.T @ lam
            c = constraint(x)
            if np.abs(c).max() <= tol * scale and np.linalg.norm(grad) <= LAGRANGE_TOLERANCE * float(np.linalg.norm(x)):
                break
            if newton == MAX_NEWTON_ITERATIONS:
                raise ControllerError(f"dipole solve, stage 2 (least dipole, Newton on the Lagrange conditions): no "
                                      f"convergence in {MAX_NEWTON_ITERATIONS} iterations, force residual "
                                      f"{np.abs(c).max():.3e} N, Lagrange residual {np.linalg.norm(grad):.3e} A·m²")
            h = hessian(lam)
            _, sv, vt = np.linalg.svd(jac)
            null = vt[int(np.sum(sv > 1e-12 * sv[0])):].T
            if null.shape[1]:  # saddle-free Newton: a negative curvature along the constraints is turned over
                low = float(np.linalg.eigvalsh(null.T @ (0.5 * (h + h.T)) @ null)[0])
                if low < 0.0:
                    h = h + (CURVATURE_FLOOR - 2.0 * low) * np.eye(n * dims)
            kkt = np.block([[h, jac.T], [jac, np.zeros((m, m))]])
            try:
                sol = np.linalg.solve(kkt, np.concatenate([-x, -c]))
            except np.linalg.LinAlgError:
                raise ControllerError(f"dipole solve, stage 2 (least dipole, Newton on the Lagrange conditions): "
                                      f"singular system at iteration {newton}, force residual {np.abs(c).max():.3e} N"
                                      ) from None
            step = sol[:n * dims]
            cap = MAX_STEP_FRACTION * float(np.linalg.norm(x))
            if np.linalg.norm(step) > cap:  # the quadratic model is not trusted that far: shorter, then restore
                step *= cap / float(np.linalg.norm(step))
            x, lam = x + step, sol[n * dims:]
            iterations[1] += 1
            for _ in range(MAX_NEWTON_ITERATIONS):
                c = constraint(x)
                if np.abs(c).max() <= RESTORE_FRACTION * scale:
                    break
                x = x - np.linalg.lstsq(jacobian(x), c, rcond=None)[0]
                iterations[0] += 1
        _, sv, vt = np.linalg.svd(jac)
        null = vt[int(np.sum(sv > 1e-12 * sv[0])):].T
        if null.shape[1] == 0:
            break
        h = hessian(lam)
        low, vec = np.linalg.eigh(null.T @ (0.5 * (h + h.T)) @ null)
        if low[0] > -1e-9:
            break
        x = x + SADDLE_STEP * float(np.linalg.norm(x)) * (null @ vec[:, 0])
    else:
        raise ControllerError(f"dipole solve, stage 2 (least dipole): still at a saddle of Σ|μ|² after "
                              f"{MAX_SADDLE_ESCAPES} escapes (reduced Hessian eigenvalue {low[0]:.3e}), force residual "
                              f"{np.abs(c).max():.3e} N")
    return DipoleSolution(unpack(x), float(np.abs(em_forces_n(pos, unpack(x)) - forces).max()), tuple(iterations))


# --------------------------------------------------------------------------------- spinning array


@dataclass(frozen=True)
class ArraySpinLaw:
    """Spin the array (places ``positions_m`` (N, 3) about its centre of mass at t = 0) about the frame z
    axis to ``rate_rad_s`` (signed), ramped at ``ramp_rad_s2`` from ``start_s``; PD ``natural_frequency_rad_s``,
    ``damping_ratio`` on each vehicle's place."""

    positions_m: np.ndarray
    rate_rad_s: float
    ramp_rad_s2: float
    start_s: float = 0.0
    natural_frequency_rad_s: float = 0.2
    damping_ratio: float = 0.9

    def reference(self, t_s: float) -> tuple[float, float, float]:
        """(θ_ref rad, ω_ref rad/s, ω̇_ref rad/s²) at ``t_s``."""
        w_max, a = abs(self.rate_rad_s), self.ramp_rad_s2
        sign = math.copysign(1.0, self.rate_rad_s)
        tau = max(0.0, t_s - self.start_s)
        t_ramp = w_max / a
        if tau < t_ramp:
            return sign * 0.5 * a * tau * tau, sign * a * tau, sign * a if tau > 0.0 else 0.0
        return sign * (0.5 * a * t_ramp * t_ramp + w_max * (tau - t_ramp)), sign * w_max, 0.0


def _rot_z(angle: float) -> np.ndarray:
    c, s = math.cos(angle), math.sin(angle)
    return np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])


class ArrayController:
    """N-vehicle spinning-array controller (module docstring). ``step(t_s, measurements)`` returns every
    vehicle's command."""

    def __init__(self, vehicles: Sequence[ControlledVehicle], frame: str, law: ArraySpinLaw,
                 attitude: AttitudeLaw, control_period_s: float, max_force_n: float) -> None:
        if len(vehicles) < 2:
            raise ControllerError(f"an array needs at least two vehicles, got {len(vehicles)}")
        if frame not in ARRAY_FRAMES:
            raise ControllerError(f"the array law spins about the frame z axis: frame must be one of {ARRAY_FRAMES}, "
                                  f"got {frame!r}")
        self.vehicles = tuple(vehicles)
        self.frame, self.law, self.attitude = frame, law, attitude
        self.dt = check_gain(control_period_s, "control_period_s", 1e-9, math.inf)
        self.max_force_n = check_gain(max_force_n, "max_force_n", 0.0, math.inf)
        self.mass = np.array([v.mass_kg for v in vehicles])
        places = np.asarray(law.positions_m, dtype=float)
        if places.shape != (len(vehicles), 3):
            raise ControllerError(f"ArraySpinLaw.positions_m must be ({len(vehicles)}, 3), got {places.shape}")
        self.places = places - self.mass @ places / self.mass.sum()
        if frame == "planar" and np.any(self.places[:, 2] != 0.0):
            raise ControllerError("planar: the array's places must have z = 0")
        self._targets: list[np.ndarray] | None = None
        self._guess: np.ndarray | None = None

    def forces(self, t_s: float, pos: np.ndarray, vel: np.ndarray) -> np.ndarray:
        """Commanded force on every vehicle (N, frame), Σ F = 0, each limited to ``max_force_n``."""
        m = self.mass
        r_cm, v_cm = m @ pos / m.sum(), m @ vel / m.sum()
        theta, w, wdot = self.law.reference(t_s)
        target = self.places @ _rot_z(theta).T
        z = np.array([0.0, 0.0, 1.0])
        target_v = w * np.cross(z, target)
        wn, zeta = self.law.natural_frequency_rad_s, self.law.damping_ratio
        acc = (-w * w * target + wdot * np.cross(z, target) - wn * wn * (pos - r_cm - target)
               - 2.0 * zeta * wn * (vel - v_cm - target_v))
        if self.frame == "planar":
            acc[:, 2] = 0.0
        force = m[:, None] * acc
        force -= m[:, None] * (force.sum(axis=0) / m.sum())
        peak = float(np.linalg.norm(force, axis=1).max())
        return force * (self.max_force_n / peak) if peak > self.max_force_n else force

    def _coil_scale(self, k: int, dipole_frame: np.ndarray, body_to_frame: np.ndarray) -> float:
        v = self.vehicles[k]
        return float(np.max(np.abs(v.coil_axes_body.T @ (body_to_frame.T @ dipole_frame)) / v.coil_max_dipole_am2))

    def step(self, t_s: float, measurements: Sequence[Measurement]) -> list[VehicleCommand]:
        """Every vehicle's command over [t_s, t_s + control period] (module docstring)."""
        if len(measurements) != len(self.vehicles):
            raise ControllerError(f"need the measurements of all {len(self.vehicles)} vehicles, got {len(measurements)}")
        pairs = list(zip(measurements, self.vehicles, strict=True))
        pos = np.array([as_vector3(ms.position_m, f"{v.name} position_m") for ms, v in pairs])
        vel = np.array([as_vector3(ms.velocity_m_s, f"{v.name} velocity_m_s") for ms, v in pairs])
        rot = [np.asarray(ms.body_to_inertial, dtype=float) for ms in measurements]
        if self._targets is None:
            self._targets = [r.copy() for r in rot]
        m = self.mass
        force = self.forces(t_s, pos, vel)
        rel = pos - m @ pos / m.sum()
        rel_v = vel - m @ vel / m.sum()
        inertia_z = float(m @ np.sum(rel[:, :2] ** 2, axis=1))
        spin = float(m @ (rel[:, 0] * rel_v[:, 1] - rel[:, 1] * rel_v[:, 0])) / inertia_z
        ahead = _rot_z(0.5 * self.dt * spin)
        rel_mid, force_mid = rel @ ahead.T, force @ ahead.T
        dip = least_dipole_solution(rel_mid, force_mid, self._guess, planar=self.frame == "planar").dipoles_am2
        self._guess = dip
        scale = max(self._coil_scale(k, dip[k], rot[k]) for k in range(len(dip)))
        if scale > 1.0:
            dip = dip / scale
        torque = np.zeros_like(dip)
        for i in range(len(dip)):
            for j in range(i + 1, len(dip)):
                _, t_i, _, t_j = dipole_pair_wrench(dip[i], dip[j], rel_mid[j] - rel_mid[i])
                torque[i] += t_i
                torque[j] += t_j
        commands = []
        for k, (ms, v) in enumerate(pairs):
            wheel = wheel_torque_command(self.attitude, v, self.frame == "planar", self._targets[k], ms, rot[k],
                                         rot[k].T @ torque[k])
            dip_body = rot[k].T @ dip[k]
            commands.append(VehicleCommand(dip_body, v.coil_axes_body.T @ dip_body, wheel, force[k], dip[k], False))
        return commands


# -------------------------------------------------------------- rotating linear array: mission efficiency


def mission_efficiency(rate_rad_s: float, array_mass_kg: float, outer_radius_m: float, dipole_am2: float) -> float:
    """Slide 64's mission efficiency of a rotating array, J = ω / (m_array √c_o), c_o = 3μ0 μ_B²/(π a_o⁵):
    the spin rate per array mass at a given coil dipole μ_B and outer radius a_o. (The extracted slide
    is garbled; this is the form for which its "J3/J2 = 2.75" follows: (2/3)√17 = 2.749.) Only ratios
    at equal μ_B and a_o are meaningful."""
    c_o = 3.0 * 4.0 * math.pi * MU0_OVER_4PI * dipole_am2 ** 2 / (math.pi * outer_radius_m ** 5)
    return rate_rad_s / (array_mass_kg * math.sqrt(c_o))


def linear_array_rate_rad_s(masses_kg: Sequence[float], positions_m: Sequence[float], dipole_am2: float) -> float:
    """Steady rate of a rotating linear array (vehicles on a line through their centre of mass, at
    ``positions_m`` along it) whose dipoles all equal ``dipole_am2`` along the line (slide 64's "same EM
    core and coil design"): the outermost vehicle's centripetal force m a ω² is the coaxial attraction
    Σ_j 3μ0 μ_B²/(2π s_j⁴) of all the others. ControllerError if the centre of mass is not at 0."""
    m = np.asarray(masses_kg, dtype=float)
    x = np.asarray(positions_m, dtype=float)
    if abs(float(m @ x)) > 1e-9 * float(m.sum() * np.abs(x).max()):
        raise ControllerError(f"positions_m {x.tolist()} are not about the centre of mass")
    k = int(np.argmax(np.abs(x)))
    force = sum(6.0 * MU0_OVER_4PI * dipole_am2 ** 2 / abs(x[k] - x[j]) ** 4 for j in range(len(x)) if j != k)
    return math.sqrt(force / (m[k] * abs(x[k])))
