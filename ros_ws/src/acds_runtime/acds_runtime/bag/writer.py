"""Write a rosbag2 bag (version 9) of raw CDR messages as rosbag2 Jazzy does, with sim-time stamps and a flush policy.

As rosbag2 Jazzy writes (on top of rosbags' writer): MCAP chunks zstd-compressed by default
(``compression='none'`` for plain chunks; sqlite3 bags are never compressed, as rosbag2's
sqlite3 storage has no storage-level compression), ``ros_distro: jazzy`` in ``metadata.yaml``
and in the storage's own copy of it, and, per MCAP channel, ``topic_type_hash`` (the RIHS01
hash of the message type, rosbag2's ``type_description_hash``) beside ``offered_qos_profiles``.
The two storage classes below extend rosbags' storage writers for that and for flushing; what
they rely on in rosbags (its MCAP record helpers, the pending chunk, the sqlite connection) is
pinned by ``tests/test_bag_format.py``, which fails if a rosbags upgrade breaks it.

Flush policy (what survives a SIGKILL): messages are buffered in the current
MCAP chunk (sqlite3: the current transaction) and made durable at most
:data:`FLUSH_PERIOD_S` wall seconds after they arrive: the writer closes the
chunk and flushes the file (sqlite3: commits) on the first message after the
period elapsed, when a chunk reaches 1 MiB, every :data:`FLUSH_MESSAGES`
messages, and on :meth:`BagWriter.flush`. A killed recorder therefore loses
at most the last second of messages; the bag it leaves has no index and no
``metadata.yaml``: :func:`.reader.open_bag` reads it, without
changing it, up to its last complete chunk, and
:func:`.recover.recover_bag` writes a repaired copy (the
``ros2 bag reindex`` equivalent). While it is open, the writer holds the bag
folder's recording lock (:mod:`acds_runtime.bag.recording`).
"""

from __future__ import annotations

import os
import shutil
import sqlite3
import struct
import threading
import time
from io import BytesIO
from pathlib import Path
from typing import Any

import yaml
from acds_common import topics
from acds_common.parameters import NoAliasDumper
from rosbags.interfaces import Qos, QosDurability, QosHistory, QosLiveliness, QosReliability, QosTime
from rosbags.rosbag2 import CompressionFormat, CompressionMode, StoragePlugin, Writer
from rosbags.rosbag2.storage_mcap import Channel, McapWriter, write_channel, write_string
from rosbags.rosbag2.storage_sqlite3 import Sqlite3Writer
from rosbags.typesys import Stores, get_typestore

from . import COMPRESSIONS, STORAGE_NAMES
from .recording import RecordingLock

#: Wall seconds after which buffered messages are made durable.
FLUSH_PERIOD_S = 1.0
#: ... or after this many messages, whichever comes first.
FLUSH_MESSAGES = 2000
#: Free space a bag needs before the run starts.
MIN_FREE_BYTES = 64 * 2**20
#: The sidecar with the run's scenario and parameters, written when recording starts.
RUN_INFO_FILE = 'acds_run.yaml'
STORAGES = dict(zip(STORAGE_NAMES, (StoragePlugin.MCAP, StoragePlugin.SQLITE3), strict=True))
#: The distribution a bag says it was written by (rosbag2 writes its ROS_DISTRO).
ROS_DISTRO = 'jazzy'
#: Topics never recorded (lockstep handshake plumbing).
SKIP = {topics.resolve(topics.READY), topics.resolve(topics.MONITOR_ACK), topics.resolve(topics.RUN_END)}

_TYPESTORE = None


def typestore() -> Any:
    """The ROS 2 Jazzy type store (shared)."""
    global _TYPESTORE
    if _TYPESTORE is None:
        _TYPESTORE = get_typestore(Stores.ROS2_JAZZY)
    return _TYPESTORE


class BagError(RuntimeError):
    """A bag cannot be written or read; the message is one line naming the path and the reason."""


def _qos(reliable: bool, transient: bool, depth: int) -> Qos:
    zero = QosTime(0, 0)
    return Qos(QosHistory.KEEP_LAST, depth,
               QosReliability.RELIABLE if reliable else QosReliability.BEST_EFFORT,
               QosDurability.TRANSIENT_LOCAL if transient else QosDurability.VOLATILE,
               zero, zero, QosLiveliness.AUTOMATIC, zero, False)


