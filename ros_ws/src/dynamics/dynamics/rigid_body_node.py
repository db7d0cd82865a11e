"""rigid_body node: the time owner; integrates the spacecraft and publishes the truth (spec §2, §3).

Step k: publish truth(t_k) and ``/clock``; wait for the actuator outputs of step k
(achieved dipole from em_driver, wheel momentum and torque from reaction_wheels;
absent nodes mean zero) and the step's ``mode``, then integrate t_k → t_k+1. The run
ends after step k when the total step count is reached or when the ``mode`` of step k
carries ``run_complete: true`` (e.g. stop at acquisition capture). A non-finite actuator
input fails the run naming the topic and the step.
"""

from __future__ import annotations

from typing import Any

import numpy as np
from acds_common import topics
from acds_common.lockstep import Input, LockstepNode, run_node
from acds_common.messages import magnetic_field, vec, vector3_stamped
from diagnostic_msgs.msg import DiagnosticArray
from geometry_msgs.msg import Vector3Stamped
from nav_msgs.msg import Odometry
from sensor_msgs.msg import Imu, MagneticField

from dynamics.configuration import build_rigid_body
from dynamics.rigid_body_model import Truth


def run_complete(mode: DiagnosticArray | None) -> bool:
    """Whether the step's ``mode`` message asks to end the run (key ``run_complete`` = 'true')."""
    return mode is not None and any(
        kv.key == 'run_complete' and kv.value == 'true' for status in mode.status for kv in status.values)


class RigidBodyNode(LockstepNode):
    """Spacecraft rigid body in its orbit and environment; owner of sim time."""

    def __init__(self) -> None:
        super().__init__('rigid_body')
        self.model = build_rigid_body(*(self.section_params(s) for s in ('spacecraft', 'orbit', 'earth', 'sun', 'dynamics')))
        for key, msg_type, topic in (
                ('odometry', Odometry, topics.TRUTH_ODOMETRY), ('b_body', MagneticField, topics.TRUTH_B_BODY),
                ('sun_cosines', Vector3Stamped, topics.TRUTH_SUN_COSINES),
                ('torque_mag', Vector3Stamped, topics.TRUTH_TORQUE_MAG),
                ('torque_gg', Vector3Stamped, topics.TRUTH_TORQUE_GG),
                ('gyro', Imu, topics.GYRO), ('sun_sensor', Vector3Stamped, topics.SUN_SENSOR)):
            self.add_output(key, msg_type, topic)
        self.add_stage('integrate', [
            Input('dipole', topics.DIPOLE_AVG, Vector3Stamped, 'em_driver'),
            Input('wheel_h', topics.WHEEL_MOMENTUM, Vector3Stamped, 'reaction_wheels'),
            Input('wheel_hdot', topics.WHEEL_TORQUE, Vector3Stamped, 'reaction_wheels'),
            Input('mode', topics.MODE, DiagnosticArray, 'ascs_mode_manager'),
        ], self.integrate)
        self._wheel_h = np.zeros(3)

    def on_start(self) -> None:
        """Publish the truth of step 0 and start the clock."""
        self.publish_truth(0, self.model.truth(self._wheel_h))
        self.publish_clock(0)

    def integrate(self, k: int, _t: float, inp: dict[str, Any]) -> None:
        """All actuator outputs of step k are in: integrate to t_k+1 and publish it."""
        if k >= self.total_steps or run_complete(inp['mode']):
            self.finish()
            return
        h, hdot, dipole = vec(inp['wheel_h']), vec(inp['wheel_hdot']), vec(inp['dipole'])
        for topic, value in ((topics.WHEEL_MOMENTUM, h), (topics.WHEEL_TORQUE, hdot), (topics.DIPOLE_AVG, dipole)):
            if not np.all(np.isfinite(value)):
                self.fail(f'non-finite {self.resolve_topic_name(topic)} at step {k}: {value.tolist()}; '
                          'the physics cannot go on')
                return
        self.model.advance(self.control_period_s, dipole, h, hdot)
        self._wheel_h = h + hdot * self.control_period_s
        self.publish_truth(k + 1, self.model.truth(self._wheel_h))
        self.publish_clock(k + 1)

    def publish_truth(self, k: int, truth: Truth) -> None:
        """Truth and ideal sensors of step k (spec §3 "Sensors in the study are ideal")."""
        odom = Odometry()
        odom.header.frame_id, odom.child_frame_id = 'eci', 'body'
        p, q = odom.pose.pose.position, odom.pose.pose.orientation
        p.x, p.y, p.z = (float(x) for x in truth.r_eci_m)
        q.x, q.y, q.z, q.w = (float(x) for x in truth.q_body_to_eci)
        lin, ang = odom.twist.twist.linear, odom.twist.twist.angular
        lin.x, lin.y, lin.z = (float(x) for x in truth.v_eci_m_s)
        ang.x, ang.y, ang.z = (float(x) for x in truth.omega_body_rad_s)
        self.publish('odometry', odom, k)
        self.publish('b_body', magnetic_field(truth.b_body_t), k)
        self.publish('sun_cosines', vector3_stamped(truth.sun_direction_cosines, 'sun_frame'), k)
        self.publish('torque_mag', vector3_stamped(truth.torque_magnetic_body_nm), k)
        self.publish('torque_gg', vector3_stamped(truth.torque_gravity_gradient_body_nm), k)
        imu = Imu()
        imu.header.frame_id = 'body'
        imu.orientation_covariance[0] = -1.0  # no orientation from rate gyros
        imu.linear_acceleration_covariance[0] = -1.0
        w = imu.angular_velocity
        w.x, w.y, w.z = (float(x) for x in truth.omega_body_rad_s)
        self.publish('gyro', imu, k)
        sun = truth.sun_body_unit if truth.sun_present else np.zeros(3)
        self.publish('sun_sensor', vector3_stamped(sun), k)


def main(args: list[str] | None = None) -> int:
    """Console-script entry point ``rigid_body``."""
    return run_node('rigid_body', RigidBodyNode, args)
