"""formation_controller stepper: one vehicle's EMFF controller (spec §10; seed 004).

Every vehicle runs the same controller on the same measurements — every vehicle's truth of step k
and wheel momentum of step k − 1 (h(t_k) = h_{k−1} + ḣ_{k−1}·Δt), the testbed's RF link (slide 70)
— so all of them solve the same dipoles (:class:`acds_controller.formation_control.FormationController`:
the relative-force command, the minimum-current pair or the Earth-dump choice) and each publishes its
own vehicle's part: ``controller/moment_command`` (body dipole, A·m², to its em_driver) and
``controller/wheel_torque`` (the wanted ḣ, N·m, to its torque-driven wheels). The law comes from the
``formation`` section: ``hold`` a relative position or ``spin_up`` the pair; ``dump`` uses the Earth
as a momentum dump in the ``hill`` frame. Telemetry (force command, frame dipole, dumping) on
``diagnostics`` every ``TELEMETRY_EVERY`` steps.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np
from acds_common.attitude import quat_to_dcm
from acds_common.environment import Orbit, OrbitConfig, hill_frame
from acds_common.inertia import inertia_tensor
from acds_common.messages import diagnostic, vec, vector3
from acds_common.stepper import Stepper
from acds_common.validation import scenario_key

from acds_controller.formation_control import (
    AttitudeLaw,
    ControlledVehicle,
    DumpLaw,
    FormationController,
    HoldLaw,
    Measurement,
    SpinUpLaw,
    VehicleCommand,
)
from acds_controller.magnetic_laws import ControllerError

#: Formation telemetry on ``diagnostics`` every this many steps.
TELEMETRY_EVERY = 20


def controlled_vehicle(name: str, sc: dict[str, Any], vh: dict[str, Any]) -> ControlledVehicle:
    """What the controller knows of a vehicle, from its ``spacecraft`` and ``vehicle`` sections."""
    n = len(vh['coil_radii'])
    axes = np.array(vh['coil_axes'], dtype=float).reshape(n, 3).T
    limits = [vh['coil_turns'][i] * vh['coil_max_current'][i] * math.pi * vh['coil_radii'][i] ** 2 for i in range(n)]
    return ControlledVehicle(name, vh['mass'], inertia_tensor(*sc['inertia']) * sc['inertia_scale'], axes,
                             np.array(limits))


class FormationControllerStep(Stepper):
    """One vehicle's formation controller (module docstring)."""

    node = 'formation_controller'

    def __init__(self, params: dict[str, Any], log: Any = None) -> None:
        super().__init__(params, log)
        self.names: list[str] = list(params['formation_vehicles'])
        if len(self.names) != 2 or self.vehicle not in self.names:
            raise ControllerError(f'formation_controller: controls a pair of vehicles and belongs to one of them, '
                                  f'got vehicles {self.names} for vehicle {self.vehicle!r}')
        self.index = self.names.index(self.vehicle)
        f = self.section('formation')
        self.frame = f['frame']
        self.orbit = None
        n = 0.0
        if self.frame == 'hill':
            o = self.section('orbit')
            with scenario_key('orbit', ValueError):
                self.orbit = Orbit(OrbitConfig(kind=o['kind'], inclination_rad=o['inclination'], raan_rad=o['raan'],
                                               altitude_m=o['altitude'], arg_latitude0_rad=o['arg_latitude0']))
            n = self.orbit.mean_motion_rad_s
        if f['law'] == 'hold':
            law: HoldLaw | SpinUpLaw = HoldLaw(f['relative_position'], f['hold_natural_frequency'],
                                               f['hold_damping_ratio'])
        else:
            law = SpinUpLaw(f['spin_separation'], f['spin_rate'], f['spin_ramp'], f['spin_start'],
                            f['radial_natural_frequency'], f['radial_damping_ratio'], f['rate_gain_per_s'])
        with scenario_key('formation', ControllerError):
            self.core = FormationController(
                [controlled_vehicle(v, self.section('spacecraft', v), self.section('vehicle', v)) for v in self.names],
                self.frame, law, AttitudeLaw(f['attitude_natural_frequency'], f['attitude_damping_ratio']),
                self.control_period_s, f['max_force'], n,
                DumpLaw(f['dump_start'], f['dump_done']) if f['dump'] else None)

    def control(self, k: int, t_s: float, inp: dict[str, Any]) -> dict[str, Any]:
        """Stage ``control``: both vehicles' commands from both vehicles' measurements; this vehicle's part."""
        frame_to_inertial = None if self.orbit is None else hill_frame(self.orbit, t_s)[0]
        measurements = measurements_of(self.names, inp, self.control_period_s, frame_to_inertial)
        command = self.core.step(t_s, measurements, frame_to_inertial)[self.index]
        return command_outputs(k, command, self.instance)


def measurements_of(names: list[str], inp: dict[str, Any], dt_s: float,
                    frame_to_inertial: np.ndarray | None = None) -> list[Measurement]:
    """Every vehicle's measurement from the stage inputs: truth of step k, wheel momentum h_{k−1} + ḣ_{k−1}·Δt."""
    measurements = []
    for v in names:
        odom = inp[f'{v}/odometry']
        rot = quat_to_dcm(odom.orientation)
        b = inp[f'{v}/b_body']
        b_inertial = None if frame_to_inertial is None or b is None else rot @ np.array(b[0])
        measurements.append(Measurement(
            np.array(odom.position), np.array(odom.velocity), rot, vec(inp[f'{v}/gyro'][0]),
            vec(inp[f'{v}/wheel_h']) + vec(inp[f'{v}/wheel_hdot']) * dt_s, b_inertial))
    return measurements


def command_outputs(k: int, command: VehicleCommand, source: str) -> dict[str, Any]:
    """This vehicle's outputs: moment and wheel-torque commands, telemetry every ``TELEMETRY_EVERY`` steps."""
    out: dict[str, Any] = {'moment': vector3(command.dipole_body_am2),
                           'wheel_torque': vector3(command.wheel_torque_body_nm)}
    if k % TELEMETRY_EVERY == 0:
        values: dict[str, object] = {'dumping': str(command.dumping).lower()}
        for name, vector in (('force_command_n', command.force_command_n),
                             ('dipole_frame_am2', command.dipole_frame_am2)):
            values.update({f'{name}_{a}': f'{c:.6g}' for a, c in zip('xyz', vector, strict=True)})
        out['diagnostics'] = diagnostic(source, values)
    return out


class ArrayMemberStep(Stepper):
    """Base of the N-vehicle laws' steppers (``array_spin``, ``lqr``): this vehicle's place among the formation's
    vehicles; :meth:`control` runs the subclass's ``core`` (set in its ``__init__``) on every vehicle's
    measurements and publishes this vehicle's part."""

    node = 'formation_controller'

    def __init__(self, params: dict[str, Any], log: Any = None) -> None:
        super().__init__(params, log)
        self.names: list[str] = list(params['formation_vehicles'])
        if self.vehicle not in self.names:
            raise ControllerError(f'formation_controller: belongs to one of the vehicles {self.names}, got '
                                  f'{self.vehicle!r}')
        self.index = self.names.index(self.vehicle)
        self.core: Any = None

    def control(self, k: int, t_s: float, inp: dict[str, Any]) -> dict[str, Any]:
        """Stage ``control``: every vehicle's command from every vehicle's measurements; this vehicle's part."""
        commands = self.core.step(t_s, measurements_of(self.names, inp, self.control_period_s))
        return command_outputs(k, commands[self.index], self.instance)