#: What the ACDS nodes offer: lockstep topics reliable + transient-local depth 1000; ground topics volatile.
LOCKSTEP_QOS = _qos(True, True, 1000)
COMMAND_QOS = _qos(True, False, 100)


def offered_qos(topic: str) -> Qos:
    """The QoS the ACDS graph offers on ``topic`` (absolute name)."""
    if topic in (topics.resolve(topics.GROUND_COMMAND), topics.resolve(topics.GROUND_ACK)):
        return COMMAND_QOS
    return LOCKSTEP_QOS


def qos_from_rclpy(profile: Any) -> Qos:
    """An rclpy QoSProfile (as seen by graph introspection) → rosbags Qos."""
    def t(d: Any) -> QosTime:
        ns = int(getattr(d, 'nanoseconds', 0))
        return QosTime(*divmod(ns, 1_000_000_000)) if 0 < ns < 2**62 else QosTime(0, 0)
    return Qos(QosHistory(int(profile.history)), int(profile.depth), QosReliability(int(profile.reliability)),
               QosDurability(int(profile.durability)), t(profile.deadline), t(profile.lifespan),
               QosLiveliness(int(profile.liveliness)), t(profile.liveliness_lease_duration), False)


def qos_from_dicts(items: Any) -> list[Qos]:
    """``offered_qos_profiles`` as stored (v9 dicts) → rosbags Qos list (for recovery)."""
    out = []
    for d in items or []:
        def t(x: Any) -> QosTime:
            return QosTime(int(x.get('sec', 0)), int(x.get('nsec', 0))) if isinstance(x, dict) else QosTime(0, 0)
        out.append(Qos(QosHistory[str(d.get('history', 'keep_last')).upper()], int(d.get('depth', 0)),
                       QosReliability[str(d.get('reliability', 'reliable')).upper()],
                       QosDurability[str(d.get('durability', 'volatile')).upper()],
                       t(d.get('deadline')), t(d.get('lifespan')),
                       QosLiveliness[str(d.get('liveliness', 'automatic')).upper()],
                       t(d.get('liveliness_lease_duration')), bool(d.get('avoid_ros_namespace_conventions', False))))
    return out


def stamped(msgtype: str) -> bool:
    """Whether the type's first field is a ``std_msgs/Header`` or a ``builtin_interfaces/Time``."""
    fields = typestore().fielddefs[msgtype][1]
    return bool(fields) and fields[0][1][1] in ('std_msgs/msg/Header', 'builtin_interfaces/msg/Time')


def cdr_stamp_ns(data: bytes) -> int:
    """Stamp of a CDR message whose first field is a Time (header.stamp, clock): integer ns."""
    fmt = '<iI' if data[1] == 1 else '>iI'
    sec, nsec = struct.unpack_from(fmt, data, 4)
    return sec * 1_000_000_000 + nsec


def writable_parent(path: Path, what: str) -> Path:
    """The nearest existing folder above ``path``; a one-line :class:`BagError` naming ``what`` if it cannot be written."""
    parent = Path(path).parent
    while not parent.exists():
        parent = parent.parent
    if not parent.is_dir() or not os.access(parent, os.W_OK | os.X_OK):
        raise BagError(f'{what} {path}: cannot write in {parent} (permission denied or not a folder)')
    return parent


def check_out_dir(path: Path, what: str = 'output folder') -> None:
    """Fail with a one-line :class:`BagError` if files cannot be written into folder ``path`` (creating nothing)."""
    path = Path(path)
    if path.exists():
        if not path.is_dir():
            raise BagError(f'{what} {path}: exists and is not a folder')
        if not os.access(path, os.W_OK | os.X_OK):
            raise BagError(f'{what} {path}: cannot write in it (permission denied)')
        return
    writable_parent(path, what)


def default_compression(storage: str) -> str:
    """The compression a bag of ``storage`` gets when none is asked for (zstd chunks for MCAP)."""
    return 'zstd' if storage == 'mcap' else 'none'


