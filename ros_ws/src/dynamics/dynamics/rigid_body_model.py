"""Rigid body with stored wheel momentum, magnetic and gravity-gradient torques (spec §3).

Equations (spec §3; seed 002 §4.3 "three-degree-of-freedom rigid body angular equations of motion"):

    I ω̇ = −ω × (I ω + h) − ḣ + T_mag + T_gg + T_d
    T_mag = M × B          (B at the spacecraft in body axes, M the achieved dipole)
    T_gg  = 3 μ/r³ · r̂_b × (I r̂_b)
    q̇ = ½ q ⊗ (ω, 0)       (Hamilton quaternion, body → ECI, stored x, y, z, w)

h is the wheels' momentum in body axes, ḣ its rate: the body feels −ḣ. T_d is an optional body-fixed
disturbance torque (seed 000: the Workshop's aerodynamic bias, :mod:`dynamics.disturbances`), applied as
its exact mean over each ``advance`` step (it varies at orbital rate, a step lasts seconds). Integration
is RK4 with a fixed number of substeps per ``advance`` call; orbit position and field are evaluated at
each RK4 stage time; the quaternion is renormalised after every substep.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
from acds_common import units
from acds_common.environment import Orbit, Sun, TiltedDipoleField, sun_frame_dcm
from acds_common.environment import ecliptic_normal_eci as default_ecliptic_normal_eci
from acds_common.environment import gravity_gradient_torque_nm as gravity_gradient_torque_nm  # the public form
from acds_common.inertia import InertiaError, inertia_tensor

from dynamics.disturbances import DisturbanceTorque
from dynamics.errors import DynamicsError, finite_float, finite_vector3

#: Default RK4 substeps per ``advance`` call (0.1 s substeps at the 0.5 s HEAO control period).
DEFAULT_SUBSTEPS = 5

#: Table 4-1 (seed 002), HEAO-A moments and products of inertia, slug-ft².
HEAO_A_INERTIA_SLUG_FT2: dict[str, float] = {
    "ixx": 1750.0, "iyy": 4030.0, "izz": 4300.0, "ixy": 96.0, "ixz": 14.0, "iyz": 17.0}
#: Table 4-1 (seed 002), HEAO-B moments and products of inertia, slug-ft².
HEAO_B_INERTIA_SLUG_FT2: dict[str, float] = {
    "ixx": 1520.0, "iyy": 7970.0, "izz": 7920.0, "ixy": 47.0, "ixz": 359.0, "iyz": 4.0}


def heao_inertia_kg_m2(table: dict[str, float]) -> np.ndarray:
    """Inertia tensor in kg·m² from a Table 4-1 dict in slug-ft² (e.g. HEAO_B_INERTIA_SLUG_FT2)."""
    return inertia_tensor(**{k: units.slugft2_to_kgm2(v) for k, v in table.items()})


def quat_to_dcm(q_xyzw: np.ndarray) -> np.ndarray:
    """Rotation matrix R (body → ECI: v_eci = R v_body) of a unit Hamilton quaternion (x, y, z, w)."""
    return np.array(_dcm(tuple(float(c) for c in q_xyzw)))


def dcm_to_quat(dcm_body_to_eci: np.ndarray) -> np.ndarray:
    """Unit quaternion (x, y, z, w), w ≥ 0, of a rotation matrix (inverse of ``quat_to_dcm``; Shepperd)."""
    m = np.asarray(dcm_body_to_eci, dtype=float)
    if m.shape != (3, 3) or not np.allclose(m @ m.T, np.eye(3), atol=1e-9) or np.linalg.det(m) < 0.0:
        raise DynamicsError("dcm_body_to_eci must be a 3x3 proper rotation matrix")
    tr = m[0, 0] + m[1, 1] + m[2, 2]
    cands = [tr, m[0, 0], m[1, 1], m[2, 2]]
    i = int(np.argmax(cands))
    if i == 0:
        w = 0.5 * math.sqrt(1.0 + tr)
        q = np.array([(m[2, 1] - m[1, 2]) / (4 * w), (m[0, 2] - m[2, 0]) / (4 * w),
                      (m[1, 0] - m[0, 1]) / (4 * w), w])
    else:
        a = i - 1
        b, c = (a + 1) % 3, (a + 2) % 3
        va = 0.5 * math.sqrt(1.0 + m[a, a] - m[b, b] - m[c, c])
        q = np.empty(4)
        q[a] = va
        q[b] = (m[b, a] + m[a, b]) / (4 * va)
        q[c] = (m[c, a] + m[a, c]) / (4 * va)
        q[3] = (m[c, b] - m[b, c]) / (4 * va)
    q = q / np.linalg.norm(q)
    return -q if q[3] < 0.0 else q


# Small-vector kernels on float tuples: the RK4 loop runs ~20 derivative evaluations per control
# step, where numpy's per-call overhead on 3-vectors would dominate.
Vec = tuple[float, float, float]
Mat = tuple[Vec, Vec, Vec]


def _cross(a: Sequence[float], b: Sequence[float]) -> Vec:
    return (a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0])


def _mv(m: Mat, v: Sequence[float]) -> Vec:
    return (m[0][0] * v[0] + m[0][1] * v[1] + m[0][2] * v[2],
            m[1][0] * v[0] + m[1][1] * v[1] + m[1][2] * v[2],
            m[2][0] * v[0] + m[2][1] * v[1] + m[2][2] * v[2])


def _mtv(m: Mat, v: Sequence[float]) -> Vec:
    return (m[0][0] * v[0] + m[1][0] * v[1] + m[2][0] * v[2],
            m[0][1] * v[0] + m[1][1] * v[1] + m[2][1] * v[2],
            m[0][2] * v[0] + m[1][2] * v[1] + m[2][2] * v[2])


def _dcm(q: Sequence[float]) -> Mat:
    x, y, z, w = q
    return ((1.0 - 2.0 * (y * y + z * z), 2.0 * (x * y - z * w), 2.0 * (x * z + y * w)),
            (2.0 * (x * y + z * w), 1.0 - 2.0 * (x * x + z * z), 2.0 * (y * z - x * w)),
            (2.0 * (x * z - y * w), 2.0 * (y * z + x * w), 1.0 - 2.0 * (x * x + y * y)))


def _as_mat(m: np.ndarray) -> Mat:
    return tuple(tuple(float(c) for c in row) for row in m)  # type: ignore[return-value]


def _gg(inertia: Mat, r_body_m: Sequence[float]) -> Vec:
    rn = math.sqrt(r_body_m[0] ** 2 + r_body_m[1] ** 2 + r_body_m[2] ** 2)
    r_hat = (r_body_m[0] / rn, r_body_m[1] / rn, r_body_m[2] / rn)
    k = 3.0 * units.EARTH_MU_M3_S2 / rn ** 3
    t = _cross(r_hat, _mv(inertia, r_hat))
    return (k * t[0], k * t[1], k * t[2])


def magnetic_torque_nm(dipole_body_am2: np.ndarray, b_body_t: np.ndarray) -> np.ndarray:
    """Magnetic torque T_mag = M × B, N·m (spec §3); dipole in A·m², field in T, both body axes."""
    return np.array(_cross([float(c) for c in dipole_body_am2], [float(c) for c in b_body_t]))


@dataclass(frozen=True)
class Truth:
    """True state at ``t_s`` for the truth topics and the ideal sensors (spec §2, §3).

    Units in the names. ``sun_direction_cosines`` = (B13, B23, B33) and ``dcm_body_sun`` = B with
    B_ij = (body axis i)·(sun-frame axis j) (seed 002 §4.3.1, Figure 4-14): B33 = cos of the z-body to
    sun angle, B23 = roll error, B13 = −pitch error, B12 = rotation about the sun line. (B13, B23,
    B33) is also the sun unit vector in body axes. Torques are averages over the last ``advance``
    (zeros before the first).
    """

    t_s: float
    q_body_to_eci: np.ndarray
    omega_body_rad_s: np.ndarray
    r_eci_m: np.ndarray
    v_eci_m_s: np.ndarray
    b_eci_t: np.ndarray
    b_body_t: np.ndarray
    sun_body_unit: np.ndarray
    sun_present: bool
    sun_direction_cosines: np.ndarray
    dcm_body_sun: np.ndarray
    torque_magnetic_body_nm: np.ndarray
    torque_gravity_gradient_body_nm: np.ndarray
    wheel_h_body_nms: np.ndarray
    h_total_body_nms: np.ndarray
    h_total_eci_nms: np.ndarray
    rotational_energy_j: float
    attitude_to_sun_deg: float


class RigidBodyModel:
    """Spacecraft attitude dynamics in its orbit and environment (spec §3).

    ``inertia_kg_m2`` 3×3 (see ``inertia_tensor``), ``orbit``, ``field``, ``sun``;
    ``ecliptic_normal_eci`` (ECI unit vector, default obliquity 23.44°) defines the sun-pointed frame;
    ``gravity_gradient`` switches T_gg; ``substeps`` RK4 substeps per ``advance``;
    ``q0_body_to_eci`` (x, y, z, w), ``omega0_body_rad_s`` body rates; ``t0_s`` start time (s).
    """

    def __init__(self, inertia_kg_m2: np.ndarray, orbit: Orbit, field: TiltedDipoleField, sun: Sun,
                 ecliptic_normal_eci: np.ndarray | None = None, gravity_gradient: bool = True,
                 substeps: int = DEFAULT_SUBSTEPS,
                 q0_body_to_eci: Sequence[float] = (0.0, 0.0, 0.0, 1.0),
                 omega0_body_rad_s: Sequence[float] = (0.0, 0.0, 0.0), t0_s: float = 0.0,
                 disturbance: DisturbanceTorque | None = None) -> None:
        inertia = np.asarray(inertia_kg_m2, dtype=float)
        if inertia.shape != (3, 3) or not np.allclose(inertia, inertia.T, rtol=0.0, atol=1e-12 * abs(
                inertia).max()):
            raise DynamicsError("inertia_kg_m2 must be a symmetric 3x3 matrix (use inertia_tensor)")
        try:
            inertia_tensor(inertia[0, 0], inertia[1, 1], inertia[2, 2], -inertia[0, 1], -inertia[0, 2],
                           -inertia[1, 2])
        except InertiaError as exc:
            raise DynamicsError(str(exc)) from None
        if int(substeps) != substeps or substeps < 1:
            raise DynamicsError(f"substeps must be a positive integer, got {substeps!r}")
        q0 = np.asarray(q0_body_to_eci, dtype=float)
        if q0.shape != (4,) or not np.all(np.isfinite(q0)) or np.linalg.norm(q0) < 1e-6:
            raise DynamicsError(f"q0_body_to_eci must be a finite non-zero (x, y, z, w) quaternion, got {q0}")
        self.inertia_kg_m2 = inertia
        self._inertia_t = _as_mat(inertia)
        self._inertia_inv_t = _as_mat(np.linalg.inv(inertia))
        self.orbit, self.field, self.sun = orbit, field, sun
        self.ecliptic_normal_eci = (default_ecliptic_normal_eci() if ecliptic_normal_eci is None
                                    else finite_vector3("ecliptic_normal_eci", ecliptic_normal_eci))
        self.gravity_gradient = bool(gravity_gradient)
        self.substeps = int(substeps)
        self._q = q0 / np.linalg.norm(q0)
        self._w = finite_vector3("omega0_body_rad_s", omega0_body_rad_s)
        self._t = finite_float("t0_s", t0_s)
        self._tmag_avg = np.zeros(3)
        self._tgg_avg = np.zeros(3)
        self.disturbance = disturbance

    @property
    def t_s(self) -> float:
        """Current time, s."""
        return self._t

    @property
    def q_body_to_eci(self) -> np.ndarray:
        """Current attitude quaternion (x, y, z, w), body → ECI."""
        return self._q.copy()

    @property
    def omega_body_rad_s(self) -> np.ndarray:
        """Current body rates, rad/s."""
        return self._w.copy()

    def _deriv(self, q: Sequence[float], w: Sequence[float], tau_s: float, env: tuple[Vec | None, Vec | None],
               step: tuple[Vec, Vec, Vec, Vec]) -> tuple[tuple[float, ...], Vec, Vec, Vec]:
        """(q̇, ω̇, T_mag, T_gg) at attitude q, rate w, ``tau_s`` into the step.

        ``env`` = (r_eci, b_eci) at the stage time (None when not needed); ``step`` = (dipole, h0, ḣ, T_d).
        """
        r_eci, b_eci = env
        dipole, h0, hdot, t_d = step
        zero = (0.0, 0.0, 0.0)
        t_mag, t_gg = zero, zero
        if r_eci is not None:
            rmat = _dcm(q)
            if b_eci is not None:
                t_mag = _cross(dipole, _mtv(rmat, b_eci))
            if self.gravity_gradient:
                t_gg = _gg(self._inertia_t, _mtv(rmat, r_eci))
        iw = _mv(self._inertia_t, w)
        gyro = _cross(w, (iw[0] + h0[0] + hdot[0] * tau_s, iw[1] + h0[1] + hdot[1] * tau_s,
                          iw[2] + h0[2] + hdot[2] * tau_s))
        net = tuple(-gyro[i] - hdot[i] + t_mag[i] + t_gg[i] + t_d[i] for i in range(3))
        wdot = _mv(self._inertia_inv_t, net)
        qv = _cross(q[:3], w)
        qdot = (0.5 * (q[3] * w[0] + qv[0]), 0.5 * (q[3] * w[1] + qv[1]), 0.5 * (q[3] * w[2] + qv[2]),
                -0.5 * (q[0] * w[0] + q[1] * w[1] + q[2] * w[2]))
        return qdot, wdot, t_mag, t_gg

    def advance(self, dt_s: float, dipole_body_am2: np.ndarray, wheel_h_body_nms: np.ndarray,
                wheel_hdot_body_nm: np.ndarray) -> None:
        """Integrate from t to t + ``dt_s`` (s).

        ``dipole_body_am2`` (A·m², constant over the step: the driver's time-averaged achieved
        dipole); wheel momentum h(τ) = ``wheel_h_body_nms`` + ``wheel_hdot_body_nm``·(τ − t) (N·m·s,
        N·m, body axes); the disturbance torque at its exact mean over the step. Records the
        step-average magnetic and gravity-gradient torques (RK4 stage weights, i.e. Simpson's rule per
        substep).
        """
        dt = finite_float("dt_s", dt_s)
        if dt <= 0.0:
            raise DynamicsError(f"dt_s must be > 0 s, got {dt}")
        t0 = self._t
        t_d = (0.0, 0.0, 0.0) if self.disturbance is None else self.disturbance.momentum_nms(t0, t0 + dt) / dt
        step: tuple[Vec, Vec, Vec, Vec] = tuple(  # type: ignore[assignment]
            tuple(float(c) for c in finite_vector3(name, v)) for name, v in (
                ("dipole_body_am2", dipole_body_am2), ("wheel_h_body_nms", wheel_h_body_nms),
                ("wheel_hdot_body_nm", wheel_hdot_body_nm), ("disturbance torque", t_d)))
        n = self.substeps
        sub = dt / n
        need_field = any(c != 0.0 for c in step[0])
        need_pos = need_field or self.gravity_gradient
        # Attitude-independent environment at the 2n+1 distinct stage times t0 + j·sub/2.
        env: list[tuple[Vec | None, Vec | None]] = []
        for j in range(2 * n + 1):
            tj = t0 + 0.5 * j * sub
            r = self.orbit.position_velocity_eci(tj)[0] if need_pos else None
            b = self.field.b_eci(r, tj) if need_field else None
            env.append((None if r is None else tuple(r.tolist()), None if b is None else tuple(b.tolist())))
        q: Sequence[float] = tuple(self._q.tolist())
        w: Sequence[float] = tuple(self._w.tolist())
        tmag_sum, tgg_sum = [0.0, 0.0, 0.0], [0.0, 0.0, 0.0]
        for k in range(n):
            slopes = []
            qs, ws = q, w
            for weight, frac, j in ((1.0, 0.0, 2 * k), (2.0, 0.5, 2 * k + 1), (2.0, 0.5, 2 * k + 1),
                                    (1.0, 1.0, 2 * k + 2)):
                if slopes:
                    a = frac * sub
                    dq, dw = slopes[-1]
                    qs = tuple(q[i] + a * dq[i] for i in range(4))
                    ws = tuple(w[i] + a * dw[i] for i in range(3))
                dq, dw, t_mag, t_gg = self._deriv(qs, ws, (k + frac) * sub, env[j], step)
                slopes.append((dq, dw))
                for i in range(3):
                    tmag_sum[i] += weight * t_mag[i]
                    tgg_sum[i] += weight * t_gg[i]
            (q1, w1), (q2, w2), (q3, w3), (q4, w4) = slopes
            c = sub / 6.0
            q = tuple(q[i] + c * (q1[i] + 2.0 * q2[i] + 2.0 * q3[i] + q4[i]) for i in range(4))
            w = tuple(w[i] + c * (w1[i] + 2.0 * w2[i] + 2.0 * w3[i] + w4[i]) for i in range(3))
            norm = math.sqrt(sum(x * x for x in q))
            q = tuple(x / norm for x in q)
        q_arr, w_arr = np.array(q), np.array(w)
        if not (np.all(np.isfinite(q_arr)) and np.all(np.isfinite(w_arr))):
            raise DynamicsError("integration diverged (non-finite state): reduce dt_s or raise substeps")
        self._q, self._w = q_arr, w_arr
        self._t = t0 + dt
        self._tmag_avg = np.array(tmag_sum) / (6.0 * n)
        self._tgg_avg = np.array(tgg_sum) / (6.0 * n)

    def truth(self, wheel_h_body_nms: np.ndarray) -> Truth:
        """Truth at the current time; ``wheel_h_body_nms`` (N·m·s, body) for the total momentum."""
        h = finite_vector3("wheel_h_body_nms", wheel_h_body_nms)
        t = self._t
        rmat = quat_to_dcm(self._q)
        r, v = self.orbit.position_velocity_eci(t)
        b_eci = self.field.b_eci(r, t)
        sun_eci = self.sun.direction_eci(t)
        dcm_body_sun = (sun_frame_dcm(sun_eci, self.ecliptic_normal_eci) @ rmat).T
        sun_body = rmat.T @ sun_eci
        h_total = self.inertia_kg_m2 @ self._w + h
        return Truth(
            t_s=t, q_body_to_eci=self._q.copy(), omega_body_rad_s=self._w.copy(), r_eci_m=r,
            v_eci_m_s=v, b_eci_t=b_eci, b_body_t=rmat.T @ b_eci, sun_body_unit=sun_body,
            sun_present=self.sun.present(r, t), sun_direction_cosines=dcm_body_sun[:, 2].copy(),
            dcm_body_sun=dcm_body_sun, torque_magnetic_body_nm=self._tmag_avg.copy(),
            torque_gravity_gradient_body_nm=self._tgg_avg.copy(), wheel_h_body_nms=h,
            h_total_body_nms=h_total, h_total_eci_nms=rmat @ h_total,
            rotational_energy_j=0.5 * float(self._w @ self.inertia_kg_m2 @ self._w),
            attitude_to_sun_deg=math.degrees(math.acos(max(-1.0, min(1.0, float(dcm_body_sun[2, 2]))))),
        )
