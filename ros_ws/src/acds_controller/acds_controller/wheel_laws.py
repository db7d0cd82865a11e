"""Reaction wheel control laws and attitude errors of the DPA (spec §7; seed 002 §4.2.2, §4.2.3, Table 4-2).

Each law has a float-triple kernel (``*_xyz``, no checks: what the DPA runs every control
period, compiled in the direct engine: :func:`acds_common.kernels.helper`) behind its checked numpy function.

Sign convention (explicit, used by every function here)
-------------------------------------------------------
* The attitude error θ_i is the body's rotation about body axis i *away from* the
  reference, positive by the right-hand rule (the body is rotated by +θ_i beyond where
  it should be). Rates ω_i are the gyro body rates.
* The law ε_i = K_pi (θ_i^L + K_ri ω_i) (eq. 4-18…4-20) is sent to the wheel drive
  unchanged: V_i = ε_i clipped to ±V_sat.
* Square-law wheel: ḣ_i = k·V_i|V_i| along body axis i, and the body feels −ḣ_i (seed:
  "torques equal and opposite to the motor torques are applied to the spacecraft body").
  So a positive error or rate gives V > 0, ḣ > 0 and a negative body torque, which drives
  θ and ω back to zero. No extra sign is needed as long as θ is defined as above.
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
from acds_common import kernels
from acds_common.attitude import Quat, conj, quat_mul, to_body
from acds_common.units import rad, rpm_to_rad_s
from acds_common.vec3 import Vec3

from acds_controller.magnetic_laws import ControllerError, as_xyz, check_gain

#: Wheel controller saturation, V (seed 002 §4.2.3.1).
V_SAT_V = 17.1
#: Acquisition maneuver rate limit, rad/s (Table 4-2: 0.1 deg/s each axis).
MANEUVER_RATE_LIMIT_RAD_S = rad(0.1)
#: Baseline celestial scan rate about z, rad/s (seed 002 §4.3.2.1: 0.03 rpm; 0.1 rpm also studied).
SCAN_RATE_RAD_S = rpm_to_rad_s(0.03)

_TRIPLE = tuple[float, float, float]
#: |ω_z| above which the scan yaw law refuses the gyro rate, rad/s.
SCAN_OMEGA_LIMIT_RAD_S = 10.0


@dataclass(frozen=True)
class WheelLawGains:
    """Per-axis (x roll, y pitch, z yaw) wheel controller gains (Table 4-2).

    ``k_p_v_per_rad``: position gain K_p, V/rad. ``theta_limit_rad``: attitude-error limit
    θ_limit, rad, or None for no limiter (normal mode). ``k_r_s``: rate gain K_r, s.
    """

    k_p_v_per_rad: _TRIPLE
    theta_limit_rad: tuple[float | None, float | None, float | None]
    k_r_s: _TRIPLE

    def __post_init__(self) -> None:
        for name in ('k_p_v_per_rad', 'theta_limit_rad', 'k_r_s'):
            if len(getattr(self, name)) != 3:
                raise ControllerError(f'WheelLawGains.{name} needs 3 values (x, y, z)')
        for i in range(3):
            check_gain(self.k_p_v_per_rad[i], f'k_p_v_per_rad[{i}] (V/rad)', 0.0, 1e8)
            check_gain(self.k_r_s[i], f'k_r_s[{i}] (s)', 0.0, 1e5)
            limit = self.theta_limit_rad[i]
            if limit is not None:
                check_gain(limit, f'theta_limit_rad[{i}] (rad)', 1e-9, math.pi)

    @property
    def row(self) -> tuple[_TRIPLE, _TRIPLE, _TRIPLE]:
        """The gains as :func:`wheel_volts_xyz` reads them: K_p, θ_limit (no limiter: +∞, which limits nothing, a
        NaN or −0 included) and K_r, float triples."""
        kp, limits, kr = self.k_p_v_per_rad, self.theta_limit_rad, self.k_r_s
        lx, ly, lz = (math.inf if v is None else float(v) for v in limits)
        return (float(kp[0]), float(kp[1]), float(kp[2])), (lx, ly, lz), (float(kr[0]), float(kr[1]), float(kr[2]))

    def with_axis(self, param: str, axis: int, value: float | None) -> WheelLawGains:
        """Copy with one axis of ``param`` ('k_p_v_per_rad', 'theta_limit_rad' or 'k_r_s') replaced."""
        values = list(getattr(self, param))
        values[axis] = value
        return dataclasses.replace(self, **{param: tuple(values)})


#: HEAO-A acquisition (Table 4-2).
HEAO_A_ACQUISITION = WheelLawGains((865.0, 162.0, 162.0), (0.0196, 0.105, 0.105), (11.2, 60.0, 60.0))
#: HEAO-B acquisition, pitch/yaw at the study's final values (§4.2.3.1: 97 V/rad, 0.075 rad, 100 s).
HEAO_B_ACQUISITION = WheelLawGains((684.0, 97.0, 97.0), (0.025, 0.075, 0.075), (14.3, 100.0, 100.0))
#: HEAO-B acquisition, Table 4-2 preliminary pitch/yaw values (300 V/rad, 0.057 rad, 32.6 s).
HEAO_B_ACQUISITION_PRELIMINARY = WheelLawGains(
    (684.0, 300.0, 300.0), (0.025, 0.057, 0.057), (14.3, 32.6, 32.6))
#: Normal mode (celestial point and scan), no error limiter (Table 4-2).
NORMAL_MODE = WheelLawGains((3.64e4, 2.16e5, 2.16e5), (None, None, None), (11.7, 5.65, 5.65))


def design_gains(
    theta_eps_rad: float, rate_limit_rad_s: float = MANEUVER_RATE_LIMIT_RAD_S, v_sat_v: float = V_SAT_V
) -> tuple[float, float]:
    """Deadbeat design relations (seed 002 eq. 4-24, 4-25): returns (K_p V/rad, K_r s).

    K_p = V_sat/θ_ε. The rate gain is the switching-line slope K_r = θ_ε/ω^L (s); the seed
    prints ω^L/θ_ε, but only θ_ε/ω^L has the unit s and reproduces Table 4-2
    (0.0196 rad / 0.1°/s = 11.2 s, 0.105 rad / 0.1°/s = 60.2 s).
    """
    theta = check_gain(theta_eps_rad, 'theta_eps_rad', 1e-9, math.pi)
    rate = check_gain(rate_limit_rad_s, 'rate_limit_rad_s', 1e-9, 1.0)
    return v_sat_v / theta, theta / rate


@kernels.helper
def axis_volts(theta: float, omega: float, kp: float, limit: float, kr: float, v_sat_v: float) -> float:
    """One axis of :func:`wheel_volts_xyz`: K_p (θ^L + K_r ω), θ^L = θ limited to ±``limit``, clipped to ±V_sat."""
    theta = min(max(theta, -limit), limit)
    return min(max(kp * (theta + kr * omega), -v_sat_v), v_sat_v)


@kernels.helper
def wheel_volts_xyz(theta_err_rad: Sequence[float], omega_rad_s: Sequence[float],
                    row: tuple[_TRIPLE, _TRIPLE, _TRIPLE], v_sat_v: float) -> Vec3:
    """Kernel of :func:`wheel_volts` on the gains' :attr:`WheelLawGains.row`."""
    kp, limits, kr = row
    return (axis_volts(theta_err_rad[0], omega_rad_s[0], kp[0], limits[0], kr[0], v_sat_v),
            axis_volts(theta_err_rad[1], omega_rad_s[1], kp[1], limits[1], kr[1], v_sat_v),
            axis_volts(theta_err_rad[2], omega_rad_s[2], kp[2], limits[2], kr[2], v_sat_v))


