"""acds_controller node: transfer assembly + DPA, one control period per lockstep step (spec §7).

Step k inputs: magnetometer volts and bias volts (k), gyro rates (k), sun sensor (k),
the ``mode`` of the mode manager (k, with any forwarded ``command/acds_controller``
law/gain commands, applied before the step is computed), the attitude reference
``truth/odometry`` (k; the ideal attitude of the cruise modes), and the wheel momentum
and rate of step k−1 (lag 1, so h(t_k) = h_{k−1} + ḣ_{k−1}·Δt exactly) and the coil
current of step k−1 (lag 1, TA telemetry only).

Step k outputs: ``controller/moment_command`` (A·m²) and ``controller/wheel_volts`` (V),
every step; DPA + TA telemetry on ``diagnostics`` every ``controller.telemetry_every``
steps and at once when something is wrong (a refused command, a non-finite input).

Absent sources: no magnetometer → zero sensed field (the magnetic laws command
nothing); no mode manager → ``mode_1a`` (magnetics-only rate reduction); no wheels →
zero wheel momentum. A non-finite input message is rejected with a diagnostic and the
step commands zero moment and zero wheel volts.
"""

from __future__ import annotations

from typing import Any

import numpy as np
from acds_common import topics
from acds_common.lockstep import Input, LockstepNode, run_node
from acds_common.messages import diagnostic, mode_status, vec, vector3_stamped
from diagnostic_msgs.msg import DiagnosticArray, DiagnosticStatus
from geometry_msgs.msg import Vector3Stamped
from nav_msgs.msg import Odometry
from sensor_msgs.msg import Imu

from acds_controller.configuration import build_dpa
from acds_controller.dpa import MODES, Dpa
from acds_controller.magnetic_laws import ControllerError

#: Excess-coil-current alarm: |I| above this multiple of the current of the maximum moment.
EXCESS_CURRENT_FACTOR = 1.1
#: Name of the mode manager's status and the key of commands forwarded to this node.


def apply_command(dpa: Dpa, text: str) -> str:
    """Apply a forwarded 'law <slot> <name>' or 'gain <name> <value>'; return what was done.

    Raises :class:`ControllerError` for anything else (the node turns it into a diagnostic).
    """
    words = text.split()
    if len(words) == 3 and words[0].lower() == 'law':
        dpa.set_law(words[1].lower(), words[2].lower())
        return f'law {words[1]} set to {words[2]}'
    if len(words) == 3 and words[0].lower() == 'gain':
        try:
            value = float(words[2])
        except ValueError as exc:
            raise ControllerError(f'gain value {words[2]!r} is not a number') from exc
        dpa.set_gain(words[1].lower(), value)
        return f'gain {words[1]} set to {value:g}'
    raise ControllerError(f'command {text!r} is not "law <slot> <name>" or "gain <name> <value>"')


