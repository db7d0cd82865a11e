"""Electromagnetic formation flight: N rigid vehicles pushing on each other with their coils (spec §10).

Seed 004 (MIT SSL / Lockheed Martin EMFF final review, 2003). What is modelled, and from where:

* Vehicles (slide 10 "EMFF Vehicle Conceptual Model"): rigid bodies with body-fixed coils (their
  dipoles add as vectors in the far field) and reaction wheels that store what the electromagnetic
  torques put in. Each vehicle has a mass, a full inertia tensor, coils and (outside this core, as in
  the single-vehicle graph) a wheel assembly whose momentum h and rate ḣ come in per step.
* Frames (``FRAMES``):
  - ``planar``: the EMFFORCE air-bearing testbed, "2-D friction-less environment provided by gas
    carriage" (slide 74): x, y and yaw only. The table reacts everything out of the plane (the z
    force, the roll and pitch torques), so a planar state stays planar.
  - ``free_space``: 3-D translation and attitude in an inertial frame with no external field.
  - ``line``: the 1-D airtrack (slides 52–55): every vehicle sits on the frame x axis (the track) and
    moves only along it; the track's air bearing and rails react everything else (the y and z forces,
    every torque), so y, z, the velocities across the track, the attitude and the body rates stay as
    they started (on the axis, at rest across it, rates zero). The track is tilted by ``track_tilt_rad``
    (> 0 rising along +x): every free vehicle feels gravity −g sin θ along x. A ``fixed`` vehicle (the
    airtrack's electromagnet, bolted to the track's end) does not move at all: its mount takes the
    magnetic force on it, which its truth still reports. Momentum is not conserved (track, mount and
    gravity are external).
  - ``hill``: relative motion about a circular LEO reference orbit by Hill's (Clohessy–Wiltshire)
    equations (slide 63 "'Stationary' Orbits"; x radial out, y along track, z along the orbit normal):

        ẍ = 3n²x + 2nẏ + a_x,   ÿ = −2nẋ + a_y,   z̈ = −n²z + a_z,

    n the reference mean motion; attitude is integrated in ECI (body → ECI quaternions, the project
    convention). Positions for the Earth's field and gravity gradient are r_ref(t) + R_ECI←Hill ρ.
* Inter-vehicle force and torque from every pair, from the vehicles' dipoles — each vehicle's coils'
  achieved dipole plus its permanent magnet (``VehicleSpec.permanent_dipole_body_am2``: a constant body
  dipole and no coil, the airtrack slider's magnet; far field only, a point dipole):
  ``far_field`` (default) the exact dipole–dipole wrench (``acds_common.dipole_field``, slides
  12–13); ``near_field`` the Biot–Savart wrench of the actual coils (``dynamics.biot_savart``), with
  Newton's third law applied pairwise (F_A = −F_B, τ_A = −τ_B − r_AB × F_B) so the internal wrenches
  conserve momentum exactly at any segment count.
* The Earth's field (``hill`` frame, optional, an injected callable b_eci(r_eci_m, t_s) → T such as
  ``acds_common.environment.TiltedDipoleField.b_eci``): torque μ × B on every dipole and the force
  ∇(μ·B) by central differences of the callable (step ``EARTH_GRADIENT_STEP_FRACTION``·|r|) —
  slide 30: "an insignificant disturbance force, but a very significant disturbance torque"; the
  force is computed and applied, not dropped. Gravity-gradient torque on each vehicle is optional
  (``gravity_gradient``), from ``rigid_body_model.gravity_gradient_torque_nm``.
* Rotational equations per vehicle (body axes), as in ``rigid_body_model``:
  I ω̇ = −ω × (I ω + h) − ḣ + τ_EM + τ_Earth + τ_gg, q̇ = ½ q ⊗ (ω, 0), with h(τ) = h0 + ḣ·τ over
  the step. In ``planar`` the table keeps ω along z and d(I_zz ω_z + h_z)/dt = τ_z.
* Integration: fixed-step RK4 (``dynamics.integrator.rk4_step``, as the rigid body's), ``substeps`` per
  ``advance`` call, deterministic (no randomness, fixed evaluation order); quaternions renormalised
  after each substep.
* Momentum bookkeeping (``FormationDynamics.momentum``): in ``free_space`` the total linear momentum
  Σ m v and angular momentum Σ (r × m v + R (I ω + h)) about the origin are constants of the motion
  (slide 3: "only internal forces are present"; slide 18: "angular momentum conserved by shearing of
  the system"); in ``planar`` their in-plane parts (p_x, p_y, L_z).

EMFFORCE testbed (slides 69–78), SI, as data (``EMFFORCE_*`` constants, ``emfforce_vehicle``):

* 2 identical self-contained vehicles of 19 kg, each with 2 electromagnets and 1 reaction wheel
  (slide 70).
* Electromagnets (slide 71): 100 wraps, radii 0.375 m and 0.345 m, American Superconductor Bi-2223
  HTS wire at 77 K in liquid nitrogen, critical current 115 A; driven up to ~100 A ("Coil: 100 Amps
  @ 5 Volts", slide 73). Interpretation: the two coils are orthogonal, nested (hence the two radii)
  and vertical, their axes along body x and y, so the dipole is steerable in the plane of motion
  (slide 76: "used vehicle's ability to steer the dipole"); both centred on the vehicle's centre of
  mass. Max dipole per coil N I π R²: 4418 A·m² (outer), 3739 A·m² (inner).
* Reaction wheel (slide 74): about the vertical (body z) axis, 0.1 N·m at 10 A (torque constant
  0.01 N·m/A), 7000 rpm maximum. The seed gives no wheel inertia, so no momentum capacity is
  assumed (``TorqueWheels`` takes one if known).
* Yaw inertia: not in the seed. ``EMFFORCE_YAW_INERTIA_KG_M2`` is an estimate (a uniform 19 kg disc of
  the outer coil radius, ½ m R² = 1.34 kg·m²), flagged here; replace it with a measured value.
* Sensors (slide 70), the models a sensor node would use (not in this core): a rate gyro about the
  vertical axis — yaw rate plus a constant bias and white noise (angle random walk), sampled at the
  control period; ultrasonic metrology — 3 US receivers per vehicle synchronised by IR pulses:
  each beacon-to-receiver range is c_sound·(time of flight), c_sound = 331.3 √(1 + T/273.15) m/s,
  with Gaussian range noise of a few mm and occasional multipath outliers, and the vehicle's x, y,
  yaw from trilateration of its 3 receivers.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np
from acds_common import units
from acds_common.attitude import dcm, quat_rates, quat_to_dcm
from acds_common.dipole_field import cross3, dipole_pair_wrench
from acds_common.environment import Orbit, hill_frame

from dynamics import biot_savart
from dynamics.errors import DynamicsError, finite_float, finite_vector3
from dynamics.integrator import rk4_step
from dynamics.rigid_body_model import DEFAULT_SUBSTEPS, gravity_gradient_torque_nm, inertia_tensor

#: Frames of relative motion (see the module docstring).
FRAMES = ("planar", "free_space", "hill", "line")
#: Inter-vehicle electromagnetic models.
EM_MODELS = ("far_field", "near_field")
#: Central-difference step of the Earth-field gradient, as a fraction of the geocentric radius
#: (truncation error ~ (1e-4)² relative, rounding ~ 1e-13 relative).
EARTH_GRADIENT_STEP_FRACTION = 1e-4
#: Most a vehicle may turn in one RK4 substep (rad): beyond it the integration is refused, not trusted
#: (RK4's stability limit on a rotation is ~2.8 rad per step; 0.5 rad keeps its error below ~1e-4).
MAX_TURN_PER_SUBSTEP_RAD = 0.5

#: EMFFORCE vehicle mass, kg (slide 70).
EMFFORCE_MASS_KG = 19.0
#: EMFFORCE electromagnet wraps (slide 71).
EMFFORCE_COIL_TURNS = 100
#: EMFFORCE electromagnet radii, m: outer coil (body x), inner coil (body y) (slide 71).
EMFFORCE_COIL_RADII_M = (0.375, 0.345)
#: EMFFORCE coil current limit, A (slide 73 "Coil: 100 Amps @ 5 Volts"; slide 70 "up to ~100 A").
EMFFORCE_COIL_MAX_CURRENT_A = 100.0
#: Bi-2223 HTS critical current below 110 K, A (slide 71).
EMFFORCE_HTS_CRITICAL_CURRENT_A = 115.0
#: EMFFORCE reaction wheel torque limit, N·m (slide 74 "0.1 Nm Torque at 10 Amps").
EMFFORCE_WHEEL_MAX_TORQUE_NM = 0.1
#: EMFFORCE wheel motor torque constant, N·m/A (slide 74: 0.1 N·m at 10 A).
EMFFORCE_WHEEL_TORQUE_CONSTANT_NM_PER_A = 0.01
#: EMFFORCE wheel speed limit, rad/s (slide 74 "Maximum wheel velocity at 7000 RPM").
EMFFORCE_WHEEL_MAX_SPEED_RAD_S = units.rpm_to_rad_s(7000.0)
#: EMFFORCE yaw inertia, kg·m²: NOT IN THE SEED — estimate ½ m R² of a 19 kg disc of the outer coil radius.
EMFFORCE_YAW_INERTIA_KG_M2 = 0.5 * EMFFORCE_MASS_KG * EMFFORCE_COIL_RADII_M[0] ** 2


# --------------------------------------------------------------------------------------- vehicles


@dataclass(frozen=True)
class Coil:
    """A body-fixed circular electromagnet: ``axis_body`` (unit; right-handed current), ``radius_m``,
    ``turns``, ``max_current_a``. Centred on the vehicle's centre of mass."""

    axis_body: np.ndarray
    radius_m: float
    turns: int
    max_current_a: float

    def __post_init__(self) -> None:
        a = finite_vector3("Coil.axis_body", self.axis_body)
        if abs(float(np.linalg.norm(a)) - 1.0) > 1e-9:
            raise DynamicsError(f"Coil.axis_body must be a unit vector, got {a.tolist()}")
        object.__setattr__(self, "axis_body", a)
        for name in ("radius_m", "max_current_a"):
            if not finite_float(f"Coil.{name}", getattr(self, name)) > 0.0:
                raise DynamicsError(f"Coil.{name} must be > 0, got {getattr(self, name)}")
        if int(self.turns) != self.turns or self.turns < 1:
            raise DynamicsError(f"Coil.turns must be a positive integer, got {self.turns!r}")

    @property
    def area_m2(self) -> float:
        """Enclosed area π R², m²."""
        return math.pi * self.radius_m ** 2

    @property
    def max_dipole_am2(self) -> float:
        """Largest dipole N I_max π R², A·m²."""
        return self.turns * self.max_current_a * self.area_m2


