"""Serialized CDR of the graph's standard messages ↔ plain Python values (spec §2; no rclpy).

Every lockstep node publishes and subscribes serialized messages (rclpy ``raw=True``,
``publish(bytes)``) and converts them here, so the per-process graph and the direct
engine (one process, no DDS) meet the cores with the *same* values, and the bytes a node
publishes are exactly the bytes the direct engine records. Values are plain floats,
tuples and strings: cheaper than rclpy message objects and exact (CDR carries IEEE
doubles; decode(encode(v)) == v).

Layout: XCDR1 little endian (encapsulation ``00 01 00 00``), primitives aligned to their
size relative to the start of the payload, strings as uint32 length (with the NUL) +
bytes + NUL, sequences as uint32 count + elements. Padding bytes are written as zeros,
so equal values always give equal bytes (rclpy's own serializer leaves whatever was in
memory in the padding), and the payload is zero-padded to a multiple of 4 bytes, as Fast DDS
pads it on the wire: what a subscriber takes, and so what the recorder writes, is byte for
byte what :meth:`Codec.encode` returns. A header's ``frame_id`` is fixed per topic (:class:`Codec`).

Value of each message type (SI, the frame names of :mod:`acds_common.frames`):

* ``rosgraph_msgs/msg/Clock``: nothing (the stamp is the value).
* ``std_msgs/msg/String``: the text.
* ``geometry_msgs/msg/Vector3Stamped``: ``(x, y, z)``.
* ``sensor_msgs/msg/MagneticField``: ``((bx, by, bz), covariance_9)`` in T and T².
* ``sensor_msgs/msg/Imu``: ``((wx, wy, wz), covariance_9)``: rate gyros only (orientation and
  linear acceleration marked "not provided", covariance[0] = −1, REP-145).
* ``nav_msgs/msg/Odometry``: :class:`OdometryValue` (pose/twist covariances zero: truth).
* ``geometry_msgs/msg/WrenchStamped``: ``((fx, fy, fz), (tx, ty, tz))`` in N and N·m.
* ``diagnostic_msgs/msg/DiagnosticArray``: a tuple of :class:`Status`.

Rows (:class:`RowLayout`, ``Codec.layout``): a fixed-layout stamped type (every type above but Clock, String and
DiagnosticArray) is a constant byte pattern with the stamp and its doubles at fixed offsets, so its value is also a
row of float64 (its numbers in the order the message carries them: ``flatten``/``unflatten``) and a block of n
messages is encoded at once, vectorized, byte for byte the concatenation of the n messages ``encode`` gives
(``Codec.encode_block``): what the direct engine's compiled blocks of steps hand the truth digest.
"""

from __future__ import annotations

import re
import struct
from collections.abc import Callable
from dataclasses import dataclass, field, replace
from typing import Any, NamedTuple

import numpy as np

ENCAPSULATION = b'\x00\x01\x00\x00'
_STAMP = struct.Struct('<iI')
_U32 = struct.Struct('<I')
_V3 = struct.Struct('<3d')
_D9 = struct.Struct('<9d')
_D36_ZERO = bytes(36 * 8)
_NOT_PROVIDED_9 = struct.pack('<9d', -1.0, *([0.0] * 8))


class CdrError(ValueError):
    """A serialized message does not decode as its declared type (names the type and the reason)."""


class Status(NamedTuple):
    """One ``diagnostic_msgs/DiagnosticStatus``: level 0 OK, 1 WARN, 2 ERROR, 3 STALE."""

    level: int
    name: str
    message: str
    hardware_id: str
    values: tuple[tuple[str, str], ...]


class OdometryValue(NamedTuple):
    """``nav_msgs/Odometry`` of the truth: ECI position (m) and velocity (m/s), q body→ECI (x, y, z, w), ω body (rad/s)."""

    position: tuple[float, float, float]
    orientation: tuple[float, float, float, float]
    velocity: tuple[float, float, float]
    angular: tuple[float, float, float]


def stamp_ns(data: bytes) -> int:
    """The stamp of a message whose first field is a Time (``header.stamp`` or ``clock``), ns."""
    sec, nsec = _STAMP.unpack_from(data, 4)
    return sec * 1_000_000_000 + nsec


