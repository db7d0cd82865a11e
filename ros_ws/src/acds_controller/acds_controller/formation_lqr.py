"""LQR formation controller about the steady spin (spec §10; seed 004 slide 44 "EMFF Linear Controller Design").

The plant is the linearised spinning array of ``formation_linear`` (12N − 6 states: relative positions,
attitude errors and their rates in the frame turning with the array; inputs every vehicle's coil
moments and wheel torques). The gain is the continuous LQR K = R⁻¹BᵀP for the weights below; the
control is u = u_nom − K x, held over the control period (the review simulates the same linear
feedback on the nonlinear and the linearised equations, slide 45).

Weights (``LqrWeights``, dimensionless, every one > 0): slide 44 chooses "relative state and control
penalties: Δr: 10 : 5, Δφ: 10⁻¹⁵ : 3, Δψ: 1 : 1 — all Euler angles and their derivatives: 1 — all
electromagnets, all reaction wheels: 1", read as (coordinate : its rate) for each relative coordinate:
radial 10, radial rate 5, tangential 10⁻¹⁵, tangential rate 3, normal 1, normal rate 1, attitude and
attitude rate 1, coils and wheels 1 (the defaults of ``emff_two_vehicle_lqr``). The review does not give
its units, so the states and inputs are normalised by their natural scales first (Bryson's rule): each
relative position by its nominal length d_i, split into its radial (along the nominal baseline, the
review's Δr), tangential (in the spin plane, d·Δφ) and normal (along the spin axis, d·Δψ) parts, its
relative velocity likewise by Ω d_i; attitude errors by 1 rad and body rates by Ω; coil moments by the
vehicle's nominal |μ|; wheel torques by Ω |h_nom|. Q = diag(q/scale²), R = diag(r/scale²).

State from the measurements at t (the array's nominal turns at Ω from its places at t = 0, body axes
along the frame's): σ_i = R_z(Ωt)ᵀ r_i, u_i = R_z(Ωt)ᵀ v_i − Ω ẑ × σ_i, δθ_i the rotation vector of
R_z(Ωt)ᵀ C_i, δω_i = ω_i − C_iᵀ R_z(Ωt) Ω ẑ; then the relative coordinates.
Coil moments beyond a coil's limit are clipped to it (each coil on its own; saturation, as a real
amplifier); the wheels clip their torque themselves.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from acds_controller.formation_control import ControlledVehicle, Measurement, VehicleCommand
from acds_controller.formation_linear import (
    LinearVehicle,
    SpinningArrayModel,
    lqr_gain,
    spin_nominal,
)
from acds_controller.magnetic_laws import ControllerError, as_vector3, check_gain

_Z = np.array([0.0, 0.0, 1.0])


#: The weights, in ``LqrWeights`` order (scenario keys ``formation.lqr_<name>_weight``).
WEIGHT_NAMES = ("radial", "tangential", "normal", "radial_rate", "tangential_rate", "normal_rate", "attitude",
                "attitude_rate", "coil", "wheel")


@dataclass(frozen=True)
class LqrWeights:
    """Dimensionless LQR weights (module docstring); each must be > 0."""

    radial: float = 1.0
    tangential: float = 1.0
    normal: float = 1.0
    radial_rate: float = 1.0
    tangential_rate: float = 1.0
    normal_rate: float = 1.0
    attitude: float = 1.0
    attitude_rate: float = 1.0
    coil: float = 1.0
    wheel: float = 1.0

    def __post_init__(self) -> None:
        for name in WEIGHT_NAMES:
            value = getattr(self, name)
            if not (isinstance(value, int | float) and math.isfinite(value) and value > 0.0):
                raise ControllerError(f"LQR weight {name} must be a positive number, got {value!r}")


def rotation_vector(dcm: np.ndarray) -> np.ndarray:
    """The rotation vector θ (rad) of a rotation matrix: C = exp([θ×]) (|θ| < π)."""
    vee = 0.5 * np.array([dcm[2, 1] - dcm[1, 2], dcm[0, 2] - dcm[2, 0], dcm[1, 0] - dcm[0, 1]])
    s = float(np.linalg.norm(vee))
    c = 0.5 * (float(np.trace(dcm)) - 1.0)
    angle = math.atan2(s, c)
    return vee * (angle / s if s > 1e-12 else 1.0)


def _rot_z(angle: float) -> np.ndarray:
    c, s = math.cos(angle), math.sin(angle)
    return np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])


class LqrFormationController:
    """LQR about the steady spin of ``vehicles`` (with ``wheel_axes_body`` per vehicle, (3, n) columns) at
    ``places_m`` (N, 3; about the centre of mass at t = 0) turning at ``rate_rad_s`` about the frame z
    (module docstring). ``step(t_s, measurements)`` returns every vehicle's command."""

    def __init__(self, vehicles: Sequence[ControlledVehicle], wheel_axes_body: Sequence[np.ndarray],
                 places_m: np.ndarray, rate_rad_s: float, weights: LqrWeights) -> None:
        if len(vehicles) < 2:
            raise ControllerError(f"an array needs at least two vehicles, got {len(vehicles)}")
        self.rate = check_gain(abs(rate_rad_s), "rate_rad_s", 1e-9, 10.0) * math.copysign(1.0, rate_rad_s)
        self.vehicles = tuple(vehicles)
        linear = [LinearVehicle(v.name, v.mass_kg, v.inertia_kg_m2, v.coil_axes_body, np.asarray(w, dtype=float))
                  for v, w in zip(vehicles, wheel_axes_body, strict=True)]
        self.nominal = spin_nominal(linear, places_m, self.rate)
        self.model = SpinningArrayModel(linear, self.nominal)
        self.a, self.b = self.model.reduced()
        self.q, self.r = self.weight_matrices(weights)
        self.k, _ = lqr_gain(self.a, self.b, self.q, self.r)
        self.to_reduced = self.model.relative_transform()[6:]

    def weight_matrices(self, w: LqrWeights) -> tuple[np.ndarray, np.ndarray]:
        """(Q, R) from the dimensionless weights (module docstring)."""
        nom, n = self.nominal, len(self.vehicles)
        m = 3 * (n - 1)
        q = np.zeros((self.a.shape[0],) * 2)
        omega = abs(nom.rate_rad_s)
        for i in range(1, n):
            rho = nom.places_m[i] - nom.places_m[0]
            d = float(np.linalg.norm(rho))
            e_r = np.array([rho[0], rho[1], 0.0]) / max(math.hypot(rho[0], rho[1]), 1e-300)
            e_t = np.cross(_Z, e_r)
            block = (w.radial * np.outer(e_r, e_r) + w.tangential * np.outer(e_t, e_t) + w.normal * np.outer(_Z, _Z))
            rates = (w.radial_rate * np.outer(e_r, e_r) + w.tangential_rate * np.outer(e_t, e_t)
                     + w.normal_rate * np.outer(_Z, _Z))
            at = 3 * (i - 1)
            q[at:at + 3, at:at + 3] = block / d ** 2
            at_v = m + 3 * n + at
            q[at_v:at_v + 3, at_v:at_v + 3] = rates / (omega * d) ** 2
        q[m:m + 3 * n, m:m + 3 * n] = w.attitude * np.eye(3 * n)
        q[2 * m + 3 * n:, 2 * m + 3 * n:] = w.attitude_rate * np.eye(3 * n) / omega ** 2
        scales = []
        for k, v in enumerate(self.vehicles):
            scales += [float(np.linalg.norm(nom.dipoles_am2[k])) / math.sqrt(w.coil)] * v.coil_axes_body.shape[1]
            torque = max(omega * float(np.linalg.norm(nom.wheel_h_nms[k])), 1e-9)
            scales += [torque / math.sqrt(w.wheel)] * self.model.input_sizes[k][1]
        return q, np.diag(1.0 / np.array(scales) ** 2)

    def state(self, t_s: float, measurements: Sequence[Measurement]) -> np.ndarray:
        """The reduced deviation state x at ``t_s`` (module docstring)."""
        turn = _rot_z(self.rate * t_s)
        omega = self.rate * _Z
        sigma, u, dtheta, domega = [], [], [], []
        for ms, v in zip(measurements, self.vehicles, strict=True):
            s = turn.T @ as_vector3(ms.position_m, f"{v.name} position_m")
            sigma.append(s)
            u.append(turn.T @ as_vector3(ms.velocity_m_s, f"{v.name} velocity_m_s") - np.cross(omega, s))
            c = np.asarray(ms.body_to_inertial, dtype=float)
            dtheta.append(rotation_vector(turn.T @ c))
            domega.append(as_vector3(ms.omega_body_rad_s, f"{v.name} omega_body_rad_s") - c.T @ turn @ omega)
        full = np.concatenate([np.ravel(sigma), np.ravel(u), np.ravel(dtheta), np.ravel(domega)])
        return self.to_reduced @ (full - self.model.nominal_state())

    def step(self, t_s: float, measurements: Sequence[Measurement]) -> list[VehicleCommand]:
        """Every vehicle's command over [t_s, t_s + control period]: u = u_nom − K x."""
        if len(measurements) != len(self.vehicles):
            raise ControllerError(f"need the measurements of all {len(self.vehicles)} vehicles, got {len(measurements)}")
        du = -self.k @ self.state(t_s, measurements)
        turn = _rot_z(self.rate * t_s)
        commands, at = [], 0
        for k, (ms, v) in enumerate(zip(measurements, self.vehicles, strict=True)):
            nc, nw = self.model.input_sizes[k]
            moments = v.coil_axes_body.T @ self.nominal.dipoles_am2[k] + du[at:at + nc]
            moments = np.clip(moments, -v.coil_max_dipole_am2, v.coil_max_dipole_am2)
            wheel_axes = self.model.vehicles[k].wheel_axes_body
            wheel = wheel_axes @ (wheel_axes.T @ self.nominal.wheel_hdot_nm[k] + du[at + nc:at + nc + nw])
            at += nc + nw
            dip_body = v.coil_axes_body @ moments
            rot = np.asarray(ms.body_to_inertial, dtype=float)
            force = turn @ (-v.mass_kg * self.rate ** 2 * self.nominal.places_m[k] * np.array([1.0, 1.0, 0.0]))
            commands.append(VehicleCommand(dip_body, moments, wheel, force, rot @ dip_body, False))
        return commands
