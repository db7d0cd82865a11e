"""formation_controller steppers, laws ``airtrack_open_loop`` and ``airtrack_lqr``: the 1-D airtrack's
electromagnet (spec §10; seed 004 slides 52–55; :mod:`acds_controller.airtrack_control`).

The controller belongs to the electromagnet's vehicle (fixed to the track, frame ``line``); the other
vehicle is the slider with its permanent magnet. The ideal displacement sensor is the formation's truth:
x = x_slider − x_magnet and ẋ from both vehicles' ``truth/odometry`` of step k. The design model is the
track the scenario builds: the slider's ``vehicle.mass``, its ``vehicle.permanent_dipole`` along the track
(body → frame by its initial attitude, which the track holds) and ``formation.track_tilt``; the set point
``formation.airtrack_separation``. Each law is its own stepper: the electromagnet's dipole command along +x
(to its body axes by its attitude) on ``controller/moment_command``, zero wheel torque (it has no wheels),
and the separation and dipole on ``diagnostics`` every ``TELEMETRY_EVERY`` steps.
"""

from __future__ import annotations

from typing import Any

import numpy as np
from acds_common.airtrack import AirtrackPlant
from acds_common.attitude import quat_to_dcm
from acds_common.messages import diagnostic, vector3
from acds_common.stepper import Stepper
from acds_common.validation import scenario_key

from acds_controller.airtrack_control import AirtrackLqr, AirtrackOpenLoop, BrysonScales
from acds_controller.formation_controller_step import TELEMETRY_EVERY
from acds_controller.magnetic_laws import ControllerError


def airtrack_plant(formation: dict[str, Any], slider_vehicle: dict[str, Any], slider_spacecraft: dict[str, Any]
                   ) -> AirtrackPlant:
    """The track a scenario builds (module docstring); ValueError naming ``formation`` if it holds nothing."""
    magnet = quat_to_dcm(slider_spacecraft['initial_quaternion_xyzw']) @ np.array(slider_vehicle['permanent_dipole'])
    with scenario_key('formation', ValueError):
        return AirtrackPlant(slider_vehicle['mass'], float(magnet[0]), formation['track_tilt'])


def bryson_scales(formation: dict[str, Any]) -> BrysonScales:
    """The ``formation.airtrack_*_scale`` keys."""
    with scenario_key('formation', ControllerError):
        return BrysonScales(*(formation[f'airtrack_{k}_scale'] for k in ('position', 'velocity', 'dipole')))


class AirtrackStep(Stepper):
    """Base of the airtrack laws' steppers: the track, the measurement and the outputs; the subclass sets
    ``core`` (an object with ``dipole_am2(x_m, v_m_s)``)."""

    node = 'formation_controller'

    def __init__(self, params: dict[str, Any], log: Any = None) -> None:
        super().__init__(params, log)
        names = list(params['formation_vehicles'])
        if len(names) != 2 or self.vehicle not in names:
            raise ControllerError(f'formation_controller: the airtrack has the electromagnet and the slider and the '
                                  f'controller belongs to the electromagnet, got vehicles {names} for {self.vehicle!r}')
        self.slider = names[1 - names.index(self.vehicle)]
        self.formation = self.section('formation')
        self.plant = airtrack_plant(self.formation, self.section('vehicle', self.slider),
                                    self.section('spacecraft', self.slider))
        self.core: Any = None

    def control(self, k: int, _t_s: float, inp: dict[str, Any]) -> dict[str, Any]:
        """Stage ``control``: the electromagnet's dipole from the measured separation and its rate."""
        magnet, slider = inp[f'{self.vehicle}/odometry'], inp[f'{self.slider}/odometry']
        x = slider.position[0] - magnet.position[0]
        dipole = self.core.dipole_am2(x, slider.velocity[0] - magnet.velocity[0])
        out: dict[str, Any] = {'moment': vector3(quat_to_dcm(magnet.orientation).T @ np.array([dipole, 0.0, 0.0])),
                               'wheel_torque': (0.0, 0.0, 0.0)}
        if k % TELEMETRY_EVERY == 0:
            out['diagnostics'] = diagnostic(self.instance, {'separation_m': f'{x:.6g}',
                                                                             'dipole_am2': f'{dipole:.6g}'})
        return out


class AirtrackOpenLoopStep(AirtrackStep):
    """Law ``airtrack_open_loop``: the constant dipole holding the slider at ``airtrack_separation``."""

    def __init__(self, params: dict[str, Any], log: Any = None) -> None:
        super().__init__(params, log)
        self.core = AirtrackOpenLoop(self.plant, self.formation['airtrack_separation'])


class AirtrackLqrStep(AirtrackStep):
    """Law ``airtrack_lqr``: that dipole plus the LQR feedback (``airtrack_*_scale`` weights)."""

    def __init__(self, params: dict[str, Any], log: Any = None) -> None:
        super().__init__(params, log)
        self.core = AirtrackLqr(self.plant, self.formation['airtrack_separation'], bryson_scales(self.formation))