def check_target(path: Path, storage: str = 'mcap', compression: str | None = None) -> None:
    """Fail with a one-line :class:`BagError` if a bag cannot be written at ``path`` (``compression`` None: the
    storage's default)."""
    path = Path(path)
    if storage not in STORAGES:
        raise BagError(f'bag {path}: unknown storage {storage!r} (choose {", ".join(STORAGES)})')
    if compression is not None and compression not in COMPRESSIONS:
        raise BagError(f'bag {path}: unknown compression {compression!r} (choose {", ".join(COMPRESSIONS)})')
    if storage == 'sqlite3' and compression == 'zstd':
        raise BagError(f'bag {path}: sqlite3 bags are not compressed (rosbag2 compresses only MCAP chunks in '
                       'storage); use --storage mcap or --compression none')
    if path.exists():
        raise BagError(f'bag {path}: already exists, not overwriting (choose a new path)')
    parent = writable_parent(path, 'bag')
    free = shutil.disk_usage(parent).free
    if free < MIN_FREE_BYTES:
        raise BagError(f'bag {path}: only {free / 2**20:.1f} MiB free on the disk of {parent} '
                       f'(a bag needs at least {MIN_FREE_BYTES / 2**20:.0f} MiB)')


def run_info(scenario: Any, steps: int, params: dict[str, Any] | None = None,
             domain_id: int | None = None, run_id: str | None = None) -> dict[str, str]:
    """The run description stored with a bag (all values are strings, as custom_data requires).

    ``run_id``: the run folder's name (``<scenario>_<time>``), which plots put in their titles.
    """
    info = {
        'scenario_name': scenario.name,
        'scenario': yaml.safe_dump(scenario.raw, sort_keys=False),
        'control_period_s': repr(scenario.control_period_s),
        'steps': str(steps),
        'nodes': ','.join(instance for instance, _node, _vehicle in scenario.instances()),  # a vehicle's too
    }
    if params is not None:
        info['params'] = yaml.dump(params, Dumper=NoAliasDumper, sort_keys=True)
    if domain_id is not None:
        info['domain_id'] = str(domain_id)
    if run_id is not None:
        info['run_id'] = run_id
    return info


def replace_file(path: Path, text: str) -> None:
    """Replace ``path`` with ``text`` atomically (through ``<name>.tmp`` beside it: a crash never leaves half of it);
    when the temporary cannot be written (disk full) it is removed and the OSError raised."""
    tmp = path.with_name(f'{path.name}.tmp')
    try:
        tmp.write_text(text)
        tmp.replace(path)
    except OSError:
        tmp.unlink(missing_ok=True)
        raise


def _jazzy(metadata_yaml: str) -> str:
    """rosbags' serialized bag metadata with ``ros_distro`` set to :data:`ROS_DISTRO`."""
    info = yaml.safe_load(metadata_yaml)
    if info.get('ros_distro') is None:
        raise BagError(f'rosbags wrote bag metadata without ros_distro: {sorted(info)}')
    info['ros_distro'] = ROS_DISTRO
    return yaml.safe_dump(info, sort_keys=False).strip()


#: An MCAP message record's opcode and length, then its fields before the data: channel id, sequence, log time, publish
#: time (the MCAP specification's Message record, as rosbags writes it); MESSAGE_FIELDS: those fields' bytes.
_MESSAGE_RECORD = struct.Struct('<BQHIQQ')
MESSAGE_FIELDS = 2 + 4 + 8 + 8


