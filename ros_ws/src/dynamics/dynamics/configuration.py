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
    EnvironmentModelError,
    Orbit,
    Sun,
    SunConfig,
    field_from_section,
    orbit_from_section,
)
from acds_common.inertia import InertiaError, inertia_tensor
from acds_common.torque_rod_record import TorqueRodRecordError, dipole_bound_am2, read_torque_rod_record
from acds_common.validation import scenario_key

from dynamics.cmg_model import CmgConfig, ControlMomentGyros
from dynamics.disturbances import DisturbanceTorque, Harmonic
from dynamics.errors import DynamicsError
from dynamics.rigid_body_model import RigidBodyModel
from dynamics.wheels_model import ReactionWheels, WheelsConfig

__all__ = ['RIGID_BODY_SECTIONS', 'ActuatorLimits', 'actuator_limits', 'build_cmgs', 'build_disturbance',
           'build_momentum_store', 'build_rigid_body', 'build_torque_wheels', 'build_wheels', 'dipole_limit_am2']

#: ``disturbance`` keys of the cyclic parts → harmonic order and the (cos, sin) slot.
_CYCLIC_KEYS = ((1, 'once_per_orbit_cos', 'once_per_orbit_sin'), (2, 'twice_per_orbit_cos', 'twice_per_orbit_sin'))


def build_disturbance(disturbance: dict[str, Any], orbit: Orbit) -> DisturbanceTorque | None:
    """The body-fixed disturbance torque of the scenario's ``disturbance`` section, or None when it is all zero.

    Constant part: ``bias_momentum_per_orbit`` / orbit period (seed 000 §5 states its bias torques as the
    momentum they build per orbit). Cyclic parts: once and twice per orbit in the argument of latitude u,
    which is 0 at the ascending node (circular orbit: u = arg_latitude0 + n t; elliptical: the mean
    argument of latitude, ω + M0 + n t; :meth:`acds_common.environment.Orbit.node_time_s`).
    """
    harmonics = tuple(Harmonic(order, tuple(disturbance[cos]), tuple(disturbance[sin]))
                      for order, cos, sin in _CYCLIC_KEYS if any(disturbance[cos]) or any(disturbance[sin]))
    if not any(disturbance['bias_momentum_per_orbit']) and not harmonics:
        return None
    constant = tuple(float(h) / orbit.period_s for h in disturbance['bias_momentum_per_orbit'])
    return DisturbanceTorque(constant, harmonics, orbit.mean_motion_rad_s, node_time_s=orbit.node_time_s())


#: The scenario sections :func:`build_rigid_body` takes, in its argument order.
RIGID_BODY_SECTIONS = ('spacecraft', 'orbit', 'earth', 'sun', 'dynamics', 'disturbance')


def build_rigid_body(spacecraft: dict[str, Any], orbit: dict[str, Any], earth: dict[str, Any], sun: dict[str, Any],
                     dynamics: dict[str, Any], disturbance: dict[str, Any]) -> RigidBodyModel:
    """The rigid body in its orbit and environment from the scenario's six sections (spec §3; seed 000 §5)."""
    with scenario_key('spacecraft.inertia', InertiaError):
        inertia = inertia_tensor(*spacecraft['inertia']) * spacecraft['inertia_scale']
    with scenario_key('orbit', EnvironmentModelError):
        orbit_model = orbit_from_section(orbit)
    with scenario_key('earth', EnvironmentModelError):
        field = field_from_section(earth)
    with scenario_key('disturbance', DynamicsError):
        torque = build_disturbance(disturbance, orbit_model)
    with scenario_key('sun', EnvironmentModelError):
        sun_model = Sun(SunConfig(right_ascension_rad=sun['right_ascension'], declination_rad=sun['declination'],
                                  eclipse=sun['eclipse']))
    with scenario_key('spacecraft', DynamicsError):  # initial attitude and rates (substeps: schema-checked)
        return RigidBodyModel(inertia, orbit_model, field, sun_model,
                              gravity_gradient=dynamics['gravity_gradient'], substeps=dynamics['substeps'],
                              q0_body_to_eci=spacecraft['initial_quaternion_xyzw'],
                              omega0_body_rad_s=spacecraft['initial_rates'], disturbance=torque)


