"""RK4 substeps per control period: accuracy study (issue 10 §3; the schema's ``dynamics.substeps``).

Two families of cases, each run at several substep counts and compared with a 100-substep
reference (RK4's error per step falls as (Δt/n)⁴, so 100 substeps is exact to rounding here):

(a) open loop, the ``heao_b_acquisition`` body, orbit and field (HEAO-B, 225 nmi, 22.5°,
    1 deg/s about each axis) tumbling for one orbit at the 0.5 s control period, torque-free
    and with gravity gradient: the attitude error (deg, the angle of q_ref* ⊗ q) and the rate
    error (deg/s, |ω − ω_ref|) at the end;
(b) closed loop, the ``heao_b_acquisition`` scenario on the direct engine: the Table 4-7
    times (magnetics only, acquisition) and the final stored wheel momentum;
(c) the step against the dynamics (issue 18 item 3): the same body tumbling torque-free (no gravity
    gradient) about (1, 1, 1)/√3 at the rate that turns it θ rad per RK4 substep, 1 substep of 0.5 s,
    until it has turned 200 rad: the largest relative drift of |H| in ECI and of the energy, per radian
    turned. The bounds of :mod:`dynamics.integration_accuracy` are read off this table.

``python tests/substep_study.py`` prints the full study (one orbit; the full acquisition, a few
minutes of CPU); ``tests/test_substep_study.py`` runs shortened cases with their tolerances.
"""

from __future__ import annotations

import math
import sys
from dataclasses import dataclass
from typing import Any

from acds_common.attitude import quat_mul
from acds_common.scenario import load_scenario
from acds_runtime.direct import DirectRun
from dynamics.configuration import RIGID_BODY_SECTIONS, build_rigid_body
from dynamics.integration_accuracy import STEP_ANGLE_LIMIT_RAD, STEP_ANGLE_WARN_RAD

#: Substep counts studied, and the reference.
SUBSTEPS = (1, 2, 5, 10, 20)
REFERENCE_SUBSTEPS = 100
SCENARIO = 'heao_b_acquisition'


@dataclass(frozen=True)
class TumbleError:
    """End-of-run error of one open-loop case against the reference: attitude (deg) and rate (deg/s)."""

    attitude_deg: float
    rate_deg_s: float


def tumble(substeps: int, gravity_gradient: bool, duration_s: float) -> tuple[tuple[float, ...], tuple[float, ...]]:
    """Final (q, ω) of the scenario's body tumbling without actuators for ``duration_s`` at its control period."""
    sc = load_scenario(SCENARIO)
    dynamics = dict(sc.values['dynamics'], substeps=substeps, gravity_gradient=gravity_gradient)
    model = build_rigid_body(*(dynamics if s == 'dynamics' else sc.values[s] for s in RIGID_BODY_SECTIONS))
    zero = (0.0, 0.0, 0.0)
    for _ in range(round(duration_s / sc.control_period_s)):
        model.advance(sc.control_period_s, zero, zero, zero)
    truth = model.truth(zero)
    return truth.q_xyzw, truth.omega_xyz


def tumble_error(substeps: int, gravity_gradient: bool, duration_s: float,
                 reference: tuple[tuple[float, ...], tuple[float, ...]]) -> TumbleError:
    """The error of ``substeps`` against ``reference`` (the same case at REFERENCE_SUBSTEPS)."""
    q, w = tumble(substeps, gravity_gradient, duration_s)
    q_ref, w_ref = reference
    rel = quat_mul((-q_ref[0], -q_ref[1], -q_ref[2], q_ref[3]), q)
    angle = 2.0 * math.atan2(math.sqrt(rel[0] ** 2 + rel[1] ** 2 + rel[2] ** 2), abs(rel[3]))
    return TumbleError(math.degrees(angle), math.degrees(math.dist(w, w_ref)))


@dataclass(frozen=True)
class AcquisitionResult:
    """The closed-loop columns compared: Table 4-7 times (min), final |h| (ft-lb-s), steps run."""

    magnetics_only_min: float | None
    acquisition_min: float | None
    final_wheel_momentum_ftlbs: float | None
    steps: int


