"""The AAP Workshop's on-board computer for the magnetic CMG momentum dump (seed 000 §3, §4, §5; Fig. 2).

Seed: ``000_aap_cmg_dump_levidow.txt``. The dump adds to the Workshop's attitude control "a magnetometer to
measure the earth's magnetic field, an electromagnet …, a control amplifier … and a small amount of digital
computer software" (abstract, §4): H_s "is obtained by sampling the CMG momentum which is already available
in the digital computer" (§4). One control period of that computer (:class:`WorkshopComputer`):

1. H_s: the CMG momentum sampled at the first step of each orbit and held for it
   (:class:`~acds_controller.cmg_dump.SampledMomentum`). With ``h_s_init='min_energy'`` the first sample is
   set as §5's simulations set it, "kH_s for the first orbit equal to the value within the brackets of
   equation (3)" — which the seed does "by both adjustment of the CMG gimbal angles at the initial sampling
   and selection of the scale factor k" (§3). The CMG momentum itself cannot be adjusted without an
   external torque, so the adjustment is kept as a constant offset δ of the sampled value:
   H_s,n = h_CMG(t_n) + δ, δ = c₀/k (+ H_0) − h_CMG(t_0), which is §5's bookkeeping exactly
   (H_{n+1} = H_n + ΔH_s, ΔH_s the CMG momentum's change) and, equivalently, the shifted law of §3 with
   its shift chosen at the first sample. ``'measured'`` takes the CMG momentum as it is (§5: "even if H_s
   were initialized to the null vector").
2. M: the selected dump law (:class:`~acds_controller.cmg_dump.CmgDumpLaw`: k·H_s × B, the shifted form, or
   the minimum-energy eq. 3) on the measured field, limited per axis; none in mode ``cmg_hold``.
3. ḣ: the CMG momentum rate that holds the target attitude (:func:`~acds_controller.cmg_hold.cmg_hold_rate`),
   with as feedforward the magnetic torque M × B the computer itself commands and the gravity-gradient
   torque of its orbit model at the measured attitude (3 μ/r³ r̂ × I r̂: the cyclic part is the largest
   torque on the Workshop, and a hold error it leaves would itself bias the gravity gradient); the
   aerodynamic torque is left to the feedback.

The field along the coming orbit (the minimum-energy law, the §5 initialisation, and the predicted loop
gains in the telemetry) is predicted on board by :class:`FieldPrediction`: the orbit and tilted-dipole
models of :mod:`acds_common.environment` (the dynamics' own models, from the controller's copy of the
``orbit`` and ``earth`` sections) seen from the held target attitude.

Modes: ``'cmg_dump'`` (hold + dump), ``'cmg_hold'`` (hold, magnets off), ``'standby'`` (nothing commanded).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field, replace

import numpy as np
from acds_common.environment import Orbit, TiltedDipoleField, gravity_gradient_torque_nm
from acds_common.modes import WORKSHOP_MODES
from acds_common.units import deg, nms_to_ftlbs, tesla_to_gauss

from acds_controller.cmg_dump import (
    CmgDumpLaw,
    DumpLawConfig,
    OrbitClock,
    SampledMomentum,
    field_gramian,
    loop_gain_k_seed,
    loop_gains,
    min_energy_peak_am2,
    min_energy_vector,
    predicted_orbit,
    proper_initial_h_s_nms,
)
from acds_controller.cmg_hold import HoldGains, cmg_hold_rate
from acds_controller.magnetic_laws import ControllerError, as_matrix3, as_vector3
from acds_controller.wheel_laws import as_unit_quaternion, inertial_hold_error, rotate_to_body

#: H_s initialisations (module docstring, step 1).
H_S_INITS = ('measured', 'min_energy')


class FieldPrediction:
    """On-board prediction of the body-axis field at the held attitude: B_body(t) = R(q_target)ᵀ B_eci(r(t), t), T."""

    def __init__(self, orbit: Orbit, field_model: TiltedDipoleField, q_target_body_to_eci: np.ndarray) -> None:
        self.orbit, self.field = orbit, field_model
        self.q_target = as_unit_quaternion(q_target_body_to_eci, 'q_target_body_to_eci')

    def __call__(self, t_s: float) -> np.ndarray:
        r_eci = self.orbit.position_velocity_eci(t_s)[0]
        return rotate_to_body(self.q_target, self.field.b_eci(r_eci, t_s))

    def gravity_gradient_nm(self, t_s: float, inertia_kg_m2: np.ndarray, q_body_to_eci: np.ndarray) -> np.ndarray:
        """The gravity-gradient torque (N·m, body) of the on-board orbit at the attitude ``q_body_to_eci``."""
        return gravity_gradient_torque_nm(inertia_kg_m2,
                                          rotate_to_body(q_body_to_eci, self.orbit.position_velocity_eci(t_s)[0]))


#: One sidereal day, s: the design looks ahead over the orbits in which the dipole turns once with the Earth
#: (§5: "16 orbits during which time the earth makes approximately a full rotation").
SIDEREAL_DAY_S = 86164.0905
#: Gain rules of the k law: the scenario's k as stated, or k from the loop-gain condition (:func:`design_dump`).
GAIN_RULES = ('stated', 'loop_gain')


@dataclass(frozen=True)
class DumpDesign:
    """What the Workshop computer derives from its field prediction before it flies (issue 21; seed 000 §3, §9, §10).

    ``k_seed``: the k it flies (seed units); ``gain_rule``: how it came; ``predicted_gains``: the smallest and
    largest eigenvalue of k·W_n over the predicted orbits; ``predicted_peak_am2``: the largest |M| of eq. (3)
    (the unconstrained minimum-energy profile, which the converged k law reproduces) over those orbits, the
    reference of the §9 limit and the §10 constant |M|; ``orbits``: how many orbits were predicted.
    """

    k_seed: float
    gain_rule: str
    predicted_gains: tuple[float, float]
    predicted_peak_am2: float | None
    orbits: int


def design_dump(dump: DumpLawConfig, prediction: FieldPrediction, clock: OrbitClock, *, gain_rule: str = 'stated',
                largest_gain: float = 1.0, moment_limit_fraction: float | None = None,
                day_moment_factor: float | None = None) -> tuple[DumpLawConfig, DumpDesign]:
    """The flown dump law and its design, from the on-board prediction over the orbits of one sidereal day.

    ``gain_rule`` 'loop_gain': k = ``largest_gain`` / max_n λ_max(W_n) (:func:`loop_gain_k_seed`), so that every
    predicted orbit's loop converges; 'stated': ``dump.k_seed`` as given (the seed's 4e6 diverges, see
    :mod:`acds_controller.cmg_dump`). ``moment_limit_fraction``: §9, |M| ≤ fraction × the predicted unconstrained
    M_m (the seed's 0.85); ``day_moment_factor``: §10, dump in daylight only at |M| = factor × that M_m (1.3).
    """
    if gain_rule not in GAIN_RULES:
        raise ControllerError(f'dump gain rule must be one of {GAIN_RULES}, got {gain_rule!r}')
    first = clock.index(0.0)
    count = math.ceil(SIDEREAL_DAY_S / clock.period_s)
    orbits = [predicted_orbit(prediction, clock, n, dump.prediction_samples) for n in range(first, first + count)]
    grams = [field_gramian(b, w) for b, w in orbits]
    k_seed = loop_gain_k_seed(grams, largest_gain) if gain_rule == 'loop_gain' else dump.k_seed
    gains = [loop_gains(w, k_seed) for w in grams]
    peak = None
    if dump.h_b_nms is not None and (moment_limit_fraction is not None or day_moment_factor is not None):
        peak = max(min_energy_peak_am2(b, w, dump.h_b_nms) for b, w in orbits)
    elif moment_limit_fraction is not None or day_moment_factor is not None:
        raise ControllerError('the moment limit (§9) and day-only dumping (§10) are set from the predicted '
                              'unconstrained M_m, which needs the bias momentum h_b_nms')
    flown = replace(dump, k_seed=k_seed,
                    moment_limit_am2=None if moment_limit_fraction is None else moment_limit_fraction * peak,
                    day_moment_am2=None if day_moment_factor is None else day_moment_factor * peak)
    design = DumpDesign(k_seed, gain_rule, (min(float(g[0]) for g in gains), max(float(g[-1]) for g in gains)),
                        peak, count)
    return flown, design


@dataclass(frozen=True)
class WorkshopConfig:
    """The Workshop computer's configuration.

    ``inertia_kg_m2``: 3×3, for the hold law; ``target_q_body_to_eci``: the held attitude (x, y, z, w);
    ``dump``: the dump law (None: no dump law, the CMGs only hold); ``hold``: the hold's bandwidth and
    damping (not in the seed); ``h_s_init``: 'measured' | 'min_energy' (module docstring).
    """

    inertia_kg_m2: np.ndarray
    target_q_body_to_eci: np.ndarray
    dump: DumpLawConfig | None
    hold: HoldGains = field(default_factory=HoldGains)
    h_s_init: str = 'measured'

    def __post_init__(self) -> None:
        object.__setattr__(self, 'inertia_kg_m2', as_matrix3(self.inertia_kg_m2, 'inertia_kg_m2'))
        object.__setattr__(self, 'target_q_body_to_eci',
                           as_unit_quaternion(self.target_q_body_to_eci, 'target_q_body_to_eci'))
        if self.h_s_init not in H_S_INITS:
            raise ControllerError(f'h_s_init must be one of {H_S_INITS}, got {self.h_s_init!r}')
        if self.h_s_init == 'min_energy' and (self.dump is None or self.dump.law == 'min_energy'):
            raise ControllerError("h_s_init 'min_energy' initialises the k laws' H_s (§5); the law "
                                  f"{'none' if self.dump is None else self.dump.law!r} samples no H_s to initialise")
        if self.h_s_init == 'min_energy' and self.dump is not None and self.dump.h_b_nms is None:
            raise ControllerError("h_s_init 'min_energy' needs the bias momentum h_b_nms of the dump law (eq. 3)")


@dataclass(frozen=True)
class WorkshopOutput:
    """One step: moment command M (A·m², body), commanded CMG momentum rate ḣ (N·m, body), the H_s used (N·m·s),
    the attitude error (rad), and telemetry strings (seed units in the key names)."""

    moment_am2: np.ndarray
    cmg_rate_nm: np.ndarray
    h_s_nms: np.ndarray
    attitude_error_rad: np.ndarray
    telemetry: dict[str, str]


class WorkshopComputer:
    """Sampled H_s, the dump law and the CMG attitude hold, one control period per :meth:`step`."""

    def __init__(self, cfg: WorkshopConfig, clock: OrbitClock, prediction: FieldPrediction,
                 design: DumpDesign | None = None) -> None:
        self.cfg, self.clock, self.prediction, self.design = cfg, clock, prediction, design
        self.sampler = SampledMomentum(clock)
        self.law = None if cfg.dump is None else CmgDumpLaw(cfg.dump, clock, prediction)
        self._offset: np.ndarray | None = None
        self._orbit: int | None = None
        self._predicted_gains: np.ndarray | None = None

    @property
    def h_s_offset_nms(self) -> np.ndarray:
        """δ = H_s − h_CMG at the samples (zero for 'measured'), N·m·s; zeros before the first step."""
        return np.zeros(3) if self._offset is None else self._offset.copy()

    def _first_sample_offset(self, n: int, h_cmg: np.ndarray) -> np.ndarray:
        if self.cfg.h_s_init == 'measured' or self.law is None:
            return np.zeros(3)
        dump = self.law.cfg
        c, _ = min_energy_vector(self.law.predicted_gramian(n), dump.h_b_nms)
        h_0 = dump.h_0_nms if dump.law == 'khb_shifted' else None
        return proper_initial_h_s_nms(c, dump.k_seed, h_0) - h_cmg

    def step(self, t_s: float, mode: str, b_sensed_t: np.ndarray, omega_rad_s: np.ndarray,
             q_body_to_eci: np.ndarray, h_cmg_nms: np.ndarray, day: bool = True) -> WorkshopOutput:
        """One control period at ``t_s``: measured field (T), gyro rates (rad/s), attitude (x, y, z, w, body→ECI)
        and the CMG momentum at t_s (N·m·s), all body axes; ``day``: the sun sensor sees the sun (§10)."""
        if mode not in WORKSHOP_MODES:
            raise ControllerError(f'unknown Workshop mode {mode!r}; choose one of {WORKSHOP_MODES}')
        b = as_vector3(b_sensed_t, 'b_sensed_t')
        omega = as_vector3(omega_rad_s, 'omega_rad_s')
        h_cmg = as_vector3(h_cmg_nms, 'h_cmg_nms')
        theta = inertial_hold_error(q_body_to_eci, self.cfg.target_q_body_to_eci)
        n = self.clock.index(t_s)
        if self._offset is None:
            self._offset = self._first_sample_offset(n, h_cmg)
        h_s = self.sampler.sample(t_s, h_cmg) + self._offset
        if n != self._orbit:
            self._orbit = n
            if self.law is not None:
                self._predicted_gains = loop_gains(self.law.predicted_gramian(n), self.law.cfg.k_seed)
        m = np.zeros(3)
        hdot = np.zeros(3)
        if mode != 'standby':
            if mode == 'cmg_dump' and self.law is not None:
                m = self.law.step(t_s, h_s, b, day)
            feedforward = np.cross(m, b) + self.prediction.gravity_gradient_nm(t_s, self.cfg.inertia_kg_m2,
                                                                                q_body_to_eci)
            hdot = cmg_hold_rate(theta, omega, self.cfg.inertia_kg_m2, h_cmg, feedforward, self.cfg.hold)
        return WorkshopOutput(m, hdot, h_s, theta, self._telemetry(mode, n, b, h_s, theta, m, hdot))

    def _telemetry(self, mode: str, n: int, b: np.ndarray, h_s: np.ndarray, theta: np.ndarray, m: np.ndarray,
                   hdot: np.ndarray) -> dict[str, str]:
        out = {'mode': mode, 'dump_law': 'none' if self.law is None else self.law.cfg.law,
               'h_s_init': self.cfg.h_s_init, 'orbit': str(n)}
        if self._predicted_gains is not None:
            out['predicted_loop_gain_min'] = f'{self._predicted_gains[0]:.4g}'
            out['predicted_loop_gain_max'] = f'{self._predicted_gains[-1]:.4g}'
        if self.law is not None:
            out['dump_k_seed'] = f'{self.law.cfg.k_seed:.6g}'
            raw = self.law.unsaturated_am2
            limit = self.law.cfg.max_moment_am2
            out['moment_saturated'] = 'true' if limit is not None and np.any(np.abs(raw) > limit) else 'false'
        h_s_ft = nms_to_ftlbs(h_s)
        offset_ft = nms_to_ftlbs(self.h_s_offset_nms)
        for i, axis in enumerate('xyz'):
            out[f'h_s_{axis}_ftlbs'] = f'{h_s_ft[i] + 0.0:.6g}'
            out[f'h_s_offset_{axis}_ftlbs'] = f'{offset_ft[i] + 0.0:.6g}'
            out[f'control_field_{axis}_gauss'] = f'{tesla_to_gauss(b[i]) + 0.0:.6g}'
            out[f'attitude_error_{axis}_deg'] = f'{deg(theta[i]) + 0.0:.6g}'
            out[f'moment_command_{axis}_am2'] = f'{m[i] + 0.0:.6g}'
            out[f'cmg_torque_command_{axis}_nm'] = f'{hdot[i] + 0.0:.6g}'
        return out