def frame_id_of(data: bytes) -> str:
    """The ``header.frame_id`` of a message that starts with a std_msgs/Header (every stamped type but the clock);
    '' when the bytes end before it (a message too short to hold one)."""
    frames = _frame_names(data, child=False)
    return '' if frames is None else frames[0]


def _frame_names(data: bytes, child: bool) -> tuple[str, str] | None:
    """(header.frame_id, child_frame_id if ``child`` else '') of a message that starts with a std_msgs/Header;
    None when the bytes do not hold them."""
    try:
        r = _Reader(data, 12)
        return r.string(), r.string() if child else ''
    except (struct.error, UnicodeDecodeError):
        return None


def _string(text: str) -> bytes:
    raw = text.encode() + b'\0'
    return _U32.pack(len(raw)) + raw


def _pad(offset: int, align: int) -> bytes:
    return bytes(-offset % align)


def _header(frame_id: str) -> bytes:
    """The constant part of a header after its stamp (frame_id) — payload offset 8 onwards."""
    return _string(frame_id)


class _Reader:
    """Sequential CDR reader over one payload (offsets relative to the payload start)."""

    __slots__ = ('data', 'pos')

    def __init__(self, data: bytes, pos: int) -> None:
        self.data = data
        self.pos = pos

    def align(self, n: int) -> None:
        self.pos += -(self.pos - 4) % n

    def u32(self) -> int:
        self.align(4)
        (v,) = _U32.unpack_from(self.data, self.pos)
        self.pos += 4
        return v

    def string(self) -> str:
        n = self.u32()
        raw = self.data[self.pos:self.pos + n - 1]
        self.pos += n
        return raw.decode()

    def doubles(self, s: struct.Struct) -> tuple[float, ...]:
        self.align(8)
        v = s.unpack_from(self.data, self.pos)
        self.pos += s.size
        return v

    def octet(self) -> int:
        v = self.data[self.pos]
        self.pos += 1
        return v


#: One field of a little-endian struct format (``<`` packs without alignment).
_TOKEN = re.compile(r'(\d*)([a-zA-Z?])')
#: The range of a Time's ``sec`` (int32).
_SEC_RANGE = (-2**31, 2**31 - 1)


def _double_runs(fmt: str) -> list[tuple[int, int]]:
    """(byte offset, count) of each run of doubles of a little-endian struct format, in order."""
    runs, offset = [], 0
    for count, code in _TOKEN.findall(fmt.lstrip('<')):
        if code == 'd':
            runs.append((offset, int(count or 1)))
        offset += struct.calcsize(f'<{count}{code}')
    return runs


