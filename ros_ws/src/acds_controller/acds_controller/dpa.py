"""Digital processor (DPA): one control period of the HEAO wheel/magnetics ACDS (spec §7; seed 002 §4.1–4.2).

Per step the DPA takes the sensed field (from the transfer assembly), gyro rates, the sun
sensor vector, the wheel momentum and the attitude reference, and returns the moment
command for the electromagnet drivers and the wheel drive volts. Modes (exact strings):

* ``'standby'``: everything zero.
* ``'mode_1a'``: rate reduction, magnetics only on the body momentum H = I·ω (B×H, G = 0.05)
  or B-dot (K_D ≈ 1), or the CubeSat detumble law M = −(k_ω/|B|)(B̂ × ω) (``b_cross_omega``,
  seed 003, :mod:`acds_controller.b_cross_omega`); wheels off (0 V).
* ``'mode_1b'``: sun acquisition; the wheels close the loop on the sun-sensor error and gyro
  rate with the acquisition gains (Table 4-2); the magnetics unload the wheels (H = h).
  With the sun absent (zero sun vector) the position term is zero: rate damping only.
* ``'celestial_scan'``: normal-mode gains; x/y hold the scan axis (the z axis of the target
  attitude) on its inertial direction, z follows the scan-rate law (eq. 4-26); unloading G = 0.01.
* ``'celestial_point'``: normal-mode gains, inertial hold of the target attitude; unloading G = 0.02.

Unloading law ``b_cross_h`` is seed 003's momentum-dumping form M = −(k_h/|B|)(B̂ × h) with one
gain k_h (s⁻¹) in every unloading mode. With no sensed field (zero vector: no magnetometer) the
two seed-003 laws command nothing, as B×H and B-dot do.

One period is one kernel, :func:`dpa_step` (:mod:`acds_common.kernels`), on the DPA's parameters
(:attr:`Dpa.params`, built when the configuration is set) and state (previous field and command): what
:meth:`Dpa.step` runs and what the stepper's compiled step calls.

Mode 1B unloading gain: the study does not quote a separate value; its acquisition runs carry
one gain label (K = .05) through the whole run, so 0.05 (s·G²)⁻¹ is the default
(``unloading_gain_mode_1b_study``).
"""

from __future__ import annotations

import dataclasses
import functools
from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np
from acds_common import kernels
from acds_common.attitude import Quat, conj, to_body
from acds_common.dpa_commands import AXES, GAIN_TABLE, LAW_CHOICES, SCALAR_GAINS
from acds_common.modes import CELESTIAL_POINT, HEAO_CRUISE_MODES, HEAO_MODES, MODE_1A, MODE_1B, STANDBY
from acds_common.units import FT_LB_NM, deg, nms_to_ftlbs, rad_s_to_rpm, rpm_to_rad_s, tesla_to_gauss
from acds_common.vec3 import ZERO, Vec3, clip, mat3, mv, norm

from acds_controller.b_cross_omega import B_ZERO_MESSAGE, K_OMEGA_SEED, cross_law_xyz
from acds_controller.magnetic_laws import (
    G_ACQUISITION_STUDY,
    G_UNLOAD_POINT_STUDY,
    G_UNLOAD_SCAN_STUDY,
    K_D_STUDY,
    MAX_MOMENT_AM2,
    ControllerError,
    as_matrix3,
    as_xyz,
    bdot_gain_to_si,
    bdot_moment_xyz,
    bxh_gain_to_si,
    bxh_moment_xyz,
    check_gain,
    compensate_coupling_xyz,
    lead_moment_xyz,
    wheel_command_momentum_xyz,
)
from acds_controller.wheel_laws import (
    HEAO_B_ACQUISITION,
    NORMAL_MODE,
    SCAN_OMEGA_LIMIT_RAD_S,
    SCAN_RATE_RAD_S,
    V_SAT_V,
    WheelLawGains,
    as_unit_quaternion,
    inertial_hold_error_xyz,
    pointing_error_xyz,
    scan_yaw_volts,
    scan_yaw_volts_xyz,
    unit_quaternion_checked,
    unit_quaternion_xyzw,
    wheel_volts_xyz,
)

