"""formation_dynamics stepper: the time owner of a formation of vehicles (spec §10; seed 004).

Built from the formation's shared sections (``formation``, ``dynamics``, and for the ``hill``
frame ``orbit``/``earth``) and every vehicle's ``spacecraft``, ``vehicle`` and ``em_driver``
sections (parameters ``<vehicle>.<name>``); a ``vehicle.magnet: permanent`` vehicle has its
``permanent_dipole`` and no coil (nor em_driver: its absent dipole input is zero). Step 0's truth is published at start; stage
``integrate`` of step k takes every vehicle's achieved dipole and wheel momentum/rate of step k
(an absent node means zero), checks them against what the hardware can produce, integrates
t_k → t_k+1 (:class:`dynamics.formation.FormationDynamics`) and returns every vehicle's truth of
step k + 1 under its namespace:

* ``<v>/truth/odometry``: position and velocity in the formation frame (the testbed's plane, the
  inertial frame, or the Hill frame of the reference orbit), attitude body → inertial (ECI in
  ``hill``), body rates;
* ``<v>/sensors/gyro``: ideal rate gyros (the seed's gyro bias and noise are not modelled);
* ``<v>/truth/b_body``: the Earth field at the vehicle, body axes (zero outside ``hill``);
* ``<v>/truth/wrench``: the step-average external force and torque on the vehicle (the other
  vehicles' coils + the Earth's field; gravity-gradient torque included), body axes.
"""

from __future__ import annotations

from typing import Any

import numpy as np
from acds_common import topics
from acds_common.attitude import quat_to_dcm
from acds_common.cdr import OdometryValue
from acds_common.environment import EarthFieldConfig, Orbit, OrbitConfig, TiltedDipoleField
from acds_common.inertia import inertia_tensor
from acds_common.messages import magnetic_field, vec, vector3
from acds_common.stepper import StepError, Stepper
from acds_common.validation import scenario_key

from dynamics.configuration import dipole_limit_am2
from dynamics.errors import DynamicsError
from dynamics.formation import (
    Coil,
    FormationConfig,
    FormationDynamics,
    FormationTruth,
    VehicleInput,
    VehicleSpec,
    VehicleState,
)

_ZERO_COV = (0.0,) * 9
_ZERO = (0.0, 0.0, 0.0)


def coils(vehicle: dict[str, Any], name: str) -> tuple[Coil, ...]:
    """The vehicle's coils from its ``vehicle`` section (axes triples, radii, turns, current limits)."""
    axes = vehicle['coil_axes']
    n = len(vehicle['coil_radii'])
    if len(axes) != 3 * n or len(vehicle['coil_turns']) != n or len(vehicle['coil_max_current']) != n:
        raise DynamicsError(f'vehicles.{name}.vehicle: coil_axes ({len(axes)} numbers), coil_radii, coil_turns and '
                            f'coil_max_current must describe the same {n} coils (3 numbers of axes per coil)')
    return tuple(Coil(np.array(axes[3 * i:3 * i + 3]), vehicle['coil_radii'][i], int(vehicle['coil_turns'][i]),
                      vehicle['coil_max_current'][i]) for i in range(n))


def check_coils_match_drives(name: str, spec: VehicleSpec, em_driver: dict[str, Any]) -> None:
    """Every coil along a body axis must be the coil that axis's drive drives: N·π·R² = its moment per ampere."""
    for coil in spec.coils:
        axis = int(np.argmax(np.abs(coil.axis_body)))
        if abs(abs(coil.axis_body[axis]) - 1.0) > 1e-9:
            continue  # a coil off the body axes: the drives' per-axis model does not describe it
        per_amp = coil.turns * coil.area_m2
        given = em_driver['coil_moment_per_amp_am2'][axis]
        if em_driver['drive_types'][axis] == 'none' or abs(given - per_amp) > 1e-6 * per_amp:
            raise DynamicsError(f'vehicles.{name}: the coil along body {"xyz"[axis]} (N·π·R² = {per_amp:.6g} A·m²/A) '
                                f'is not what em_driver.coil_moment_per_amp_am2[{axis}] = {given:.6g} drives '
                                f'(drive {em_driver["drive_types"][axis]})')


