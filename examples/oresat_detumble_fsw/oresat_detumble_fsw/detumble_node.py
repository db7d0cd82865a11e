"""The OreSat detumble flight software as a ROS 2 node: plain rclpy, standard messages, no import of the emulator.

It implements the contract of ``acds_controller`` in the emulator's ``oresat_detumble`` scenario
(``./scripts/acds contract oresat_detumble --node acds_controller``):

* inputs (reliable, transient local, keep last 1000): ``/acds/magnetometer/volts`` and
  ``/acds/magnetometer/bias_volts`` (geometry_msgs/Vector3Stamped, V) and ``/acds/sensors/gyro``
  (sensor_msgs/Imu, angular_velocity in rad/s), each once per step, stamped with the step time;
* output: ``/acds/controller/moment_command`` (geometry_msgs/Vector3Stamped, A·m², frame base_link), one per
  step, stamped with the step time of the inputs it answers, once it holds all three of that step.

Parameters (names as in the contract's parameters file): ``controller_detumble_orbit_period_s``,
``controller_magnetic_inclination_rad``, ``controller_detumble_j_min_kg_m2``, ``controller_max_moment_am2``,
``controller_adc_bits``. Run it with ``ros2 run oresat_detumble_fsw oresat_detumble_fsw`` on the run's
ROS_DOMAIN_ID, beside ``acds run oresat_detumble --external acds_controller=oresat_detumble_fsw``.
"""

from __future__ import annotations

import rclpy
from geometry_msgs.msg import Vector3Stamped
from rcl_interfaces.msg import FloatingPointRange, IntegerRange, ParameterDescriptor
from rclpy.executors import ExternalShutdownException
from rclpy.experimental import EventsExecutor
from rclpy.node import Node
from rclpy.qos import DurabilityPolicy, HistoryPolicy, QoSProfile, ReliabilityPolicy
from sensor_msgs.msg import Imu

from oresat_detumble_fsw.law import Magnetometer, detumble_gain, detumble_moment

#: The contract's QoS: every step is delivered, to a reader that joins late as well.
LOCKSTEP = QoSProfile(reliability=ReliabilityPolicy.RELIABLE, durability=DurabilityPolicy.TRANSIENT_LOCAL,
                      history=HistoryPolicy.KEEP_LAST, depth=1000)
INPUTS = ('volts', 'bias', 'gyro')


def _float(lo: float, hi: float, text: str) -> ParameterDescriptor:
    return ParameterDescriptor(description=text, read_only=True,
                               floating_point_range=[FloatingPointRange(from_value=lo, to_value=hi)])


class DetumbleNode(Node):
    """Collects each step's field and rates, answers with that step's dipole command."""

    def __init__(self) -> None:
        super().__init__('oresat_detumble_fsw')
        p = {
            'orbit': self.declare_parameter('controller_detumble_orbit_period_s', 5560.8,
                                            _float(1e3, 1e6, 'T_orb, s (seed 003: the ISS orbit)')).value,
            'xi': self.declare_parameter('controller_magnetic_inclination_rad', 0.90129,
                                         _float(0.0, 1.5707963267948966, 'ξ, rad (seed 003: 51.64°)')).value,
            'j_min': self.declare_parameter('controller_detumble_j_min_kg_m2', 5094047.43e-9,
                                            _float(1e-6, 1e9, 'J_min, kg·m² (seed 003: 5,094,047.43 g·mm²)')).value,
            'max_m': self.declare_parameter('controller_max_moment_am2', 0.1552,
                                            _float(0.0, 1e4, "the rods' moment, A·m²")).value,
            'bits': self.declare_parameter('controller_adc_bits', 10, ParameterDescriptor(
                description='magnetometer ADC width, bits', read_only=True,
                integer_range=[IntegerRange(from_value=8, to_value=24, step=1)])).value,
        }
        self.k_omega = detumble_gain(p['orbit'], p['xi'], p['j_min'])
        self.max_moment = p['max_m']
        self.magnetometer = Magnetometer(p['bits'])
        self.pending: dict[tuple[int, int], dict[str, tuple[float, float, float]]] = {}
        self.pub = self.create_publisher(Vector3Stamped, '/acds/controller/moment_command', LOCKSTEP)
        self.create_subscription(Vector3Stamped, '/acds/magnetometer/volts', lambda m: self.take('volts', m), LOCKSTEP)
        self.create_subscription(Vector3Stamped, '/acds/magnetometer/bias_volts', lambda m: self.take('bias', m),
                                 LOCKSTEP)
        self.create_subscription(Imu, '/acds/sensors/gyro', lambda m: self.take('gyro', m), LOCKSTEP)
        self.get_logger().info(f'detumble gain k_omega = {self.k_omega:.6e} kg m^2/s, rods {self.max_moment} A m^2')

    def take(self, key: str, msg: Vector3Stamped | Imu) -> None:
        """One input of a step; when the step has all three, its command goes out with the same stamp."""
        v = msg.angular_velocity if key == 'gyro' else msg.vector
        stamp = (msg.header.stamp.sec, msg.header.stamp.nanosec)
        step = self.pending.setdefault(stamp, {})
        step[key] = (v.x, v.y, v.z)
        if len(step) < len(INPUTS):
            return
        del self.pending[stamp]
        b = self.magnetometer.field_t(step['volts'], step['bias'])
        m = detumble_moment(b, step['gyro'], self.k_omega, self.max_moment)
        out = Vector3Stamped()
        out.header.stamp = msg.header.stamp
        out.header.frame_id = 'base_link'
        out.vector.x, out.vector.y, out.vector.z = m
        self.pub.publish(out)


def main() -> None:
    rclpy.init()
    node = DetumbleNode()
    executor = EventsExecutor()
    executor.add_node(node)
    try:
        while rclpy.ok():
            executor.spin_once(timeout_sec=0.1)
    except (KeyboardInterrupt, ExternalShutdownException):
        pass
    finally:
        executor.shutdown()
        node.destroy_node()
        rclpy.try_shutdown()


if __name__ == '__main__':
    main()