@dataclass(frozen=True)
class VehicleSpec:
    """One vehicle: ``name``, ``mass_kg``, ``inertia_kg_m2`` (3×3, body axes), ``coils`` (orthonormal
    axes, so a body dipole splits uniquely into coil moments; none for a permanent magnet only),
    ``permanent_dipole_body_am2`` (A·m², body axes, constant: a permanent magnet), ``fixed`` (frame
    ``line`` only: held in place by its mount)."""

    name: str
    mass_kg: float
    inertia_kg_m2: np.ndarray
    coils: tuple[Coil, ...]
    permanent_dipole_body_am2: np.ndarray = field(default_factory=lambda: np.zeros(3))
    fixed: bool = False

    def __post_init__(self) -> None:
        if not finite_float(f"{self.name}.mass_kg", self.mass_kg) > 0.0:
            raise DynamicsError(f"{self.name}.mass_kg must be > 0 kg, got {self.mass_kg}")
        inertia = np.asarray(self.inertia_kg_m2, dtype=float)
        if inertia.shape != (3, 3) or not np.allclose(inertia, inertia.T, rtol=1e-12, atol=0.0):
            raise DynamicsError(f"{self.name}.inertia_kg_m2 must be a symmetric 3x3 matrix")
        inertia_tensor(inertia[0, 0], inertia[1, 1], inertia[2, 2], -inertia[0, 1], -inertia[0, 2], -inertia[1, 2])
        object.__setattr__(self, "inertia_kg_m2", inertia)
        permanent = finite_vector3(f"{self.name}.permanent_dipole_body_am2", self.permanent_dipole_body_am2)
        object.__setattr__(self, "permanent_dipole_body_am2", permanent)
        if not self.coils and not np.any(permanent):
            raise DynamicsError(f"{self.name} needs at least one coil or a permanent magnet")
        axes = self.coil_axes_body
        if not np.allclose(axes.T @ axes, np.eye(len(self.coils)), atol=1e-9):
            raise DynamicsError(f"{self.name}: coil axes must be orthonormal, got {axes.T.tolist()}")

    @property
    def coil_axes_body(self) -> np.ndarray:
        """Coil axes as columns (3, n_coils), body axes."""
        return np.stack([c.axis_body for c in self.coils], axis=1) if self.coils else np.zeros((3, 0))

    def with_magnet(self, coils_dipole_body_am2: np.ndarray) -> np.ndarray:
        """The vehicle's whole body dipole (A·m²): its coils' plus its permanent magnet's (the coils' as they are,
        signed zeros kept, when it has none)."""
        if np.any(self.permanent_dipole_body_am2):
            return coils_dipole_body_am2 + self.permanent_dipole_body_am2
        return coils_dipole_body_am2

    def coil_moments_am2(self, dipole_body_am2: np.ndarray) -> np.ndarray:
        """Split a body dipole (A·m²) into the coils' signed moments; DynamicsError if the dipole has a
        component no coil can make (more than 1e-9 of its size)."""
        mu = finite_vector3(f"{self.name} dipole_body_am2", dipole_body_am2)
        axes = self.coil_axes_body
        moments = axes.T @ mu
        if np.linalg.norm(mu - axes @ moments) > 1e-9 * max(float(np.linalg.norm(mu)), 1.0):
            raise DynamicsError(f"{self.name}: dipole {mu.tolist()} A·m² is outside the span of its coils "
                                f"{axes.T.tolist()}")
        return moments