class _McapStorage(McapWriter):
    """rosbags' MCAP storage with rosbag2 Jazzy's channel metadata and ``ros_distro``, and an explicit flush."""

    def add_connection(self, connection: Any, offered_qos_profiles: str) -> None:
        """A channel whose metadata is rosbag2's: ``offered_qos_profiles`` and ``topic_type_hash`` (RIHS01)."""
        metadata = BytesIO()
        for key, value in (('offered_qos_profiles', offered_qos_profiles), ('topic_type_hash', connection.digest)):
            write_string(metadata, key)
            write_string(metadata, value)
        self.channels.append(Channel(connection.id, connection.msgtype, connection.topic,
                                     connection.ext.serialization_format, metadata.getvalue()))
        self.channel_stats[connection.id] = 0
        write_channel(self.chunk.bio, self.channels[-1], self.schemas)

    def write(self, connection: Any, timestamp: int, data: bytes | memoryview) -> None:
        """rosbags' message record (opcode 0x05: channel, sequence 0, log and publish time, the data), the same bytes
        and statistics, packed in one call (the recorder writes every message of a run: ~9 → ~3 µs a message)."""
        if timestamp < self.message_start_time:
            self.message_start_time = timestamp
        if timestamp > self.message_end_time:
            self.message_end_time = timestamp
        self.channel_stats[connection.id] += 1
        chunk = self.chunk
        if timestamp < chunk.message_start_time:
            chunk.message_start_time = timestamp
        if timestamp > chunk.message_end_time:
            chunk.message_end_time = timestamp
        bio = chunk.bio
        chunk.msgs[connection.id].append((timestamp, bio.tell()))
        bio.write(_MESSAGE_RECORD.pack(0x05, MESSAGE_FIELDS + len(data), connection.id, 0, timestamp, timestamp))
        bio.write(data)
        if bio.tell() > 2**20:
            self.close_chunk()

    def flush(self) -> None:
        """Close the pending chunk (if it holds messages) and hand the file's buffer to the OS."""
        if self.chunk.msgs:
            self.close_chunk()
        self.bio.flush()

    def close(self, version: int, metadata: str) -> None:
        """Write the summary with the Jazzy metadata record."""
        super().close(version, _jazzy(metadata))


class _Sqlite3Storage(Sqlite3Writer):
    """rosbags' sqlite3 storage saying ``ros_distro`` jazzy, writable from the subscriber's thread, with a flush."""

    def __init__(self, path: Path, compression: CompressionMode) -> None:
        super().__init__(path, compression)
        self.conn.execute('UPDATE schema SET ros_distro = ?', (ROS_DISTRO,))
        self.conn.commit()
        self.conn.close()  # written from the subscriber's thread, not the one that opened it
        self.conn = sqlite3.connect(f'file:{self.path}', uri=True, check_same_thread=False)
        self.cursor = self.conn.cursor()

    def flush(self) -> None:
        """Commit the current transaction."""
        self.conn.commit()

    def close(self, version: int, metadata: str) -> None:
        """Store the Jazzy metadata and close."""
        super().close(version, _jazzy(metadata))


class _LockedWriter(Writer):
    """The rosbags writer with the storages above, holding the folder's recording lock from before the
    storage file exists; ``metadata.yaml`` says ``ros_distro: jazzy``."""

    STORAGE_PLUGINS = {StoragePlugin.MCAP: _McapStorage, StoragePlugin.SQLITE3: _Sqlite3Storage}
    recording: RecordingLock | None = None

    def open(self) -> None:
        """Create the bag folder, take its recording lock, then create the storage file."""
        self.path.mkdir(mode=0o755, parents=True)  # FileExistsError if it appeared since check_target
        self.recording = RecordingLock(self.path)
        try:
            self.storage = self.STORAGE_PLUGINS[self.storage_plugin](self.path, self.compression_mode)
        except BaseException:
            self.release()
            raise

    def close(self) -> None:
        """Close the storage and write ``metadata.yaml`` (atomically replaced, with ros_distro jazzy); on a write
        failure (disk full) no ``metadata.yaml.tmp`` is left (rosbags writes its metadata through that temporary)."""
        try:
            super().close()
        except OSError:
            self.metapath.with_name(f'{self.metapath.name}.tmp').unlink(missing_ok=True)
            raise
        data = yaml.safe_load(self.metapath.read_text())
        data['rosbag2_bagfile_information']['ros_distro'] = ROS_DISTRO
        replace_file(self.metapath, yaml.safe_dump(data, sort_keys=False))

    def write(self, connection: Any, timestamp: int, data: bytes | memoryview) -> None:
        """rosbags' ``Writer.write`` for the storage-compressed bags this writer makes, without its check that the
        connection is one of its own (a comparison of dataclasses per connection and message; :class:`BagWriter`
        only passes connections this writer returned)."""
        self.storage.write(connection, timestamp, data)  # type: ignore[union-attr]
        self.counts[connection.id] += 1
        if timestamp < self.min_timestamp:
            self.min_timestamp = timestamp
        if timestamp > self.max_timestamp:
            self.max_timestamp = timestamp

    def release(self) -> None:
        """Drop the recording lock (the recording is over, closed or not)."""
        if self.recording is not None:
            self.recording.release()