@dataclass(frozen=True)
class RowLayout:
    """A fixed-layout message type as rows of float64 (module docstring): ``width`` numbers a message,
    ``flatten(value) -> tuple[float, ...]``, ``unflatten(row) -> value``; one message is ``template`` (its bytes at
    stamp 0 and zero values) with the stamp (``sec``, ``nanosec``) and the runs of doubles (``fields``: name,
    first column, count) written at their offsets (``dtype``, a structured view of one message)."""

    width: int
    flatten: Callable[[Any], tuple[float, ...]]
    unflatten: Callable[[Any], Any]
    template: np.ndarray
    dtype: np.dtype
    fields: tuple[tuple[str, int, int], ...]
    #: The template repeated, as messages (:attr:`dtype`) and as their bytes, reused from block to block (only the stamps
    #: and the doubles change; one thread).
    _repeated: list[np.ndarray] = field(default_factory=list, compare=False, repr=False)

    @classmethod
    def of(cls, packer: struct.Struct, encode: Callable[[int, Any], bytes], flatten: Callable[[Any], tuple[float, ...]],
           unflatten: Callable[[Any], Any]) -> RowLayout:
        """The layout of the messages ``packer`` packs as ``(encapsulation, sec, nanosec, ...)`` and ``encode``
        writes."""
        assert packer.format.startswith('<4siI'), packer.format  # the stamp right after the encapsulation
        runs = _double_runs(packer.format)
        width = sum(count for _offset, count in runs)
        names = ['sec', 'nanosec', *(f'd{i}' for i in range(len(runs)))]
        formats = ['<i4', '<u4', *(('<f8', (count,)) for _offset, count in runs)]
        offsets = [4, 8, *(offset for offset, _count in runs)]
        dtype = np.dtype({'names': names, 'formats': formats, 'offsets': offsets, 'itemsize': packer.size})
        template = np.frombuffer(encode(0, unflatten((0.0,) * width)), dtype=np.uint8)
        firsts = np.cumsum([0, *(count for _offset, count in runs)])
        fields = tuple((f'd{i}', int(firsts[i]), count) for i, (_offset, count) in enumerate(runs))
        return cls(width, flatten, unflatten, template, dtype, fields)

    def encode_block(self, t_ns: np.ndarray, rows: np.ndarray) -> memoryview:
        """:meth:`Codec.encode_block`: the template repeated, the stamps split as ``divmod(t_ns, 10⁹)`` (floor,
        as :meth:`Codec.encode`; a ``sec`` beyond int32 raises as its ``struct.pack`` does) and the rows' doubles
        copied bit for bit (NaN payloads and −0.0 kept), written into a buffer kept from block to block: the view
        returned holds them until the next block of this layout (no copy: a digest takes it as it is)."""
        t_ns = np.asarray(t_ns, dtype=np.int64)
        rows = np.asarray(rows, dtype=np.float64)
        n = len(t_ns)
        if t_ns.ndim != 1 or rows.shape != (n, self.width):
            raise CdrError(f'a block of {n} stamps needs rows of shape ({n}, {self.width}), not {rows.shape}')
        sec, nanosec = np.divmod(t_ns, 1_000_000_000)
        if n and (sec.min() < _SEC_RANGE[0] or sec.max() > _SEC_RANGE[1]):
            raise CdrError(f'a stamp of the block is beyond the int32 seconds of a Time: {t_ns.min()}…{t_ns.max()} ns')
        messages = self._templates(n)
        messages['sec'] = sec
        messages['nanosec'] = nanosec
        for name, first, count in self.fields:
            messages[name] = rows[:, first:first + count]
        return memoryview(self._repeated[1])[:n * self.dtype.itemsize]

    def _templates(self, n: int) -> np.ndarray:
        """n templates, as messages (:attr:`dtype`): the first n of the ones kept, repeated anew when too few."""
        if not self._repeated or len(self._repeated[0]) < n:
            raw = np.tile(self.template, n)
            self._repeated[:] = [raw.view(self.dtype), raw]
        return self._repeated[0][:n]


def _layout(msg_type: str, frame_id: str, child_frame_id: str, packer: struct.Struct, encode: Callable[[int, Any], bytes]
            ) -> RowLayout:
    """The :class:`RowLayout` of a codec's messages, worked out once per process for each type and frames (the
    layout's buffer is each codec's own: it starts empty)."""
    key = (msg_type, frame_id, child_frame_id)
    known = _LAYOUTS.get(key)
    if known is None:
        known = _LAYOUTS[key] = RowLayout.of(packer, encode, *_ROWS[msg_type])
    return replace(known, _repeated=[])


#: :func:`_layout` by (message type, frame_id, child_frame_id).
_LAYOUTS: dict[tuple[str, str, str], RowLayout] = {}