def wheel_volts(
    theta_err_rad: np.ndarray, omega_rad_s: np.ndarray, gains: WheelLawGains, v_sat_v: float = V_SAT_V
) -> np.ndarray:
    """Wheel drive volts ε_i = K_pi (θ_i^L + K_ri ω_i), θ^L limited to ±θ_limit, clipped to ±V_sat.

    Seed 002 eq. 4-18…4-20. ``theta_err_rad``: attitude error (rad, body, sign convention in
    the module docstring); ``omega_rad_s``: gyro rates (rad/s); ``v_sat_v``: saturation (V).
    Returns volts per body axis; positive volts drive the body torque negative.
    """
    theta = as_xyz(theta_err_rad, 'theta_err_rad')
    omega = as_xyz(omega_rad_s, 'omega_rad_s')
    v_sat = check_gain(v_sat_v, 'v_sat_v', 0.0, 1e3)
    return np.array(wheel_volts_xyz(theta, omega, gains.row, v_sat))


@kernels.helper
def scan_yaw_volts_xyz(omega_z: float, omega_z0: float, k_pz: float, k_rz: float, v_sat_v: float) -> float:
    """Kernel of :func:`scan_yaw_volts` (no checks)."""
    return min(max(k_pz * k_rz * (omega_z - omega_z0), -v_sat_v), v_sat_v)


def scan_yaw_volts(
    omega_z: float, omega_z0: float, k_pz: float, k_rz: float, v_sat_v: float = V_SAT_V
) -> float:
    """Celestial scan yaw law ε_z = K_pz K_rz (ω_z − ω_z0), clipped to ±V_sat (seed 002 eq. 4-26).

    ``omega_z``: gyro z rate, ``omega_z0``: desired scan rate (rad/s; 0.03 rpm baseline);
    ``k_pz`` V/rad, ``k_rz`` s. Spinning faster than ω_z0 gives V > 0, a negative body torque.
    """
    lim = SCAN_OMEGA_LIMIT_RAD_S
    wz = check_gain(omega_z, 'omega_z (rad/s)', -lim, lim)
    wz0 = check_gain(omega_z0, 'omega_z0 (rad/s)', -lim, lim)
    kp, kr = check_gain(k_pz, 'k_pz (V/rad)', 0.0, 1e8), check_gain(k_rz, 'k_rz (s)', 0.0, 1e5)
    return scan_yaw_volts_xyz(wz, wz0, kp, kr, check_gain(v_sat_v, 'v_sat_v', 0.0, 1e3))