def emfforce_vehicle(name: str) -> VehicleSpec:
    """An EMFFORCE testbed vehicle (slides 70–74; see the module docstring for the interpretation)."""
    inertia = np.diag([EMFFORCE_YAW_INERTIA_KG_M2 / 2.0, EMFFORCE_YAW_INERTIA_KG_M2 / 2.0, EMFFORCE_YAW_INERTIA_KG_M2])
    coils = tuple(Coil(axis, r, EMFFORCE_COIL_TURNS, EMFFORCE_COIL_MAX_CURRENT_A)
                  for axis, r in zip(np.eye(3)[:2], EMFFORCE_COIL_RADII_M, strict=True))
    return VehicleSpec(name, EMFFORCE_MASS_KG, inertia, coils)


@dataclass(frozen=True)
class VehicleState:
    """Initial state of one vehicle: position (m) and velocity (m/s) in the formation frame (Hill
    frame: relative to the reference orbit, velocity relative to the rotating frame), attitude
    quaternion (x, y, z, w) body → inertial (ECI for ``hill``), body rates (rad/s)."""

    position_m: Sequence[float] = (0.0, 0.0, 0.0)
    velocity_m_s: Sequence[float] = (0.0, 0.0, 0.0)
    q_body_to_inertial: Sequence[float] = (0.0, 0.0, 0.0, 1.0)
    omega_body_rad_s: Sequence[float] = (0.0, 0.0, 0.0)


@dataclass(frozen=True)
class VehicleInput:
    """What one vehicle's actuators do over a step: achieved dipole (A·m², body axes, constant over the
    step), wheel momentum at the step start (N·m·s, body) and its rate (N·m, body; the body feels −ḣ)."""

    dipole_body_am2: Sequence[float] = (0.0, 0.0, 0.0)
    wheel_h_body_nms: Sequence[float] = (0.0, 0.0, 0.0)
    wheel_hdot_body_nm: Sequence[float] = (0.0, 0.0, 0.0)


