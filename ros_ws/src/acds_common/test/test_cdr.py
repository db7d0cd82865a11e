"""The graph's CDR codec: byte-identical to rosbags' serializer, round trips through rclpy, exact values."""

from __future__ import annotations

import math

import pytest
from acds_common.cdr import CdrError, Codec, OdometryValue, Status, stamp_ns
from hypothesis import given
from hypothesis import strategies as st
from rosbags.typesys import Stores, get_typestore

TS = get_typestore(Stores.ROS2_JAZZY)
finite = st.floats(allow_nan=False, allow_infinity=False)
vec3 = st.tuples(finite, finite, finite)
cov9 = st.tuples(*[finite] * 9)
text = st.text(max_size=12)
stamps = st.integers(min_value=0, max_value=2**31 * 10**9 - 1)
frames = st.sampled_from(['', 'b', 'body', 'eci', 'sun_frame', 'magnetometer_a'])


def _rosbags_bytes(msg_type: str, t_ns: int, value, frame: str, child: str = '') -> bytes:
    """The same message built and serialized with rosbags (zero padding, like ours)."""
    m = TS.types
    Time, Header = m['builtin_interfaces/msg/Time'], m['std_msgs/msg/Header']
    V3, Q = m['geometry_msgs/msg/Vector3'], m['geometry_msgs/msg/Quaternion']
    import numpy as np
    header = Header(stamp=Time(sec=t_ns // 10**9, nanosec=t_ns % 10**9), frame_id=frame)
    if msg_type == 'geometry_msgs/msg/Vector3Stamped':
        msg = m[msg_type](header=header, vector=V3(*value))
    elif msg_type == 'geometry_msgs/msg/WrenchStamped':
        W = m['geometry_msgs/msg/Wrench']
        msg = m[msg_type](header=header, wrench=W(force=V3(*value[0]), torque=V3(*value[1])))
    elif msg_type == 'sensor_msgs/msg/MagneticField':
        msg = m[msg_type](header=header, magnetic_field=V3(*value[0]), magnetic_field_covariance=np.array(value[1]))
    elif msg_type == 'sensor_msgs/msg/Imu':
        nope = np.array([-1.0] + [0.0] * 8)
        msg = m[msg_type](header=header, orientation=Q(0.0, 0.0, 0.0, 1.0), orientation_covariance=nope,
                          angular_velocity=V3(*value[0]), angular_velocity_covariance=np.array(value[1]),
                          linear_acceleration=V3(0.0, 0.0, 0.0), linear_acceleration_covariance=nope)
    elif msg_type == 'nav_msgs/msg/Odometry':
        P, T = m['geometry_msgs/msg/Pose'], m['geometry_msgs/msg/Twist']
        PC, TC, Pt = m['geometry_msgs/msg/PoseWithCovariance'], m['geometry_msgs/msg/TwistWithCovariance'], \
            m['geometry_msgs/msg/Point']
        msg = m[msg_type](header=header, child_frame_id=child,
                          pose=PC(P(Pt(*value.position), Q(*value.orientation)), np.zeros(36)),
                          twist=TC(T(V3(*value.velocity), V3(*value.angular)), np.zeros(36)))
    elif msg_type == 'diagnostic_msgs/msg/DiagnosticArray':
        DS, KV = m['diagnostic_msgs/msg/DiagnosticStatus'], m['diagnostic_msgs/msg/KeyValue']
        msg = m[msg_type](header=header, status=[
            DS(level=s.level, name=s.name, message=s.message, hardware_id=s.hardware_id,
               values=[KV(key=k, value=v) for k, v in s.values]) for s in value])
    elif msg_type == 'rosgraph_msgs/msg/Clock':
        msg = m[msg_type](clock=Time(sec=t_ns // 10**9, nanosec=t_ns % 10**9))
    else:
        msg = m[msg_type](data=value)
    return bytes(TS.serialize_cdr(msg, msg_type))


statuses = st.tuples(*[st.builds(Status, st.integers(0, 3), text, text, text,
                                 st.lists(st.tuples(text, text), max_size=3).map(tuple))] * 2)
CASES = [
    ('geometry_msgs/msg/Vector3Stamped', vec3),
    ('geometry_msgs/msg/WrenchStamped', st.tuples(vec3, vec3)),
    ('sensor_msgs/msg/MagneticField', st.tuples(vec3, cov9)),
    ('sensor_msgs/msg/Imu', st.tuples(vec3, cov9)),
    ('nav_msgs/msg/Odometry', st.builds(OdometryValue, vec3, st.tuples(finite, finite, finite, finite), vec3, vec3)),
    ('diagnostic_msgs/msg/DiagnosticArray', statuses),
]


@pytest.mark.parametrize('msg_type,values', CASES, ids=[c[0] for c in CASES])
@given(data=st.data(), t_ns=stamps, frame=frames, child=frames)
def test_encode_equals_rosbags_and_decodes_exactly(msg_type, values, data, t_ns, frame, child):
    value = data.draw(values)
    codec = Codec(msg_type, frame, child)
    raw = codec.encode(t_ns, value)
    ref = _rosbags_bytes(msg_type, t_ns, value, frame, child)
    assert raw == ref + bytes(-len(ref) % 4)  # rosbags' bytes, zero-padded to 4 as DDS sends them
    t_back, back = codec.decode(raw)
    assert t_back == t_ns and stamp_ns(raw) == t_ns
    assert back == value  # exact: CDR carries the doubles bit for bit


@pytest.mark.parametrize('msg_type,values', CASES[:-1], ids=[c[0] for c in CASES[:-1]])
@given(data=st.data(), t_ns=stamps, frame=frames, child=frames, other=frames)
def test_a_subscribers_codec_takes_its_publishers_frames_from_the_first_message(msg_type, values, data, t_ns, frame,
                                                                               child, other):
    sent = [(Codec(msg_type, f, c), data.draw(values)) for f, c in ((frame, child), (frame, child), (other, frame))]
    reader = Codec(msg_type)  # a subscriber's: it does not know its publisher's frame names
    for codec, value in sent:
        assert reader.decode(codec.encode(t_ns, value)) == (t_ns, value)
    first = (frame, child if msg_type == 'nav_msgs/msg/Odometry' else '')
    assert reader.read_frames == first  # kept after a message with other frames


@given(t_ns=stamps, words=text)
def test_clock_and_string(t_ns, words):
    clock = Codec('rosgraph_msgs/msg/Clock')
    assert clock.encode(t_ns) == _rosbags_bytes('rosgraph_msgs/msg/Clock', t_ns, None, '')
    assert clock.decode(clock.encode(t_ns))[0] == t_ns
    s = Codec('std_msgs/msg/String')
    ref = _rosbags_bytes('std_msgs/msg/String', 0, words, '')
    assert s.encode(0, words) == ref + bytes(-len(ref) % 4)
    assert s.decode(s.encode(0, words))[1] == words


def test_rclpy_reads_what_we_write_and_we_read_rclpy():
    """rclpy's own (de)serializer agrees with the codec (its padding bytes are not zeroed, so compare values)."""
    from geometry_msgs.msg import Vector3Stamped
    from nav_msgs.msg import Odometry
    from rclpy.serialization import deserialize_message, serialize_message

    v = Codec('geometry_msgs/msg/Vector3Stamped', 'body')
    msg = deserialize_message(v.encode(1_500_000_000, (1.0, -2.5, math.pi)), Vector3Stamped)
    assert (msg.header.stamp.sec, msg.header.stamp.nanosec, msg.header.frame_id) == (1, 500_000_000, 'body')
    assert (msg.vector.x, msg.vector.y, msg.vector.z) == (1.0, -2.5, math.pi)
    odom = Odometry()
    odom.header.frame_id, odom.child_frame_id = 'eci', 'body'
    odom.pose.pose.position.x, odom.twist.twist.angular.z = 7e6, -0.017
    odom.pose.pose.orientation.w = 1.0
    value = Codec('nav_msgs/msg/Odometry', 'eci', 'body').decode(serialize_message(odom))[1]
    assert value == OdometryValue((7e6, 0.0, 0.0), (0.0, 0.0, 0.0, 1.0), (0.0, 0.0, 0.0), (0.0, 0.0, -0.017))


def test_unknown_type_is_refused_by_name():
    with pytest.raises(CdrError, match='sensor_msgs/msg/Range'):
        Codec('sensor_msgs/msg/Range')
