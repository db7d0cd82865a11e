"""Rigid body with stored wheel momentum, magnetic and gravity-gradient torques (spec §3).

Equations (spec §3; seed 002 §4.3 "three-degree-of-freedom rigid body angular equations of motion"):

    I ω̇ = −ω × (I ω + h) − ḣ + T_mag + T_gg + T_d
    T_mag = M × B          (B at the spacecraft in body axes, M the achieved dipole)
    T_gg  = 3 μ/r³ · r̂_b × (I r̂_b)
    q̇ = ½ q ⊗ (ω, 0)       (Hamilton quaternion, body → ECI, stored x, y, z, w)

h is the wheels' momentum in body axes, ḣ its rate: the body feels −ḣ. T_d is an optional body-fixed
disturbance torque (seed 000: the Workshop's aerodynamic bias, :mod:`dynamics.disturbances`), applied as
its exact mean over each ``advance`` step (it varies at orbital rate, a step lasts seconds). Integration
is RK4 (:func:`dynamics.integrator.rk4_step`, written out on floats) with a fixed number of substeps per
``advance`` call; orbit position and field are evaluated once at each distinct RK4 stage time (2n + 1
per call, the end one shared with ``truth`` and the next call's start); the quaternion is renormalised
after every substep.

Speed: the kernel (:func:`attitude_rk4`) is written on plain Python floats (one derivative is ~200 float
operations on 3-vectors, where numpy's per-call overhead would dominate); IEEE doubles without fused
operations give the same bits on every machine. The direct engine runs it compiled
(:mod:`acds_common.kernels`: the same bits, 8× faster). One ``advance`` is one kernel call
(:func:`advance_circular_dipole` or :func:`advance_stages`): the RK4, the mean torques and the truth's
float values at the new time (:func:`truth_values`: B and the Sun in body axes, sun presence). Numpy appears
only at the API edge (``Truth``'s arrays and derived quantities are built when read).
"""

from __future__ import annotations

import math
import struct
from collections.abc import Sequence

import numpy as np
from acds_common import kernels, units
from acds_common.attitude import Quat, dcm
from acds_common.environment import (
    CircularDipole,
    MagneticFieldModel,
    Orbit,
    Sun,
    circular_dipole_environment,
    circular_dipole_parameters,
    field_xyz,
    sun_frame_dcm,
    sun_present_xyz,
)
from acds_common.environment import ecliptic_normal_eci as default_ecliptic_normal_eci
from acds_common.environment import gravity_gradient_torque_nm as gravity_gradient_torque_nm  # the public form
from acds_common.inertia import InertiaError, inertia_tensor
from acds_common.vec3 import ZERO, Mat3, Vec3, cross, mat3, mtv, mv

from dynamics.disturbances import DisturbanceTorque
from dynamics.errors import DynamicsError, finite_float, finite_vector3, finite_xyz, positive_dt

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


def magnetic_torque_nm(dipole_body_am2: np.ndarray, b_body_t: np.ndarray) -> np.ndarray:
    """Magnetic torque T_mag = M × B, N·m (spec §3); dipole in A·m², field in T, both body axes."""
    return np.array(cross([float(c) for c in dipole_body_am2], [float(c) for c in b_body_t]))


#: The truth's float values at one time, what the stepper publishes: r_eci (m), q body → ECI (x, y, z, w),
#: v_eci (m/s), ω body (rad/s), B body (T), sun direction cosines (B13, B23, B33), mean T_mag and T_gg over the
#: last ``advance`` (body, N·m), the Sun in body axes, sun present (:func:`truth_values`).
TruthValues = tuple[Vec3, Quat, Vec3, Vec3, Vec3, Vec3, Vec3, Vec3, Vec3, bool]

#: The Sun as :func:`truth_values` takes it: the ECI direction rotated for the sun sensor, the sun line (the
#: sun frame's z axis), whether those two are the same row (one rotation gives both), and the Sun's own direction
#: and eclipse flag (sun presence, :func:`acds_common.environment.sun_present_xyz`).
SunAxes = tuple[Vec3, Vec3, bool, Vec3, bool]