class Codec:
    """Encoder/decoder of one topic: its message type and, for stamped types, its fixed frame_id.

    ``encode(t_ns, value) -> bytes`` and ``decode(data) -> (t_ns, value)``.
    """

    def __init__(self, msg_type: str, frame_id: str = '', child_frame_id: str = '') -> None:
        if msg_type not in _TYPES:
            raise CdrError(f'no codec for message type {msg_type!r} (known: {", ".join(sorted(_TYPES))})')
        self.msg_type = msg_type
        self.frame_id = frame_id
        self.child_frame_id = child_frame_id
        self.stamped = msg_type != 'std_msgs/msg/String'
        #: The (frame_id, child_frame_id) whose messages :meth:`decode` reads in one ``unpack`` (a fixed-layout type).
        self.read_frames = (frame_id, child_frame_id)
        self._head = _header(frame_id)
        # Offset (in the payload) where the body after the header starts, before its alignment.
        self._body_offset = 8 + len(self._head)
        encode, self.decode, packer = _TYPES[msg_type](self)
        #: The rows of a fixed-layout type (module docstring), None for the others.
        self.layout = None if packer is None else _layout(msg_type, frame_id, child_frame_id, packer, encode)
        if packer is not None:  # one struct, already padded to 4 bytes (_stamped)
            self.encode = encode
            if not frame_id and not child_frame_id and msg_type != 'rosgraph_msgs/msg/Clock':  # a header's frames
                self.decode = self._learning(self.decode)
            return

        def padded(t_ns: int, value: Any = None) -> bytes:
            data = encode(t_ns, value)
            pad = -len(data) % 4
            return data + bytes(pad) if pad else data
        self.encode = padded

    def _learning(self, decode: Callable[[bytes], Any]) -> Callable[[bytes], Any]:
        """A subscriber's decode: a codec made without frame names (it does not know its publisher's) takes those of
        the first message it decodes, so the messages after it that carry the same are read in one ``unpack`` (the
        values are the same either way; a message with other frame names is read field by field)."""
        def first(data: bytes) -> Any:
            frames = _frame_names(data, self.msg_type == 'nav_msgs/msg/Odometry')
            if frames is None or not any(frames):
                self.decode = decode
            else:
                self.decode, self.read_frames = Codec(self.msg_type, *frames).decode, frames
            return self.decode(data)
        return first

    def encode_block(self, t_ns: np.ndarray, rows: np.ndarray) -> memoryview:
        """The messages of stamps ``t_ns`` (int64, n) and values ``rows`` (float64, n × width), concatenated:
        ``b''.join(encode(t, unflatten(row)))`` byte for byte (:class:`RowLayout`), as a view valid until the next
        block of this codec (``bytes(...)`` to keep it); CdrError for a type that is not of fixed layout."""
        if self.layout is None:
            raise CdrError(f'{self.msg_type} is not of fixed layout: no rows, encode each message')
        return self.layout.encode_block(t_ns, rows)

    def __repr__(self) -> str:
        return f'Codec({self.msg_type!r}, frame_id={self.frame_id!r})'


def _clock(c: Codec) -> tuple[Any, Any, struct.Struct]:
    packer = _stamped('')

    def encode(t_ns: int, _value: Any = None) -> bytes:
        sec, nsec = divmod(t_ns, 1_000_000_000)
        return packer.pack(ENCAPSULATION, sec, nsec)

    def decode(data: bytes) -> tuple[int, None]:
        return stamp_ns(data), None
    return encode, decode, packer


def _text(c: Codec) -> tuple[Any, Any, None]:
    def encode(_t_ns: int, value: str) -> bytes:
        return ENCAPSULATION + _string(value)

    def decode(data: bytes) -> tuple[int, str]:
        return 0, _Reader(data, 4).string()
    return encode, decode, None


def _stamped(body: str) -> struct.Struct:
    """One struct for a fixed-layout stamped message: encapsulation, stamp, then ``body`` (its constant
    parts as ``s`` fields), zero-padded to a multiple of 4 bytes: a message is one ``pack``."""
    size = struct.calcsize(f'<4siI{body}')
    return struct.Struct(f'<4siI{body}{-size % 4}x')


def _fixed_reader(c: Codec, body: str, *, child: bool = False) -> tuple[struct.Struct, tuple[int, ...]]:
    """One struct that reads a stamped message laid out as :meth:`Codec.encode` writes it for this topic (its
    frame_id, and ``child``: its child_frame_id), and the string lengths that layout has: a decoder checks them and
    reads the whole message in one ``unpack`` (the stamp, those lengths, then ``body``), falling back to reading field
    by field when another frame name moved the fields (a message from outside the graph)."""
    frame = len(c.frame_id.encode()) + 1
    if not child:
        pad = -(c._body_offset) % 8
        return struct.Struct(f'<4xiII{frame}x{pad}x{body}'), (frame,)
    second = len(c.child_frame_id.encode()) + 1
    at = c._body_offset + -c._body_offset % 4 + 4 + second
    return struct.Struct(f'<4xiII{frame}x{-c._body_offset % 4}xI{second}x{-at % 8}x{body}'), (frame, second)