class BagWriter:
    """Thread-safe raw-CDR bag writer: connections added on a topic's first message.

    From construction to :meth:`close` it holds the bag folder's recording lock
    (:mod:`acds_runtime.bag.recording`), so readers can tell a bag being recorded
    from one whose recorder died.
    """

    def __init__(self, path: Path | str, storage: str = 'mcap', info: dict[str, str] | None = None,
                 flush_period_s: float = FLUSH_PERIOD_S, compression: str | None = None) -> None:
        self.path = Path(path)
        self.storage = storage
        check_target(self.path, storage, compression)
        self.compression = compression or default_compression(storage)
        self.flush_period_s = flush_period_s
        self._lock = threading.Lock()
        self._writer = _LockedWriter(self.path, version=9, storage_plugin=STORAGES[storage])
        if self.compression == 'zstd':
            self._writer.set_compression(CompressionMode.STORAGE, CompressionFormat.ZSTD)
        self.info = dict(info or {})
        #: The sidecar's YAML but for the publishers, and what it was dumped from (:meth:`_write_run_info`).
        self._head_key: tuple[Any, ...] = ()
        self._head_yaml = ''
        self.publishers: dict[str, set[str]] = {}
        self.counts: dict[str, int] = {}
        self.flushed_counts: dict[str, int] = {}
        self._pending = 0
        self._conns: dict[str, Any] = {}
        self._stamped: dict[str, bool] = {}
        self.last_clock_ns = 0
        self.error: str | None = None
        self.closed = False
        try:
            self.path.parent.mkdir(parents=True, exist_ok=True)
            self._writer.open()
            self._write_run_info()
        except OSError as exc:
            self._writer.release()
            raise BagError(f'bag {self.path}: cannot create it: {exc.strerror or exc}') from None
        except BaseException:
            self._writer.release()
            raise
        self._last_flush = time.monotonic()

    def _publishers_yaml(self) -> str:
        return yaml.safe_dump({t: sorted(v) for t, v in sorted(self.publishers.items())}, sort_keys=True)

    def _write_run_info(self) -> None:
        """The sidecar, replaced atomically (a crash never leaves half of it); publishers as known so far.

        It is rewritten as each topic's publishers become known (some twenty times as a run starts): the YAML of
        everything but the publishers (the scenario and the parameters, long strings) is dumped once and reused while
        it does not change; the publishers' mapping follows it, as the last key of one dump would."""
        head = {'storage': self.storage, 'compression': self.compression, 'flush_period_s': self.flush_period_s,
                **{k: v for k, v in self.info.items() if k != 'publishers'}}
        key = tuple(head.items())
        if key != self._head_key:
            self._head_key, self._head_yaml = key, yaml.safe_dump(head, sort_keys=False)
        publishers = self._publishers_yaml() if self.publishers else self.info.get('publishers')
        tail = '' if publishers is None else yaml.safe_dump({'publishers': publishers}, sort_keys=False)
        replace_file(self.path / RUN_INFO_FILE, self._head_yaml + tail)

    # ---- writing ------------------------------------------------------------------------------------
    def write(self, topic: str, data: bytes, *, msgtype: str | None = None, qos: list[Qos] | None = None,
              t_ns: int | None = None) -> None:
        """Write one raw message of ``topic`` (absolute name).

        Its bag timestamp is ``t_ns`` when given (a copy keeps the original's), else its header stamp,
        else the last /clock.
        """
        if topic in SKIP:
            return
        with self._lock:
            if self.closed or self.error:
                return
            try:
                conn = self._conns.get(topic)
                if conn is None:
                    msgtype = msgtype or topics.type_of(topic)
                    conn = self._writer.add_connection(topic, msgtype, typestore=typestore(),
                                                       offered_qos_profiles=qos or [offered_qos(topic)])
                    self._conns[topic] = conn
                    self._stamped[topic] = stamped(msgtype)
                    self.counts[topic] = 0
                if t_ns is None:
                    t_ns = cdr_stamp_ns(data) if self._stamped[topic] else self.last_clock_ns
                if topic == topics.CLOCK and t_ns > self.last_clock_ns:
                    self.last_clock_ns = t_ns
                self._writer.write(conn, t_ns, data)
                self.counts[topic] += 1
                self._pending += 1
                if self._pending >= FLUSH_MESSAGES or time.monotonic() - self._last_flush >= self.flush_period_s:
                    self._flush()
            except OSError as exc:
                self.error = f'bag {self.path}: write failed: {exc.strerror or exc}'
            except Exception as exc:  # noqa: BLE001 (never kill the subscriber thread; the run reports it)
                self.error = f'bag {self.path}: write failed on {topic}: {type(exc).__name__}: {exc}'

    def note_publishers(self, topic: str, names: list[str]) -> None:
        """Remember which nodes published ``topic`` (stored as ``acds.publishers``; in the sidecar at once)."""
        with self._lock:
            known = self.publishers.setdefault(topic, set())
            new = {n for n in names if n} - known
            if not new:
                return
            known.update(new)
            if self.closed:
                return
            try:
                self._write_run_info()
            except OSError as exc:
                self.error = f'bag {self.path}: writing {RUN_INFO_FILE} failed: {exc.strerror or exc}'

    def _flush(self) -> None:
        storage = self._writer.storage
        if storage is None:
            return
        storage.flush()
        self._pending = 0
        self._last_flush = time.monotonic()
        self.flushed_counts = dict(self.counts)

    def flush(self) -> None:
        """Make every message written so far durable."""
        with self._lock:
            if not self.closed and not self.error:
                try:
                    self._flush()
                except OSError as exc:
                    self.error = f'bag {self.path}: flush failed: {exc.strerror or exc}'

    def close(self) -> None:
        """Write the index, the custom data and ``metadata.yaml``, then release the recording lock (idempotent)."""
        with self._lock:
            if self.closed:
                return
            self.closed = True
            info = {**self.info, 'publishers': self._publishers_yaml()}
            for key, value in info.items():
                self._writer.set_custom_data(f'acds.{key}', value)
            try:
                self._writer.close()
                self.info = info
                self._write_run_info()
            except OSError as exc:
                self.error = f'bag {self.path}: closing failed: {exc.strerror or exc}'
            finally:
                self._writer.release()


