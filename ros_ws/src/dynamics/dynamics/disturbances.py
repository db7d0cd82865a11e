"""Body-fixed disturbance torques of the AAP Workshop that build the CMG bias momentum (seed 000 §1, §5).

Seed: ``000_aap_cmg_dump_levidow.txt``. "Gravity gradient and aerodynamic torques acting on the AAP
Workshop are counteracted by the momentum exchange action of the control moment gyros" (§1); their
*bias* components accumulate in the CMGs orbit after orbit and must be dumped, their *cyclic*
components only make the CMG momentum swing between the once-per-orbit samples (§5). The vehicle is
inertially stabilised (§2), so in body axes the orbit normal is fixed and the Earth direction turns
once per orbit: every torque is a constant plus harmonics of the orbital rate.

Physical sources per attitude mode (§5, Fig. 3; per-orbit bias momenta in vehicle axes, ft-lb-sec):

* POP, long (x) axis perpendicular to the orbital plane, H_b = (0, 0, −255): mostly the bias
  aerodynamic torque from the diurnal bulge (the atmosphere's day-side density bulge makes the drag
  torque over an orbit not average out; 225 ft-lb-sec per orbit from Bellcomm's aerodynamic model
  with the sun in the orbital plane) plus the gravity-gradient bias of the misalignment between
  principal and geometric axes (reduced to 30 ft-lb-sec by a small Z-axis maneuver); both lie in the
  orbital plane. With principal axes exactly aligned the gravity-gradient bias of this attitude is
  zero (see :func:`gravity_gradient_inertial_hold`).
* IOP, long axis in the orbital plane, telescope 45° out of the plane to a star, sun in the plane,
  H_b = (575, 160, −160): an aerodynamic bias perpendicular to the orbital plane (|(0, 160, −160)|
  = 226 ft-lb-sec) and a gravity-gradient bias in the plane, along x (575).
* 45° OP, z in the orbital plane, x 45° out of it, H_b = (0, 0, 19000): gravity gradient (the
  upper limit of its bias), aerodynamic bias negligible.

The orbit normal in body axes follows from those statements (:data:`MODE_GEOMETRY`), and the exact
gravity-gradient bias of an inertially held body, −(3n²/2)·n̂ × (I n̂) per unit time, then gives
(3π/2)·n·(I_z − I_y) = 573 ft-lb-sec along x for IOP and (3π/2)·n·(I_y − I_x) = 18,500 ft-lb-sec
along z for 45° OP with the Second Workshop inertias on the 220 nmi orbit — the seed's 575 and
19,000 within its rounding (its §12 writes the latter 0.0665 (I_z − I_x)/12.5 = 19,080; I_y ≈ I_z).
The seed gives no cyclic aerodynamic torque; the cyclic parts here are the exact gravity-gradient
ones (twice orbital rate).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from acds_common import units

from dynamics.errors import DynamicsError, finite_float, finite_vector3

#: Second Workshop principal moments of inertia I_x, I_y, I_z, slug-ft² (§5, "calculated by W. W. Hough").
WORKSHOP_INERTIA_SLUG_FT2 = (634_400.0, 4_112_900.0, 4_220_600.0)
#: Per-orbit bias momentum H_b per attitude mode in vehicle axes, ft-lb-sec (§5 table).
SEED_BIAS_MOMENTUM_FTLBS: dict[str, tuple[float, float, float]] = {
    'pop': (0.0, 0.0, -255.0),
    'iop': (575.0, 160.0, -160.0),
    '45op': (0.0, 0.0, 19000.0),
}
_R2 = 1.0 / math.sqrt(2.0)


@dataclass(frozen=True)
class ModeGeometry:
    """Inertial attitude of a mode relative to the orbit, in body axes (unit vectors).

    ``orbit_normal_body``: the orbit's angular-momentum direction; ``node_body``: the body direction
    of the ascending node (where the vehicle is at argument of latitude 0), perpendicular to it.
    """

    orbit_normal_body: tuple[float, float, float]
    node_body: tuple[float, float, float]

    def __post_init__(self) -> None:
        n = finite_vector3('ModeGeometry.orbit_normal_body', self.orbit_normal_body)
        e = finite_vector3('ModeGeometry.node_body', self.node_body)
        if abs(np.linalg.norm(n) - 1.0) > 1e-9 or abs(np.linalg.norm(e) - 1.0) > 1e-9 or abs(n @ e) > 1e-9:
            raise DynamicsError('ModeGeometry needs orthonormal orbit_normal_body and node_body, got '
                                f'{n.tolist()} and {e.tolist()}')

    def in_plane_axes(self) -> tuple[np.ndarray, np.ndarray]:
        """(ê1, ê2) in body axes: ê1 toward the ascending node, ê2 = n̂ × ê1 (90° further along the orbit)."""
        n, e1 = np.array(self.orbit_normal_body), np.array(self.node_body)
        return e1, np.cross(n, e1)

    def body_to_eci_dcm(self, inclination_rad: float, raan_rad: float) -> np.ndarray:
        """Body → ECI rotation holding this geometry on an orbit of that inclination and node (columns = body axes)."""
        i, o = finite_float('inclination_rad', inclination_rad), finite_float('raan_rad', raan_rad)
        node = np.array([math.cos(o), math.sin(o), 0.0])
        normal = np.array([math.sin(o) * math.sin(i), -math.cos(o) * math.sin(i), math.cos(i)])
        eci = np.column_stack([node, np.cross(normal, node), normal])
        e1, e2 = self.in_plane_axes()
        body = np.column_stack([e1, e2, np.array(self.orbit_normal_body)])
        return eci @ body.T


#: Mode attitudes (body axes = principal axes). Orbit normals from §5: POP x ⟂ plane; IOP: the
#: aerodynamic bias (0, 160, −160) is ⟂ the plane, so n̂ = (0, 1, −1)/√2 (x in the plane, telescope
#: 45° out); 45° OP: z in the plane, x 45° out of it, n̂ = (1, −1, 0)/√2 (the sign pair that gives the
#: +z gravity-gradient bias of the table). The node direction only phases the cyclic torque (not in
#: the seed): POP y, IOP x (long axis), 45° OP z at the ascending node.
MODE_GEOMETRY: dict[str, ModeGeometry] = {
    'pop': ModeGeometry((1.0, 0.0, 0.0), (0.0, 1.0, 0.0)),
    'iop': ModeGeometry((0.0, _R2, -_R2), (1.0, 0.0, 0.0)),
    '45op': ModeGeometry((_R2, -_R2, 0.0), (0.0, 0.0, 1.0)),
}


@dataclass(frozen=True)
class Harmonic:
    """One harmonic of orbital rate: cos_nm·cos(kθ) + sin_nm·sin(kθ), N·m, body axes (θ = n (t − t_node))."""

    order: int
    cos_nm: tuple[float, float, float]
    sin_nm: tuple[float, float, float]

    def __post_init__(self) -> None:
        if int(self.order) != self.order or self.order < 1:
            raise DynamicsError(f'Harmonic.order must be an integer >= 1, got {self.order!r}')
        finite_vector3('Harmonic.cos_nm', self.cos_nm)
        finite_vector3('Harmonic.sin_nm', self.sin_nm)


@dataclass(frozen=True)
class DisturbanceTorque:
    """Body-fixed disturbance torque T(t) = constant + Σ harmonics of orbital rate, N·m.

    ``orbit_rate_rad_s``: mean motion n; ``node_time_s``: a time at which the vehicle is at the
    ascending node (θ = 0). Over any whole orbit the harmonics integrate to zero, so the momentum
    delivered per orbit is exactly ``constant_nm`` × 2π/n.
    """

    constant_nm: tuple[float, float, float]
    harmonics: tuple[Harmonic, ...]
    orbit_rate_rad_s: float
    node_time_s: float = 0.0

    def __post_init__(self) -> None:
        finite_vector3('DisturbanceTorque.constant_nm', self.constant_nm)
        if finite_float('DisturbanceTorque.orbit_rate_rad_s', self.orbit_rate_rad_s) <= 0.0:
            raise DynamicsError(f'DisturbanceTorque.orbit_rate_rad_s must be > 0, got {self.orbit_rate_rad_s}')
        finite_float('DisturbanceTorque.node_time_s', self.node_time_s)

    @property
    def period_s(self) -> float:
        """Orbit period 2π/n, s."""
        return 2.0 * math.pi / self.orbit_rate_rad_s

    def torque_body_nm(self, t_s: float) -> np.ndarray:
        """T(t), N·m, body axes."""
        theta = self.orbit_rate_rad_s * (finite_float('t_s', t_s) - self.node_time_s)
        out = np.array(self.constant_nm, dtype=float)
        for h in self.harmonics:
            out += np.array(h.cos_nm) * math.cos(h.order * theta) + np.array(h.sin_nm) * math.sin(h.order * theta)
        return out

    def momentum_nms(self, t0_s: float, t1_s: float) -> np.ndarray:
        """∫ T dt from ``t0_s`` to ``t1_s`` in closed form, N·m·s."""
        n = self.orbit_rate_rad_s
        a = n * (finite_float('t0_s', t0_s) - self.node_time_s)
        b = n * (finite_float('t1_s', t1_s) - self.node_time_s)
        out = np.array(self.constant_nm, dtype=float) * (t1_s - t0_s)
        for h in self.harmonics:
            k = h.order
            out += (np.array(h.cos_nm) * (math.sin(k * b) - math.sin(k * a))
                    - np.array(h.sin_nm) * (math.cos(k * b) - math.cos(k * a))) / (k * n)
        return out


def workshop_inertia_kg_m2() -> np.ndarray:
    """Second Workshop principal inertia tensor (§5), kg·m²."""
    return np.diag([units.slugft2_to_kgm2(i) for i in WORKSHOP_INERTIA_SLUG_FT2])


def gravity_gradient_inertial_hold(inertia_kg_m2: np.ndarray, geometry: ModeGeometry, orbit_rate_rad_s: float,
                                   node_time_s: float = 0.0) -> DisturbanceTorque:
    """Exact gravity-gradient torque of an inertially held body on a circular orbit, as bias + 2nd harmonic.

    With r̂ = cos θ ê1 + sin θ ê2 in body axes and μ/r³ = n², T = 3n² r̂ × (I r̂) (spec §3) splits into
    (3n²/2)[(ê1×Iê1 + ê2×Iê2) + cos 2θ (ê1×Iê1 − ê2×Iê2) + sin 2θ (ê1×Iê2 + ê2×Iê1)]; the bias equals
    −(3n²/2) n̂ × (I n̂), zero when the orbit normal is a principal axis.
    """
    inertia = np.asarray(inertia_kg_m2, dtype=float)
    if inertia.shape != (3, 3) or not np.all(np.isfinite(inertia)):
        raise DynamicsError(f'inertia_kg_m2 must be a finite 3×3 matrix, got shape {inertia.shape}')
    n = finite_float('orbit_rate_rad_s', orbit_rate_rad_s)
    e1, e2 = geometry.in_plane_axes()
    g = 1.5 * n * n

    def f(a: np.ndarray, b: np.ndarray) -> np.ndarray:
        return np.cross(a, inertia @ b)

    bias = g * (f(e1, e1) + f(e2, e2))
    second = Harmonic(2, tuple(g * (f(e1, e1) - f(e2, e2))), tuple(g * (f(e1, e2) + f(e2, e1))))
    return DisturbanceTorque(tuple(bias), (second,), n, node_time_s)


def seed_disturbance(mode: str, orbit_rate_rad_s: float, *, rigid_body_gravity_gradient: bool,
                     inertia_kg_m2: np.ndarray | None = None, node_time_s: float = 0.0) -> DisturbanceTorque:
    """The body-fixed torque input that makes the per-orbit bias momentum exactly the seed's H_b (§5 table).

    ``mode``: 'pop' | 'iop' | '45op' (attitude of :data:`MODE_GEOMETRY`). With
    ``rigid_body_gravity_gradient=False`` the body model adds no gravity gradient, so this torque is
    the whole disturbance: constant H_b/T plus the mode's exact cyclic gravity-gradient torque. With
    ``True`` the body model computes gravity gradient itself (its bias and cyclic parts), so this
    torque is only the rest of the seed's bias, (H_b − H_gg,bias)/T, constant (the aerodynamic bias
    and, for POP, the axis-misalignment gravity-gradient bias). Either way the total momentum over
    one orbit of held attitude is H_b.
    """
    if mode not in SEED_BIAS_MOMENTUM_FTLBS:
        raise DynamicsError(f'mode must be one of {tuple(SEED_BIAS_MOMENTUM_FTLBS)}, got {mode!r}')
    inertia = workshop_inertia_kg_m2() if inertia_kg_m2 is None else np.asarray(inertia_kg_m2, dtype=float)
    gg = gravity_gradient_inertial_hold(inertia, MODE_GEOMETRY[mode], orbit_rate_rad_s, node_time_s)
    h_b = units.ftlbs_to_nms(np.array(SEED_BIAS_MOMENTUM_FTLBS[mode]))
    bias_rate = h_b / gg.period_s
    if rigid_body_gravity_gradient:
        return DisturbanceTorque(tuple(bias_rate - np.array(gg.constant_nm)), (), gg.orbit_rate_rad_s, node_time_s)
    return DisturbanceTorque(tuple(bias_rate), gg.harmonics, gg.orbit_rate_rad_s, node_time_s)
