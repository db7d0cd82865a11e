"""Topic names of the ACDS graph (spec §2), under the ``/acds`` namespace: the names packages share.

The names below are the interface between the shipped packages (a consumer names the topic it reads
from another package's node). Each topic's message type, unit and meaning are declared by the
package that publishes it (:class:`acds_common.graph.Topic`); a new node's own topics are declared
in its package alone (docs: Architecture, "Adding a node"). The mechanism's own topics and their types are
:data:`TYPES`.

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
RUN_END = '/acds/lockstep/run_end'              #: rosgraph_msgs/Clock: the time owner's last step; no later step comes

#: Message type of the mechanism's own topics (lockstep handshake, ground commands, diagnostics); every
#: other topic's type is declared by the package that publishes it (:class:`acds_common.graph.Topic`).
TYPES: dict[str, str] = {
    CLOCK: 'rosgraph_msgs/msg/Clock',
    READY: 'std_msgs/msg/String',
    GROUND_COMMAND: 'std_msgs/msg/String',
    DIAGNOSTICS: 'diagnostic_msgs/msg/DiagnosticArray',
    MONITOR_ACK: 'rosgraph_msgs/msg/Clock',
    RUN_END: 'rosgraph_msgs/msg/Clock',
}


def resolve(topic: str) -> str:
    """Absolute topic name (``/acds/...``, or ``/clock``)."""
    return topic if topic.startswith('/') else f'{NAMESPACE}/{topic}'


def relative(name: str) -> str:
    """The relative name of an absolute or relative topic name (inverse of :func:`resolve`)."""
    prefix = f'{NAMESPACE}/'
    return name[len(prefix):] if name.startswith(prefix) else name


def type_of(name: str) -> str:
    """Message type of a topic, absolute or relative, of the graph or of one vehicle of a formation.

    A formation's per-vehicle topics are the single-vehicle names under the vehicle's namespace
    (``/acds/<vehicle>/truth/odometry``, or relative to ``/acds``: ``<vehicle>/truth/odometry``).
    """
    types = all_types()
    if name in types:  # an absolute name of its own (/clock, the lockstep handshake)
        return types[name]
    key = relative(name)
    if key in types:
        return types[key]
    head, sep, rest = key.partition('/')
    if sep and rest in types:
        return types[rest]
    raise KeyError(f'topic {name!r} is not a topic of the ACDS graph')


def all_types() -> dict[str, str]:
    """Message type of every topic: the mechanism's (:data:`TYPES`) and every package's declared ones."""
    from acds_common.graph import declared_topics  # the graph module imports this one
    return {**TYPES, **{name: t.type for name, t in declared_topics().items()}}