def _vector3_stamped(c: Codec) -> tuple[Any, Any, struct.Struct]:
    head = c._head + _pad(c._body_offset, 8)
    packer = _stamped(f'{len(head)}s3d')
    reader, (frame,) = _fixed_reader(c, '3d')

    def encode(t_ns: int, value: Any) -> bytes:
        sec, nsec = divmod(t_ns, 1_000_000_000)
        return packer.pack(ENCAPSULATION, sec, nsec, head, value[0], value[1], value[2])

    def decode(data: bytes) -> tuple[int, tuple[float, float, float]]:
        if len(data) >= reader.size:
            sec, nsec, n, x, y, z = reader.unpack_from(data)
            if n == frame:
                return sec * 1_000_000_000 + nsec, (x, y, z)
        r = _Reader(data, 12)
        r.string()
        return stamp_ns(data), r.doubles(_V3)  # type: ignore[return-value]
    return encode, decode, packer


def _magnetic_field(c: Codec) -> tuple[Any, Any, struct.Struct]:
    head = c._head + _pad(c._body_offset, 8)
    packer = _stamped(f'{len(head)}s3d9d')
    reader, (frame,) = _fixed_reader(c, '3d9d')

    def encode(t_ns: int, value: Any) -> bytes:
        b, cov = value
        sec, nsec = divmod(t_ns, 1_000_000_000)
        return packer.pack(ENCAPSULATION, sec, nsec, head, *b, *cov)

    def decode(data: bytes) -> tuple[int, Any]:
        if len(data) >= reader.size:
            sec, nsec, n, *v = reader.unpack_from(data)
            if n == frame:
                return sec * 1_000_000_000 + nsec, (tuple(v[:3]), tuple(v[3:]))
        r = _Reader(data, 12)
        r.string()
        return stamp_ns(data), (r.doubles(_V3), r.doubles(_D9))
    return encode, decode, packer


_V6 = struct.Struct('<6d')


def _wrench_stamped(c: Codec) -> tuple[Any, Any, struct.Struct]:
    head = c._head + _pad(c._body_offset, 8)
    packer = _stamped(f'{len(head)}s6d')

    def encode(t_ns: int, value: Any) -> bytes:
        force, torque = value
        sec, nsec = divmod(t_ns, 1_000_000_000)
        return packer.pack(ENCAPSULATION, sec, nsec, head, *force, *torque)

    def decode(data: bytes) -> tuple[int, Any]:
        r = _Reader(data, 12)
        r.string()
        v = r.doubles(_V6)
        return stamp_ns(data), (v[:3], v[3:])
    return encode, decode, packer


_QUAT = struct.Struct('<4d')
_IDENTITY_ORIENTATION = _QUAT.pack(0.0, 0.0, 0.0, 1.0)


def _imu(c: Codec) -> tuple[Any, Any, struct.Struct]:
    head = c._head + _pad(c._body_offset, 8) + _IDENTITY_ORIENTATION + _NOT_PROVIDED_9
    tail = _V3.pack(0.0, 0.0, 0.0) + _NOT_PROVIDED_9
    packer = _stamped(f'{len(head)}s3d9d{len(tail)}s')
    reader, (frame,) = _fixed_reader(c, f'{len(_IDENTITY_ORIENTATION) + len(_NOT_PROVIDED_9)}x3d9d')

    def encode(t_ns: int, value: Any) -> bytes:
        w, cov = value
        sec, nsec = divmod(t_ns, 1_000_000_000)
        return packer.pack(ENCAPSULATION, sec, nsec, head, *w, *cov, tail)

    def decode(data: bytes) -> tuple[int, Any]:
        if len(data) >= reader.size:
            sec, nsec, n, *v = reader.unpack_from(data)
            if n == frame:
                return sec * 1_000_000_000 + nsec, (tuple(v[:3]), tuple(v[3:]))
        r = _Reader(data, 12)
        r.string()
        r.doubles(_QUAT)
        r.doubles(_D9)
        return stamp_ns(data), (r.doubles(_V3), r.doubles(_D9))
    return encode, decode, packer


