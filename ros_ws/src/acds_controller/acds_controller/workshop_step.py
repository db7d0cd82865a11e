"""acds_controller stepper, AAP Workshop variant: the Workshop's computer with its CMGs (seed 000; ``wheels.kind`` cmg).

Stage ``control`` of step k takes the same inputs as the HEAO DPA's
(:mod:`acds_controller.controller_step`; the wheel inputs are the CMG momentum and rate, lag 1)
and runs :mod:`acds_controller.workshop`: modes ``cmg_dump`` / ``cmg_hold`` / ``standby``
(``cmg_dump`` when no mode manager is in the graph), and every step ``moment`` (A·m², the dump law's
command to the coils), ``cmg_torque`` (N·m, the momentum rate the attitude hold asks of the CMGs) and
``sampled_momentum`` (N·m·s, the H_s the dump law used); no wheel volts. The sun sensor tells it
orbital day (a zero vector in the Earth's shadow) for day-only dumping (seed 000 §10). Workshop telemetry
(H_s, its initialisation offset, attitude error, the predicted per-orbit loop gains) on
``diagnostics`` every ``controller.telemetry_every`` steps. A non-finite input commands zero
moment and zero CMG torque for the step (H_s held), with a diagnostic.
"""

from __future__ import annotations

from typing import Any

import numpy as np
from acds_common.messages import diagnostic, vec, vector3, xyz
from acds_common.mode_report import mode_status
from acds_common.modes import WORKSHOP_MODES
from acds_common.stepper import Stepper

from acds_controller.configuration import build_workshop
from acds_controller.controller_step import MID_SCALE_V, ZERO, check_finite, resolve_mode, store_momentum, warned
from acds_controller.magnetic_laws import ControllerError


class WorkshopComputerStep(Stepper):
    """The AAP Workshop's computer: sampled momentum H_s, the magnetic dump law, the CMG attitude hold."""

    node = 'acds_controller'

    def __init__(self, params: dict[str, Any], log: Any = None) -> None:
        super().__init__(params, log)
        c = self.section('controller')
        self.telemetry_period = c['telemetry_every']
        self.ta, self.workshop = build_workshop(self.section('spacecraft'), c, self.section('orbit'),
                                                self.section('earth'))
        self._h_s = ZERO

    def control(self, k: int, t_s: float, inp: dict[str, Any]) -> dict[str, Any]:
        """Stage ``control``: one control period of the Workshop computer (seed 000): H_s, the dump law, the CMG hold."""
        warnings: list[tuple[str, dict[str, str]]] = []
        mode, commands = mode_status(inp['mode'], self.node)
        for text in commands:
            warnings.append((f'command refused: {text!r}: the Workshop computer takes no forwarded commands',
                             {'command': text}))
        mode = resolve_mode(mode, 'cmg_dump', WORKSHOP_MODES, warnings,
                             '{!r} is not a Workshop mode (' + ', '.join(WORKSHOP_MODES) + ')')
        try:
            volts, bias = vec(inp['mag_volts'], MID_SCALE_V), vec(inp['mag_bias'], MID_SCALE_V)
            omega, h = vec(None if inp['gyro'] is None else inp['gyro'][0]), np.array(store_momentum(inp, self.control_period_s))
            check_finite((('magnetometer volts', volts), ('bias volts', bias), ('gyro', omega),
                           ('CMG momentum', h)))
            if inp['odometry'] is None:
                raise ControllerError('the CMG attitude hold needs the attitude reference truth/odometry')
            out = self.workshop.step(t_s, mode, self.ta.sense(volts, bias), omega, np.array(inp['odometry'].orientation),
                                     h, day=any(x != 0.0 for x in xyz(inp['sun'])))
            self._h_s = vector3(out.h_s_nms)
            result: dict[str, Any] = {'moment': vector3(out.moment_am2), 'cmg_torque': vector3(out.cmg_rate_nm),
                                      'sampled_momentum': self._h_s}
            if k % self.telemetry_period == 0:
                result['diagnostics'] = diagnostic(self.instance, out.telemetry)
        except ControllerError as exc:
            warnings.append((f'input rejected, zero commands this step: {exc}', {}))
            result = {'moment': ZERO, 'cmg_torque': ZERO, 'sampled_momentum': self._h_s}
        return warned(self, k, result, warnings)

