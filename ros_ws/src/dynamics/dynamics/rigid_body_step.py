"""rigid_body stepper: the time owner's logic; integrates the spacecraft and gives the truth (spec §2, §3).

Step 0's truth is published at start. Stage ``integrate`` of step k takes the actuator
outputs of step k (the em_driver's step-average achieved dipole, the wheels' momentum
h(t_k) and rate ḣ over [t_k, t_k+1]; absent nodes mean zero) and the step's ``mode``,
integrates t_k → t_k+1 and returns the truth of step k + 1. With the cold-gas subsystem in the graph its
step-average thruster torque (``cold_gas/wrench``, step k) is applied as well. The run ends after step k
when the total step count is reached, when the ``mode`` of step k asks it
(:attr:`~acds_common.mode_report.ModeReport.run_complete`: stop at acquisition capture), or, with
``dynamics.stop_when_detumbled``, when the truth has been detumbled for the hold (:mod:`dynamics.detumbled`). A
non-finite actuator input, or one
beyond what the hardware can produce (:func:`~dynamics.configuration.actuator_limits`),
fails the run naming the topic and the step.

Health on ``/diagnostics`` (one ``DiagnosticStatus`` named ``rigid_body``) every
:data:`DIAGNOSTICS_EVERY` steps: the state is finite, ‖q‖ − 1 of the attitude quaternion, and, for
a run that has been torque-free so far (no gravity gradient, zero dipole, zero wheel torque: angular
momentum in ECI and rotational energy are then constants of the motion, so their change is
integration error), the relative drift of H_ECI and of the energy since step 0; WARN beyond
:data:`QUATERNION_NORM_TOLERANCE` or :data:`DRIFT_TOLERANCE`. It also reports the wall time of the
stage (``wall_*`` keys: measurements of the machine, not data; comparisons of runs skip them).

The step against the dynamics (:mod:`dynamics.integration_accuracy`): the step angle
θ = (|ω| + 2 ω_orbit)·Δt/substeps is checked at construction (the pre-flight builds this stepper: a θ
beyond the hard bound refuses the scenario naming ``dynamics.substeps``) and after every step (beyond
the hard bound the run stops naming the key; above the warning bound one ``warn`` line, once per run);
``/diagnostics`` carries the largest θ so far (``step_angle_max_rad``).

The rate gyros are the study's ideal gyros (spec §3): ``sensors/gyro`` carries the true body
rates with an all-zero ``angular_velocity_covariance``.
"""

from __future__ import annotations

import math
import time
from typing import Any

import numpy as np
from acds_common import kernels, topics
from acds_common.cdr import OdometryValue
from acds_common.fused import FusedStage, Output
from acds_common.messages import OK, WALL_CLOCK_PREFIX, WARN, diagnostic, xyz
from acds_common.mode_report import ModeValueReader, run_complete
from acds_common.stepper import StepError, Stepper

from dynamics import integration_accuracy as accuracy
from dynamics.configuration import RIGID_BODY_SECTIONS, actuator_limits, build_rigid_body
from dynamics.detumbled import detumbled_stop
from dynamics.errors import DynamicsError, positive_dt
from dynamics.rigid_body_model import Truth, TruthValues, advance_circular_dipole

#: ``angular_velocity_covariance`` of the ideal gyros, rad²/s² (row-major 3×3).
GYRO_COVARIANCE = (0.0,) * 9
#: Integration health on /diagnostics every this many steps.
DIAGNOSTICS_EVERY = 20
#: WARN when the attitude quaternion's norm departs from 1 by more than this (renormalised every substep).
QUATERNION_NORM_TOLERANCE = 1e-9
#: WARN when a torque-free run's momentum or energy has drifted by more than this fraction of its initial value.
DRIFT_TOLERANCE = 1e-6
_ZERO_COV = (0.0,) * 9  # a truth field's covariance: unknown
_ZERO = (0.0, 0.0, 0.0)