class ControllerNode(LockstepNode):
    """Transfer assembly and digital processor of the HEAO ACDS."""

    def __init__(self) -> None:
        super().__init__('acds_controller')
        sc = self.section_params('spacecraft')
        c = self.section_params('controller')
        mag = self.section_params('magnetometer')
        self.section_params('wheels')  # declared: the launcher passes the section (capacities stay in the wheels)
        self.telemetry_period = c['telemetry_every']
        try:
            self.ta, self.dpa = build_dpa(sc, c, mag)
        except ControllerError as exc:
            raise ValueError(f'acds_controller: {exc}') from None
        self.excess_current_a = EXCESS_CURRENT_FACTOR * c['max_moment_am2'] / self.ta.moment_per_amp_am2_per_a
        self.add_output('moment', Vector3Stamped, topics.MOMENT_COMMAND)
        self.add_output('volts', Vector3Stamped, topics.WHEEL_VOLTS)
        self.add_output('diagnostics', DiagnosticArray, topics.DIAGNOSTICS)
        self.add_stage('dpa', [
            Input('mag_volts', topics.MAG_VOLTS, Vector3Stamped, 'magnetometer_sim'),
            Input('mag_bias', topics.MAG_BIAS_VOLTS, Vector3Stamped, 'magnetometer_sim'),
            Input('gyro', topics.GYRO, Imu, 'rigid_body'),
            Input('sun', topics.SUN_SENSOR, Vector3Stamped, 'rigid_body'),
            Input('odometry', topics.TRUTH_ODOMETRY, Odometry, 'rigid_body'),
            Input('mode', topics.MODE, DiagnosticArray, 'ascs_mode_manager'),
            Input('wheel_h', topics.WHEEL_MOMENTUM, Vector3Stamped, 'reaction_wheels', lag=1),
            Input('wheel_hdot', topics.WHEEL_TORQUE, Vector3Stamped, 'reaction_wheels', lag=1),
            Input('coil_current', topics.COIL_CURRENT, Vector3Stamped, 'em_driver', lag=1),
        ], self.step)

    def _warn(self, k: int, message: str, values: dict[str, str] | None = None) -> None:
        self.get_logger().warning(f'step {k}: {message}')
        self.publish('diagnostics', diagnostic(self.get_name(), values or {}, message,
                                               DiagnosticStatus.WARN), k)

    def step(self, k: int, _t: float, inp: dict[str, Any]) -> None:
        """One DPA control period."""
        mode, commands = mode_status(inp['mode'], self.get_name())
        for text in commands:
            try:
                done = apply_command(self.dpa, text)
                self.get_logger().info(f'step {k}: {done}')
            except ControllerError as exc:
                self._warn(k, f'command refused: {text!r}: {exc}', {'command': text, 'reason': str(exc)})
        if mode is None:
            mode = 'mode_1a'
        elif mode not in MODES:
            self._warn(k, f'unknown mode {mode!r} from the mode manager: standby', {'mode': mode})
            mode = 'standby'
        try:
            volts = vec(inp['mag_volts'], (2.5, 2.5, 2.5))
            bias = vec(inp['mag_bias'], (2.5, 2.5, 2.5))
            gyro = inp['gyro']
            omega = np.zeros(3) if gyro is None else np.array(
                [gyro.angular_velocity.x, gyro.angular_velocity.y, gyro.angular_velocity.z])
            sun = vec(inp['sun'])
            dt = self.control_period_s
            h = vec(inp['wheel_h']) + vec(inp['wheel_hdot']) * dt
            q = None
            if inp['odometry'] is not None:
                o = inp['odometry'].pose.pose.orientation
                q = np.array([o.x, o.y, o.z, o.w])
            coil = vec(inp['coil_current'])
            for name, v in (('magnetometer volts', volts), ('bias volts', bias), ('gyro', omega),
                            ('sun sensor', sun), ('wheel momentum', h), ('coil current', coil)):
                if not np.all(np.isfinite(v)):
                    raise ControllerError(f'{name} input is not finite: {v.tolist()}')
            b = self.ta.sense(volts, bias)
            out = self.dpa.step(mode, b, omega, sun, h, q, dt)
            moment, wheel_volts = out.moment_command_am2, out.wheel_volts_v
        except ControllerError as exc:
            self._warn(k, f'input rejected, zero commands this step: {exc}')
            self.publish('moment', vector3_stamped(np.zeros(3)), k)
            self.publish('volts', vector3_stamped(np.zeros(3)), k)
            return
        self.publish('moment', vector3_stamped(moment), k)
        self.publish('volts', vector3_stamped(wheel_volts), k)
        if k % self.telemetry_period == 0:
            alarms = [bool(abs(i) > self.excess_current_a) for i in coil]
            telemetry = {**out.telemetry, **self.ta.telemetry(b, moment, bias, coil, alarms)}
            self.publish('diagnostics', diagnostic(self.get_name(), telemetry), k)


def main(args: list[str] | None = None) -> int:
    """Console-script entry point ``acds_controller``."""
    return run_node('acds_controller', ControllerNode, args)