@kernels.helper
def truth_values(q: Quat, w: Vec3, r: Vec3, v: Vec3, b: Vec3, tmag: Vec3, tgg: Vec3, sun: SunAxes) -> TruthValues:
    """:data:`TruthValues` at attitude ``q``, rates ``w``, position ``r``, velocity ``v`` and ECI field ``b``,
    with the mean torques ``tmag`` and ``tgg``: B and the Sun rotated into body axes (Rᵀ v, R of q), the direction
    cosines (B13, B23, B33) the sun line in body axes (:class:`Truth`)."""
    rmat = dcm(q)
    sun_eci, sun_line, same, direction, eclipse = sun
    sun_body = mtv(rmat, sun_eci)
    cosines = sun_body if same else mtv(rmat, sun_line)
    return (r, q, v, w, mtv(rmat, b), cosines, tmag, tgg, sun_body, sun_present_xyz(direction, eclipse, r))


class Truth:
    """True state at ``t_s`` for the truth topics and the ideal sensors (spec §2, §3).

    Units in the names. ``sun_direction_cosines`` = (B13, B23, B33) and ``dcm_body_sun`` = B with
    B_ij = (body axis i)·(sun-frame axis j) (seed 002 §4.3.1, Figure 4-14): B33 = cos of the z-body to
    sun angle, B23 = roll error, B13 = −pitch error, B12 = rotation about the sun line. (B13, B23,
    B33) is also the sun unit vector in body axes. Torques are averages over the last ``advance``
    (zeros before the first).

    The model computes the state as float triples (``values``, :data:`TruthValues`, also kept in the ``*_xyz``
    attributes: what the stepper publishes); the numpy attributes (``q_body_to_eci``, ``b_body_t``, …) and the
    derived quantities (``dcm_body_sun``, total momentum, energy) are built when read.
    """

    __slots__ = ('t_s', 'values', 'r_xyz', 'q_xyzw', 'v_xyz', 'omega_xyz', 'b_body_xyz', 'sun_cosines_xyz',
                 'torque_magnetic_xyz', 'torque_gravity_gradient_xyz', 'sun_body_xyz', 'sun_present', 'b_eci_xyz',
                 'wheel_h_xyz', '_inertia', '_sun_frame')

    def __init__(self, t_s: float, values: TruthValues, b_eci_xyz: Vec3, wheel_h_xyz: Vec3, inertia: Mat3,
                 sun_frame: Mat3) -> None:
        self.t_s = t_s
        self.values = values
        (self.r_xyz, self.q_xyzw, self.v_xyz, self.omega_xyz, self.b_body_xyz, self.sun_cosines_xyz,
         self.torque_magnetic_xyz, self.torque_gravity_gradient_xyz, self.sun_body_xyz, self.sun_present) = values
        self.b_eci_xyz = b_eci_xyz
        self.wheel_h_xyz = wheel_h_xyz
        self._inertia = inertia
        self._sun_frame = sun_frame

    @property
    def _rmat(self) -> Mat3:
        """R (body → ECI) of the attitude."""
        return dcm(self.q_xyzw)

    @property
    def q_body_to_eci(self) -> np.ndarray:
        """Attitude quaternion (x, y, z, w), body → ECI."""
        return np.array(self.q_xyzw)

    @property
    def omega_body_rad_s(self) -> np.ndarray:
        """Body rates, rad/s."""
        return np.array(self.omega_xyz)

    @property
    def r_eci_m(self) -> np.ndarray:
        """ECI position, m."""
        return np.array(self.r_xyz)

    @property
    def v_eci_m_s(self) -> np.ndarray:
        """ECI velocity, m/s."""
        return np.array(self.v_xyz)

    @property
    def b_eci_t(self) -> np.ndarray:
        """Earth field at the spacecraft, ECI, T."""
        return np.array(self.b_eci_xyz)

    @property
    def b_body_t(self) -> np.ndarray:
        """Earth field at the spacecraft, body axes, T."""
        return np.array(self.b_body_xyz)

    @property
    def sun_body_unit(self) -> np.ndarray:
        """Unit vector to the Sun, body axes."""
        return np.array(self.sun_body_xyz)

    @property
    def sun_direction_cosines(self) -> np.ndarray:
        """(B13, B23, B33), see the class docstring."""
        return np.array(self.sun_cosines_xyz)

    @property
    def dcm_body_sun(self) -> np.ndarray:
        """B (3×3), B_ij = (body axis i)·(sun-frame axis j)."""
        rmat = self._rmat
        return np.array([mtv(rmat, axis) for axis in self._sun_frame]).T

    @property
    def torque_magnetic_body_nm(self) -> np.ndarray:
        """Magnetic torque averaged over the last ``advance``, body, N·m."""
        return np.array(self.torque_magnetic_xyz)

    @property
    def torque_gravity_gradient_body_nm(self) -> np.ndarray:
        """Gravity-gradient torque averaged over the last ``advance``, body, N·m."""
        return np.array(self.torque_gravity_gradient_xyz)

    @property
    def wheel_h_body_nms(self) -> np.ndarray:
        """Wheel momentum given to ``truth``, body, N·m·s."""
        return np.array(self.wheel_h_xyz)

    @property
    def h_total_body_nms(self) -> np.ndarray:
        """Total angular momentum I·ω + h, body, N·m·s."""
        iw = mv(self._inertia, self.omega_xyz)
        return np.array([iw[i] + self.wheel_h_xyz[i] for i in range(3)])

    @property
    def h_total_eci_nms(self) -> np.ndarray:
        """Total angular momentum in ECI, N·m·s."""
        return np.array(mv(self._rmat, self.h_total_body_nms.tolist()))

    @property
    def rotational_energy_j(self) -> float:
        """Body rotational energy ½ ωᵀ I ω, J."""
        w = self.omega_xyz
        iw = mv(self._inertia, w)
        return 0.5 * (w[0] * iw[0] + w[1] * iw[1] + w[2] * iw[2])

    @property
    def attitude_to_sun_deg(self) -> float:
        """Angle between body z and the sun line, deg (acos B33)."""
        return math.degrees(math.acos(max(-1.0, min(1.0, self.sun_cosines_xyz[2]))))