def truth_outputs(values: TruthValues) -> dict[str, Any]:
    """Truth and ideal sensors of one step (spec §3 "Sensors in the study are ideal") from the truth's values."""
    r, q, v, omega, b_body, sun_cosines, torque_mag, torque_gg, sun_body, sun_present = values
    return {
        'odometry': OdometryValue(r, q, v, omega),
        'b_body': (b_body, _ZERO_COV),
        'sun_cosines': sun_cosines,
        'torque_mag': torque_mag,
        'torque_gg': torque_gg,
        'gyro': (omega, GYRO_COVARIANCE),
        'sun_sensor': sun_body if sun_present else _ZERO,
    }


#: The truth outputs of the fused stage (:func:`integrate_fused`), their shapes and values (:func:`truth_outputs`).
FUSED_OUTPUTS = (Output('odometry', (3, 4, 3, 3), OdometryValue._make), Output('b_body', (3, 9)),
                 Output('sun_cosines', 3), Output('torque_mag', 3), Output('torque_gg', 3), Output('gyro', (3, 9)),
                 Output('sun_sensor', 3))


@kernels.helper
def integrate_fused(p: tuple, s: tuple, k: int, _t: float, dipole: Any, wheel_h: Any, wheel_hdot: Any) -> tuple:
    """Stage ``integrate`` of step k as a kernel (:mod:`acds_common.fused`) in the circular orbit and tilted dipole,
    no disturbance, no thrusters, no telemetry: quiet unless the run ends at step k, an actuator input is
    non-finite or beyond the hardware, the state diverges, or the step angle passes the warning bound (the Python
    stage then does what it does). ``p``: (body parameters, orbit, Δt, total steps, the dipole and wheel bounds,
    the orbit rate, control period, substeps); ``s``: (t, B_eci at t, the truth's values at t, the wheels'
    momentum at t, torque-free so far, the largest |ω| checked, the largest step angle)."""
    body, orbit, dt, total_steps, bounds, orbit_rate, period, substeps = p
    t0, b0, values, _h_end, torque_free, omega_checked, theta_max = s
    h, hdot, m = wheel_h, wheel_hdot, dipole
    quiet = k < total_steps
    h_end = (h[0] + hdot[0] * dt, h[1] + hdot[1] * dt, h[2] + hdot[2] * dt)
    (m0, m1, m2), (w0, w1, w2) = bounds
    if not (-m0 <= m[0] <= m0 and -m1 <= m[1] <= m1 and -m2 <= m[2] <= m2
            and -w0 <= h[0] <= w0 and -w1 <= h[1] <= w1 and -w2 <= h[2] <= w2
            and -w0 <= h_end[0] <= w0 and -w1 <= h_end[1] <= w1 and -w2 <= h_end[2] <= w2):
        quiet = False
    new = s
    if quiet:
        r = values[0]
        need_field = m[0] != 0.0 or m[1] != 0.0 or m[2] != 0.0
        finite, b1, v1 = advance_circular_dipole(body, orbit, values[1], values[3], t0, dt,
                                                 (r[0], r[1], r[2], b0[0], b0[1], b0[2]), m, h, hdot,
                                                 (0.0, 0.0, 0.0), need_field)
        w = v1[3]
        omega = math.sqrt(w[0] * w[0] + w[1] * w[1] + w[2] * w[2])
        checked, largest = omega_checked, theta_max
        if omega > omega_checked:  # RigidBodyStep._check_step below the warning bound
            checked = omega
            theta = accuracy.step_angle_rad(omega, orbit_rate, period, substeps)
            if theta > largest:
                largest = theta
            if theta > accuracy.STEP_ANGLE_WARN_RAD:
                quiet = False
        free = torque_free and not (m[0] or m[1] or m[2] or hdot[0] or hdot[1] or hdot[2])
        if not finite:
            quiet = False
        if quiet:
            values = v1
            new = (t0 + dt, b1, v1, h_end, free, checked, largest)
    r, q, v, w, b_body, cosines, tmag, tgg, sun_body, present = values
    return (quiet, new, (r, q, v, w), (b_body, _ZERO_COV), cosines, tmag, tgg, (w, GYRO_COVARIANCE),
            sun_body if present else _ZERO)