def publisher_info(node: Any, topic: str) -> tuple[list[str], list[Qos]]:
    """Names and offered QoS of the publishers of ``topic`` that ``node`` has discovered."""
    try:
        infos = node.get_publishers_info_by_topic(topic)
    except Exception:  # noqa: BLE001 (graph introspection is best-effort)
        return [], []
    names = sorted({i.node_name for i in infos})
    qos = []
    for i in infos:
        try:
            q = qos_from_rclpy(i.qos_profile)
        except (ValueError, AttributeError):
            continue
        if q not in qos:
            qos.append(q)
    return names, qos


class RecordingSink:
    """Feeds a :class:`BagWriter` from raw subscription callbacks of ``node`` (monitor or recorder)."""

    def __init__(self, writer: BagWriter, node: Any) -> None:
        self.writer = writer
        self.node = node
        self._seen: set[str] = set()

    def __call__(self, topic: str, data: bytes, t_ns: int | None = None) -> None:
        """One raw message of ``topic`` (absolute name); ``t_ns``: its stamp when the caller has read it already."""
        if topic not in self._seen:
            self._seen.add(topic)
            self.writer.note_publishers(topic, publisher_info(self.node, topic)[0])
        # QoS stored is what the ACDS graph offers (discovery does not convey history depth).
        self.writer.write(topic, data, t_ns=t_ns)

    def close(self) -> None:
        """Refresh who published what, then close the bag."""
        for topic in sorted(self._seen):
            self.writer.note_publishers(topic, publisher_info(self.node, topic)[0])
        self.writer.close()
