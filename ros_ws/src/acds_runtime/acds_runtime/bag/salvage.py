"""Read the storage file of an unclosed bag (no ``metadata.yaml``: its recorder died) without writing anything.

MCAP (:class:`UnclosedMcap`): the writer makes a chunk durable as a whole, so
what a killed recorder leaves is a run of complete chunks, maybe followed by a
truncated record. A first pass reads the records in file order up to the first
incomplete one, noting the channels and each chunk's earliest timestamp; the
messages are then streamed in timestamp order (equal times: in recorded order)
by merging the chunks as the file is read again, holding only the chunks whose
time range is still open (what the rosbags reader does with an index).

sqlite3 (:func:`committed_view`): a writer killed inside a transaction leaves a
hot rollback journal, and the database file may already hold pages of the
transaction that never committed. Opening it read-write would roll it back —
a write. Instead the original pages are taken from the journal (SQLite file
format, "The Rollback Journal") and laid over the database file in a
read-only view, which rosbags then opens ``immutable``: the committed
transactions, exactly, and nothing on disk changes.
"""

from __future__ import annotations

import heapq
import itertools
import struct
from collections.abc import Collection, Iterator
from dataclasses import dataclass, field
from pathlib import Path
from types import SimpleNamespace
from typing import Any, BinaryIO

import yaml

from .writer import BagError, qos_from_dicts

MCAP_MAGIC = b'\x89MCAP0\r\n'
JOURNAL_MAGIC = bytes((0xD9, 0xD5, 0x05, 0xF9, 0x20, 0xA1, 0x63, 0xD7))


class _Truncated(Exception):
    """A record runs past the end of the file (the part the killed writer never finished)."""


class _Exact:
    """A read-only file view that refuses reads past the end (a truncated record) instead of returning less."""

    def __init__(self, fh: BinaryIO, size: int) -> None:
        self.fh = fh
        self.size = size

    def read(self, n: int) -> bytes:
        if n > self.size - self.fh.tell():
            raise _Truncated
        return self.fh.read(n)


@dataclass
class UnclosedMcap:
    """The complete chunks of an MCAP file that was never finished, read-only, streamed in timestamp order."""

    file: Path
    #: channel id → (topic, message type, offered QoS)
    channels: dict[int, tuple[str, str, list[Any]]] = field(default_factory=dict)
    counts: dict[str, int] = field(default_factory=dict)
    #: Earliest timestamp of each complete chunk (or chunk-less message), in file order.
    starts: list[int] = field(default_factory=list)
    #: Whether the file ends with its footer (it is complete; only ``metadata.yaml`` is missing).
    complete: bool = False

    def __post_init__(self) -> None:
        for start, msgs in self._groups():
            self.starts.append(start)
            for msg in msgs:
                topic = self.channels[msg.channel_id][0]
                self.counts[topic] = self.counts.get(topic, 0) + 1

    def _groups(self) -> Iterator[tuple[int, list[Any]]]:
        """(earliest timestamp, messages) of each complete chunk in file order; registers the channels."""
        from mcap.exceptions import UnsupportedCompressionError
        from mcap.records import Channel, Chunk, Footer, Header, Message, Schema
        from mcap.stream_reader import StreamReader, breakup_chunk

        schemas: dict[int, str] = {}
        channels: dict[int, tuple[str, str, list[Any]]] = {}
        with self.file.open('rb') as fh:
            size = self.file.stat().st_size
            if fh.read(8) != MCAP_MAGIC:
                raise BagError(f'bag {self.file}: not an MCAP file (it does not start with the MCAP magic bytes)')
            records = iter(StreamReader(_Exact(fh, size), skip_magic=True, emit_chunks=True,  # type: ignore[arg-type]
                                        record_size_limit=size).records)
            first = True
            while True:
                try:
                    rec = next(records)
                    contents = breakup_chunk(rec) if isinstance(rec, Chunk) else [rec]
                except StopIteration:
                    return
                except UnsupportedCompressionError as exc:
                    raise BagError(f'bag {self.file}: its chunks use a compression this reader lacks ({exc})') from None
                except Exception as exc:  # noqa: BLE001 (a truncated or torn record: what reached the disk ends here)
                    if first:
                        why = 'is cut off' if isinstance(exc, _Truncated) else f'is unreadable ({type(exc).__name__})'
                        raise BagError(f'bag {self.file}: not a readable MCAP file (its first record {why})') from None
                    return
                if first and not (isinstance(rec, Header) and rec.profile == 'ros2'):
                    raise BagError(f'bag {self.file}: not an MCAP file of ROS 2 messages (no "ros2" header record)')
                first = False
                msgs = []
                for item in contents:
                    if isinstance(item, Schema):
                        schemas[item.id] = item.name
                    elif isinstance(item, Channel):
                        qos = yaml.safe_load(item.metadata.get('offered_qos_profiles', '') or '[]')
                        channels[item.id] = (item.topic, schemas.get(item.schema_id, ''), qos_from_dicts(qos))
                        self.channels[item.id] = channels[item.id]
                    elif isinstance(item, Message) and item.channel_id in channels:
                        msgs.append(item)
                if isinstance(rec, Footer):
                    self.complete = True
                    return
                if msgs:
                    yield rec.message_start_time if isinstance(rec, Chunk) else msgs[0].log_time, msgs

    def messages(self, topics: Collection[str] | None = None) -> Iterator[tuple[str, int, bytes]]:
        """(topic, timestamp ns, raw CDR) in timestamp order; at equal times in recorded order."""
        wanted = {cid for cid, (topic, _, _) in self.channels.items() if topics is None or topic in topics}
        if not wanted:
            return
        # earliest start of group i and every later one: anything in the heap at or before it is final
        later = list(itertools.accumulate(reversed(self.starts), min))[::-1] + [2**63]
        heap: list[tuple[int, int, int, str, bytes]] = []
        for i, (_start, msgs) in enumerate(itertools.islice(self._groups(), len(self.starts))):
            while heap and heap[0][0] <= later[i]:
                t, _, _, topic, data = heapq.heappop(heap)
                yield topic, t, data
            for j, msg in enumerate(msgs):
                if msg.channel_id in wanted:
                    heapq.heappush(heap, (msg.log_time, i, j, self.channels[msg.channel_id][0], bytes(msg.data)))
        while heap:
            t, _, _, topic, data = heapq.heappop(heap)
            yield topic, t, data