#: Wheel torque gain k for ḣ = k·V|V|, N·m/V²: 0.117 ft-lb (Table 4-2 design torque) at V_sat.
WHEEL_TORQUE_GAIN_NM_PER_V2 = 0.117 * FT_LB_NM / V_SAT_V**2
#: Lead-law time constant, s: ≈ 1/(G_unld·B²) for G = 0.02 (s·G²)⁻¹ and |B| ≈ 0.3 G.
LEAD_TIME_S = 500.0
#: A sun-sensor vector shorter than this means "sun absent" (the sensor sends zeros).
_SUN_PRESENT_MIN_NORM = 0.5

#: Ground-command gain sets and parameters → the DpaConfig / WheelLawGains fields they set.
_WHEEL_SET_FIELDS = {'acquisition': 'wheel_gains_acquisition', 'normal': 'wheel_gains_normal'}
_WHEEL_PARAM_FIELDS = {'kp': 'k_p_v_per_rad', 'kr': 'k_r_s', 'theta_limit': 'theta_limit_rad'}
_SCALAR_GAIN_FIELDS = {
    'acquisition_gain': 'acquisition_gain_study',
    'bdot_gain': 'bdot_gain_study',
    'unloading_gain_mode_1b': 'unloading_gain_mode_1b_study',
    'unloading_gain_scan': 'unloading_gain_scan_study',
    'unloading_gain_point': 'unloading_gain_point_study',
    'max_moment': 'max_moment_am2',
    'scan_rate_rpm': 'scan_rate_rad_s',
    'lead_time': 'lead_time_s',
    'detumble_gain': 'detumble_gain_kg_m2_s',
    'dump_gain': 'dump_gain_per_s',
}


