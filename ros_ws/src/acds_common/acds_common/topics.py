"""Topic names of the ACDS graph (spec §2), all under the ``/acds`` namespace.

Every node runs in namespace ``/acds``; names here are relative so they
resolve to ``/acds/<name>``, except ``/clock``. Lockstep data topics carry a
``std_msgs/Header`` whose stamp is the sim time t_k = k·Δt of the step they
belong to. Units are SI unless the name says otherwise.
"""

NAMESPACE = '/acds'

CLOCK = '/clock'                                #: rosgraph_msgs/Clock, published by rigid_body
READY = 'lockstep/ready'                        #: std_msgs/String, node name when its inputs are matched

# dynamics/rigid_body truth (step k, state at t_k)
TRUTH_ODOMETRY = 'truth/odometry'               #: nav_msgs/Odometry: ECI position/velocity, q body→ECI, ω body (rad/s)
TRUTH_B_BODY = 'truth/b_body'                   #: sensor_msgs/MagneticField: Earth field at the spacecraft, body axes, T
TRUTH_SUN_COSINES = 'truth/sun_direction_cosines'  #: geometry_msgs/Vector3Stamped: (B13, B23, B33) vs the sun frame
TRUTH_TORQUE_MAG = 'truth/torque_magnetic'      #: geometry_msgs/Vector3Stamped: M × B_true over the step, N·m (body)
TRUTH_TORQUE_GG = 'truth/torque_gravity_gradient'  #: geometry_msgs/Vector3Stamped: N·m (body)
GYRO = 'sensors/gyro'                           #: sensor_msgs/Imu: ideal rate gyros (angular_velocity, rad/s, body)
SUN_SENSOR = 'sensors/sun'                      #: geometry_msgs/Vector3Stamped: unit sun vector in body; zero vector = sun absent

# dynamics/reaction_wheels (step k)
WHEEL_MOMENTUM = 'wheels/momentum'              #: geometry_msgs/Vector3Stamped: total wheel momentum h(t_k), body, N·m·s
WHEEL_TORQUE = 'wheels/torque'                  #: geometry_msgs/Vector3Stamped: ḣ over [t_k, t_k+1], body, N·m

# magnetometer_sim (step k)
MAG_FIELD = 'magnetometer/field'                #: sensor_msgs/MagneticField: the field the volts mean, body, T
MAG_VOLTS = 'magnetometer/volts'                #: geometry_msgs/Vector3Stamped: per-axis output volts (0…5 V)
MAG_BIAS_VOLTS = 'magnetometer/bias_volts'      #: geometry_msgs/Vector3Stamped: per-axis bias reference volts (2.5 V nominal)

# acds_controller (step k)
MOMENT_COMMAND = 'controller/moment_command'    #: geometry_msgs/Vector3Stamped: commanded dipole, body, A·m²
WHEEL_VOLTS = 'controller/wheel_volts'          #: geometry_msgs/Vector3Stamped: wheel drive volts per body axis, V
CMG_TORQUE = 'controller/cmg_torque'            #: geometry_msgs/Vector3Stamped: commanded CMG momentum rate ḣ, body, N·m
SAMPLED_MOMENTUM = 'controller/sampled_momentum'  #: geometry_msgs/Vector3Stamped: H_s the dump law uses (step k), body, N·m·s

# em_driver (step k)
DIPOLE_AVG = 'em_driver/dipole_avg'             #: geometry_msgs/Vector3Stamped: achieved dipole averaged over the step, A·m²
DIPOLE_END = 'em_driver/dipole_end'             #: geometry_msgs/Vector3Stamped: achieved dipole at t_k+1, A·m²
COIL_CURRENT = 'em_driver/coil_current'         #: geometry_msgs/Vector3Stamped: coil current at t_k+1 (signed), A
E_FT = 'em_driver/e_ft'                         #: geometry_msgs/Vector3Stamped: current-sensor telemetry voltage e_ft, V