def _bits(v: Vec3) -> bytes:
    """A float triple's IEEE bits (equal bits: the same results from every product with it)."""
    return struct.pack('<3d', *v)


#: One RK4 stage's attitude-independent environment: r_eci (m) and b_eci (T) as six floats.
_Env = tuple[float, float, float, float, float, float]


#: A stage that needs no environment (no field, no gravity gradient): r and B unused.
_NO_ENV: _Env = (0.0, 0.0, 0.0, 0.0, 0.0, 0.0)


@kernels.helper
def stage_environment(env: tuple[_Env, ...], orbit: CircularDipole | None, end: tuple[Vec3, Vec3, Vec3] | None,
                      j: int, stages: int, t0: float, dt: float, pos: bool, field: bool) -> _Env:
    """The environment at RK4 stage time t0 + dt·j/``stages`` (0 < j ≤ stages): ``env[j]``, or, with the circular
    orbit and tilted dipole ``orbit``, ``end``'s r and B at the end, else computed
    (:func:`acds_common.environment.circular_dipole_environment`; r and, with ``field``, B only when ``pos``)."""
    if orbit is None:
        return env[j]
    if j == stages:
        return end[0] + end[2]
    if not pos:
        return _NO_ENV
    r, _v, b = circular_dipole_environment(orbit, t0 + dt * (j / stages), field)
    return r + b