@dataclass(frozen=True)
class DpaConfig:
    """DPA configuration (spec §7). Gains in the study's units where the name says ``_study``.

    ``inertia_kg_m2``: spacecraft inertia tensor (3×3, kg·m², symmetric positive definite),
    used for H = I·ω in Mode 1A. ``acquisition_law``: 'bxh' | 'bdot'. ``unloading_law``:
    'bxh' | 'lead' | 'none'. ``acquisition_gain_study``, ``unloading_gain_*_study``: (s·G²)⁻¹.
    ``bdot_gain_study``: ft-lb-s/G². ``max_moment_am2``: per-axis limit, A·m².
    ``coupling_compensation`` with ``coupling_delta_t_per_am2`` (3×3, T per A·m²): subtract
    Δ·M_prev from the sensed field. ``scan_rate_rad_s``: ω_z0. ``target_q_body_to_eci``:
    (x, y, z, w) attitude held in celestial point; its z axis is the celestial scan axis.
    ``v_sat_v``: wheel drive limit, V. ``wheel_torque_gain_nm_per_v2`` and ``lead_time_s``:
    express the wheel command as momentum for the lead law. ``detumble_gain_kg_m2_s``: k_ω of the
    ``b_cross_omega`` law, kg·m²/s (default: the seed's 2.054e-5). ``dump_gain_per_s``: k_h of the
    ``b_cross_h`` unloading law, s⁻¹.
    """

    inertia_kg_m2: np.ndarray
    acquisition_law: str = 'bxh'
    unloading_law: str = 'bxh'
    acquisition_gain_study: float = G_ACQUISITION_STUDY
    bdot_gain_study: float = K_D_STUDY
    unloading_gain_mode_1b_study: float = G_ACQUISITION_STUDY
    unloading_gain_scan_study: float = G_UNLOAD_SCAN_STUDY
    unloading_gain_point_study: float = G_UNLOAD_POINT_STUDY
    max_moment_am2: float = MAX_MOMENT_AM2
    coupling_compensation: bool = False
    coupling_delta_t_per_am2: np.ndarray = field(default_factory=lambda: np.zeros((3, 3)))
    wheel_gains_acquisition: WheelLawGains = HEAO_B_ACQUISITION
    wheel_gains_normal: WheelLawGains = NORMAL_MODE
    scan_rate_rad_s: float = SCAN_RATE_RAD_S
    target_q_body_to_eci: np.ndarray = field(default_factory=lambda: np.array([0.0, 0.0, 0.0, 1.0]))
    v_sat_v: float = V_SAT_V
    wheel_torque_gain_nm_per_v2: float = WHEEL_TORQUE_GAIN_NM_PER_V2
    lead_time_s: float = LEAD_TIME_S
    detumble_gain_kg_m2_s: float = K_OMEGA_SEED
    dump_gain_per_s: float = 0.0

    def __post_init__(self) -> None:
        inertia = as_matrix3(self.inertia_kg_m2, 'inertia_kg_m2')
        if not np.allclose(inertia, inertia.T) or np.min(np.linalg.eigvalsh(inertia)) <= 0.0:
            raise ControllerError('inertia_kg_m2 must be symmetric positive definite (kg·m²)')
        object.__setattr__(self, 'inertia_kg_m2', inertia)
        object.__setattr__(self, 'coupling_delta_t_per_am2',
                           as_matrix3(self.coupling_delta_t_per_am2, 'coupling_delta_t_per_am2'))
        object.__setattr__(self, 'target_q_body_to_eci',
                           as_unit_quaternion(self.target_q_body_to_eci, 'target_q_body_to_eci'))
        for slot in LAW_CHOICES:
            law = getattr(self, f'{slot}_law')
            if law not in LAW_CHOICES[slot]:
                raise ControllerError(f'{slot}_law {law!r} unknown; choose one of {LAW_CHOICES[slot]}')
        for name, (lo, hi, unit) in SCALAR_GAINS.items():
            value = getattr(self, _SCALAR_GAIN_FIELDS[name])
            if name == 'scan_rate_rpm':
                value = rad_s_to_rpm(value)
            check_gain(value, f'{name} ({unit})', lo, hi)
        check_gain(self.v_sat_v, 'v_sat_v (V)', 0.0, 1e3)
        check_gain(self.wheel_torque_gain_nm_per_v2, 'wheel_torque_gain_nm_per_v2', 0.0, 1e3)


class DpaOutput:
    """One DPA step's result: moment command (A·m², body), wheel drive volts (V, body axes), telemetry.

    ``moment_xyz`` / ``volts_xyz`` are the float triples the DPA computed (what the stepper
    publishes); ``moment_command_am2`` / ``wheel_volts_v`` are them as arrays. ``telemetry``
    (key/value strings) is formatted when first read, from ``telemetry_args`` (:func:`dpa_telemetry`'s arguments,
    kept as they are), so only telemetry steps pay for it.
    """

    def __init__(self, moment_xyz: Vec3, volts_xyz: Vec3, telemetry_args: tuple[Any, ...]) -> None:
        self.moment_xyz = moment_xyz
        self.volts_xyz = volts_xyz
        self._telemetry_args = telemetry_args

    @property
    def moment_command_am2(self) -> np.ndarray:
        """Moment command, A·m², body axes."""
        return np.array(self.moment_xyz)

    @property
    def wheel_volts_v(self) -> np.ndarray:
        """Wheel drive volts per body axis, V."""
        return np.array(self.volts_xyz)

    @functools.cached_property
    def telemetry(self) -> dict[str, str]:
        """DPA telemetry as key/value strings (see :func:`dpa_telemetry`)."""
        return dpa_telemetry(*self._telemetry_args)