def build_torque_wheels(wheels: dict[str, Any]) -> Any:
    """Torque-commanded wheels (``wheels.drive: torque``, a formation vehicle's; seed 004 slide 74)."""
    from dynamics.formation import TorqueWheels

    with scenario_key('wheels', DynamicsError):
        axes = wheels['torque_axes']
        if not axes or len(axes) % 3:
            raise DynamicsError(f'torque_axes must hold one (x, y, z) triple per wheel, got {len(axes)} numbers')
        capacity = wheels['capacity'] if wheels['capacity'] > 0.0 else None
        return TorqueWheels(np.array(axes, dtype=float).reshape(-1, 3).T, wheels['max_torque'], capacity,
                            h0_nms=np.array(axes, dtype=float).reshape(-1, 3) @ np.array(wheels['initial_momentum']))


def build_wheels(wheels: dict[str, Any]) -> ReactionWheels:
    """The wheel cluster from the scenario's ``wheels`` section (spec §4); ``failed_wheel`` −1 means none."""
    with scenario_key('wheels', DynamicsError):
        failed = wheels['failed_wheel'] if wheels['failed_wheel'] >= 0 else None
        return ReactionWheels(WheelsConfig(layout=wheels['layout'], failed_wheel=failed),
                              h0_body_nms=np.array(wheels['initial_momentum']))


def build_cmgs(wheels: dict[str, Any]) -> ControlMomentGyros:
    """The CMG store of a ``wheels`` section with ``kind: cmg`` (seed 000): capacity and initial momentum."""
    with scenario_key('wheels', DynamicsError):
        return ControlMomentGyros(CmgConfig(capacity_nms=wheels['cmg_capacity']),
                                  h0_body_nms=np.array(wheels['initial_momentum']))


def build_momentum_store(wheels: dict[str, Any]) -> ReactionWheels | ControlMomentGyros:
    """The momentum store the ``wheels`` section's ``kind`` names: reaction wheels or CMGs."""
    return build_cmgs(wheels) if wheels['kind'] == 'cmg' else build_wheels(wheels)


@dataclass(frozen=True)
class ActuatorLimits:
    """The most the actuators can physically give per body axis: dipole (A·m²) and wheel momentum (N·m·s)."""

    dipole_am2: np.ndarray
    wheel_momentum_nms: np.ndarray


def dipole_limit_am2(em_driver: dict[str, Any]) -> np.ndarray:
    """Most dipole per body axis the em_driver's hardware can make: both windings (active and standby)
    at the full bus current E/R with no transistor drop — more than any drive makes (spec §6); for
    ``driver_kind: torque_rod`` the same bound from the rod's design record
    (:func:`acds_common.torque_rod_record.dipole_bound_am2`, seed 003); zero on an axis whose drive is
    ``none`` (no coil there: a formation vehicle's, seed 004)."""
    if em_driver['driver_kind'] == 'torque_rod':
        with scenario_key('em_driver.torque_rod_design', DynamicsError):
            try:
                record = read_torque_rod_record(em_driver['torque_rod_design'])
            except TorqueRodRecordError as exc:
                raise DynamicsError(str(exc)) from None
        return np.full(3, dipole_bound_am2(record, em_driver['supply_v']))
    per_amp = np.asarray(em_driver['coil_moment_per_amp_am2'], dtype=float)
    i_max = em_driver['supply_v'] / np.asarray(em_driver['coil_resistance_ohm'], dtype=float)
    return np.where(np.array(em_driver['drive_types']) == 'none', 0.0, 2.0 * per_amp * i_max)


def actuator_limits(em_driver: dict[str, Any], wheels: dict[str, Any]) -> ActuatorLimits:
    """Physical bounds of the actuator inputs of the rigid body (issue 9 §3: nothing injected beyond them).

    Dipole per axis: both windings (active and standby) carrying the full bus current E/R, with no
    transistor drop — more than any drive can make (spec §6), so only a value from outside the graph
    exceeds it (:func:`dipole_limit_am2`). Wheel momentum per axis: every wheel at its capacity along that
    axis, Σ_j |a_ij|·H_j (the single-axis maximum; Table 4-6's box is what every axis holds at once);
    CMGs: the radius of their spherical envelope on every axis.
    """
    dipole = dipole_limit_am2(em_driver)
    if wheels['kind'] == 'cmg':
        return ActuatorLimits(dipole, np.full(3, build_cmgs(wheels).cfg.capacity_nms))
    cluster = build_wheels(wheels)
    axes = np.abs(cluster.wheel_axes_body())
    return ActuatorLimits(dipole, axes @ cluster.wheel_capacities_nms())
