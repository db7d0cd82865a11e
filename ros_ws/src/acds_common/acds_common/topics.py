"""Topic names of the ACDS graph (spec §2), under the ``/acds`` namespace.

Every node runs in namespace ``/acds`` (a formation vehicle's nodes in ``/acds/<vehicle>``); names
here are relative so they resolve in the node's namespace, except the lockstep handshake topics,
which every node of a graph shares, and the two every ROS tool looks for at the root: ``/clock`` and
``/diagnostics`` (``diagnostic_aggregator``, ``rqt_robot_monitor``: one ``DiagnosticStatus`` per node,
named after it, level OK/WARN/ERROR, ``hardware_id`` the node). Frames: :mod:`acds_common.frames`.
Lockstep data topics carry a
``std_msgs/Header`` whose stamp is the sim time t_k = k·Δt of the step they
belong to. Units are SI unless the name says otherwise.
"""

NAMESPACE = '/acds'

CLOCK = '/clock'                                #: rosgraph_msgs/Clock, published by rigid_body
READY = '/acds/lockstep/ready'                  #: std_msgs/String, node instance when its inputs are matched

# dynamics/rigid_body truth (step k, state at t_k)
TRUTH_ODOMETRY = 'truth/odometry'               #: nav_msgs/Odometry: ECI position/velocity, q body→ECI, ω body (rad/s)
TRUTH_B_BODY = 'truth/b_body'                   #: sensor_msgs/MagneticField: Earth field at the spacecraft, body axes, T
TRUTH_SUN_COSINES = 'truth/sun_direction_cosines'  #: geometry_msgs/Vector3Stamped: (B13, B23, B33) vs the sun frame
TRUTH_TORQUE_MAG = 'truth/torque_magnetic'      #: geometry_msgs/Vector3Stamped: M × B_true over the step, N·m (body)
TRUTH_TORQUE_GG = 'truth/torque_gravity_gradient'  #: geometry_msgs/Vector3Stamped: N·m (body)
GYRO = 'sensors/gyro'                           #: sensor_msgs/Imu: ideal rate gyros (angular_velocity, rad/s, body; covariance 0)
TRUTH_WRENCH = 'truth/wrench'                   #: geometry_msgs/WrenchStamped: formation: external force + torque, body
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
WHEEL_TORQUE_COMMAND = 'controller/wheel_torque'  #: geometry_msgs/Vector3Stamped: wanted ḣ of torque-driven wheels, body, N·m
CMG_TORQUE = 'controller/cmg_torque'            #: geometry_msgs/Vector3Stamped: commanded CMG momentum rate ḣ, body, N·m
SAMPLED_MOMENTUM = 'controller/sampled_momentum'  #: geometry_msgs/Vector3Stamped: H_s the dump law uses (step k), body, N·m·s
GAS_ON_TIME = 'controller/gas_on_time'          #: geometry_msgs/Vector3Stamped: valve on-time per body axis, s (sign: torque)

# cold_gas (step k, over [t_k, t_k+1])
COLD_GAS_WRENCH = 'cold_gas/wrench'             #: geometry_msgs/WrenchStamped: thrust force N, torque N·m, step average, body
COLD_GAS_STATE = 'cold_gas/state'               #: diagnostic_msgs/DiagnosticArray: thrust times, gas, pressures, valves

# em_driver (step k)
DIPOLE_AVG = 'em_driver/dipole_avg'             #: geometry_msgs/Vector3Stamped: achieved dipole averaged over the step, A·m²
DIPOLE_END = 'em_driver/dipole_end'             #: geometry_msgs/Vector3Stamped: achieved dipole at t_k+1, A·m²
COIL_CURRENT = 'em_driver/coil_current'         #: geometry_msgs/Vector3Stamped: coil current at t_k+1 (signed), A
E_FT = 'em_driver/e_ft'                         #: geometry_msgs/Vector3Stamped: current-sensor telemetry voltage e_ft, V
# em_driver, torque-rod kind only (step k, over [t_k, t_k+1])
COIL_POWER = 'em_driver/power'                  #: geometry_msgs/Vector3Stamped: net bus power per axis, step average, W
COIL_DUTY = 'em_driver/duty'                    #: geometry_msgs/Vector3Stamped: |PWM duty| of the active winding per axis