#: A law as the kernel reads it: its index in LAW_CHOICES[slot].
BXH, BDOT, B_CROSS_OMEGA = (LAW_CHOICES['acquisition'].index(law) for law in ('bxh', 'bdot', 'b_cross_omega'))
UNLOAD_BXH, LEAD, NO_UNLOADING, B_CROSS_H = (LAW_CHOICES['unloading'].index(law)
                                             for law in ('bxh', 'lead', 'none', 'b_cross_h'))
#: A kernel step's status: done, or why it refused the step (nothing changed; :meth:`Dpa.refusal` says it).
DONE, FIELD_ZERO, NO_REFERENCE, BAD_REFERENCE, SCAN_RATE_RANGE = range(5)
#: A DPA's state before its first step: no previous field (B-dot commands nothing), zero previous command.
INITIAL_STATE = (False, ZERO, ZERO)
#: The attitude reference the kernel is given when there is none (read only in the cruise modes).
NO_Q: Quat = (0.0, 0.0, 0.0, 1.0)

DpaState = tuple[bool, Vec3, Vec3]
#: (m_cmd, volts, b, h_used, theta, m_raw): the step's command (A·m²), wheel volts (V) and telemetry figures.
DpaFigures = tuple[Vec3, Vec3, Vec3, Vec3, Vec3, Vec3]
NO_FIGURES: DpaFigures = (ZERO, ZERO, ZERO, ZERO, ZERO, ZERO)


@kernels.helper
def wheel_loop(p: tuple, mode: int, omega: Vec3, sun: Vec3, q: Quat, q_given: bool) -> tuple[int, Vec3, Vec3]:
    """Status, attitude error (rad) and wheel volts for modes 1B, scan and point (seed 002 §4.2.2, §4.2.3).
    ``p``: :attr:`Dpa.params`."""
    v_sat, gains_acquisition, gains_normal = p[13], p[11], p[12]
    if mode == MODE_1B:
        theta = pointing_error_xyz(sun) if norm(sun) >= _SUN_PRESENT_MIN_NORM else ZERO
        return DONE, theta, wheel_volts_xyz(theta, omega, gains_acquisition, v_sat)
    if not q_given:
        return NO_REFERENCE, ZERO, ZERO
    status, _norm, qn = unit_quaternion_checked(q[0], q[1], q[2], q[3])
    if status != 0:
        return BAD_REFERENCE, ZERO, ZERO
    if mode == CELESTIAL_POINT:
        theta = inertial_hold_error_xyz(qn, p[17])
        return DONE, theta, wheel_volts_xyz(theta, omega, gains_normal, v_sat)
    theta = pointing_error_xyz(to_body(qn, p[18]))
    vx, vy, _vz = wheel_volts_xyz(theta, omega, gains_normal, v_sat)
    if not -SCAN_OMEGA_LIMIT_RAD_S <= omega[2] <= SCAN_OMEGA_LIMIT_RAD_S:
        return SCAN_RATE_RANGE, ZERO, ZERO
    kp, _limits, kr = gains_normal
    return DONE, theta, (vx, vy, scan_yaw_volts_xyz(omega[2], p[16], kp[2], kr[2], v_sat))


@kernels.helper
def unloading_moment(p: tuple, mode: int, b: Vec3, h_wheel: Vec3, volts: Vec3) -> tuple[bool, Vec3]:
    """Unloading moment on the wheel momentum with the mode's gain (seed 002 §4.2.3.2, eq. 4-37); False when
    the ``b_cross_h`` law finds |B|² not > 0. ``p``: :attr:`Dpa.params`."""
    law = p[1]
    gain = p[7][mode - MODE_1B]
    if law == NO_UNLOADING:
        return True, ZERO
    if law == B_CROSS_H:
        if b[0] != 0.0 or b[1] != 0.0 or b[2] != 0.0:
            return cross_law_xyz(b, h_wheel, p[10])
        return True, ZERO
    if law == LEAD:
        eps = wheel_command_momentum_xyz(volts, p[14], p[15])
        return True, lead_moment_xyz(b, h_wheel, eps, gain)
    return True, bxh_moment_xyz(b, h_wheel, gain)