class FormationDynamicsStep(Stepper):
    """Every vehicle of the formation, pushing on each other with their coils; owner of sim time."""

    node = 'formation_dynamics'

    def __init__(self, params: dict[str, Any], log: Any = None) -> None:
        super().__init__(params, log)
        self.total_steps: int = params['total_steps']
        self.names: list[str] = list(params['formation_vehicles'])
        f, dyn = self.section('formation'), self.section('dynamics')
        if dyn['stop_when_detumbled']:
            raise DynamicsError('dynamics.stop_when_detumbled: a single spacecraft\'s run end (rigid_body); a '
                                'formation runs its duration')
        orbit = field = None
        if f['frame'] == 'hill':
            o, e = self.section('orbit'), self.section('earth')
            with scenario_key('orbit', ValueError):
                orbit = Orbit(OrbitConfig(kind=o['kind'], inclination_rad=o['inclination'], raan_rad=o['raan'],
                                          altitude_m=o['altitude'], arg_latitude0_rad=o['arg_latitude0']))
            if f['earth_field']:
                field = TiltedDipoleField(EarthFieldConfig(
                    dipole_moment_am2=e['dipole_moment'], tilt_rad=e['dipole_tilt'],
                    dipole_longitude_rad=e['dipole_longitude'], greenwich_angle0_rad=e['greenwich_angle0'])).b_eci
        specs, states, self.limits = [], [], []
        for name in self.names:
            sc, vh, em = (self.section(s, name) for s in ('spacecraft', 'vehicle', 'em_driver'))
            with scenario_key(f'vehicles.{name}', DynamicsError):
                permanent = vh['magnet'] == 'permanent'
                spec = VehicleSpec(name, vh['mass'], inertia_tensor(*sc['inertia']) * sc['inertia_scale'],
                                   () if permanent else coils(vh, name),
                                   np.array(vh['permanent_dipole'] if permanent else _ZERO), vh['fixed'])
                check_coils_match_drives(name, spec, em)
            specs.append(spec)
            states.append(VehicleState(vh['initial_position'], vh['initial_velocity'], sc['initial_quaternion_xyzw'],
                                       sc['initial_rates']))
            self.limits.append(dipole_limit_am2(em))
        with scenario_key('formation', DynamicsError):
            self.model = FormationDynamics(FormationConfig(
                frame=f['frame'], em_model=f['em_model'], segments=f['segments'], substeps=dyn['substeps'],
                orbit=orbit, earth_field=field, gravity_gradient=f['frame'] == 'hill' and dyn['gravity_gradient'],
                track_tilt_rad=f['track_tilt']),
                specs, states)
        self._wheel_h = [np.zeros(3) for _ in self.names]

    def start(self) -> dict[str, Any]:
        """The truth of step 0."""
        return self.truth_outputs(self.model.truth())

    def truth_outputs(self, truth: FormationTruth) -> dict[str, Any]:
        """Every vehicle's truth topics of one step (module docstring)."""
        out: dict[str, Any] = {}
        for name, v in zip(self.names, truth.vehicles, strict=True):
            rot_t = quat_to_dcm(v.q_body_to_inertial).T
            frame_to_body = rot_t if truth.hill_to_eci is None else rot_t @ truth.hill_to_eci
            force = frame_to_body @ (v.em_force_avg_n + v.earth_force_avg_n)
            torque = v.em_torque_avg_body_nm + v.earth_torque_avg_body_nm + v.gg_torque_avg_body_nm
            omega = vector3(v.omega_body_rad_s)
            out[f'{name}/odometry'] = OdometryValue(vector3(v.position_m), tuple(float(c) for c in v.q_body_to_inertial),
                                                    vector3(v.velocity_m_s), omega)
            out[f'{name}/gyro'] = (omega, _ZERO_COV)
            out[f'{name}/b_body'] = magnetic_field(_ZERO if v.b_body_t is None else v.b_body_t)
            out[f'{name}/wrench'] = (vector3(force), vector3(torque))
        return out

    def integrate(self, k: int, _t: float, inp: dict[str, Any]) -> dict[str, Any]:
        """Every vehicle's actuator outputs of step k are in: integrate to t_k+1 and return its truth."""
        if k >= self.total_steps:
            self.finished = True
            return {}
        dt = self.control_period_s
        inputs = []
        for i, name in enumerate(self.names):
            dipole, h, hdot = (vec(inp[f'{name}/{key}']) for key in ('dipole', 'wheel_h', 'wheel_hdot'))
            for topic, value in ((topics.DIPOLE_AVG, dipole), (topics.WHEEL_MOMENTUM, h), (topics.WHEEL_TORQUE, hdot)):
                if not np.all(np.isfinite(value)):
                    raise StepError(f'non-finite /acds/{name}/{topic} at step {k}: {value.tolist()}')
            if np.any(np.abs(dipole) > self.limits[i] * (1.0 + 1e-9)):
                raise StepError(f'/acds/{name}/{topics.DIPOLE_AVG} at step {k} gives {dipole.tolist()} A·m², beyond '
                                f'what its drives can produce (±{self.limits[i].tolist()} per axis): not from this '
                                "graph's actuators; the run stops")
            inputs.append(VehicleInput(dipole, h, hdot))
            self._wheel_h[i] = h + hdot * dt
        try:
            self.model.advance(dt, inputs)
        except DynamicsError as exc:
            raise StepError(f'step {k}: {exc}') from None
        return self.truth_outputs(self.model.truth())