@dataclass(frozen=True)
class FormationConfig:
    """``frame`` (FRAMES), ``em_model`` (EM_MODELS), ``segments`` per coil for the near field,
    ``substeps`` RK4 substeps per ``advance``; for ``hill``: ``orbit`` (circular ``Orbit``, the
    reference), ``earth_field`` (callable b_eci(r_eci_m, t_s) → T, or None), ``gravity_gradient``;
    for ``line``: ``track_tilt_rad`` (signed, > 0 rising along +x)."""

    frame: str = "planar"
    em_model: str = "far_field"
    segments: int = biot_savart.DEFAULT_SEGMENTS
    substeps: int = DEFAULT_SUBSTEPS
    orbit: Orbit | None = None
    earth_field: Callable[[np.ndarray, float], np.ndarray] | None = None
    gravity_gradient: bool = False
    track_tilt_rad: float = 0.0

    def __post_init__(self) -> None:
        if self.frame not in FRAMES:
            raise DynamicsError(f"FormationConfig.frame must be one of {FRAMES}, got {self.frame!r}")
        if self.em_model not in EM_MODELS:
            raise DynamicsError(f"FormationConfig.em_model must be one of {EM_MODELS}, got {self.em_model!r}")
        for name in ("segments", "substeps"):
            v = getattr(self, name)
            if int(v) != v or v < (3 if name == "segments" else 1):
                raise DynamicsError(f"FormationConfig.{name} must be a positive integer (segments >= 3), got {v!r}")
        if self.frame == "hill":
            if self.orbit is None or self.orbit.cfg.kind != "circular":
                raise DynamicsError("FormationConfig.frame 'hill' needs a circular reference orbit "
                                    "(Hill/Clohessy–Wiltshire equations, slide 63)")
        elif self.orbit is not None or self.earth_field is not None or self.gravity_gradient:
            raise DynamicsError(f"FormationConfig.frame {self.frame!r} has no orbit: orbit, earth_field and "
                                "gravity_gradient apply to frame 'hill' only")
        if not abs(finite_float("FormationConfig.track_tilt_rad", self.track_tilt_rad)) < math.pi / 2:
            raise DynamicsError(f"FormationConfig.track_tilt_rad must be within ±90°, got {self.track_tilt_rad} rad")
        if self.track_tilt_rad != 0.0 and self.frame != "line":
            raise DynamicsError(f"FormationConfig.track_tilt_rad is the airtrack's tilt (frame 'line'), got frame "
                                f"{self.frame!r}")


# -------------------------------------------------------------------------------------- wrenches


@dataclass(frozen=True)
class Wrenches:
    """Per-vehicle forces (N, formation frame) and torques (N·m, body axes) at one instant.

    ``em_*`` inter-vehicle; ``earth_*`` the Earth's field; ``gg_torque`` gravity gradient (zeros
    where not modelled). Arrays are (N, 3)."""

    em_force_n: np.ndarray
    em_torque_body_nm: np.ndarray
    earth_force_n: np.ndarray
    earth_torque_body_nm: np.ndarray
    gg_torque_body_nm: np.ndarray


@dataclass(frozen=True)
class VehicleTruth:
    """One vehicle's true state at ``FormationTruth.t_s`` (SI; formation frame unless named).

    ``yaw_rad`` is the rotation about the frame's z axis (the testbed's heading; meaningful in
    ``planar``). ``r_eci_m``/``v_eci_m_s``/``b_eci_t``/``b_body_t`` are None outside ``hill`` (field
    None without an Earth field). ``*_avg`` are step averages over the last ``advance`` (RK4 stage
    weights; zeros before the first)."""

    name: str
    position_m: np.ndarray
    velocity_m_s: np.ndarray
    q_body_to_inertial: np.ndarray
    omega_body_rad_s: np.ndarray
    yaw_rad: float
    r_eci_m: np.ndarray | None
    v_eci_m_s: np.ndarray | None
    b_eci_t: np.ndarray | None
    b_body_t: np.ndarray | None
    em_force_avg_n: np.ndarray
    em_torque_avg_body_nm: np.ndarray
    earth_force_avg_n: np.ndarray
    earth_torque_avg_body_nm: np.ndarray
    gg_torque_avg_body_nm: np.ndarray


@dataclass(frozen=True)
class FormationTruth:
    """Truth of the whole formation at ``t_s``: ``vehicles`` in spec order, ``hill_to_eci`` (3×3,
    columns the Hill axes in ECI; None outside ``hill``)."""

    t_s: float
    vehicles: tuple[VehicleTruth, ...]
    hill_to_eci: np.ndarray | None = field(default=None)