def acquisition(substeps: int, scenario: str = SCENARIO, steps: int | None = None) -> AcquisitionResult:
    """The scenario on the direct engine with ``substeps`` RK4 substeps per control period."""
    sc = load_scenario(scenario)
    sc.values['dynamics']['substeps'] = substeps
    summary: dict[str, Any] = DirectRun(sc, steps=steps).run().summary
    return AcquisitionResult(summary['time_magnetics_only_min'], summary['acquisition_time_min'],
                             summary['final_wheel_momentum_ftlbs'], summary['steps'])


#: Step angles of part (c), rad per substep, and the angle each case turns through.
STEP_ANGLES = (0.02, 0.05, STEP_ANGLE_WARN_RAD, 0.2, STEP_ANGLE_LIMIT_RAD, 0.87)
TURNED_RAD = 200.0


@dataclass(frozen=True)
class Drift:
    """Part (c): the largest relative drift of |H| (ECI) and of the rotational energy per radian turned."""

    momentum_per_rad: float
    energy_per_rad: float


def step_angle_drift(theta_rad: float, turned_rad: float = TURNED_RAD) -> Drift:
    """Part (c) at step angle ``theta_rad``: torque-free tumble, 1 substep of the scenario's control period."""
    sc = load_scenario(SCENARIO)
    dt = sc.control_period_s
    rate = theta_rad / dt
    values = dict(sc.values, dynamics=dict(sc.values['dynamics'], substeps=1, gravity_gradient=False),
                  spacecraft=dict(sc.values['spacecraft'], initial_rates=[rate / math.sqrt(3.0)] * 3))
    model = build_rigid_body(*(values[s] for s in RIGID_BODY_SECTIONS))
    zero = (0.0, 0.0, 0.0)
    first = model.truth(zero)
    h0, e0 = first.h_total_eci_nms, first.rotational_energy_j
    dh = de = 0.0
    for _ in range(round(turned_rad / theta_rad)):
        model.advance(dt, zero, zero, zero)
        truth = model.truth(zero)
        dh = max(dh, math.dist(truth.h_total_eci_nms, h0) / math.hypot(*h0))
        de = max(de, abs(truth.rotational_energy_j - e0) / e0)
    return Drift(dh / turned_rad, de / turned_rad)


def main() -> int:
    """Print the full study: one orbit open loop, the whole acquisition closed loop."""
    sc = load_scenario(SCENARIO)
    period_s = build_rigid_body(*(sc.values[s] for s in RIGID_BODY_SECTIONS)).orbit.period_s
    print(f'(a) open loop, one orbit ({period_s / 60:.1f} min) at {sc.control_period_s} s, error against '
          f'{REFERENCE_SUBSTEPS} substeps')
    for gg in (False, True):
        ref = tumble(REFERENCE_SUBSTEPS, gg, period_s)
        print(f'  {"gravity gradient" if gg else "torque-free"}')
        for n in SUBSTEPS:
            e = tumble_error(n, gg, period_s, ref)
            print(f'    substeps {n:3d}: attitude {e.attitude_deg:.3e} deg, rate {e.rate_deg_s:.3e} deg/s')
    print(f'(b) closed loop, {SCENARIO} on the direct engine')
    ref_acq = acquisition(REFERENCE_SUBSTEPS)
    for n in (*SUBSTEPS, REFERENCE_SUBSTEPS):
        r = ref_acq if n == REFERENCE_SUBSTEPS else acquisition(n)
        dh = (None if r.final_wheel_momentum_ftlbs is None or ref_acq.final_wheel_momentum_ftlbs is None
              else r.final_wheel_momentum_ftlbs - ref_acq.final_wheel_momentum_ftlbs)
        print(f'    substeps {n:3d}: Mode 1B at {r.magnetics_only_min} min, capture at {r.acquisition_min} min '
              f'(step {r.steps}), final |h| {r.final_wheel_momentum_ftlbs} ft-lb-s (Δ {dh})')
    print(f'(c) torque-free tumble turning {TURNED_RAD:g} rad, 1 substep of {sc.control_period_s} s: drift per radian '
          'turned against the step angle θ')
    for theta in STEP_ANGLES:
        d = step_angle_drift(theta)
        print(f'    θ {theta:5.3f} rad: |H| {d.momentum_per_rad:.2e}/rad, energy {d.energy_per_rad:.2e}/rad')
    return 0


if __name__ == '__main__':
    sys.exit(main())