@kernels.helper
def attitude_rk4(q: Quat, w: Vec3, n: int, t0: float, dt: float, env: tuple[_Env, ...], orbit: CircularDipole | None,
                 end: tuple[Vec3, Vec3, Vec3] | None, inertia: Mat3, inertia_inv: Mat3, m: Vec3, h0: Vec3, hdot: Vec3,
                 td: Vec3, gg: bool, field: bool) -> tuple[Quat, Vec3, Vec3, Vec3]:
    """``n`` RK4 substeps of dt/n s of the attitude equations (module docstring) from (q, ω) at ``t0``: the new q
    (renormalised after each substep), ω and the RK4-weighted sums Σ (T_mag, T_gg) (divide by 6n for the mean).

    The stage environment (r_eci m, B_eci T as 6 floats) at the 2n+1 stage times t0 + dt·j/(2n)
    (:func:`stage_environment`): ``env``, all of them (``orbit`` and ``end`` None), or the start's only, with the
    circular orbit and tilted dipole ``orbit`` and the environment (r, v, B) ``end`` at t0 + dt
    (:func:`attitude_rk4_circular_dipole`). Dipole ``m`` A·m²; wheel momentum h0 + hdot·τ N·m·s; disturbance
    ``td`` N·m; ``gg`` gravity gradient on; ``field`` T_mag on.
    :func:`dynamics.integrator.rk4_step` written out on the seven floats (the same operations in the same
    order, so the same bits): a kernel (:mod:`acds_common.kernels`), compiled in the direct engine.
    """
    (i00, i01, i02), (i10, i11, i12), (i20, i21, i22) = inertia
    (j00, j01, j02), (j10, j11, j12), (j20, j21, j22) = inertia_inv
    mx, my, mz = m
    hx0, hy0, hz0 = h0
    hdx, hdy, hdz = hdot
    tdx, tdy, tdz = td
    pos = gg or field
    k_gg = 3.0 * units.EARTH_MU_M3_S2
    sub = dt / n
    stages = 2 * n

    def deriv(qx: float, qy: float, qz: float, qw: float, wx: float, wy: float, wz: float, tau: float,
              stage: _Env) -> tuple[float, ...]:
        """(q̇, ω̇, T_mag, T_gg) as 13 floats at attitude q, rate ω, ``tau`` into the step."""
        ex, ey, ez, bx, by, bz = stage
        tmx = tmy = tmz = tgx = tgy = tgz = 0.0
        if pos:
            # R (body → ECI) of q, acds_common.attitude.dcm inlined; a vector's body components are Rᵀ v.
            xx, yy, zz = qx * qx, qy * qy, qz * qz
            xy, xz, yz, xw, yw, zw = qx * qy, qx * qz, qy * qz, qx * qw, qy * qw, qz * qw
            r00, r01, r02 = 1.0 - 2.0 * (yy + zz), 2.0 * (xy - zw), 2.0 * (xz + yw)
            r10, r11, r12 = 2.0 * (xy + zw), 1.0 - 2.0 * (xx + zz), 2.0 * (yz - xw)
            r20, r21, r22 = 2.0 * (xz - yw), 2.0 * (yz + xw), 1.0 - 2.0 * (xx + yy)
            if field:  # T_mag = M × B_body
                ux = r00 * bx + r10 * by + r20 * bz
                uy = r01 * bx + r11 * by + r21 * bz
                uz = r02 * bx + r12 * by + r22 * bz
                tmx, tmy, tmz = my * uz - mz * uy, mz * ux - mx * uz, mx * uy - my * ux
            if gg:  # T_gg = 3μ/|r|⁵ · r_b × (I r_b)
                sx = r00 * ex + r10 * ey + r20 * ez
                sy = r01 * ex + r11 * ey + r21 * ez
                sz = r02 * ex + r12 * ey + r22 * ez
                r2 = sx * sx + sy * sy + sz * sz
                c = k_gg / (r2 * r2 * math.sqrt(r2))
                isx = i00 * sx + i01 * sy + i02 * sz
                isy = i10 * sx + i11 * sy + i12 * sz
                isz = i20 * sx + i21 * sy + i22 * sz
                tgx, tgy, tgz = c * (sy * isz - sz * isy), c * (sz * isx - sx * isz), c * (sx * isy - sy * isx)
        # Total momentum I ω + h(τ); net torque −ω × H − ḣ + T_mag + T_gg + T_d; ω̇ = I⁻¹ net.
        hx = i00 * wx + i01 * wy + i02 * wz + hx0 + hdx * tau
        hy = i10 * wx + i11 * wy + i12 * wz + hy0 + hdy * tau
        hz = i20 * wx + i21 * wy + i22 * wz + hz0 + hdz * tau
        nx = -(wy * hz - wz * hy) - hdx + tmx + tgx + tdx
        ny = -(wz * hx - wx * hz) - hdy + tmy + tgy + tdy
        nz = -(wx * hy - wy * hx) - hdz + tmz + tgz + tdz
        return (0.5 * (qw * wx + (qy * wz - qz * wy)), 0.5 * (qw * wy + (qz * wx - qx * wz)),
                0.5 * (qw * wz + (qx * wy - qy * wx)), -0.5 * (qx * wx + qy * wy + qz * wz),
                j00 * nx + j01 * ny + j02 * nz, j10 * nx + j11 * ny + j12 * nz, j20 * nx + j21 * ny + j22 * nz,
                tmx, tmy, tmz, tgx, tgy, tgz)

    qx, qy, qz, qw = q
    wx, wy, wz = w
    smx = smy = smz = sgx = sgy = sgz = 0.0  # Σ stage weight · (T_mag, T_gg)
    half, sixth = 0.5 * sub, sub / 6.0
    e1 = env[0]
    for k in range(n):
        e0 = e1
        eh = stage_environment(env, orbit, end, 2 * k + 1, stages, t0, dt, pos, field)
        e1 = stage_environment(env, orbit, end, 2 * k + 2, stages, t0, dt, pos, field)
        a = deriv(qx, qy, qz, qw, wx, wy, wz, k * sub, e0)
        b = deriv(qx + half * a[0], qy + half * a[1], qz + half * a[2], qw + half * a[3],
                  wx + half * a[4], wy + half * a[5], wz + half * a[6], (k + 0.5) * sub, eh)
        c = deriv(qx + half * b[0], qy + half * b[1], qz + half * b[2], qw + half * b[3],
                  wx + half * b[4], wy + half * b[5], wz + half * b[6], (k + 0.5) * sub, eh)
        d = deriv(qx + sub * c[0], qy + sub * c[1], qz + sub * c[2], qw + sub * c[3],
                  wx + sub * c[4], wy + sub * c[5], wz + sub * c[6], (k + 1.0) * sub, e1)
        qx += sixth * (a[0] + 2.0 * b[0] + 2.0 * c[0] + d[0])
        qy += sixth * (a[1] + 2.0 * b[1] + 2.0 * c[1] + d[1])
        qz += sixth * (a[2] + 2.0 * b[2] + 2.0 * c[2] + d[2])
        qw += sixth * (a[3] + 2.0 * b[3] + 2.0 * c[3] + d[3])
        wx += sixth * (a[4] + 2.0 * b[4] + 2.0 * c[4] + d[4])
        wy += sixth * (a[5] + 2.0 * b[5] + 2.0 * c[5] + d[5])
        wz += sixth * (a[6] + 2.0 * b[6] + 2.0 * c[6] + d[6])
        norm = math.sqrt(qx * qx + qy * qy + qz * qz + qw * qw)
        qx, qy, qz, qw = qx / norm, qy / norm, qz / norm, qw / norm
        smx += a[7] + 2.0 * b[7] + 2.0 * c[7] + d[7]
        smy += a[8] + 2.0 * b[8] + 2.0 * c[8] + d[8]
        smz += a[9] + 2.0 * b[9] + 2.0 * c[9] + d[9]
        sgx += a[10] + 2.0 * b[10] + 2.0 * c[10] + d[10]
        sgy += a[11] + 2.0 * b[11] + 2.0 * c[11] + d[11]
        sgz += a[12] + 2.0 * b[12] + 2.0 * c[12] + d[12]
    return (qx, qy, qz, qw), (wx, wy, wz), (smx, smy, smz), (sgx, sgy, sgz)


