"""The integration step against the dynamics: how far the body turns in one RK4 substep (spec §2 "fixed substeps").

The rigid body integrates a control period in ``dynamics.substeps`` RK4 substeps of h = Δt / substeps.
What sets RK4's error is the angle the integrand turns through in one substep, the **step angle**

    θ = (|ω| + 2 ω_orbit) · h

|ω| the body rate, ω_orbit the orbit's fastest angular rate (at perigee): the field and the
gravity-gradient direction turn in the body at up to |ω| + 2 ω_orbit (a dipole field turns twice per
orbit). RK4's error per substep goes as θ⁵, so per radian turned as θ⁴. The substep study
(``tests/substep_study.py`` part (c): the HEAO-B body tumbling torque-free with no gravity gradient,
200 rad turned) measures the relative drift of |H| in ECI and of the rotational energy, per radian
turned:

    θ (rad)   |H| drift/rad   energy drift/rad
    0.02      3.7e-12         6.1e-13
    0.05      1.5e-10         5.9e-11
    0.1       2.5e-09         1.9e-09     ← WARN: 1e-6 (the rigid body's DRIFT_TOLERANCE) after ~400 rad turned
    0.2       4.9e-08         6.1e-08
    0.5       3.5e-06         5.9e-06     ← REFUSED: 1e-3 after ~300 rad, the heao_b_acquisition tumble's hour
    0.87      5.1e-05         9.1e-05       (57 deg/s per axis at 0.5 s: 36 % |H| drift over a run)

The shipped scenarios stay below 0.08 (``oresat_detumble``: 5 deg/s per axis, 0.5 s substeps).
:func:`refusal` is the pre-flight's and the running check's hard bound; :func:`warning` the one-line
warning; both name the key to change (``dynamics.substeps`` or ``control_period_s``).
"""

from __future__ import annotations

import math

from acds_common import kernels, units
from acds_common.environment import Orbit

#: Step angle above which a run is warned (one line): drift 2.5e-9 of |H| per radian turned.
STEP_ANGLE_WARN_RAD = 0.1
#: Step angle above which a scenario is refused (pre-flight) or a run stopped: drift 3.5e-6 of |H| per radian.
STEP_ANGLE_LIMIT_RAD = 0.5
#: Where the bounds come from.
STUDY = 'tests/substep_study.py (c)'


def orbit_rate_max_rad_s(orbit: Orbit) -> float:
    """The orbit's fastest angular rate, rad/s: at perigee, √(μ a (1 − e²)) / r_p²."""
    a, e, rp = orbit.semi_major_axis_m, orbit.eccentricity, orbit.perigee_radius_m
    return math.sqrt(units.EARTH_MU_M3_S2 * a * (1.0 - e * e)) / (rp * rp)


@kernels.helper
def step_angle_rad(omega_rad_s: float, orbit_rate_rad_s: float, control_period_s: float, substeps: int) -> float:
    """θ = (|ω| + 2 ω_orbit) · Δt / substeps (module docstring)."""
    return (omega_rad_s + 2.0 * orbit_rate_rad_s) * control_period_s / substeps


def _advice(omega_rad_s: float, orbit_rate_rad_s: float, control_period_s: float, substeps: int, bound: float) -> str:
    rate = omega_rad_s + 2.0 * orbit_rate_rad_s
    need = math.ceil(rate * control_period_s / bound)
    return (f'raise dynamics.substeps to at least {need} (θ ≤ {bound:g} rad) or shorten control_period_s to at most '
            f'{bound * substeps / rate:.3g} s')


def _state(what: str, omega_rad_s: float, orbit_rate_rad_s: float, control_period_s: float, substeps: int) -> str:
    theta = step_angle_rad(omega_rad_s, orbit_rate_rad_s, control_period_s, substeps)
    return (f'{substeps} RK4 substep(s) per {control_period_s:g} s control period turn {theta:.3g} rad per substep '
            f'at {what} |ω| {math.degrees(omega_rad_s):.3g} deg/s (θ = (|ω| + 2 ω_orbit)·Δt/substeps)')


def refusal(what: str, omega_rad_s: float, orbit_rate_rad_s: float, control_period_s: float, substeps: int) -> str | None:
    """The one-line reason the step is refused (θ above :data:`STEP_ANGLE_LIMIT_RAD`), else None."""
    if step_angle_rad(omega_rad_s, orbit_rate_rad_s, control_period_s, substeps) <= STEP_ANGLE_LIMIT_RAD:
        return None
    return (f'dynamics.substeps: {_state(what, omega_rad_s, orbit_rate_rad_s, control_period_s, substeps)}, beyond the '
            f'{STEP_ANGLE_LIMIT_RAD:g} rad RK4 keeps accurate ({STUDY}: 3.5e-6 of |H| drift per radian turned there); '
            + _advice(omega_rad_s, orbit_rate_rad_s, control_period_s, substeps, STEP_ANGLE_WARN_RAD))


def warning(what: str, omega_rad_s: float, orbit_rate_rad_s: float, control_period_s: float, substeps: int) -> str | None:
    """The one-line warning (θ above :data:`STEP_ANGLE_WARN_RAD`), else None."""
    if step_angle_rad(omega_rad_s, orbit_rate_rad_s, control_period_s, substeps) <= STEP_ANGLE_WARN_RAD:
        return None
    return (f'integration accuracy: {_state(what, omega_rad_s, orbit_rate_rad_s, control_period_s, substeps)}, above '
            f'{STEP_ANGLE_WARN_RAD:g} rad ({STUDY}: 2.5e-9 of |H| drift per radian turned there, growing as θ⁴); '
            + _advice(omega_rad_s, orbit_rate_rad_s, control_period_s, substeps, STEP_ANGLE_WARN_RAD))
