"""Magnetic control laws of the DPA: B-dot, B×H and the proposed lead law (spec §7; seed 002 §4.2.1).

Conventions
-----------
* Field ``b_t`` in tesla, body axes; momentum in N·m·s; moments in A·m² (= amp-turn-m²).
* The torque on the spacecraft is ``T = M × B`` (seed eq. 4-2, 4-11).
* Gains are taken in the study's units at the call (they are what a ground
  command or a scenario quotes) and converted to SI here, in one place:

  - B×H gain G in (s·G²)⁻¹: with B in G and H in ft-lb-s the study's moment
    comes out in ft-lb/G, and 1 ft-lb/G = 13558.2 A·m²
    (``acds_common.units.FTLB_PER_GAUSS_AM2``); in SI the same gain is
    G / (1e-4)² = G·1e8 (s·T²)⁻¹ (:func:`bxh_gain_to_si`).
  - B-dot gain K_D in ft-lb-s/G²: with Ḃ in G/s the moment is in ft-lb/G;
    in SI K_D·13558.2/1e-4 = K_D·1.3558e8 A·m²·s/T (:func:`bdot_gain_to_si`).

This module also holds the package's exception :class:`ControllerError` and
the input checks every acds_controller core uses. Each law has a float-triple kernel
(``*_xyz``, SI gains, no checks: what the DPA runs every control period) behind its checked
numpy function; the DPA's compiled step (:func:`acds_controller.dpa.dpa_step`) calls the kernels
(:func:`acds_common.kernels.helper`).
"""

from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np
from acds_common import kernels, validation
from acds_common.units import FT_LB_S_NMS, FTLB_PER_GAUSS_AM2, GAUSS_T
from acds_common.vec3 import Mat3, Vec3, clip, cross, mat3, mv

#: Baseline per-axis electromagnet moment limit, A·m² (seed 002 §4.3.1; 1000 and 3000 also studied).
MAX_MOMENT_AM2 = 2000.0
#: B×H acquisition gain (Mode 1A, H = I·ω), (s·G²)⁻¹ (seed 002 §4.2.3.1, figures "K=.05").
G_ACQUISITION_STUDY = 0.05
#: B×H unloading gain for HEAO-A celestial scan, (s·G²)⁻¹ (seed 002 §4.2.3.2).
G_UNLOAD_SCAN_STUDY = 0.01
#: B×H unloading gain for HEAO-B celestial point, (s·G²)⁻¹ (seed 002 §4.3.2.2).
G_UNLOAD_POINT_STUDY = 0.02
#: B-dot gain found satisfactory, ft-lb-s/G² (seed 002 §4.2.3.1; range studied 1–10).
K_D_STUDY = 1.0


class ControllerError(ValueError):
    """Invalid input, gain or configuration given to an acds_controller core (spec §7)."""


def as_vector3(x: object, name: str) -> np.ndarray:
    """Return ``x`` as a finite float (3,) array or raise :class:`ControllerError` naming ``name``."""
    return validation.finite_vector3(name, x, ControllerError)


def as_xyz(x: object, name: str) -> Vec3:
    """Return ``x`` as a finite float triple or raise :class:`ControllerError` naming ``name`` (no numpy)."""
    return validation.finite_xyz(name, x, ControllerError)


def as_matrix3(x: object, name: str) -> np.ndarray:
    """Return ``x`` as a finite float (3, 3) array or raise :class:`ControllerError` naming ``name``."""
    try:
        m = np.asarray(x, dtype=float)
    except (TypeError, ValueError) as exc:
        raise ControllerError(f'{name} must be a 3×3 matrix of numbers, got {x!r}') from exc
    if m.shape != (3, 3):
        raise ControllerError(f'{name} must be a 3×3 matrix, got shape {m.shape}')
    if not np.all(np.isfinite(m)):
        raise ControllerError(f'{name} must be finite, got {m.tolist()}')
    return m


def check_gain(value: float, name: str, lo: float, hi: float) -> float:
    """Return ``value`` as float if finite and within [lo, hi], else raise :class:`ControllerError`."""
    try:
        v = float(value)
    except (TypeError, ValueError) as exc:
        raise ControllerError(f'{name} must be a number, got {value!r}') from exc
    if not math.isfinite(v) or not lo <= v <= hi:
        raise ControllerError(f'{name} = {value!r} is out of range [{lo:g}, {hi:g}]')
    return v


def bxh_gain_to_si(gain_study: float) -> float:
    """B×H gain (s·G²)⁻¹ → SI (s·T²)⁻¹, so that M[A·m²] = G_SI·(B[T] × H[N·m·s]) (seed 002 eq. 4-17).

    Derivation: M[ft-lb/G] = G·B[G]·H[ft-lb-s]; M[A·m²] = 13558.2·M[ft-lb/G];
    B[G] = B[T]/1e-4; H[ft-lb-s] = H[N·m·s]/1.3558179.
    """
    return gain_study * FTLB_PER_GAUSS_AM2 / (GAUSS_T * FT_LB_S_NMS)


