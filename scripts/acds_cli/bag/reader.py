"""Read ACDS bags (either storage) with ``rosbags``; recover a bag whose recorder was killed.

A bag without ``metadata.yaml`` was not closed (recorder SIGKILLed, power
lost). :func:`recover_bag` rebuilds it from what reached the disk: every
complete MCAP chunk (read with the ``mcap`` stream reader, which stops at the
first truncated record) or every committed sqlite3 transaction, rewritten
through ``rosbags`` with an index and ``metadata.yaml``. :func:`open_bag`
does this automatically and says so on stderr.
"""

from __future__ import annotations

import shutil
import sqlite3
import sys
from collections.abc import Iterator
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import yaml
from acds_common import topics
from rosbags.rosbag2 import Reader, Writer
from rosbags.rosbag2.errors import ReaderError

from .writer import RUN_INFO_FILE, STORAGES, BagError, qos_from_dicts, typestore

CLOCK = topics.CLOCK


@dataclass
class Bag:
    """A bag read into memory: per-topic raw messages in recorded order, with sim-time stamps."""

    path: Path
    storage: str
    types: dict[str, str]
    #: topic → [(timestamp ns, raw CDR)], in recorded (arrival) order.
    raw: dict[str, list[tuple[int, bytes]]]
    #: The run description (``acds.*`` custom data without the prefix, or the sidecar file).
    info: dict[str, str] = field(default_factory=dict)
    qos: dict[str, list[Any]] = field(default_factory=dict)
    recovered: int | None = None

    def count(self, topic: str) -> int:
        """Number of messages of ``topic`` (relative or absolute name)."""
        return len(self.raw.get(topics.resolve(topic), []))

    def has(self, topic: str) -> bool:
        """Whether the bag holds messages of ``topic``."""
        return self.count(topic) > 0

    def messages(self, topic: str) -> list[tuple[int, Any]]:
        """[(timestamp ns, deserialized message)] of ``topic`` (rosbags message objects)."""
        name = topics.resolve(topic)
        ts = typestore()
        msgtype = self.types.get(name)
        return [(t, ts.deserialize_cdr(d, msgtype)) for t, d in self.raw.get(name, [])]

    def ordered(self, selected: set[str] | None = None) -> list[tuple[int, str, bytes]]:
        """Every message as (timestamp, topic, raw) in sim-time order; at equal times /clock first."""
        items = []
        for topic, msgs in self.raw.items():
            if selected is not None and topic not in selected:
                continue
            rank = 0 if topic == CLOCK else 1
            items.extend((t, rank, i, topic, d) for i, (t, d) in enumerate(msgs))
        items.sort(key=lambda x: (x[0], x[1], x[3], x[2]))
        return [(t, topic, d) for t, _r, _i, topic, d in items]

    def span_ns(self) -> tuple[int, int]:
        """First and last timestamp in the bag (0, 0 when empty)."""
        stamps = [t for msgs in self.raw.values() for t, _ in msgs]
        return (min(stamps), max(stamps)) if stamps else (0, 0)

    @property
    def control_period_ns(self) -> int | None:
        """Δt of the recorded run (from the run info, else from consecutive /clock stamps)."""
        if 'control_period_s' in self.info:
            return round(float(self.info['control_period_s']) * 1e9)
        clock = [t for t, _ in self.raw.get(CLOCK, [])]
        return clock[1] - clock[0] if len(clock) > 1 else None


def _storage_files(path: Path) -> list[Path]:
    return sorted([*path.glob('*.mcap'), *path.glob('*.db3')])


def unfinished(path: Path) -> bool:
    """Whether ``path`` is a bag folder whose recorder never closed it."""
    path = Path(path)
    return path.is_dir() and not (path / 'metadata.yaml').exists() and bool(_storage_files(path))


def _read_info_file(path: Path) -> dict[str, str]:
    f = path / RUN_INFO_FILE
    if not f.exists():
        return {}
    data = yaml.safe_load(f.read_text()) or {}
    return {str(k): str(v) for k, v in data.items()}


def _salvage_mcap(file: Path) -> tuple[list[tuple[str, str, list[Any]]], list[tuple[str, int, bytes]]]:
    from mcap.records import Channel, Message, Schema
    from mcap.stream_reader import StreamReader

    schemas: dict[int, str] = {}
    channels: dict[int, tuple[str, str, list[Any]]] = {}
    msgs: list[tuple[str, int, bytes]] = []
    with file.open('rb') as fh:
        try:
            for rec in StreamReader(fh, skip_magic=False).records:
                if isinstance(rec, Schema):
                    schemas[rec.id] = rec.name
                elif isinstance(rec, Channel):
                    qos = qos_from_dicts(yaml.safe_load(rec.metadata.get('offered_qos_profiles', '[]') or '[]'))
                    channels[rec.id] = (rec.topic, schemas.get(rec.schema_id, ''), qos)
                elif isinstance(rec, Message) and rec.channel_id in channels:
                    msgs.append((channels[rec.channel_id][0], rec.log_time, bytes(rec.data)))
        except Exception:  # noqa: BLE001 (a truncated record ends what reached the disk)
            pass
    return list(channels.values()), msgs