@kernels.helper
def attitude_rk4_circular_dipole(q: Quat, w: Vec3, n: int, t0: float, dt: float, start: _Env, orbit: CircularDipole,
                                 inertia: Mat3, inertia_inv: Mat3, m: Vec3, h0: Vec3, hdot: Vec3, td: Vec3, gg: bool,
                                 field: bool) -> tuple[Quat, Vec3, Vec3, Vec3, tuple[Vec3, Vec3, Vec3]]:
    """:func:`attitude_rk4` in a circular orbit and the tilted-dipole field ``orbit``
    (:func:`acds_common.environment.circular_dipole_parameters`, spec §3) evaluated here at the stage times
    after the first (``start``, the environment at t0, is known from the last step): its results and the full
    environment (r_eci m, v_eci m/s, B_eci T) at t0 + dt, where the truth is wanted. A kernel: one compiled call
    replaces the stage environment's Python (:mod:`acds_common.kernels`)."""
    end = circular_dipole_environment(orbit, t0 + dt, True)
    q1, w1, smag, sgg = attitude_rk4(q, w, n, t0, dt, (start,), orbit, end, inertia, inertia_inv, m, h0, hdot, td,
                                     gg, field)
    return q1, w1, smag, sgg, end


#: What :func:`advance_circular_dipole` and :func:`advance_stages` take once per model: RK4 substeps, inertia and
#: its inverse, the gravity gradient on, the Sun (:data:`SunAxes`).
BodyParams = tuple[int, Mat3, Mat3, bool, SunAxes]


@kernels.helper
def advanced(q: Quat, w: Vec3, smag: Vec3, sgg: Vec3, n: int, end: tuple[Vec3, Vec3, Vec3],
             sun: SunAxes) -> tuple[bool, Vec3, TruthValues]:
    """After ``n`` RK4 substeps to (q, ω) with the weighted torque sums ``smag``, ``sgg`` (:func:`attitude_rk4`) and
    the environment (r, v, B) ``end`` there: (q and ω finite, B_eci, :func:`truth_values` with the mean torques)."""
    finite = math.isfinite(q[0] + q[1] + q[2] + q[3] + (w[0] + w[1] + w[2]))  # a finite sum: every component finite
    w6 = 6.0 * n
    r, v, b = end
    return finite, b, truth_values(q, w, r, v, b, (smag[0] / w6, smag[1] / w6, smag[2] / w6),
                                   (sgg[0] / w6, sgg[1] / w6, sgg[2] / w6), sun)