def bdot_gain_to_si(k_d_study: float) -> float:
    """B-dot gain ft-lb-s/G² → SI A·m²·s/T, so that M[A·m²] = −K_SI·Ḃ[T/s] (seed 002 eq. 4-9)."""
    return k_d_study * FTLB_PER_GAUSS_AM2 / GAUSS_T


@kernels.helper
def bdot_moment_xyz(b_now_t: Sequence[float], b_prev_t: Sequence[float], dt_s: float, k_si: float) -> Vec3:
    """Kernel of :func:`bdot_moment`: −K·(B_now − B_prev)/Δt with K in SI (A·m²·s/T)."""
    c = -k_si
    return (c * (b_now_t[0] - b_prev_t[0]) / dt_s, c * (b_now_t[1] - b_prev_t[1]) / dt_s,
            c * (b_now_t[2] - b_prev_t[2]) / dt_s)


def bdot_moment(b_now_t: np.ndarray, b_prev_t: np.ndarray, dt_s: float, k_d: float) -> np.ndarray:
    """B-dot law M = −K_D·dB/dt, dB/dt by backward difference of two field samples (seed 002 eq. 4-9).

    ``b_now_t``, ``b_prev_t``: sensed field (T, body) now and one control period ``dt_s`` (s) ago;
    ``k_d``: gain in the study's ft-lb-s/G² (1–10 studied, ≈1 satisfactory). Returns A·m²
    (unsaturated). Each moment component has the polarity opposite to the field rate (eq. 4-8),
    so the rate of work M·Ḃ (eq. 4-6) is negative.
    """
    b_now = as_xyz(b_now_t, 'b_now_t')
    b_prev = as_xyz(b_prev_t, 'b_prev_t')
    dt = check_gain(dt_s, 'dt_s', 0.0, np.inf)
    if dt == 0.0:
        raise ControllerError('dt_s must be > 0 s for the B-dot difference')
    k = check_gain(k_d, 'k_d (ft-lb-s/G²)', 0.0, np.inf)
    return np.array(bdot_moment_xyz(b_now, b_prev, dt, bdot_gain_to_si(k)))


@kernels.helper
def bxh_moment_xyz(b_t: Sequence[float], h_nms: Sequence[float], gain_si: float) -> Vec3:
    """Kernel of :func:`bxh_moment`: −G·(B × H) with G in SI ((s·T²)⁻¹)."""
    c = -gain_si
    bh = cross(b_t, h_nms)
    return c * bh[0], c * bh[1], c * bh[2]


def bxh_moment(b_t: np.ndarray, h_nms: np.ndarray, gain_study: float) -> np.ndarray:
    """B×H law M = −G (B × H) with K/B² held constant as G (seed 002 eq. 4-17, §4.2.3.1).

    ``b_t``: field (T, body); ``h_nms``: momentum to remove (N·m·s, body): I·ω in Mode 1A,
    wheel momentum h in Mode 1B and cruise; ``gain_study``: G in (s·G²)⁻¹ (0.05 acquisition,
    0.01 HEAO-A scan unloading, 0.02 HEAO-B point unloading). Returns A·m² (unsaturated),
    perpendicular to B. The torque M × B = −G·B²·H⊥ opposes the part of H normal to B,
    so it never increases |H|. In the study's units |M| = G·|B|[G]·|H|[ft-lb-s]·13558.2
    for B ⊥ H.
    """
    b = as_xyz(b_t, 'b_t')
    h = as_xyz(h_nms, 'h_nms')
    g = check_gain(gain_study, 'gain_study ((s·G²)⁻¹)', 0.0, np.inf)
    return np.array(bxh_moment_xyz(b, h, bxh_gain_to_si(g)))


@kernels.helper
def wheel_command_momentum_xyz(wheel_volts_v: Sequence[float], wheel_torque_gain_nm_per_v2: float,
                               lead_time_s: float) -> Vec3:
    """Kernel of :func:`wheel_command_momentum_nms`: τ_lead·k·V|V| per axis."""
    c = lead_time_s * wheel_torque_gain_nm_per_v2
    v0, v1, v2 = wheel_volts_v
    return c * v0 * abs(v0), c * v1 * abs(v1), c * v2 * abs(v2)


