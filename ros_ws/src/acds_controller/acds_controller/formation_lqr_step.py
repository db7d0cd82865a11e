"""formation_controller stepper, law ``lqr``: one vehicle's LQR controller of a spinning array about its
steady spin (spec §10; seed 004 slides 40–45, :mod:`acds_controller.formation_lqr`).

Every vehicle designs the same gain at start (from the linearised array: its vehicles' masses,
inertias, coils and wheel axes, their ``vehicle.array_position`` places, ``formation.spin_rate`` and
the ``formation.lqr_*_weight`` weights), runs the same feedback on every vehicle's measurements and
publishes its own part.
"""

from __future__ import annotations

from typing import Any

import numpy as np
from acds_common.validation import scenario_key

from acds_controller.formation_controller_step import ArrayMemberStep, controlled_vehicle
from acds_controller.formation_lqr import WEIGHT_NAMES, LqrFormationController, LqrWeights
from acds_controller.magnetic_laws import ControllerError


def lqr_controller(formation: dict[str, Any], names: list[str], section: Any) -> LqrFormationController:
    """The LQR controller of a scenario's formation (``section(name, vehicle)`` gives a vehicle's section)."""
    places = np.array([section('vehicle', v)['array_position'] for v in names], dtype=float)
    wheel_axes = []
    for v in names:
        axes = section('wheels', v)['torque_axes']
        wheel_axes.append(np.array(axes, dtype=float).reshape(len(axes) // 3, 3).T)
    with scenario_key('formation', ControllerError):
        weights = LqrWeights(*(formation[f'lqr_{k}_weight'] for k in WEIGHT_NAMES))
        return LqrFormationController(
            [controlled_vehicle(v, section('spacecraft', v), section('vehicle', v)) for v in names], wheel_axes,
            places, formation['spin_rate'], weights)


class FormationLqrStep(ArrayMemberStep):
    """One vehicle's LQR formation controller (module docstring)."""

    def __init__(self, params: dict[str, Any], log: Any = None) -> None:
        super().__init__(params, log)
        self.core = lqr_controller(self.section('formation'), self.names, self.section)