def _within(value: Any, bound: tuple[float, ...]) -> bool:
    """Every |component| within its bound."""
    return abs(value[0]) <= bound[0] and abs(value[1]) <= bound[1] and abs(value[2]) <= bound[2]


class RigidBodyStep(Stepper):
    """Spacecraft rigid body in its orbit and environment; owner of sim time."""

    node = 'rigid_body'

    def __init__(self, params: dict[str, Any], log: Any = None) -> None:
        super().__init__(params, log)
        self.total_steps: int = params['total_steps']
        self.model = build_rigid_body(*(self.section(s) for s in RIGID_BODY_SECTIONS))
        self._dt = positive_dt(self.control_period_s)
        self.limits = actuator_limits(self.section('em_driver'), self.section('wheels'))
        self._bounds = tuple(tuple(float(x) * (1.0 + 1e-9) for x in limit)
                             for limit in (self.limits.dipole_am2, self.limits.wheel_momentum_nms))
        if not all(math.isfinite(b) for bound in self._bounds for b in bound):  # what integrate's check relies on
            raise DynamicsError(f'actuator limits must be finite, got {self._bounds}')
        self._wheel_h = _ZERO
        #: Whether the step's ``mode`` value asks the run to end, read when a new value arrives.
        self._run_complete = ModeValueReader(run_complete)
        #: The detumbled run end (None: off), fed |ω| of every truth published.
        self._detumbled = detumbled_stop(self.section('dynamics'), self._dt)
        #: Torque-free so far (external and wheel torques all zero): the drifts are integration error.
        self.torque_free = not self.model.gravity_gradient and self.model.disturbance is None
        self._h0_eci: np.ndarray | None = None  # H in ECI and the rotational energy at t_0
        self._e0_j = 0.0
        self._wall_s = 0.0
        self._wall_steps = 0
        self._orbit_rate = accuracy.orbit_rate_max_rad_s(self.model.orbit)
        self._warned = False
        self.step_angle_max_rad = 0.0
        #: The largest |ω| checked so far: θ grows with |ω| (IEEE + and × by positive constants are monotonic), so a
        #: step whose |ω| is not above it has a θ already checked and recorded.
        self._omega_checked = float(np.linalg.norm(self.model.omega_body_rad_s))
        self._check_step(self._omega_checked)

    def _check_step(self, omega_rad_s: float, k: int | None = None) -> None:
        """The step angle at body rate ``omega_rad_s`` (initial, or at the end of step k): past the hard bound refuse
        the scenario (construction: DynamicsError, the pre-flight's) or stop the run; above the warning bound warn once."""
        theta = accuracy.step_angle_rad(omega_rad_s, self._orbit_rate, self.control_period_s, self.model.substeps)
        if theta > self.step_angle_max_rad:
            self.step_angle_max_rad = theta
        if theta <= accuracy.STEP_ANGLE_WARN_RAD:
            return
        what = 'its initial' if k is None else f"step {k + 1}'s"
        args = (omega_rad_s, self._orbit_rate, self.control_period_s, self.model.substeps)
        refused = accuracy.refusal(what, *args)
        if refused is not None:
            if k is None:
                raise DynamicsError(refused)
            raise StepError(f'{refused}; the run stops')
        if not self._warned:
            self._warned = True
            self.log('warn', accuracy.warning(what, *args))

    def start(self) -> dict[str, Any]:
        """The truth of step 0."""
        values = self.model.truth(self._wheel_h).values
        if self._detumbled is not None:
            w = values[3]
            self._detumbled.observe(0, math.sqrt(w[0] * w[0] + w[1] * w[1] + w[2] * w[2]))
        return truth_outputs(values)

    def health(self, truth: Truth, wall_step_s: float) -> tuple:
        """The integration health status of the step just integrated (module docstring)."""
        state = np.concatenate([truth.q_body_to_eci, truth.omega_body_rad_s, truth.r_eci_m, truth.v_eci_m_s])
        finite = bool(np.all(np.isfinite(state)))
        norm_error = abs(float(np.linalg.norm(truth.q_body_to_eci)) - 1.0)
        values: dict[str, object] = {'state_finite': str(finite).lower(), 'quaternion_norm_error': f'{norm_error:.3e}',
                                     'torque_free': str(self.torque_free).lower(),
                                     'step_angle_max_rad': f'{self.step_angle_max_rad:.3e}'}
        problems = [] if finite else ['non-finite state']
        if norm_error > QUATERNION_NORM_TOLERANCE:
            problems.append(f'quaternion norm off by {norm_error:.2e}')
        if self.torque_free:
            assert self._h0_eci is not None
            h0 = float(np.linalg.norm(self._h0_eci))
            drifts = {'momentum_drift_rel': float(np.linalg.norm(truth.h_total_eci_nms - self._h0_eci)) / h0 if h0 else 0.0,
                      'energy_drift_rel': abs(truth.rotational_energy_j - self._e0_j) / self._e0_j if self._e0_j else 0.0}
            values.update((key, f'{d:.3e}') for key, d in drifts.items())
            problems += [f'{key} {d:.2e}' for key, d in drifts.items() if d > DRIFT_TOLERANCE]
        values[f'{WALL_CLOCK_PREFIX}step_ms'] = f'{wall_step_s * 1e3:.3f}'
        values[f'{WALL_CLOCK_PREFIX}mean_step_ms'] = f'{self._wall_s / max(self._wall_steps, 1) * 1e3:.3f}'
        self._wall_s, self._wall_steps = 0.0, 0
        return diagnostic(self.instance, values, '; '.join(problems) or 'integration healthy', WARN if problems else OK)

    def fused(self, stage: str, held: dict[str, Any]) -> FusedStage | None:
        """Stage ``integrate`` as :func:`integrate_fused` (:mod:`acds_common.fused`), or None when it does not cover
        the step: thrusters in the graph, telemetry wanted, no circular dipole, a disturbance, before the first
        step, or a ``mode`` that ends the run."""
        parts = self.model.kernel_parts()
        if (stage != 'integrate' or parts is None or self.present('cold_gas') or self.telemetry_wanted
                or self._h0_eci is None or self._run_complete(held.get('mode'))):
            return None
        body, orbit, (t, b, values) = parts
        params = (body, orbit, self._dt, self.total_steps, self._bounds, self._orbit_rate, self.control_period_s,
                  self.model.substeps)
        state = (t, b, values, self._wheel_h, self.torque_free, self._omega_checked, self.step_angle_max_rad)
        inputs = tuple(key for key, node in (('dipole', 'em_driver'), ('wheel_h', 'reaction_wheels'),
                                             ('wheel_hdot', 'reaction_wheels')) if self.present(node))
        if len(inputs) != 3:
            return None
        return FusedStage(integrate_fused, params, state, inputs, FUSED_OUTPUTS, self._restore)

    def _restore(self, s: tuple) -> None:
        """A state of :func:`integrate_fused` into the stepper and its model."""
        t, b, values, self._wheel_h, self.torque_free, self._omega_checked, self.step_angle_max_rad = s
        self.model.set_kernel_state(t, b, values)

    def integrate(self, k: int, _t: float, inp: dict[str, Any]) -> dict[str, Any]:
        """All actuator outputs of step k are in: integrate to t_k+1 and return its truth."""
        if (k >= self.total_steps or self._run_complete(inp['mode'])
                or (self._detumbled is not None and self._detumbled.done(k))):
            self.finished = True
            return {}
        h, hdot, dipole = xyz(inp['wheel_h']), xyz(inp['wheel_hdot']), xyz(inp['dipole'])
        dt = self._dt
        h_end = (h[0] + hdot[0] * dt, h[1] + hdot[1] * dt, h[2] + hdot[2] * dt)
        # -b <= x <= b is |x| <= b, false for a NaN, and for ±inf (the bounds are finite hardware limits): with
        # h_end it also refuses a non-finite ḣ (h finite, then h + ḣ·dt is not).
        (m0, m1, m2), (w0, w1, w2) = self._bounds
        if not (-m0 <= dipole[0] <= m0 and -m1 <= dipole[1] <= m1 and -m2 <= dipole[2] <= m2
                and -w0 <= h[0] <= w0 and -w1 <= h[1] <= w1 and -w2 <= h[2] <= w2
                and -w0 <= h_end[0] <= w0 and -w1 <= h_end[1] <= w1 and -w2 <= h_end[2] <= w2):
            self._refuse(k, h, hdot, dipole, h_end)
        gas = None if inp['gas_wrench'] is None else inp['gas_wrench'][1]
        if gas is not None and not all(math.isfinite(x) for x in gas):
            raise StepError(f'non-finite {topics.resolve(topics.COLD_GAS_WRENCH)} torque at step {k}: {list(gas)}; '
                            'the physics cannot go on')
        telemetry = self.telemetry_wanted  # the wall time is reported on /diagnostics only
        wall0 = time.perf_counter() if telemetry else 0.0
        model = self.model
        if self._h0_eci is None:  # the constants of the motion at t_0, with the wheels' momentum h(t_0)
            truth0 = model.truth_unchecked(h)
            self._h0_eci, self._e0_j = truth0.h_total_eci_nms, truth0.rotational_energy_j
        values = model.advance_unchecked(dt, dipole, h, hdot, gas)  # the inputs were checked above
        self._wheel_h = h_end
        out = truth_outputs(values)
        w = values[3]
        omega = math.sqrt(w[0] * w[0] + w[1] * w[1] + w[2] * w[2])
        if self._detumbled is not None:
            self._detumbled.observe(k + 1, omega)
        if omega > self._omega_checked:
            self._omega_checked = omega
            self._check_step(omega, k)
        if self.torque_free and (any(dipole) or any(hdot) or (gas is not None and any(gas))):
            self.torque_free = False
        if telemetry:
            wall = time.perf_counter() - wall0
            self._wall_s += wall
            self._wall_steps += 1
            if k % DIAGNOSTICS_EVERY == 0:
                out['diagnostics'] = self.health(model.truth_unchecked(h_end), wall)
        return out

    def _refuse(self, k: int, h: Any, hdot: Any, dipole: Any, h_end: Any) -> None:
        """Raise the StepError naming the actuator input that is non-finite or beyond the hardware."""
        for topic, value in ((topics.WHEEL_MOMENTUM, h), (topics.WHEEL_TORQUE, hdot), (topics.DIPOLE_AVG, dipole)):
            if not all(math.isfinite(x) for x in value):
                raise StepError(f'non-finite {topics.resolve(topic)} at step {k}: {list(value)}; '
                                'the physics cannot go on')
        dipole_bound, wheel_bound = self._bounds
        for topic, value, bound, limit, unit in (
                (topics.DIPOLE_AVG, dipole, dipole_bound, self.limits.dipole_am2, 'A·m²'),
                (topics.WHEEL_MOMENTUM, h, wheel_bound, self.limits.wheel_momentum_nms, 'N·m·s'),
                (topics.WHEEL_TORQUE, h_end, wheel_bound, self.limits.wheel_momentum_nms, 'N·m·s at the step end')):
            if not _within(value, bound):
                raise StepError(f'{topics.resolve(topic)} at step {k} gives {list(value)} {unit}, beyond what '
                                f'the hardware can produce (±{limit.tolist()} per axis): not from this graph\'s '
                                'actuators; the run stops')
