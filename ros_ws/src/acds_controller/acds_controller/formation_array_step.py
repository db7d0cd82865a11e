"""formation_controller stepper, law ``array_spin``: one vehicle's controller of a spinning array of N
vehicles (spec §10; seed 004 slides 21–23, :mod:`acds_controller.formation_array`).

As ``formation_controller_step`` (every vehicle runs the same deterministic computation on every
vehicle's measurements and publishes its own part), for any number of vehicles: each vehicle's place
in the array is its ``vehicle.array_position``; the array spins about the frame z axis to
``formation.spin_rate`` at ``formation.spin_ramp`` from ``formation.spin_start``, each vehicle on
its place by a PD (``array_natural_frequency``, ``array_damping_ratio``); the dipoles are the
least-Σ|μ|² solution for the commanded forces.
"""

from __future__ import annotations

from typing import Any

import numpy as np
from acds_common.validation import scenario_key

from acds_controller.formation_array import ArrayController, ArraySpinLaw
from acds_controller.formation_control import AttitudeLaw
from acds_controller.formation_controller_step import ArrayMemberStep, controlled_vehicle
from acds_controller.magnetic_laws import ControllerError


class FormationArrayStep(ArrayMemberStep):
    """One vehicle's array controller (module docstring)."""

    def __init__(self, params: dict[str, Any], log: Any = None) -> None:
        super().__init__(params, log)
        f = self.section('formation')
        places = np.array([self.section('vehicle', v)['array_position'] for v in self.names], dtype=float)
        with scenario_key('formation', ControllerError):
            law = ArraySpinLaw(places, f['spin_rate'], f['spin_ramp'], f['spin_start'], f['array_natural_frequency'],
                               f['array_damping_ratio'])
            self.core = ArrayController(
                [controlled_vehicle(v, self.section('spacecraft', v), self.section('vehicle', v)) for v in self.names],
                f['frame'], law, AttitudeLaw(f['attitude_natural_frequency'], f['attitude_damping_ratio']),
                self.control_period_s, f['max_force'])