def _salvage_sqlite(file: Path) -> tuple[list[tuple[str, str, list[Any]]], list[tuple[str, int, bytes]]]:
    conn = sqlite3.connect(str(file))  # read-write: rolls back a hot journal of the killed writer
    try:
        rows = conn.execute('SELECT id, name, type, offered_qos_profiles FROM topics ORDER BY id').fetchall()
        names = {r[0]: r[1] for r in rows}
        conns = [(r[1], r[2], qos_from_dicts(yaml.safe_load(r[3] or '[]'))) for r in rows]
        msgs = [(names[tid], ts, bytes(d)) for tid, ts, d in
                conn.execute('SELECT topic_id, timestamp, data FROM messages ORDER BY id') if tid in names]
    finally:
        conn.close()
    return conns, msgs


def recover_bag(path: Path | str) -> int:
    """Rebuild an unclosed bag in place from what reached the disk; return the number of messages kept."""
    path = Path(path)
    files = _storage_files(path)
    if not files:
        raise BagError(f'bag {path}: no .mcap or .db3 storage file in it')
    file = files[0]
    storage = 'mcap' if file.suffix == '.mcap' else 'sqlite3'
    conns, msgs = _salvage_mcap(file) if storage == 'mcap' else _salvage_sqlite(file)
    tmp = path.with_name(path.name + '.recovering')
    if tmp.exists():
        shutil.rmtree(tmp)
    writer = Writer(tmp, version=9, storage_plugin=STORAGES[storage])
    writer.open()
    by_topic = {}
    for topic, msgtype, qos in conns:
        by_topic[topic] = writer.add_connection(topic, msgtype, typestore=typestore(), offered_qos_profiles=qos)
    for topic, t, data in msgs:
        writer.write(by_topic[topic], t, data)
    info = _read_info_file(path)
    for key, value in info.items():
        if key not in ('storage', 'flush_period_s'):
            writer.set_custom_data(f'acds.{key}', value)
    writer.set_custom_data('acds.recovered', f'{len(msgs)} messages from an unclosed bag')
    writer.close()
    for f in path.iterdir():
        if f.name != RUN_INFO_FILE:
            f.unlink()
    for f in tmp.iterdir():
        new = f.name.replace(tmp.name, path.name) if f.name != 'metadata.yaml' else f.name
        f.rename(path / new)
    tmp.rmdir()
    meta = path / 'metadata.yaml'
    meta.write_text(meta.read_text().replace(tmp.name, path.name))
    return len(msgs)


def open_bag(path: Path | str, *, recover: bool = True) -> Bag:
    """Read a whole bag (MCAP or sqlite3) into memory; recover it first if it was never closed."""
    path = Path(path)
    if not path.exists():
        raise BagError(f'bag {path}: no such file or folder')
    if path.is_file():  # a storage file given directly: its folder is the bag
        path = path.parent
    recovered = None
    if unfinished(path):
        if not recover:
            raise BagError(f'bag {path}: was never closed (recorder killed?); open it with recovery')
        recovered = recover_bag(path)
        print(f'[acds] bag {path} was not closed (recorder killed?): recovered {recovered} messages '
              f'up to its last flushed chunk', file=sys.stderr)
    try:
        reader = Reader(path)
        reader.open()
    except (ReaderError, OSError) as exc:
        raise BagError(f'bag {path}: cannot read it: {exc}') from None
    try:
        types = {c.topic: c.msgtype for c in reader.connections}
        qos = {c.topic: list(c.ext.offered_qos_profiles) for c in reader.connections}
        raw: dict[str, list[tuple[int, bytes]]] = {t: [] for t in types}
        for conn, t, data in reader.messages():
            raw[conn.topic].append((t, bytes(data)))
        meta = getattr(reader.storage, 'metadata', None)  # the directory reader's parsed metadata.yaml
        custom = (meta.get('custom') if isinstance(meta, dict) else getattr(meta, 'custom', None)) or {}
    finally:
        reader.close()
    info = {k.removeprefix('acds.'): v for k, v in custom.items() if k.startswith('acds.')} or _read_info_file(path)
    info.pop('storage', None)
    files = _storage_files(path)
    storage = ('sqlite3' if files[0].suffix == '.db3' else 'mcap') if files else ''
    return Bag(path, storage, types, raw, info, qos, recovered)


def iter_fields(msg: Any, prefix: str = '') -> Iterator[tuple[str, Any]]:
    """(dotted field path, leaf value) of a rosbags message object, arrays element by element."""
    import numpy as np

    if hasattr(msg, '__dataclass_fields__'):
        for name in msg.__dataclass_fields__:
            if name == '__msgtype__':
                continue
            yield from iter_fields(getattr(msg, name), f'{prefix}.{name}' if prefix else name)
    elif isinstance(msg, (list, tuple)) or isinstance(msg, np.ndarray):
        for i, v in enumerate(msg):
            yield from iter_fields(v, f'{prefix}[{i}]')
    else:
        yield prefix, msg