@kernels.helper
def advance_circular_dipole(p: BodyParams, orbit: CircularDipole, q: Quat, w: Vec3, t0: float, dt: float, start: _Env,
                            m: Vec3, h0: Vec3, hdot: Vec3, td: Vec3, field: bool) -> tuple[bool, Vec3, TruthValues]:
    """One :meth:`RigidBodyModel.advance` in the circular orbit and tilted dipole ``orbit``
    (:func:`attitude_rk4_circular_dipole` from the environment ``start`` at t0) and its end (:func:`advanced`).
    A kernel (:mod:`acds_common.kernels`): the model's one compiled call per step."""
    n, inertia, inertia_inv, gg, sun = p
    q1, w1, smag, sgg, end = attitude_rk4_circular_dipole(q, w, n, t0, dt, start, orbit, inertia, inertia_inv, m, h0,
                                                          hdot, td, gg, field)
    return advanced(q1, w1, smag, sgg, n, end, sun)


def advance_stages(p: BodyParams, q: Quat, w: Vec3, t0: float, dt: float, env: tuple[_Env, ...],
                   end: tuple[Vec3, Vec3, Vec3], m: Vec3, h0: Vec3, hdot: Vec3, td: Vec3,
                   field: bool) -> tuple[bool, Vec3, TruthValues]:
    """One :meth:`RigidBodyModel.advance` for any orbit and field: :func:`attitude_rk4` on the stage environment
    ``env`` and the end (:func:`advanced`) at the environment ``end`` (r, v, B at t0 + dt). A kernel
    (:mod:`acds_common.kernels`)."""
    n, inertia, inertia_inv, gg, sun = p
    q1, w1, smag, sgg = attitude_rk4(q, w, n, t0, dt, env, None, None, inertia, inertia_inv, m, h0, hdot, td, gg,
                                     field)
    return advanced(q1, w1, smag, sgg, n, end, sun)