class FormationDynamics:
    """The formation's translational and rotational dynamics (module docstring), the time owner's core.

    ``vehicles`` and ``initial`` (one VehicleState each, same order); ``t0_s`` start time (s).
    ``advance(dt_s, inputs)`` integrates one control step; ``truth()`` and ``momentum(wheel_h)`` read
    the state.
    """

    def __init__(self, cfg: FormationConfig, vehicles: Sequence[VehicleSpec], initial: Sequence[VehicleState],
                 t0_s: float = 0.0) -> None:
        if len(vehicles) < 1 or len(vehicles) != len(initial):
            raise DynamicsError(f"need one VehicleState per vehicle: {len(vehicles)} vehicles, {len(initial)} states")
        names = [v.name for v in vehicles]
        if len(set(names)) != len(names):
            raise DynamicsError(f"vehicle names must be unique, got {names}")
        self.cfg = cfg
        self.vehicles = tuple(vehicles)
        self._mass = np.array([v.mass_kg for v in vehicles])
        self._inertia = np.stack([v.inertia_kg_m2 for v in vehicles])
        self._inertia_inv = np.linalg.inv(self._inertia)
        pos, vel, q, w = [], [], [], []
        for spec, s in zip(vehicles, initial, strict=True):
            pos.append(finite_vector3(f"{spec.name} position_m", s.position_m))
            vel.append(finite_vector3(f"{spec.name} velocity_m_s", s.velocity_m_s))
            qi = np.asarray(s.q_body_to_inertial, dtype=float)
            if qi.shape != (4,) or not np.all(np.isfinite(qi)) or np.linalg.norm(qi) < 1e-6:
                raise DynamicsError(f"{spec.name} q_body_to_inertial must be a finite non-zero (x, y, z, w), got {qi}")
            q.append(qi / np.linalg.norm(qi))
            w.append(finite_vector3(f"{spec.name} omega_body_rad_s", s.omega_body_rad_s))
        self._pos, self._vel, self._q, self._w = np.array(pos), np.array(vel), np.array(q), np.array(w)
        if cfg.frame == "planar":
            self._check_planar()
        self._fixed = np.array([v.fixed for v in vehicles])
        self._permanent = np.stack([v.permanent_dipole_body_am2 for v in vehicles])
        if cfg.frame == "line":
            self._check_line()
        elif np.any(self._fixed):
            raise DynamicsError("fixed vehicles are the airtrack's (frame 'line'), got frame " + repr(cfg.frame))
        if cfg.em_model == "near_field" and np.any(self._permanent):
            raise DynamicsError("a permanent magnet is a point dipole: em_model 'far_field' only")
        self._t = finite_float("t0_s", t0_s)
        self._pairs = [(i, j) for i in range(len(vehicles)) for j in range(i + 1, len(vehicles))]
        self._ii = np.array([i for i, _ in self._pairs], dtype=np.intp)  # each pair's first vehicle
        self._jj = np.array([j for _, j in self._pairs], dtype=np.intp)  # and its second
        # ``_sum_pairs``' plan: vehicle k's rows of the stacked pair terms (row p: pair p's term on its first
        # vehicle, row P + p: on its second), those as first vehicle then those as second, each in pair order;
        # as n − 1 index arrays, the m-th holding every vehicle's m-th row.
        n_pairs = len(self._pairs)
        rows = [[p for p, (i, _) in enumerate(self._pairs) if i == k]
                + [n_pairs + p for p, (_, j) in enumerate(self._pairs) if j == k] for k in range(len(vehicles))]
        self._pair_rows = tuple(np.array(term, dtype=np.intp) for term in zip(*rows, strict=True))
        self._check_contact()
        self._n_rad_s = cfg.orbit.mean_motion_rad_s if cfg.frame == "hill" else 0.0
        #: Gravity along the airtrack on every free vehicle (frame ``line``), m/s².
        self._track_gravity = -units.STANDARD_GRAVITY_M_S2 * math.sin(cfg.track_tilt_rad)
        zeros = np.zeros((len(vehicles), 3))
        self._avg = Wrenches(zeros, zeros, zeros, zeros, zeros)

    def _check_planar(self) -> None:
        for i, spec in enumerate(self.vehicles):
            tilt = quat_to_dcm(self._q[i])[:, 2]
            if (abs(self._pos[i, 2]) > 0.0 or abs(self._vel[i, 2]) > 0.0 or np.any(self._w[i, :2] != 0.0)
                    or np.linalg.norm(tilt - np.array([0.0, 0.0, 1.0])) > 1e-12):
                raise DynamicsError(f"{spec.name}: frame 'planar' needs z = 0, v_z = 0, body z along the frame z "
                                    "and rates about z only (the air-bearing table, slide 74)")
            if abs(self.vehicles[i].inertia_kg_m2[0, 2]) > 0.0 or abs(self.vehicles[i].inertia_kg_m2[1, 2]) > 0.0:
                raise DynamicsError(f"{spec.name}: frame 'planar' needs body z principal (Ixz = Iyz = 0)")

    def _check_line(self) -> None:
        for i, spec in enumerate(self.vehicles):
            if (np.any(self._pos[i, 1:] != 0.0) or np.any(self._vel[i, 1:] != 0.0) or np.any(self._w[i] != 0.0)
                    or (spec.fixed and self._vel[i, 0] != 0.0)):
                raise DynamicsError(f"{spec.name}: frame 'line' needs every vehicle on the track (y = z = 0), moving "
                                    "only along it (v_y = v_z = 0, rates zero) and a fixed vehicle at rest (slides 52–55)")

    def _check_contact(self) -> None:
        """Vehicles closer than the sum of their largest coil radii have collided: refuse to go on."""
        for i, j in self._pairs:
            sep = float(np.linalg.norm(self._pos[j] - self._pos[i]))
            reach = (max((c.radius_m for c in self.vehicles[i].coils), default=0.0)
                     + max((c.radius_m for c in self.vehicles[j].coils), default=0.0))
            if sep < reach:
                raise DynamicsError(f"vehicles {self.vehicles[i].name} and {self.vehicles[j].name} collided at "
                                    f"t = {self._t:.6g} s: separation {sep:.4g} m < {reach:.4g} m (sum of coil radii)")

    # ----------------------------------------------------------------------------- properties

    @property
    def t_s(self) -> float:
        """Current time, s."""
        return self._t

    @property
    def n_rad_s(self) -> float:
        """Reference mean motion n, rad/s (0 outside ``hill``)."""
        return self._n_rad_s

    def _hill_to_eci(self, t_s: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """(R_ECI←Hill, r_ref, v_ref) at ``t_s``: columns radial, along-track, orbit normal."""
        assert self.cfg.orbit is not None
        return hill_frame(self.cfg.orbit, t_s)

    # ---------------------------------------------------------------------------------- physics

    def _em_wrenches(self, pos: np.ndarray, dip_frame: np.ndarray,
                     to_frame: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Inter-vehicle forces and torques (N, N·m; both formation frame) from every pair."""
        n = len(self.vehicles)
        if not self._pairs:
            return np.zeros((n, 3)), np.zeros((n, 3))
        if self.cfg.em_model == "far_field":
            ii, jj = self._ii, self._jj
            f_a, t_a, f_b, t_b = dipole_pair_wrench(dip_frame.take(ii, axis=0), dip_frame.take(jj, axis=0),
                                                    pos.take(jj, axis=0) - pos.take(ii, axis=0))
            return self._sum_pairs(f_a, f_b), self._sum_pairs(t_a, t_b)
        force, torque = np.zeros((n, 3)), np.zeros((n, 3))
        nodes = [biot_savart.discretise(self._loops(k, pos[k], to_frame[k], dip_frame[k]), self.cfg.segments)
                 for k in range(n)]
        for i, j in self._pairs:
            f_b, t_b = biot_savart.wrench(nodes[i], nodes[j], pos[j])
            force[j] += f_b
            torque[j] += t_b
            force[i] -= f_b
            torque[i] -= t_b + cross3(pos[j] - pos[i], f_b)
        return force, torque

    def _sum_pairs(self, on_first: np.ndarray, on_second: np.ndarray) -> np.ndarray:
        """Every vehicle's sum (N, 3) of its pairs' terms, ``on_first[p]`` acting on pair p's first vehicle and
        ``on_second[p]`` on its second: from +0.0, its terms as first vehicle then as second, each in pair order.
        That is the order (and so the bits) of np.add.at into zeros over the first vehicles then the second,
        without its per-call cost; the plan is ``_pair_rows``."""
        terms = np.concatenate((on_first, on_second))
        total = 0.0
        for rows in self._pair_rows:
            total = total + terms.take(rows, axis=0)
        return total

    def _loops(self, k: int, centre: np.ndarray, body_to_frame: np.ndarray,
               dip_frame: np.ndarray) -> list[biot_savart.Loop]:
        """Vehicle k's coils as Biot–Savart loops in the formation frame (amp-turns from the dipole)."""
        spec = self.vehicles[k]
        axes = body_to_frame @ spec.coil_axes_body
        moments = axes.T @ dip_frame
        return [biot_savart.Loop(centre, axes[:, c], coil.radius_m, moments[c] / coil.area_m2)
                for c, coil in enumerate(spec.coils)]

    def _wrenches(self, t_s: float, pos: np.ndarray, q: np.ndarray, dip_body: np.ndarray) -> np.ndarray:
        """All forces (frame) and torques (body) at time ``t_s`` and state (pos, q): one (5, N, 3) array, its
        rows the ``Wrenches`` fields in their order (zeros where not modelled), so that ``advance`` sums a
        stage's five in one operation."""
        n = len(self.vehicles)
        rot = np.array([dcm(qk) for qk in q.tolist()])  # body → inertial (``quat_to_dcm`` of each row)
        out = np.zeros((5, n, 3))
        if self.cfg.frame == "hill":
            h2e, r_ref, _ = self._hill_to_eci(t_s)
            to_frame = np.einsum("ji,njk->nik", h2e, rot)  # body → Hill
            dip_eci = np.einsum("nij,nj->ni", rot, dip_body)
            r_eci = r_ref + pos @ h2e.T
            if self.cfg.earth_field is not None:
                out[2], out[3] = self._earth_wrench(t_s, r_eci, dip_eci, rot, h2e)
            if self.cfg.gravity_gradient:
                for k in range(n):
                    out[4, k] = gravity_gradient_torque_nm(self._inertia[k], rot[k].T @ r_eci[k])
        else:
            to_frame = rot
        dip_frame = np.einsum("nij,nj->ni", to_frame, dip_body)
        out[0], em_t_frame = self._em_wrenches(pos, dip_frame, to_frame)
        out[1] = np.einsum("nji,nj->ni", to_frame, em_t_frame)
        return out

    def _earth_wrench(self, t_s: float, r_eci: np.ndarray, dip_eci: np.ndarray, rot: np.ndarray,
                      h2e: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Earth-field force (Hill frame, N) ∇(μ·B) by central differences and torque (body, N·m) μ × B."""
        b_of = self.cfg.earth_field
        force, torque = np.zeros_like(r_eci), np.zeros_like(r_eci)
        for k in range(len(r_eci)):
            b = np.asarray(b_of(r_eci[k], t_s), dtype=float)
            torque[k] = rot[k].T @ cross3(dip_eci[k], b)
            h = EARTH_GRADIENT_STEP_FRACTION * float(np.linalg.norm(r_eci[k]))
            grad = np.empty(3)
            for axis in range(3):
                e = np.zeros(3)
                e[axis] = h
                grad[axis] = (dip_eci[k] @ np.asarray(b_of(r_eci[k] + e, t_s))
                              - dip_eci[k] @ np.asarray(b_of(r_eci[k] - e, t_s))) / (2.0 * h)
            force[k] = h2e.T @ grad
        return force, torque

    def _deriv(self, t_s: float, y: Sequence[np.ndarray], inputs: tuple[np.ndarray, ...],
               tau_s: float) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """(ṗ, v̇, q̇, ω̇) and the wrenches (``_wrenches``' array) at time ``t_s``, state y, ``tau_s`` into the step."""
        pos, vel, q, w = y
        dip_body, h0, hdot = inputs
        em_f, em_t, earth_f, earth_t, gg_t = wr = self._wrenches(t_s, pos, q, dip_body)
        acc = (em_f + earth_f) / self._mass[:, None]
        n = self._n_rad_s
        if self.cfg.frame == "hill":
            acc = acc + np.stack([3.0 * n * n * pos[:, 0] + 2.0 * n * vel[:, 1], -2.0 * n * vel[:, 0],
                                  -n * n * pos[:, 2]], axis=1)
        if self.cfg.frame == "line":  # the track reacts every torque
            acc[:, 0] += self._track_gravity
            acc[:, 1:] = 0.0
            acc[self._fixed] = 0.0
            return vel, acc, quat_rates(q, w), np.zeros_like(w), wr
        torque = em_t + earth_t + gg_t - hdot
        if self.cfg.frame == "planar":
            acc[:, 2] = 0.0
            wdot = np.zeros_like(w)
            wdot[:, 2] = torque[:, 2] / self._inertia[:, 2, 2]
        else:
            h = h0 + hdot * tau_s
            iw = np.einsum("nij,nj->ni", self._inertia, w)
            wdot = np.einsum("nij,nj->ni", self._inertia_inv, torque - cross3(w, iw + h))
        return vel, acc, quat_rates(q, w), wdot, wr

    def advance(self, dt_s: float, inputs: Sequence[VehicleInput]) -> None:
        """Integrate t → t + ``dt_s`` with each vehicle's ``VehicleInput`` (same order as the vehicles).

        Records the step-average wrenches (RK4 stage weights) for ``truth``.
        """
        dt = finite_float("dt_s", dt_s)
        if dt <= 0.0:
            raise DynamicsError(f"dt_s must be > 0 s, got {dt}")
        if len(inputs) != len(self.vehicles):
            raise DynamicsError(f"need one VehicleInput per vehicle ({len(self.vehicles)}), got {len(inputs)}")
        dip, h0, hdot = [], [], []
        for spec, u in zip(self.vehicles, inputs, strict=True):
            spec.coil_moments_am2(u.dipole_body_am2)  # reject dipoles its coils cannot make
            dip.append(spec.with_magnet(finite_vector3(f"{spec.name} dipole_body_am2", u.dipole_body_am2)))
            h0.append(finite_vector3(f"{spec.name} wheel_h_body_nms", u.wheel_h_body_nms))
            hdot.append(finite_vector3(f"{spec.name} wheel_hdot_body_nm", u.wheel_hdot_body_nm))
        step = (np.array(dip), np.array(h0), np.array(hdot))
        m = self.cfg.substeps
        sub = dt / m
        self._check_resolution(sub, step[1])
        y = (self._pos, self._vel, self._q, self._w)
        sums = np.zeros((5, len(self.vehicles), 3))  # the Wrenches fields' weighted sums
        for k in range(m):
            t_k = self._t + k * sub

            def rate(ys: Sequence[np.ndarray], frac: float, t_k: float = t_k, k: int = k) -> tuple[Any, ...]:
                """(ṗ, v̇, q̇, ω̇, the stage's wrenches) ``frac`` into substep k."""
                return self._deriv(t_k + frac * sub, ys, step, (k + frac) * sub)

            y, stages = rk4_step(y, rate, sub)
            for weight, stage in zip((1.0, 2.0, 2.0, 1.0), stages, strict=True):
                sums += weight * stage[4]
            y = (y[0], y[1], y[2] / np.linalg.norm(y[2], axis=1, keepdims=True), y[3])
        if not all(np.all(np.isfinite(a)) for a in y):
            raise DynamicsError("formation integration diverged (non-finite state): reduce dt_s or raise substeps")
        self._pos, self._vel, self._q, self._w = y
        self._check_contact()
        self._t += dt
        self._avg = Wrenches(*(sums / (6.0 * m)))

    def _check_resolution(self, sub_s: float, wheel_h: np.ndarray) -> None:
        """Refuse a substep the RK4 cannot resolve: a vehicle turning (body rate |ω| plus the wheels'
        gyroscopic nutation rate |h|/I_min, not in ``planar``, which has no gyroscopic coupling) more than
        MAX_TURN_PER_SUBSTEP_RAD per substep."""
        for k, spec in enumerate(self.vehicles):
            rate = float(np.linalg.norm(self._w[k]))
            if self.cfg.frame != "planar":
                rate += float(np.linalg.norm(wheel_h[k])) / float(np.min(np.linalg.eigvalsh(self._inertia[k])))
            if rate * sub_s > MAX_TURN_PER_SUBSTEP_RAD:
                need = math.ceil(rate * sub_s * self.cfg.substeps / MAX_TURN_PER_SUBSTEP_RAD)
                raise DynamicsError(
                    f"vehicle {spec.name} turns at {rate:.4g} rad/s (|ω| + |h_wheel|/I_min) at t = {self._t:.6g} s: "
                    f"{rate * sub_s:.3g} rad per {sub_s:.4g} s substep is more than the integrator resolves "
                    f"({MAX_TURN_PER_SUBSTEP_RAD} rad); raise dynamics.substeps to {need} or more, or look at why "
                    "it spins")

    # ------------------------------------------------------------------------------------ output

    def truth(self) -> FormationTruth:
        """Every vehicle's true state now, with the last step's average wrenches."""
        t = self._t
        h2e = r_ref = v_ref = None
        if self.cfg.frame == "hill":
            h2e, r_ref, v_ref = self._hill_to_eci(t)
        out = []
        for k, spec in enumerate(self.vehicles):
            rot = quat_to_dcm(self._q[k])
            r_eci = v_eci = b_eci = b_body = None
            if h2e is not None:
                r_eci = r_ref + h2e @ self._pos[k]
                omega_hill = np.array([0.0, 0.0, self._n_rad_s])
                v_eci = v_ref + h2e @ (self._vel[k] + cross3(omega_hill, self._pos[k]))
                if self.cfg.earth_field is not None:
                    b_eci = np.asarray(self.cfg.earth_field(r_eci, t), dtype=float)
                    b_body = rot.T @ b_eci
            out.append(VehicleTruth(
                spec.name, self._pos[k].copy(), self._vel[k].copy(), self._q[k].copy(), self._w[k].copy(),
                math.atan2(rot[1, 0], rot[0, 0]), r_eci, v_eci, b_eci, b_body,
                self._avg.em_force_n[k].copy(), self._avg.em_torque_body_nm[k].copy(),
                self._avg.earth_force_n[k].copy(), self._avg.earth_torque_body_nm[k].copy(),
                self._avg.gg_torque_body_nm[k].copy()))
        return FormationTruth(t, tuple(out), h2e)

    def wrenches_now(self, dipoles_body_am2: Sequence[Sequence[float]]) -> Wrenches:
        """Instantaneous wrenches at the current state for the given body dipoles of the coils (A·m²; the
        permanent magnets added)."""
        dip = np.array([s.with_magnet(finite_vector3(f"{s.name} dipole_body_am2", d))
                        for s, d in zip(self.vehicles, dipoles_body_am2, strict=True)])
        return Wrenches(*self._wrenches(self._t, self._pos, self._q, dip))

    def momentum(self, wheel_h_body_nms: Sequence[Sequence[float]]) -> tuple[np.ndarray, np.ndarray]:
        """Total linear (N·s) and angular (N·m·s, about the frame origin) momentum in the inertial frame,
        wheels included (``wheel_h_body_nms`` per vehicle, body axes). ``free_space`` and ``planar``
        only (in ``hill`` the Earth's gravity exchanges momentum with the formation, in ``line`` the track)."""
        if self.cfg.frame not in ("free_space", "planar"):
            raise DynamicsError("momentum bookkeeping is for frames 'free_space' and 'planar' (no external forces)")
        p = np.zeros(3)
        ang = np.zeros(3)
        for k in range(len(self.vehicles)):
            h = finite_vector3(f"{self.vehicles[k].name} wheel_h_body_nms", wheel_h_body_nms[k])
            mv = self._mass[k] * self._vel[k]
            p += mv
            ang += cross3(self._pos[k], mv) + quat_to_dcm(self._q[k]) @ (self._inertia[k] @ self._w[k] + h)
        return p, ang


# ---------------------------------------------------------------------------------------- wheels


class TorqueWheels:
    """Torque-commanded reaction wheels with orthonormal ``axes_body`` (columns), a per-wheel torque
    limit ``max_torque_nm`` and an optional per-wheel momentum ``capacity_nms`` (None: unlimited).

    The EMFFORCE wheel (slide 74) is a current-driven motor: torque = K_t·I, 0.1 N·m at 10 A; a
    commanded torque is clipped to the limit per wheel, and a wheel reaching capacity mid-step stops
    there. ``step`` returns (h at the step start, mean ḣ) in body axes, the ``VehicleInput`` wheel
    fields; ``current_a`` the motor currents of the last step.
    """

    def __init__(self, axes_body: np.ndarray, max_torque_nm: float, capacity_nms: float | None = None,
                 torque_constant_nm_per_a: float = EMFFORCE_WHEEL_TORQUE_CONSTANT_NM_PER_A,
                 h0_nms: Sequence[float] | None = None) -> None:
        axes = np.asarray(axes_body, dtype=float)
        if axes.ndim != 2 or axes.shape[0] != 3 or not np.allclose(axes.T @ axes, np.eye(axes.shape[1]), atol=1e-9):
            raise DynamicsError(f"TorqueWheels.axes_body must be orthonormal columns (3, n), got {axes.tolist()}")
        for name, v in (("max_torque_nm", max_torque_nm), ("torque_constant_nm_per_a", torque_constant_nm_per_a)):
            if not finite_float(f"TorqueWheels.{name}", v) > 0.0:
                raise DynamicsError(f"TorqueWheels.{name} must be > 0, got {v}")
        if capacity_nms is not None and not finite_float("TorqueWheels.capacity_nms", capacity_nms) > 0.0:
            raise DynamicsError(f"TorqueWheels.capacity_nms must be > 0 N·m·s or None, got {capacity_nms}")
        self.axes_body = axes
        self.max_torque_nm = float(max_torque_nm)
        self.capacity_nms = capacity_nms
        self.torque_constant_nm_per_a = float(torque_constant_nm_per_a)
        self._h = np.zeros(axes.shape[1]) if h0_nms is None else np.asarray(h0_nms, dtype=float).copy()
        if self._h.shape != (axes.shape[1],) or not np.all(np.isfinite(self._h)):
            raise DynamicsError(f"TorqueWheels.h0_nms must be {axes.shape[1]} finite wheel momenta, got {h0_nms}")
        self._torque = np.zeros_like(self._h)

    def momentum_body_nms(self) -> np.ndarray:
        """Total wheel momentum, body axes, N·m·s."""
        return self.axes_body @ self._h

    @property
    def current_a(self) -> np.ndarray:
        """Motor current of each wheel over the last step, A (|τ|/K_t, signed)."""
        return self._torque / self.torque_constant_nm_per_a

    def step(self, torque_command_body_nm: np.ndarray, dt_s: float) -> tuple[np.ndarray, np.ndarray]:
        """Apply a body-axis wheel torque command (N·m, the wanted ḣ) for ``dt_s``; (h start, mean ḣ)."""
        cmd = finite_vector3("torque_command_body_nm", torque_command_body_nm)
        dt = finite_float("dt_s", dt_s)
        if dt <= 0.0:
            raise DynamicsError(f"dt_s must be > 0 s, got {dt}")
        self._torque = np.clip(self.axes_body.T @ cmd, -self.max_torque_nm, self.max_torque_nm)
        h_start = self._h
        h_end = h_start + self._torque * dt
        if self.capacity_nms is not None:
            h_end = np.clip(h_end, -self.capacity_nms, self.capacity_nms)
        self._h = h_end
        return self.axes_body @ h_start, self.axes_body @ (h_end - h_start) / dt