# ascs_mode_manager
MODE = 'mode'                                   #: diagnostic_msgs/DiagnosticArray: current mode (step k), transition cause
GROUND_COMMAND = 'ground/command'               #: std_msgs/String: ground commands (not lockstep; applied at a step boundary)
GROUND_ACK = 'ground/ack'                       #: std_msgs/String: acknowledgements and refusals with reasons
EVENTS = 'events'                               #: std_msgs/String: mode transitions, automatic turn-on/off, with sim time

DIAGNOSTICS = 'diagnostics'                     #: diagnostic_msgs/DiagnosticArray: health and telemetry of every node
MONITOR_ACK = 'lockstep/monitor_ack'            #: rosgraph_msgs/Clock: the run monitor has received /clock step k

#: Message type of every topic, as 'package/msg/Type' (used by the monitor, recorder and player).
TYPES: dict[str, str] = {
    CLOCK: 'rosgraph_msgs/msg/Clock',
    READY: 'std_msgs/msg/String',
    TRUTH_ODOMETRY: 'nav_msgs/msg/Odometry',
    TRUTH_B_BODY: 'sensor_msgs/msg/MagneticField',
    TRUTH_SUN_COSINES: 'geometry_msgs/msg/Vector3Stamped',
    TRUTH_TORQUE_MAG: 'geometry_msgs/msg/Vector3Stamped',
    TRUTH_TORQUE_GG: 'geometry_msgs/msg/Vector3Stamped',
    GYRO: 'sensor_msgs/msg/Imu',
    SUN_SENSOR: 'geometry_msgs/msg/Vector3Stamped',
    WHEEL_MOMENTUM: 'geometry_msgs/msg/Vector3Stamped',
    WHEEL_TORQUE: 'geometry_msgs/msg/Vector3Stamped',
    MAG_FIELD: 'sensor_msgs/msg/MagneticField',
    MAG_VOLTS: 'geometry_msgs/msg/Vector3Stamped',
    MAG_BIAS_VOLTS: 'geometry_msgs/msg/Vector3Stamped',
    MOMENT_COMMAND: 'geometry_msgs/msg/Vector3Stamped',
    WHEEL_VOLTS: 'geometry_msgs/msg/Vector3Stamped',
    CMG_TORQUE: 'geometry_msgs/msg/Vector3Stamped',
    SAMPLED_MOMENTUM: 'geometry_msgs/msg/Vector3Stamped',
    DIPOLE_AVG: 'geometry_msgs/msg/Vector3Stamped',
    DIPOLE_END: 'geometry_msgs/msg/Vector3Stamped',
    COIL_CURRENT: 'geometry_msgs/msg/Vector3Stamped',
    E_FT: 'geometry_msgs/msg/Vector3Stamped',
    MODE: 'diagnostic_msgs/msg/DiagnosticArray',
    GROUND_COMMAND: 'std_msgs/msg/String',
    GROUND_ACK: 'std_msgs/msg/String',
    EVENTS: 'std_msgs/msg/String',
    DIAGNOSTICS: 'diagnostic_msgs/msg/DiagnosticArray',
    MONITOR_ACK: 'rosgraph_msgs/msg/Clock',
}

#: Truth topics (hashed into the run's truth digest).
TRUTH = (TRUTH_ODOMETRY, TRUTH_B_BODY, TRUTH_SUN_COSINES, TRUTH_TORQUE_MAG, TRUTH_TORQUE_GG, GYRO, SUN_SENSOR)


def resolve(topic: str) -> str:
    """Absolute topic name (``/acds/...``, or ``/clock``)."""
    return topic if topic.startswith('/') else f'{NAMESPACE}/{topic}'


def relative(name: str) -> str:
    """The key of :data:`TYPES` for an absolute or relative topic name (inverse of :func:`resolve`)."""
    prefix = f'{NAMESPACE}/'
    return name[len(prefix):] if name.startswith(prefix) else name