class RigidBodyModel:
    """Spacecraft attitude dynamics in its orbit and environment (spec §3).

    ``inertia_kg_m2`` 3×3 (see ``inertia_tensor``), ``orbit``, ``field`` (any ``MagneticFieldModel``),
    ``sun`` (its direction is fixed over a run, so the sun-pointed frame is computed once);
    ``ecliptic_normal_eci`` (ECI unit vector, default obliquity 23.44°) defines the sun-pointed frame;
    ``gravity_gradient`` switches T_gg; ``substeps`` RK4 substeps per ``advance``;
    ``q0_body_to_eci`` (x, y, z, w), ``omega0_body_rad_s`` body rates; ``t0_s`` start time (s).
    """

    def __init__(self, inertia_kg_m2: np.ndarray, orbit: Orbit, field: MagneticFieldModel, sun: Sun,
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
        self._inertia_t = mat3(inertia)
        self._inertia_inv_t = mat3(np.linalg.inv(inertia))
        self.orbit, self.field, self.sun = orbit, field, sun
        self._b_eci = field_xyz(field)
        self.ecliptic_normal_eci = (default_ecliptic_normal_eci() if ecliptic_normal_eci is None
                                    else finite_vector3("ecliptic_normal_eci", ecliptic_normal_eci))
        self._sun_frame = mat3(sun_frame_dcm(np.array(sun.direction_xyz), self.ecliptic_normal_eci))
        sun_line = self._sun_frame[2]  # the direction normalised: often the very same bits (a unit direction)
        #: The Sun's ECI direction given to ``Truth``: the sun line's row itself when the bits are the same, so that
        #: ``Truth`` rotates it once for both the sun sensor and the direction cosines.
        self._sun_eci = sun_line if _bits(sun_line) == _bits(sun.direction_xyz) else sun.direction_xyz
        self.gravity_gradient = bool(gravity_gradient)
        self.substeps = int(substeps)
        self._q: tuple[float, float, float, float] = tuple(float(c) for c in q0 / np.linalg.norm(q0))  # type: ignore
        self._w = finite_xyz("omega0_body_rad_s", omega0_body_rad_s)
        self._t = finite_float("t0_s", t0_s)
        #: The truth's values at the current time (None until the first ``advance`` or ``truth``).
        self._values: TruthValues | None = None
        self.disturbance = disturbance
        #: A circular orbit and the tilted dipole as floats: the kernel evaluates them at the stage times itself.
        self._circular_dipole = circular_dipole_parameters(orbit, field)
        #: The Sun as the truth takes it (:data:`SunAxes`; the row itself and ``is``: one rotation when it is the
        #: sun line) and the per-model constants of the advance kernel (:data:`BodyParams`).
        self._sun = (self._sun_eci, sun_line, self._sun_eci is sun_line, sun.direction_xyz, bool(sun.cfg.eclipse))
        self._params: BodyParams = (self.substeps, self._inertia_t, self._inertia_inv_t, self.gravity_gradient,
                                    self._sun)
        #: The advance kernel bound to the one signature :meth:`advance_unchecked` calls it with
        #: (:func:`kernels.bound`): the types are fixed by construction there: the parameters built here (an ``int``,
        #: float rows from :func:`mat3`, ``bool``s, the Sun's float triples: :func:`mat3` and
        #: :class:`~acds_common.environment.Sun`'s floats), the circular dipole's parameters fixed here, q and ω
        #: float tuples (from ``float``/:func:`finite_xyz` here, then the kernel's own results), t a float
        #: (:func:`finite_float`, then float sums), dt a float (:func:`positive_dt`; :meth:`advance_unchecked`'s
        #: contract, the stepper's ``positive_dt``), the environment float sextuples and (r, v, B) triples (the
        #: orbit's and field's floats or the kernel's end environment), m, h0 and ḣ float triples (:meth:`advance`
        #: makes them with :func:`finite_xyz`; the stepper passes its inputs' Vector3Stamped values, plain floats from
        #: :func:`acds_common.messages.vector3` or a kernel, the direct engine running only the built-in steppers),
        #: the disturbance a float triple whatever numbers the thrusters give (sums with the floats of ZERO or
        #: :func:`finite_xyz`), the field flag a ``bool`` (a comparison there). The test suite runs every shipped
        #: scenario with the check on (:func:`kernels.checking`).
        if self._circular_dipole is None:
            self._advance = kernels.bound(advance_stages, self._params, self._q, self._w, self._t, 1.0,
                                          (_NO_ENV,) * (2 * self.substeps + 1), (ZERO, ZERO, ZERO), ZERO, ZERO, ZERO,
                                          ZERO, True)
        else:
            self._advance = kernels.bound(advance_circular_dipole, self._params, self._circular_dipole, self._q,
                                          self._w, self._t, 1.0, _NO_ENV, ZERO, ZERO, ZERO, ZERO, True)
        #: The environment (t, r, v, b) at the last time it was needed in full: an ``advance`` ends
        #: where ``truth`` and the next ``advance`` start.
        self._env_cache: tuple[float, Vec3, Vec3, Vec3] | None = None

    @property
    def t_s(self) -> float:
        """Current time, s."""
        return self._t

    @property
    def q_body_to_eci(self) -> np.ndarray:
        """Current attitude quaternion (x, y, z, w), body → ECI."""
        return np.array(self._q)

    @property
    def omega_body_rad_s(self) -> np.ndarray:
        """Current body rates, rad/s."""
        return np.array(self._w)

    def _environment(self, t_s: float) -> tuple[Vec3, Vec3, Vec3]:
        """(r_eci, v_eci, b_eci) at ``t_s``, from the one-entry cache when it is that time."""
        cache = self._env_cache
        if cache is not None and cache[0] == t_s:
            return cache[1], cache[2], cache[3]
        r, v = self.orbit.state_xyz(t_s)
        b = self._b_eci(r, t_s)
        self._env_cache = (t_s, r, v, b)
        return r, v, b

    def _stage_environment(self, t0: float, dt: float, need_pos: bool, need_field: bool) -> tuple[_Env, ...]:
        """The attitude-independent environment at the 2n+1 distinct stage times t0 + dt·j/(2n)."""
        m = 2 * self.substeps
        env: list[_Env] = []
        for j in range(m + 1):
            tj = t0 + dt * (j / m)
            if not need_pos:
                env.append(_NO_ENV)
                continue
            if j == 0 or j == m:
                r, _v, b = self._environment(tj)
            else:
                r = self.orbit.position_xyz(tj)
                b = self._b_eci(r, tj) if need_field else ZERO
            env.append((*r, *b) if need_field else (*r, 0.0, 0.0, 0.0))
        return tuple(env)

    def advance(self, dt_s: float, dipole_body_am2: Sequence[float], wheel_h_body_nms: Sequence[float],
                wheel_hdot_body_nm: Sequence[float], thruster_torque_body_nm: Sequence[float] | None = None) -> None:
        """Integrate from t to t + ``dt_s`` (s).

        ``dipole_body_am2`` (A·m², constant over the step: the driver's time-averaged achieved
        dipole); wheel momentum h(τ) = ``wheel_h_body_nms`` + ``wheel_hdot_body_nm``·(τ − t) (N·m·s,
        N·m, body axes), 3-vectors as arrays or float triples; the disturbance torque at its exact mean
        over the step; ``thruster_torque_body_nm``: the cold-gas thrusters' step-average torque (N·m, body;
        None: no thrusters), added to the disturbance term. Records the step-average magnetic and
        gravity-gradient torques (RK4 stage weights, i.e. Simpson's rule per substep).
        """
        dt = positive_dt(dt_s)
        m = finite_xyz("dipole_body_am2", dipole_body_am2)
        h0 = finite_xyz("wheel_h_body_nms", wheel_h_body_nms)
        hdot = finite_xyz("wheel_hdot_body_nm", wheel_hdot_body_nm)
        gas = None if thruster_torque_body_nm is None else finite_xyz("thruster_torque_body_nm",
                                                                       thruster_torque_body_nm)
        self.advance_unchecked(dt, m, h0, hdot, gas)

    def advance_unchecked(self, dt: float, m: Vec3, h0: Vec3, hdot: Vec3, gas: Vec3 | None) -> TruthValues:
        """:meth:`advance` for a caller that has checked its inputs (the stepper, every step): ``dt`` a float
        > 0, the 3-vectors finite float triples (``gas`` the thruster torque or None). Spec §3. Returns the
        truth's values at the new time (:data:`TruthValues`, what :meth:`truth` gives as ``values``)."""
        t0 = self._t
        td = ZERO
        if self.disturbance is not None:
            td = finite_xyz("disturbance torque", self.disturbance.momentum_nms(t0, t0 + dt) / dt)
        if gas is not None:
            gx, gy, gz = gas
            td = (td[0] + gx, td[1] + gy, td[2] + gz)
        need_field = m[0] != 0.0 or m[1] != 0.0 or m[2] != 0.0
        t1 = t0 + dt
        if self._circular_dipole is None:
            env = self._stage_environment(t0, dt, need_field or self.gravity_gradient, need_field)
            end = self._environment(t1)
            finite, b, values = self._advance(self._params, self._q, self._w, t0, dt, env, end, m, h0, hdot, td,
                                              need_field)
        else:  # the kernel evaluates the orbit and field after the start, and gives the end's for truth
            r, _v, b = self._environment(t0)
            finite, b, values = self._advance(self._params, self._circular_dipole, self._q, self._w, t0, dt,
                                              (*r, *b), m, h0, hdot, td, need_field)
            self._env_cache = (t1, values[0], values[2], b)
        if not finite:
            raise DynamicsError("integration diverged (non-finite state): reduce dt_s or raise substeps")
        self._q, self._w = values[1], values[3]
        self._t = t1
        self._values = values
        return values

    def kernel_parts(self) -> tuple[BodyParams, CircularDipole, tuple[float, Vec3, TruthValues]] | None:
        """What a compiled caller needs to run :func:`advance_circular_dipole` in place of :meth:`advance_unchecked`
        (the direct engine's fused loop, :mod:`acds_common.fused`): the per-model parameters, the circular orbit and
        tilted dipole, and the state (t, B_eci at t, the truth's values at t); None when another path would run (no
        circular dipole, a disturbance torque) or before the first ``advance``."""
        cache = self._env_cache
        if (self._circular_dipole is None or self.disturbance is not None or self._values is None or cache is None
                or cache[0] != self._t):
            return None
        return self._params, self._circular_dipole, (self._t, cache[3], self._values)

    def set_kernel_state(self, t: float, b: Vec3, values: TruthValues) -> None:
        """The state :meth:`kernel_parts` gave, advanced by a compiled caller: t, B_eci at t, the truth's values."""
        self._t, self._q, self._w, self._values = t, values[1], values[3], values
        self._env_cache = (t, values[0], values[2], b)

    def truth(self, wheel_h_body_nms: Sequence[float]) -> Truth:
        """Truth at the current time; ``wheel_h_body_nms`` (N·m·s, body) for the total momentum."""
        return self.truth_unchecked(finite_xyz("wheel_h_body_nms", wheel_h_body_nms))

    def truth_unchecked(self, h: Vec3) -> Truth:
        """:meth:`truth` for a caller that has checked ``h`` (a finite float triple): the stepper, every step."""
        t = self._t
        r, v, b = self._environment(t)
        if self._values is None:  # before the first advance: no torques yet
            self._values = truth_values(self._q, self._w, r, v, b, ZERO, ZERO, self._sun)
        return Truth(t, self._values, b, h, self._inertia_t, self._sun_frame)