@kernels.helper
def dpa_step(p: tuple, state: DpaState, mode: int, b_sensed: Vec3, omega: Vec3, sun: Vec3, h_wheel: Vec3,
             q: Quat, q_given: bool, dt: float) -> tuple[int, DpaState, DpaFigures]:
    """One control period of the DPA (spec §7; seed 002 Figure 4-2): ``p`` its :attr:`Dpa.params`, ``state``
    (a previous field held, B_prev, M_prev), the mode's index, the inputs of :meth:`Dpa.step_xyz` as float
    triples, the attitude reference (read only in the cruise modes, when ``q_given``) and Δt. Returns the status,
    the new state and the figures; a refused step (status not :data:`DONE`) keeps ``state``.

    A kernel (:mod:`acds_common.kernels`): compiled in the direct engine, inside the stepper's one call a step.
    """
    has_prev, b_prev, m_prev = state
    b = compensate_coupling_xyz(b_sensed, p[3], m_prev) if p[2] else b_sensed
    theta = volts = h_used = m = ZERO
    if mode == MODE_1A:
        law = p[0]
        if law == BXH:
            h_used = mv(p[4], omega)
            m = bxh_moment_xyz(b, h_used, p[5])
        elif law == B_CROSS_OMEGA:
            if b[0] != 0.0 or b[1] != 0.0 or b[2] != 0.0:
                defined, m = cross_law_xyz(b, omega, p[9])
                if not defined:
                    return FIELD_ZERO, state, NO_FIGURES
        elif has_prev:
            m = bdot_moment_xyz(b, b_prev, dt, p[6])
    elif mode != STANDBY:
        status, theta, volts = wheel_loop(p, mode, omega, sun, q, q_given)
        if status != DONE:
            return status, state, NO_FIGURES
        h_used = h_wheel
        defined, m = unloading_moment(p, mode, b, h_wheel, volts)
        if not defined:
            return FIELD_ZERO, state, NO_FIGURES
    m_cmd = clip(m, p[8])
    return DONE, (True, b, m_cmd), (m_cmd, volts, b, h_used, theta, m)