def wheel_command_momentum_nms(
    wheel_volts_v: np.ndarray, wheel_torque_gain_nm_per_v2: float, lead_time_s: float
) -> np.ndarray:
    """Wheel command vector ε expressed as momentum for the lead law (seed 002 eq. 4-37), N·m·s.

    The seed adds the wheel command ε (volts) to the stored momentum H without a unit.
    Here ε is the momentum the wheels will have absorbed ``lead_time_s`` seconds ahead at
    the present command: ε = τ_lead·k·V|V| per axis (square-law wheel torque ḣ = k·V|V|,
    ``wheel_torque_gain_nm_per_v2`` = k in N·m/V²). It points the way h is growing, so
    H + ε anticipates the build-up of wheel momentum.
    """
    v = as_xyz(wheel_volts_v, 'wheel_volts_v')
    k = check_gain(wheel_torque_gain_nm_per_v2, 'wheel_torque_gain_nm_per_v2', 0.0, np.inf)
    tau = check_gain(lead_time_s, 'lead_time_s', 0.0, np.inf)
    return np.array(wheel_command_momentum_xyz(v, k, tau))


@kernels.helper
def lead_moment_xyz(b_t: Sequence[float], h_nms: Sequence[float], eps_wheel_cmd: Sequence[float],
                    gain_si: float) -> Vec3:
    """Kernel of :func:`lead_moment`: the B×H kernel on H + ε."""
    return bxh_moment_xyz(b_t, (h_nms[0] + eps_wheel_cmd[0], h_nms[1] + eps_wheel_cmd[1],
                                h_nms[2] + eps_wheel_cmd[2]), gain_si)


def lead_moment(b_t: np.ndarray, h_nms: np.ndarray, eps_wheel_cmd: np.ndarray, gain: float) -> np.ndarray:
    """Proposed lead unloading law M = K_unld (H + ε) × B (seed 002 eq. 4-37, never developed there).

    ``b_t``: field (T, body); ``h_nms``: stored wheel momentum (N·m·s); ``eps_wheel_cmd``: the
    wheel command expressed as momentum, N·m·s (see :func:`wheel_command_momentum_nms`);
    ``gain``: K_unld in the study's (s·G²)⁻¹. Returns A·m² (unsaturated).

    Sign: (H + ε) × B = −B × (H + ε), so with ε = 0 this is exactly the B×H law. The torque
    M × B = −K·B²·(H + ε)⊥ reduces |H + ε|, the anticipated momentum; it may briefly raise
    |H| when the wheel command opposes the stored momentum (that is the lead action).
    """
    b = as_xyz(b_t, 'b_t')
    h = as_xyz(h_nms, 'h_nms')
    eps = as_xyz(eps_wheel_cmd, 'eps_wheel_cmd')
    g = check_gain(gain, 'gain_study ((s·G²)⁻¹)', 0.0, np.inf)
    return np.array(lead_moment_xyz(b, h, eps, bxh_gain_to_si(g)))


def saturate(m: np.ndarray, max_moment_am2: float = MAX_MOMENT_AM2) -> np.ndarray:
    """Clip each axis of the moment command to ±``max_moment_am2`` (A·m²) (seed 002 §4.3.1).

    Per-axis clipping keeps each component's sign, so a saturated B×H command still
    removes momentum (M_sat·(B × H) has the sign of M·(B × H)).
    """
    mv3 = as_xyz(m, 'm')
    limit = check_gain(max_moment_am2, 'max_moment_am2', 0.0, np.inf)
    return np.array(clip(mv3, limit))


@kernels.helper
def compensate_coupling_xyz(b_sensed_t: Sequence[float], delta_t_per_am2: Mat3, m_prev_am2: Sequence[float]) -> Vec3:
    """Kernel of :func:`compensate_coupling`: B_sensed − Δ·M."""
    dm = mv(delta_t_per_am2, m_prev_am2)
    return b_sensed_t[0] - dm[0], b_sensed_t[1] - dm[1], b_sensed_t[2] - dm[2]


def compensate_coupling(
    b_sensed_t: np.ndarray, delta_t_per_am2: np.ndarray, m_prev_am2: np.ndarray
) -> np.ndarray:
    """Remove the electromagnets' known field at the magnetometer: B = B_sensed − Δ·M (spec §5, seed 002 eq. 4-30).

    ``delta_t_per_am2``: 3×3 coupling Δ in T per A·m² (the study's 8.75e-6 G per A·m² is
    8.75e-10 T per A·m²); ``m_prev_am2``: the moment being produced while the field was
    sensed (the previous command), A·m². Returns T.
    """
    b = as_xyz(b_sensed_t, 'b_sensed_t')
    delta = as_matrix3(delta_t_per_am2, 'delta_t_per_am2')
    m = as_xyz(m_prev_am2, 'm_prev_am2')
    return np.array(compensate_coupling_xyz(b, mat3(delta), m))
