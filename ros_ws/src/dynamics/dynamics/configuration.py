"""Scenario sections → the dynamics cores (pure, no rclpy).

The steppers of ``rigid_body`` and ``reaction_wheels`` receive their scenario
sections as SI values ({field: value}, see ``acds_common.scenario.SCHEMA``) and
build their models here; the launcher's pre-flight builds the same steppers
before any process starts, so a model's own check (inertia positive definite
and physical, apogee above perigee, a normalisable attitude, a wheel failure
only on the 4-wheel cluster, ...) fails there first. Each error names the
scenario section or key it came from.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np
from acds_common.environment import (
    EarthFieldConfig,
    EnvironmentModelError,
    IgrfConfig,
    IgrfField,
    MagneticFieldModel,
    Orbit,
    OrbitConfig,
    Sun,
    SunConfig,
    TiltedDipoleField,
)
from acds_common.inertia import InertiaError, inertia_tensor
from acds_common.validation import scenario_key

from dynamics.errors import DynamicsError
from dynamics.rigid_body_model import RigidBodyModel
from dynamics.wheels_model import ReactionWheels, WheelsConfig

__all__ = ['ActuatorLimits', 'actuator_limits', 'build_field', 'build_rigid_body', 'build_wheels']


def build_rigid_body(spacecraft: dict[str, Any], orbit: dict[str, Any], earth: dict[str, Any], sun: dict[str, Any],
                     dynamics: dict[str, Any]) -> RigidBodyModel:
    """The rigid body in its orbit and environment from the scenario's five sections (spec §3)."""
    with scenario_key('spacecraft.inertia', InertiaError):
        inertia = inertia_tensor(*spacecraft['inertia']) * spacecraft['inertia_scale']
    with scenario_key('orbit', EnvironmentModelError):
        orbit_model = Orbit(OrbitConfig(
            kind=orbit['kind'], inclination_rad=orbit['inclination'], raan_rad=orbit['raan'],
            altitude_m=orbit['altitude'], arg_latitude0_rad=orbit['arg_latitude0'],
            perigee_altitude_m=orbit['perigee_altitude'], apogee_radius_m=orbit['apogee_radius'],
            arg_perigee_rad=orbit['arg_perigee'], mean_anomaly0_rad=orbit['mean_anomaly0']))
    with scenario_key('earth', EnvironmentModelError):
        field = build_field(earth)
    with scenario_key('sun', EnvironmentModelError):
        sun_model = Sun(SunConfig(right_ascension_rad=sun['right_ascension'], declination_rad=sun['declination'],
                                  eclipse=sun['eclipse']))
    with scenario_key('spacecraft', DynamicsError):  # initial attitude and rates (substeps: schema-checked)
        return RigidBodyModel(inertia, orbit_model, field, sun_model,
                              gravity_gradient=dynamics['gravity_gradient'], substeps=dynamics['substeps'],
                              q0_body_to_eci=spacecraft['initial_quaternion_xyzw'],
                              omega0_body_rad_s=spacecraft['initial_rates'])


def build_field(earth: dict[str, Any]) -> MagneticFieldModel:
    """The Earth field of the scenario's ``earth`` section: the study's tilted dipole (default) or IGRF-14 (spec §3)."""
    if earth['model'] == 'igrf':
        return IgrfField(IgrfConfig(epoch_year=earth['epoch'], greenwich_angle0_rad=earth['greenwich_angle0']))
    return TiltedDipoleField(EarthFieldConfig(
        dipole_moment_am2=earth['dipole_moment'], tilt_rad=earth['dipole_tilt'],
        dipole_longitude_rad=earth['dipole_longitude'], greenwich_angle0_rad=earth['greenwich_angle0']))


def build_wheels(wheels: dict[str, Any]) -> ReactionWheels:
    """The wheel cluster from the scenario's ``wheels`` section (spec §4); ``failed_wheel`` −1 means none."""
    with scenario_key('wheels', DynamicsError):
        failed = wheels['failed_wheel'] if wheels['failed_wheel'] >= 0 else None
        return ReactionWheels(WheelsConfig(layout=wheels['layout'], failed_wheel=failed),
                              h0_body_nms=np.array(wheels['initial_momentum']))


@dataclass(frozen=True)
class ActuatorLimits:
    """The most the actuators can physically give per body axis: dipole (A·m²) and wheel momentum (N·m·s)."""

    dipole_am2: np.ndarray
    wheel_momentum_nms: np.ndarray


def actuator_limits(em_driver: dict[str, Any], wheels: dict[str, Any]) -> ActuatorLimits:
    """Physical bounds of the actuator inputs of the rigid body (issue 9 §3: nothing injected beyond them).

    Dipole per axis: both windings (active and standby) carrying the full bus current E/R, with no
    transistor drop — more than any drive can make (spec §6), so only a value from outside the graph
    exceeds it. Wheel momentum per axis: every wheel at its capacity along that axis, Σ_j |a_ij|·H_j
    (the single-axis maximum; Table 4-6's box is what every axis holds at once).
    """
    per_amp = np.asarray(em_driver['coil_moment_per_amp_am2'], dtype=float)
    i_max = em_driver['supply_v'] / np.asarray(em_driver['coil_resistance_ohm'], dtype=float)
    cluster = build_wheels(wheels)
    axes = np.abs(cluster.wheel_axes_body())
    return ActuatorLimits(2.0 * per_amp * i_max, axes @ cluster.wheel_capacities_nms())