def _odometry(c: Codec) -> tuple[Any, Any, struct.Struct]:
    head = c._head + _pad(c._body_offset, 4) + _string(c.child_frame_id)
    head += _pad(8 + len(head), 8)
    _P = struct.Struct('<3d4d')
    _T = struct.Struct('<3d3d')
    packer = _stamped(f'{len(head)}s7d{len(_D36_ZERO)}x6d{len(_D36_ZERO)}x')  # covariances: zeros
    reader, (frame, child) = _fixed_reader(c, f'7d{len(_D36_ZERO)}x6d', child=True)

    def encode(t_ns: int, value: OdometryValue) -> bytes:
        sec, nsec = divmod(t_ns, 1_000_000_000)
        return packer.pack(ENCAPSULATION, sec, nsec, head, *value.position, *value.orientation, *value.velocity,
                           *value.angular)

    def decode(data: bytes) -> tuple[int, OdometryValue]:
        if len(data) >= reader.size:
            sec, nsec, n, m, *v = reader.unpack_from(data)
            if n == frame and m == child:
                return sec * 1_000_000_000 + nsec, OdometryValue(tuple(v[0:3]), tuple(v[3:7]), tuple(v[7:10]),
                                                                 tuple(v[10:13]))  # type: ignore[arg-type]
        r = _Reader(data, 12)
        r.string()
        r.string()
        p = r.doubles(_P)
        r.pos += 36 * 8
        t = r.doubles(_T)
        return stamp_ns(data), OdometryValue(p[:3], p[3:], t[:3], t[3:])  # type: ignore[arg-type]
    return encode, decode, packer


#: Zero bytes that pad a buffer of length n to a multiple of 4, indexed by n % 4.
_PAD4 = (b'', b'\0\0\0', b'\0\0', b'\0')
#: Encoded CDR strings (length + bytes + NUL) of recent texts: diagnostic keys repeat every message.
_STRING_CACHE: dict[str, bytes] = {}
_STRING_CACHE_SIZE = 4096


def _cached_string(text: str) -> bytes:
    raw = _STRING_CACHE.get(text)
    if raw is None:
        if len(_STRING_CACHE) >= _STRING_CACHE_SIZE:
            _STRING_CACHE.clear()
        raw = _STRING_CACHE[text] = _string(text)
    return raw


def _diagnostic_array(c: Codec) -> tuple[Any, Any, None]:
    head = c._head

    sent: list[Any] = [None, b'']  # the last statuses encoded (an immutable tuple) and their bytes after the stamp

    def encode(t_ns: int, value: tuple[Status, ...]) -> bytes:
        stamp = _STAMP.pack(*divmod(t_ns, 1_000_000_000))
        if value is sent[0]:  # a stepper that hands the same statuses again (its mode has not changed)
            return ENCAPSULATION + stamp + sent[1]
        # Offsets relative to the payload start; every string and count is 4-aligned (_PAD4).
        out = bytearray(stamp + head)
        out += _PAD4[len(out) & 3]
        out += _U32.pack(len(value))
        for st in value:
            out.append(st.level)
            for text in (st.name, st.message, st.hardware_id):
                out += _PAD4[len(out) & 3]
                out += _cached_string(text)
            out += _PAD4[len(out) & 3]
            out += _U32.pack(len(st.values))
            for key, text in st.values:
                out += _PAD4[len(out) & 3]
                out += _cached_string(key)
                out += _PAD4[len(out) & 3]
                out += _cached_string(text)
        sent[:] = value, bytes(out[8:])
        return ENCAPSULATION + bytes(out)

    last: list[Any] = [None, ()]  # the bytes after the stamp of the last message read, and its statuses

    def decode(data: bytes) -> tuple[int, tuple[Status, ...]]:
        body = data[12:]
        if body == last[0]:  # a mode or status that has not changed since the last step: the same (immutable) value
            return stamp_ns(data), last[1]
        r = _Reader(data, 12)
        r.string()
        statuses = []
        for _ in range(r.u32()):
            level = r.octet()
            name, message, hardware_id = r.string(), r.string(), r.string()
            values = tuple((r.string(), r.string()) for _ in range(r.u32()))
            statuses.append(Status(level, name, message, hardware_id, values))
        last[:] = body, tuple(statuses)
        return stamp_ns(data), last[1]
    return encode, decode, None


