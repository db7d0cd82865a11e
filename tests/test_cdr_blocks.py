"""A block of fixed-layout messages encoded at once is the messages encoded one by one, byte for byte
(acds_common.cdr ``RowLayout``, ``Codec.encode_block``: what the direct engine's blocks of steps hash into the
truth digest, spec §2 "the same data bit for bit")."""

from __future__ import annotations

import math
import struct

import numpy as np
import pytest
from acds_common.cdr import CdrError, Codec, OdometryValue, Status
from hypothesis import given, settings
from hypothesis import strategies as st

#: Every fixed-layout type a time owner publishes per step in a shipped scenario (the truth topics), and the clock.
FIXED = ('geometry_msgs/msg/Vector3Stamped', 'geometry_msgs/msg/WrenchStamped', 'sensor_msgs/msg/MagneticField',
         'sensor_msgs/msg/Imu', 'nav_msgs/msg/Odometry', 'rosgraph_msgs/msg/Clock')
WIDTH = {'geometry_msgs/msg/Vector3Stamped': 3, 'geometry_msgs/msg/WrenchStamped': 6,
         'sensor_msgs/msg/MagneticField': 12, 'sensor_msgs/msg/Imu': 12, 'nav_msgs/msg/Odometry': 13,
         'rosgraph_msgs/msg/Clock': 0}
#: Stamps at the ends of a Time's range (sec is int32; floor division gives a negative time's sec and nanosec).
T_MIN, T_MAX = -2**31 * 10**9, (2**31 - 1) * 10**9 + 999_999_999
SPECIAL = (0.0, -0.0, math.inf, -math.inf, math.nan, 5e-324, -1.7976931348623157e308,
           struct.unpack('<d', struct.pack('<Q', 0x7ff8_dead_beef_0001))[0])  # a NaN with a payload
FRAMES = (('', ''), ('body', ''), ('eci', 'body'), ('a_longer_frame', 'x'))

doubles = st.one_of(st.floats(allow_nan=True, allow_infinity=True), st.sampled_from(SPECIAL))
stamps = st.one_of(st.integers(T_MIN, T_MAX), st.sampled_from((0, -1, 1, T_MIN, T_MAX, -10**9, 10**9 - 1)))


def _one_by_one(codec: Codec, t_ns: np.ndarray, rows: np.ndarray) -> bytes:
    return b''.join(codec.encode(int(t), codec.layout.unflatten(row.tolist())) for t, row in zip(t_ns, rows, strict=True))


@pytest.mark.parametrize('msg_type', FIXED)
@settings(max_examples=60, deadline=None)
@given(data=st.data(), frames=st.sampled_from(FRAMES))
def test_block_is_the_messages_byte_for_byte(msg_type, data, frames):
    codec = Codec(msg_type, *frames)
    assert codec.layout.width == WIDTH[msg_type]
    n = data.draw(st.integers(0, 9))
    t_ns = np.array(data.draw(st.lists(stamps, min_size=n, max_size=n)), dtype=np.int64)
    rows = np.array(data.draw(st.lists(st.lists(doubles, min_size=WIDTH[msg_type], max_size=WIDTH[msg_type]),
                                       min_size=n, max_size=n)), dtype=np.float64).reshape(n, WIDTH[msg_type])
    assert codec.encode_block(t_ns, rows) == _one_by_one(codec, t_ns, rows)


@pytest.mark.parametrize('msg_type', FIXED)
def test_random_blocks_and_the_flattening(msg_type):
    rng = np.random.default_rng(7)
    codec = Codec(msg_type, 'body', 'eci')
    rows = rng.normal(size=(500, WIDTH[msg_type])) * 10.0 ** rng.integers(-300, 300, size=(500, WIDTH[msg_type]))
    rows.flat[rng.integers(0, rows.size, size=min(rows.size, 40))] = rng.choice(SPECIAL, size=min(rows.size, 40))
    t_ns = rng.integers(T_MIN, T_MAX, size=500, dtype=np.int64)
    assert codec.encode_block(t_ns, rows) == _one_by_one(codec, t_ns, rows)
    for row in rows[:50]:  # flatten inverts unflatten, bit for bit (NaN payloads too)
        back = np.array(codec.layout.flatten(codec.layout.unflatten(row.tolist())), dtype=np.float64)
        assert back.tobytes() == row.tobytes()


def test_the_value_types_of_the_rows():
    odom = Codec('nav_msgs/msg/Odometry').layout.unflatten([float(i) for i in range(13)])
    assert odom == OdometryValue((0.0, 1.0, 2.0), (3.0, 4.0, 5.0, 6.0), (7.0, 8.0, 9.0), (10.0, 11.0, 12.0))
    assert Codec('sensor_msgs/msg/MagneticField').layout.flatten(((1.0, 2.0, 3.0), (0.5,) * 9)) == (1.0, 2.0, 3.0,
                                                                                                    *(0.5,) * 9)


@pytest.mark.parametrize('t', (T_MIN - 1, T_MAX + 1))
def test_a_stamp_beyond_a_time_raises_in_both(t):
    codec = Codec('geometry_msgs/msg/Vector3Stamped', 'body')
    with pytest.raises(struct.error):
        codec.encode(t, (0.0, 0.0, 0.0))
    with pytest.raises(CdrError, match='int32 seconds'):
        codec.encode_block(np.array([0, t]), np.zeros((2, 3)))


def test_rows_of_the_wrong_shape_are_refused():
    with pytest.raises(CdrError, match=r'shape \(2, 13\)'):
        Codec('nav_msgs/msg/Odometry').encode_block(np.array([0, 1]), np.zeros((2, 12)))


@pytest.mark.parametrize('msg_type', ('std_msgs/msg/String', 'diagnostic_msgs/msg/DiagnosticArray'))
def test_a_type_without_fixed_layout_says_so(msg_type):
    codec = Codec(msg_type)
    assert codec.layout is None
    with pytest.raises(CdrError, match='not of fixed layout'):
        codec.encode_block(np.array([0]), np.zeros((1, 1)))
    value = 'text' if msg_type.endswith('String') else (Status(0, 'n', 'm', 'h', (('k', 'v'),)),)
    assert codec.decode(codec.encode(0, value))[1] == value  # the message-by-message codec is unchanged


@pytest.mark.parametrize('msg_type', FIXED)
def test_one_codec_block_after_block(msg_type):
    """A codec encodes block after block of any size, each the messages of its own rows (nothing of the one before)."""
    rng = np.random.default_rng(3)
    codec = Codec(msg_type, 'body', 'eci')
    for n in (5, 2, 9, 0, 3, 9, 1):
        rows = rng.normal(size=(n, WIDTH[msg_type]))
        t_ns = rng.integers(-10**15, 10**15, size=n, dtype=np.int64)
        assert codec.encode_block(t_ns, rows) == _one_by_one(codec, t_ns, rows)
