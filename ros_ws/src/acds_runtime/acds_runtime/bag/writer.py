"""Write a rosbag2 bag (version 9) of raw CDR messages, with sim-time stamps and a flush policy.

Flush policy (what survives a SIGKILL): messages are buffered in the current
MCAP chunk (sqlite3: the current transaction) and made durable at most
:data:`FLUSH_PERIOD_S` wall seconds after they arrive: the writer closes the
chunk and flushes the file (sqlite3: commits) on the first message after the
period elapsed, when a chunk reaches 1 MiB, every :data:`FLUSH_MESSAGES`
messages, and on :meth:`BagWriter.flush`. A killed recorder therefore loses
at most the last second of messages; the bag it leaves has no index and no
``metadata.yaml``: :func:`acds_cli.bag.reader.open_bag` reads it, without
changing it, up to its last complete chunk, and
:func:`acds_cli.bag.recover.recover_bag` writes a repaired copy (the
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
from pathlib import Path
from typing import Any

import yaml
from acds_common import topics
from acds_common.parameters import NoAliasDumper
from rosbags.interfaces import Qos, QosDurability, QosHistory, QosLiveliness, QosReliability, QosTime
from rosbags.rosbag2 import StoragePlugin, Writer
from rosbags.typesys import Stores, get_typestore

from .recording import RecordingLock

#: Wall seconds after which buffered messages are made durable.
FLUSH_PERIOD_S = 1.0
#: ... or after this many messages, whichever comes first.
FLUSH_MESSAGES = 2000
#: Free space a bag needs before the run starts.
MIN_FREE_BYTES = 64 * 2**20
#: The sidecar with the run's scenario and parameters, written when recording starts.
RUN_INFO_FILE = 'acds_run.yaml'
STORAGES = {'mcap': StoragePlugin.MCAP, 'sqlite3': StoragePlugin.SQLITE3}
#: Topics never recorded (lockstep handshake plumbing).
SKIP = {topics.resolve(topics.READY), topics.resolve(topics.MONITOR_ACK)}
#: Absolute topic name → message type.
ABS_TYPES = {topics.resolve(t): ty for t, ty in topics.TYPES.items()}

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


def check_target(path: Path, storage: str = 'mcap') -> None:
    """Fail with a one-line :class:`BagError` if a bag cannot be written at ``path``."""
    path = Path(path)
    if storage not in STORAGES:
        raise BagError(f'bag {path}: unknown storage {storage!r} (choose {", ".join(STORAGES)})')
    if path.exists():
        raise BagError(f'bag {path}: already exists, not overwriting (choose a new path)')
    parent = writable_parent(path, 'bag')
    free = shutil.disk_usage(parent).free
    if free < MIN_FREE_BYTES:
        raise BagError(f'bag {path}: only {free / 2**20:.1f} MiB free on the disk of {parent} '
                       f'(a bag needs at least {MIN_FREE_BYTES / 2**20:.0f} MiB)')


def run_info(scenario: Any, steps: int, params: dict[str, Any] | None = None,
             domain_id: int | None = None) -> dict[str, str]:
    """The run description stored with a bag (all values are strings, as custom_data requires)."""
    info = {
        'scenario_name': scenario.name,
        'scenario': yaml.safe_dump(scenario.raw, sort_keys=False),
        'control_period_s': repr(scenario.control_period_s),
        'steps': str(steps),
        'nodes': ','.join(scenario.get('', 'nodes')),
    }
    if params is not None:
        info['params'] = yaml.dump(params, Dumper=NoAliasDumper, sort_keys=True)
    if domain_id is not None:
        info['domain_id'] = str(domain_id)
    return info


class _LockedWriter(Writer):
    """The rosbags writer, holding the folder's recording lock from before the storage file exists."""

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
                 flush_period_s: float = FLUSH_PERIOD_S) -> None:
        self.path = Path(path)
        self.storage = storage
        check_target(self.path, storage)
        self.flush_period_s = flush_period_s
        self._lock = threading.Lock()
        self._writer = _LockedWriter(self.path, version=9, storage_plugin=STORAGES[storage])
        self.info = dict(info or {})
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
            if storage == 'sqlite3':  # written from the subscriber's thread, not the one that opened it
                st = self._writer.storage
                st.conn.commit()
                st.conn.close()
                st.conn = sqlite3.connect(f'file:{st.path}', uri=True, check_same_thread=False)
                st.cursor = st.conn.cursor()
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
        """The sidecar, replaced atomically (a crash never leaves half of it); publishers as known so far."""
        info = dict(self.info)
        if self.publishers:
            info['publishers'] = self._publishers_yaml()
        tmp = self.path / f'{RUN_INFO_FILE}.tmp'
        tmp.write_text(yaml.safe_dump({'storage': self.storage, 'flush_period_s': self.flush_period_s, **info},
                                      sort_keys=False))
        tmp.replace(self.path / RUN_INFO_FILE)

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
                    msgtype = msgtype or ABS_TYPES[topic]
                    conn = self._writer.add_connection(topic, msgtype, typestore=typestore(),
                                                       offered_qos_profiles=qos or [offered_qos(topic)])
                    self._conns[topic] = conn
                    self._stamped[topic] = stamped(msgtype)
                    self.counts[topic] = 0
                if t_ns is None and self._stamped[topic]:
                    t_ns = cdr_stamp_ns(data)
                    if topic == topics.CLOCK:
                        self.last_clock_ns = max(self.last_clock_ns, t_ns)
                elif t_ns is None:
                    t_ns = self.last_clock_ns
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
        if self.storage == 'mcap':
            if storage.chunk.msgs:
                storage.close_chunk()
            storage.bio.flush()
        else:
            storage.conn.commit()
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

    def __call__(self, topic: str, data: bytes) -> None:
        """One raw message of ``topic`` (absolute name)."""
        if topic not in self._seen:
            self._seen.add(topic)
            self.writer.note_publishers(topic, publisher_info(self.node, topic)[0])
        # QoS stored is what the ACDS graph offers (discovery does not convey history depth).
        self.writer.write(topic, data)

    def close(self) -> None:
        """Refresh who published what, then close the bag."""
        for topic in sorted(self._seen):
            self.writer.note_publishers(topic, publisher_info(self.node, topic)[0])
        self.writer.close()