_TYPES = {
    'rosgraph_msgs/msg/Clock': _clock,
    'std_msgs/msg/String': _text,
    'geometry_msgs/msg/Vector3Stamped': _vector3_stamped,
    'geometry_msgs/msg/WrenchStamped': _wrench_stamped,
    'sensor_msgs/msg/MagneticField': _magnetic_field,
    'sensor_msgs/msg/Imu': _imu,
    'nav_msgs/msg/Odometry': _odometry,
    'diagnostic_msgs/msg/DiagnosticArray': _diagnostic_array,
}


def _pair(row: Any) -> tuple[tuple[float, ...], tuple[float, ...]]:
    """A (vector, covariance_9) value of a row of 12 numbers."""
    return tuple(row[:3]), tuple(row[3:12])


#: ``(flatten, unflatten)`` of each fixed-layout type (:class:`RowLayout`): the numbers in the order ``encode``
#: packs them, and back to the value (a row is any sequence of floats: ``ndarray.tolist()`` gives exact floats).
_ROWS: dict[str, tuple[Callable[[Any], tuple[float, ...]], Callable[[Any], Any]]] = {
    'rosgraph_msgs/msg/Clock': (lambda _v: (), lambda _row: None),
    'geometry_msgs/msg/Vector3Stamped': (lambda v: (v[0], v[1], v[2]), lambda row: tuple(row[:3])),
    'geometry_msgs/msg/WrenchStamped': (lambda v: (*v[0], *v[1]), lambda row: (tuple(row[:3]), tuple(row[3:6]))),
    'sensor_msgs/msg/MagneticField': (lambda v: (*v[0], *v[1]), _pair),
    'sensor_msgs/msg/Imu': (lambda v: (*v[0], *v[1]), _pair),
    'nav_msgs/msg/Odometry': (lambda v: (*v.position, *v.orientation, *v.velocity, *v.angular),
                              lambda row: OdometryValue(tuple(row[:3]), tuple(row[3:7]), tuple(row[7:10]),
                                                        tuple(row[10:13]))),
}

#: The fields that carry data in each message type (what :class:`Codec` writes and reads; everything else is
#: written as a constant): the contract an outside node reads or fills (``acds contract``). Units: the topic's.
DATA_FIELDS: dict[str, str] = {
    'rosgraph_msgs/msg/Clock': 'clock (the step time)',
    'std_msgs/msg/String': 'data (text)',
    'geometry_msgs/msg/Vector3Stamped': 'vector.x, vector.y, vector.z',
    'geometry_msgs/msg/WrenchStamped': 'wrench.force.{x,y,z} (N), wrench.torque.{x,y,z} (N·m)',
    'sensor_msgs/msg/MagneticField': 'magnetic_field.{x,y,z}, magnetic_field_covariance (row-major 3×3, unit², '
                                     'zeros = unknown)',
    'sensor_msgs/msg/Imu': 'angular_velocity.{x,y,z}, angular_velocity_covariance (row-major 3×3); orientation and '
                           'linear acceleration not provided (covariance[0] = −1, REP-145)',
    'nav_msgs/msg/Odometry': 'pose.pose.position (ECI, m), pose.pose.orientation (q body→ECI, x y z w), '
                             'twist.twist.linear (ECI velocity, m/s), twist.twist.angular (ω body, rad/s); '
                             'covariances zero',
    'diagnostic_msgs/msg/DiagnosticArray': 'status[]: level, name (the node), message, hardware_id, values '
                                           '(key/value strings)',
}