@kernels.helper
def pointing_error_xyz(target_body: Sequence[float]) -> Vec3:
    """Kernel of :func:`pointing_error` (raises :class:`ControllerError` for a zero vector)."""
    sx, sy, sz = target_body
    norm = math.sqrt(sx * sx + sy * sy + sz * sz)
    if norm < 1e-9:
        raise ControllerError('target_body_unit is the zero vector: no direction to point at')
    sx, sy, sz = sx / norm, sy / norm, sz / norm
    sin_angle = math.sqrt(sy * sy + sx * sx)  # |(s_y, −s_x, 0)|
    angle = math.atan2(sin_angle, sz)
    if sin_angle < 1e-12:
        return angle, 0.0, 0.0
    return sy / sin_angle * angle, -sx / sin_angle * angle, 0.0


def pointing_error(target_body_unit: np.ndarray) -> np.ndarray:
    """Error (rad, body) of the body z axis from a target direction given in body axes.

    Used for sun acquisition (target = sun sensor vector) and for the scan axis hold.
    The error is the rotation angle acos(s_z) about the axis s × ẑ / |s × ẑ|: for a small
    tilt it is (s_y, −s_x, 0), i.e. roll error = B23 and pitch error = −B13 as in the
    study's plots (§4.3.1). Its z component is zero: rotation about the target line is not
    controlled (B12 free), only its rate is nulled by the K_r·ω_z term. A target exactly
    behind (s = −ẑ) gives π about body x.
    """
    return np.array(pointing_error_xyz(as_xyz(target_body_unit, 'target_body_unit')))


@kernels.helper
def unit_quaternion_checked(x: float, y: float, z: float, w: float) -> tuple[int, float, Quat]:
    """Kernel of :func:`unit_quaternion_xyzw` on four floats: (0, |q|, q/|q|); status 1 when not finite, 2 when
    |q| is more than 1e-3 from 1 (then the quaternion is (0, 0, 0, 1))."""
    if not (math.isfinite(x) and math.isfinite(y) and math.isfinite(z) and math.isfinite(w)):
        return 1, 0.0, (0.0, 0.0, 0.0, 1.0)
    norm = math.sqrt(x * x + y * y + z * z + w * w)
    if abs(norm - 1.0) > 1e-3:
        return 2, norm, (0.0, 0.0, 0.0, 1.0)
    return 0, norm, (x / norm, y / norm, z / norm, w / norm)


def unit_quaternion_xyzw(q: object, name: str) -> Quat:
    """:func:`as_unit_quaternion` as a float 4-tuple: the same checks."""
    try:
        x, y, z, w = (float(c) for c in q)  # type: ignore[attr-defined]
    except (TypeError, ValueError):
        raise ControllerError(f'{name} must be a finite (x, y, z, w) quaternion, got {q!r}') from None
    status, norm, unit = unit_quaternion_checked(x, y, z, w)
    if status == 1:
        raise ControllerError(f'{name} must be a finite (x, y, z, w) quaternion, got {q!r}')
    if status == 2:
        raise ControllerError(f'{name} must be a unit quaternion, |q| = {norm:.6g}')
    return unit


def as_unit_quaternion(q: object, name: str) -> np.ndarray:
    """Return ``q`` as a finite unit (x, y, z, w) quaternion or raise :class:`ControllerError`."""
    return np.array(unit_quaternion_xyzw(q, name))


def rotate_to_body(q_body_to_eci: np.ndarray, v_eci: np.ndarray) -> np.ndarray:
    """Express an ECI vector in body axes: R(q)ᵀ v, q body→ECI (x, y, z, w)."""
    q = unit_quaternion_xyzw(q_body_to_eci, 'q_body_to_eci')
    return np.array(to_body(q, as_xyz(v_eci, 'v_eci')))


@kernels.helper
def inertial_hold_error_xyz(q: Sequence[float], q_target: Sequence[float]) -> Vec3:
    """Kernel of :func:`inertial_hold_error` (unit quaternions)."""
    x, y, z, w = quat_mul(conj(q_target), q)
    c = 2.0 * (1.0 if w >= 0.0 else -1.0)
    return c * x, c * y, c * z


def inertial_hold_error(q_body_to_eci: np.ndarray, q_target_body_to_eci: np.ndarray) -> np.ndarray:
    """Celestial point attitude error (rad, body): small-angle vector 2·sign(w)·vec(q_t* ⊗ q).

    q_t* ⊗ q is the body attitude relative to the target frame; a body rotated by +φ about
    its x axis beyond the target gives (φ, 0, 0), matching the wheel-law sign convention.
    """
    q = unit_quaternion_xyzw(q_body_to_eci, 'q_body_to_eci')
    qt = unit_quaternion_xyzw(q_target_body_to_eci, 'q_target_body_to_eci')
    return np.array(inertial_hold_error_xyz(q, qt))