def _journal_pages(journal: Path) -> tuple[int, int, dict[int, bytes]] | None:
    """(database size in pages before the transaction, page size, {page number: original page}) of a hot journal.

    None when there is nothing to roll back (no journal, or a zeroed / foreign header).
    Records are taken while their checksums hold (SQLite stops its playback there too).
    """
    try:
        data = journal.read_bytes()
    except FileNotFoundError:
        return None
    if len(data) < 28 or data[:8] != JOURNAL_MAGIC:
        return None
    pages: dict[int, bytes] = {}
    _, _, db_pages, sector, page_size = struct.unpack_from('>iIIII', data, 8)
    if page_size < 512 or sector < 28:
        return None
    offset = 0
    while offset + 28 <= len(data) and data[offset:offset + 8] == JOURNAL_MAGIC:
        n_rec, nonce = struct.unpack_from('>iI', data, offset + 8)
        rec = offset + sector
        if n_rec < 0:  # -1: every record up to the end of the file
            n_rec = (len(data) - rec) // (page_size + 8)
        for _ in range(n_rec):
            if rec + page_size + 8 > len(data):
                return db_pages, page_size, pages
            (pgno,) = struct.unpack_from('>I', data, rec)
            page = data[rec + 4:rec + 4 + page_size]
            (checksum,) = struct.unpack_from('>I', data, rec + 4 + page_size)
            if (nonce + sum(page[page_size - 200::-200])) & 0xFFFFFFFF != checksum:
                return db_pages, page_size, pages
            if pgno <= db_pages:
                pages.setdefault(pgno, page)  # the first copy of a page is its content before the transaction
            rec += page_size + 8
        if n_rec == 0:
            break
        offset = -(-rec // sector) * sector  # the next segment's header starts on a sector boundary
    return db_pages, page_size, pages


class _CommittedView:
    """A read-only path-like (the rosbags ``RPath`` protocol) of a database with its journal's pages put back."""

    suffix = '.db3'

    def __init__(self, db: Path, db_pages: int, page_size: int, pages: dict[int, bytes]) -> None:
        self.db = db
        self.name = db.name
        self.page_size = page_size
        self.pages = pages
        self.size = db_pages * page_size

    def __str__(self) -> str:
        return str(self.db)

    def exists(self) -> bool:
        return True

    def is_dir(self) -> bool:
        return False

    def stat(self, **_kwargs: Any) -> SimpleNamespace:
        return SimpleNamespace(st_size=self.size)

    def open(self, *_args: Any, **_kwargs: Any) -> _CommittedFile:
        return _CommittedFile(self)


class _CommittedFile:
    """Reads of :class:`_CommittedView`: journal pages where the journal has them, else the database file."""

    def __init__(self, view: _CommittedView) -> None:
        self.view = view
        self.fh = view.db.open('rb')
        self.pos = 0

    def seek(self, pos: int, whence: int = 0) -> int:
        self.pos = pos if whence == 0 else self.pos + pos if whence == 1 else self.view.size + pos
        return self.pos

    def read(self, n: int = -1) -> bytes:
        view = self.view
        end = view.size if n < 0 else min(self.pos + n, view.size)
        out = bytearray()
        while self.pos < end:
            index, skip = divmod(self.pos, view.page_size)
            take = min(view.page_size - skip, end - self.pos)
            page = view.pages.get(index + 1)
            if page is None:
                self.fh.seek(self.pos)
                piece = self.fh.read(take)
            else:
                piece = page[skip:skip + take]
            if not piece:
                break
            out += piece
            self.pos += len(piece)
        return bytes(out)

    def close(self) -> None:
        self.fh.close()


def committed_view(db: Path) -> tuple[Path | _CommittedView, bool]:
    """What rosbags should open for an unclosed sqlite3 storage file, and whether a transaction was rolled back.

    The file itself when there is no hot journal; else a read-only view with the
    interrupted transaction's pages restored from ``DB-journal``.
    """
    found = _journal_pages(db.with_name(db.name + '-journal'))
    if found is None:
        return db, False
    return _CommittedView(db, *found), True