class Dpa:
    """The per-step digital processor (spec §7; seed 002 Figure 4-2). Holds the previous field and command."""

    def __init__(self, config: DpaConfig) -> None:
        self.config = config
        #: (a previous field held, B_prev T, M_prev A·m²): :func:`dpa_step`'s state, float triples.
        self.state: DpaState = INITIAL_STATE
        self._step = kernels.compiled(dpa_step)

    @property
    def config(self) -> DpaConfig:
        """The configuration in force (``set_gain`` / ``set_law`` replace it)."""
        return self._config

    @config.setter
    def config(self, config: DpaConfig) -> None:
        """Set the configuration and :attr:`params`, its form for the per-step kernel (SI gains, 3×3 rows)."""
        self._config = config
        qt = unit_quaternion_xyzw(config.target_q_body_to_eci, 'target_q_body_to_eci')
        scan_axis_eci = to_body(unit_quaternion_xyzw(conj(qt), 'q_body_to_eci'), (0.0, 0.0, 1.0))
        #: :func:`dpa_step`'s parameters, fixed types (ints, a bool, floats, tuples of floats): acquisition and
        #: unloading law indices, coupling compensation and Δ, inertia rows, the acquisition and B-dot gains, the
        #: unloading gains of mode 1B, scan and point (SI), max moment, k_ω, k_h, the acquisition and normal
        #: wheel gain rows, V_sat, the wheel torque gain, the lead time, the scan rate, the target attitude and
        #: the scan axis (ECI).
        self.params = (
            LAW_CHOICES['acquisition'].index(config.acquisition_law),
            LAW_CHOICES['unloading'].index(config.unloading_law),
            bool(config.coupling_compensation), mat3(config.coupling_delta_t_per_am2), mat3(config.inertia_kg_m2),
            bxh_gain_to_si(float(config.acquisition_gain_study)), bdot_gain_to_si(float(config.bdot_gain_study)),
            (bxh_gain_to_si(float(config.unloading_gain_mode_1b_study)),
             bxh_gain_to_si(float(config.unloading_gain_scan_study)),
             bxh_gain_to_si(float(config.unloading_gain_point_study))),
            float(config.max_moment_am2), float(config.detumble_gain_kg_m2_s), float(config.dump_gain_per_s),
            config.wheel_gains_acquisition.row, config.wheel_gains_normal.row, float(config.v_sat_v),
            float(config.wheel_torque_gain_nm_per_v2), float(config.lead_time_s), float(config.scan_rate_rad_s),
            qt, scan_axis_eci)


    def set_gain(self, name: str, value: float) -> None:
        """Change a gain at run time; unknown name or out-of-range value raises :class:`ControllerError`.

        Names and ranges: :data:`GAIN_TABLE` (e.g. 'unloading_gain_point' in (s·G²)⁻¹,
        'wheel_acquisition_kp_y' in V/rad, 'scan_rate_rpm').
        """
        if name not in GAIN_TABLE:
            raise ControllerError(f'unknown gain {name!r}; known gains: {", ".join(sorted(GAIN_TABLE))}')
        lo, hi, unit = GAIN_TABLE[name]
        v = check_gain(value, f'gain {name} ({unit})', lo, hi)
        if name in _SCALAR_GAIN_FIELDS:
            attr = _SCALAR_GAIN_FIELDS[name]
            self.config = dataclasses.replace(
                self.config, **{attr: rpm_to_rad_s(v) if name == 'scan_rate_rpm' else v})
            return
        set_name, rest = name[len('wheel_'):].split('_', 1)
        param, axis = rest.rsplit('_', 1)
        attr = _WHEEL_SET_FIELDS[set_name]
        gains: WheelLawGains = getattr(self.config, attr)
        self.config = dataclasses.replace(
            self.config, **{attr: gains.with_axis(_WHEEL_PARAM_FIELDS[param], AXES.index(axis), v)})

    def set_law(self, slot: str, law: str) -> None:
        """Select the magnetic law of a slot ('acquisition': bxh|bdot, 'unloading': bxh|lead|none)."""
        if slot not in LAW_CHOICES:
            raise ControllerError(f'unknown law slot {slot!r}; choose one of {tuple(LAW_CHOICES)}')
        if law not in LAW_CHOICES[slot]:
            raise ControllerError(f'{slot} law {law!r} unknown; choose one of {LAW_CHOICES[slot]}')
        self.config = dataclasses.replace(self.config, **{f'{slot}_law': law})

    def step(
        self,
        mode: str,
        b_sensed_t: Sequence[float],
        omega_rad_s: Sequence[float],
        sun_body_unit: Sequence[float],
        wheel_h_nms: Sequence[float],
        q_body_to_eci: Sequence[float] | None,
        dt_s: float,
    ) -> DpaOutput:
        """Compute one control period (spec §7).

        ``b_sensed_t``: TA field (T, body); ``omega_rad_s``: gyro rates; ``sun_body_unit``: sun
        unit vector in body (zeros = absent); ``wheel_h_nms``: total wheel momentum (N·m·s,
        body); ``q_body_to_eci``: attitude reference (x, y, z, w), needed in the cruise modes;
        ``dt_s``: control period (s), the B-dot difference interval. Vectors as arrays or
        float sequences.
        """
        if mode not in HEAO_MODES:
            raise ControllerError(f'unknown mode {mode!r}; choose one of {HEAO_MODES}')
        return self.step_xyz(mode, as_xyz(b_sensed_t, 'b_sensed_t'), as_xyz(omega_rad_s, 'omega_rad_s'),
                             as_xyz(sun_body_unit, 'sun_body_unit'), as_xyz(wheel_h_nms, 'wheel_h_nms'),
                             q_body_to_eci, check_gain(dt_s, 'dt_s (s)', 1e-6, 1e4))

    def step_xyz(self, mode: str, b_sensed: Vec3, omega: Vec3, sun: Vec3, h_wheel: Vec3,
                 q_body_to_eci: Sequence[float] | None, dt: float) -> DpaOutput:
        """:meth:`step` without its checks (spec §7): a mode of :data:`HEAO_MODES`, finite float triples, Δt
        within 1e-6…1e4 s (the attitude reference is still checked). One :func:`dpa_step`."""
        q, q_given = NO_Q, False
        if q_body_to_eci is not None:
            try:
                x, y, z, w = (float(c) for c in q_body_to_eci)
                q, q_given = (x, y, z, w), True
            except (TypeError, ValueError):  # refused in the modes that read it, ignored in the others
                if mode in HEAO_CRUISE_MODES:
                    unit_quaternion_xyzw(q_body_to_eci, 'q_body_to_eci')
        status, state, figures = self._step(self.params, self.state, HEAO_MODES.index(mode), b_sensed, omega, sun,
                                            h_wheel, q, q_given, float(dt))
        if status != DONE:
            raise self.refusal(status, mode, omega, q_body_to_eci)
        self.state = state
        return self.output(mode, figures)

    def output(self, mode: str, figures: DpaFigures) -> DpaOutput:
        """A :func:`dpa_step`'s figures as the step's :class:`DpaOutput`."""
        m_cmd, volts, b, h_used, theta, m = figures
        return DpaOutput(m_cmd, volts, (self._config, mode, b, h_used, theta, m, m_cmd, volts))

    def refusal(self, status: int, mode: str, omega: Sequence[float], q_body_to_eci: object) -> ControllerError:
        """The error of a step :func:`dpa_step` refused with ``status``, with the message the check gives."""
        if status == FIELD_ZERO:
            return ControllerError(B_ZERO_MESSAGE)
        if status == NO_REFERENCE or q_body_to_eci is None:
            return ControllerError(f'mode {mode} needs the attitude reference q_body_to_eci')
        try:
            if status == BAD_REFERENCE:
                unit_quaternion_xyzw(q_body_to_eci, 'q_body_to_eci')
            c = self._config
            scan_yaw_volts(omega[2], c.scan_rate_rad_s, c.wheel_gains_normal.k_p_v_per_rad[2],
                           c.wheel_gains_normal.k_r_s[2], c.v_sat_v)
        except ControllerError as exc:
            return exc
        raise AssertionError(f'dpa_step refused a step with status {status} its checks pass')


def dpa_telemetry(c: DpaConfig, mode: str, b: Vec3, h_used: Vec3, theta: Vec3, m_raw: Vec3, m_cmd: Vec3,
                  volts: Vec3) -> dict[str, str]:
    """DPA telemetry as key/value strings, seed units in the key names (+ 0.0 turns −0 into 0)."""
    out = {
        'mode': mode,
        'acquisition_law': c.acquisition_law,
        'unloading_law': c.unloading_law,
        'moment_saturated': 'true' if any(abs(x) > c.max_moment_am2 for x in m_raw) else 'false',
    }
    for i, axis in enumerate(AXES):
        out[f'control_field_{axis}_gauss'] = f'{tesla_to_gauss(b[i]) + 0.0:.6g}'
        out[f'control_momentum_{axis}_ftlbs'] = f'{nms_to_ftlbs(h_used[i]) + 0.0:.6g}'
        out[f'attitude_error_{axis}_deg'] = f'{deg(theta[i]) + 0.0:.6g}'
        out[f'moment_command_{axis}_am2'] = f'{m_cmd[i] + 0.0:.6g}'
        out[f'wheel_volts_{axis}_v'] = f'{volts[i] + 0.0:.6g}'
    return out