# ascs_mode_manager
MODE = 'mode'                                   #: diagnostic_msgs/DiagnosticArray: current mode (step k), transition cause
GROUND_COMMAND = 'ground/command'               #: std_msgs/String: ground commands (not lockstep; applied at a step boundary)
GROUND_ACK = 'ground/ack'                       #: std_msgs/String: acknowledgements and refusals with reasons
EVENTS = 'events'                               #: std_msgs/String: mode transitions, automatic turn-on/off, with sim time

DIAGNOSTICS = '/diagnostics'                    #: diagnostic_msgs/DiagnosticArray: health and telemetry of every node
MONITOR_ACK = '/acds/lockstep/monitor_ack'      #: rosgraph_msgs/Clock: the run monitor has received /clock step k

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
    TRUTH_WRENCH: 'geometry_msgs/msg/WrenchStamped',
    SUN_SENSOR: 'geometry_msgs/msg/Vector3Stamped',
    WHEEL_MOMENTUM: 'geometry_msgs/msg/Vector3Stamped',
    WHEEL_TORQUE: 'geometry_msgs/msg/Vector3Stamped',
    MAG_FIELD: 'sensor_msgs/msg/MagneticField',
    MAG_VOLTS: 'geometry_msgs/msg/Vector3Stamped',
    MAG_BIAS_VOLTS: 'geometry_msgs/msg/Vector3Stamped',
    MOMENT_COMMAND: 'geometry_msgs/msg/Vector3Stamped',
    WHEEL_VOLTS: 'geometry_msgs/msg/Vector3Stamped',
    WHEEL_TORQUE_COMMAND: 'geometry_msgs/msg/Vector3Stamped',
    CMG_TORQUE: 'geometry_msgs/msg/Vector3Stamped',
    SAMPLED_MOMENTUM: 'geometry_msgs/msg/Vector3Stamped',
    GAS_ON_TIME: 'geometry_msgs/msg/Vector3Stamped',
    COLD_GAS_WRENCH: 'geometry_msgs/msg/WrenchStamped',
    COLD_GAS_STATE: 'diagnostic_msgs/msg/DiagnosticArray',
    DIPOLE_AVG: 'geometry_msgs/msg/Vector3Stamped',
    DIPOLE_END: 'geometry_msgs/msg/Vector3Stamped',
    COIL_CURRENT: 'geometry_msgs/msg/Vector3Stamped',
    E_FT: 'geometry_msgs/msg/Vector3Stamped',
    COIL_POWER: 'geometry_msgs/msg/Vector3Stamped',
    COIL_DUTY: 'geometry_msgs/msg/Vector3Stamped',
    MODE: 'diagnostic_msgs/msg/DiagnosticArray',
    GROUND_COMMAND: 'std_msgs/msg/String',
    GROUND_ACK: 'std_msgs/msg/String',
    EVENTS: 'std_msgs/msg/String',
    DIAGNOSTICS: 'diagnostic_msgs/msg/DiagnosticArray',
    MONITOR_ACK: 'rosgraph_msgs/msg/Clock',
}

def resolve(topic: str) -> str:
    """Absolute topic name (``/acds/...``, or ``/clock``)."""
    return topic if topic.startswith('/') else f'{NAMESPACE}/{topic}'


def relative(name: str) -> str:
    """The key of :data:`TYPES` for an absolute or relative topic name (inverse of :func:`resolve`)."""
    prefix = f'{NAMESPACE}/'
    return name[len(prefix):] if name.startswith(prefix) else name


def type_of(name: str) -> str:
    """Message type of a topic, absolute or relative, of the graph or of one vehicle of a formation.

    A formation's per-vehicle topics are the single-vehicle names under the vehicle's namespace
    (``/acds/<vehicle>/truth/odometry``, or relative to ``/acds``: ``<vehicle>/truth/odometry``).
    """
    if name in TYPES:  # an absolute name of its own (/clock, the lockstep handshake)
        return TYPES[name]
    key = relative(name)
    if key in TYPES:
        return TYPES[key]
    head, sep, rest = key.partition('/')
    if sep and rest in TYPES:
        return TYPES[rest]
    raise KeyError(f'topic {name!r} is not a topic of the ACDS graph')
