"""Read ACDS bags (either storage) strictly read-only, streaming messages from the storage.

:func:`open_bag` never creates, renames, truncates or deletes a file and never
opens a storage file for writing. It reads the bag's description (topics,
types, QoS, counts, the run's ``acds.*`` data) and returns a :class:`Bag` whose
messages are streamed from the storage on each iteration, in timestamp order
(equal times: recorded order), so no verb holds a whole bag in memory.

- A closed bag (``metadata.yaml``) is read with ``rosbags``; its messages, when it is one indexed MCAP
  file (what the recorder and ``ros2 bag record`` write), from the chunk index (:mod:`.indexed_mcap`:
  the same messages in the same order, ~4× faster).
- A bag being recorded (no ``metadata.yaml``, its writer's recording lock held,
  :mod:`.recording`) is refused with one line: reading it would
  race its writer.
- An unclosed bag (no ``metadata.yaml``, lock free: the recorder died) is read
  as far as it is readable (:mod:`.salvage`): MCAP up to its last
  complete chunk, sqlite3 up to its last committed transaction; the run data
  comes from the sidecar ``acds_run.yaml``. One line says so;
  :func:`.recover.recover_bag` writes a repaired copy.
- Anything else (random bytes named ``.mcap``, an empty file, a folder without
  storage, a truncated ``metadata.yaml``) is a :class:`BagError` of one line
  naming the path and what is wrong.
"""

from __future__ import annotations

import sys
from collections.abc import Callable, Iterable, Iterator
from contextlib import closing
from dataclasses import dataclass, field
from itertools import islice
from pathlib import Path
from typing import Any

import yaml
from acds_common import topics
from rosbags.rosbag2 import Reader

from .indexed_mcap import IndexedMcap, indexed
from .recording import LOCK_FILE, being_recorded
from .salvage import UnclosedMcap, committed_view
from .writer import RUN_INFO_FILE, BagError

CLOCK = topics.CLOCK
#: Storage file suffix → rosbag2 storage name.
STORAGE_SUFFIXES = {'.mcap': 'mcap', '.db3': 'sqlite3'}


def _one_line(exc: BaseException) -> str:
    text = ' '.join(str(exc).split())
    return f'{type(exc).__name__}: {text}' if text else type(exc).__name__


@dataclass(frozen=True)
class TopicStats:
    """Messages of one topic: how many, first and last timestamp (ns)."""

    count: int
    first_ns: int
    last_ns: int


class _Rosbags:
    """Messages through ``rosbags``: a closed bag folder, or the committed view of an unclosed sqlite3 file."""

    def __init__(self, target: Any) -> None:
        self.target = target

    def messages(self, names: set[str] | None) -> Iterator[tuple[str, int, bytes]]:
        with Reader(self.target) as reader:
            conns = [c for c in reader.connections if names is None or c.topic in names]
            if conns:  # an empty selection would mean "everything" to rosbags
                for conn, t, data in reader.messages(connections=conns):
                    yield conn.topic, t, bytes(data)


@dataclass
class Bag:
    """A bag's description, and its messages streamed from the storage on demand (never all in memory)."""

    #: The bag folder (where the storage file is).
    path: Path
    storage: str
    #: The storage files read.
    files: list[Path]
    types: dict[str, str]
    qos: dict[str, list[Any]]
    counts: dict[str, int]
    #: The run description (``acds.*`` custom data without the prefix, or the sidecar file).
    info: dict[str, str] = field(default_factory=dict)
    #: How an unclosed bag was read (e.g. "up to its last complete chunk"); None for a closed bag.
    unclosed: str | None = None
    source: Any = field(default=None, repr=False)
    _stats: dict[str, TopicStats] | None = field(default=None, repr=False)

    def scenario(self) -> Any:
        """The recorded run's scenario (:class:`acds_common.scenario.Scenario`, from the merged YAML the writer
        stored), or None when the bag holds none. A stored scenario that no longer loads is a BagError."""
        import os
        import tempfile

        from acds_common.scenario import ScenarioError, load_scenario

        text = self.info.get('scenario')
        if not text:
            return None
        with tempfile.NamedTemporaryFile('w', suffix='.yaml', delete=False) as fh:
            fh.write(text)
        try:
            return load_scenario(fh.name)
        except ScenarioError as exc:
            raise BagError(f'bag {self.path}: its recorded scenario does not load: {exc}') from None
        finally:
            os.unlink(fh.name)

    def count(self, topic: str) -> int:
        """Number of messages of ``topic`` (relative or absolute name)."""
        return self.counts.get(topics.resolve(topic), 0)

    def has(self, topic: str) -> bool:
        """Whether the bag holds messages of ``topic``."""
        return self.count(topic) > 0

    @property
    def total(self) -> int:
        """Number of messages in the bag."""
        return sum(self.counts.values())

    def messages(self, selected: Iterable[str] | None = None) -> Iterator[tuple[str, int, bytes]]:
        """(absolute topic, timestamp ns, raw CDR) of the ``selected`` topics (all by default), streamed in
        timestamp order, at equal times in recorded order."""
        names = None if selected is None else {topics.resolve(t) for t in selected}
        try:
            yield from self.source.messages(names)
        except BagError:
            raise
        except Exception as exc:  # noqa: BLE001 (a storage error while streaming: one line naming the bag)
            raise BagError(f'bag {self.path}: reading its messages failed: {_one_line(exc)}') from None

    def ordered(self, selected: Iterable[str] | None = None) -> Iterator[tuple[int, list[tuple[str, bytes]]]]:
        """The messages grouped by timestamp, streamed: (t_ns, [(topic, raw), ...]); in a group /clock first,
        then by topic name, each topic in recorded order."""
        group_t: int | None = None
        items: list[tuple[str, bytes]] = []
        for topic, t, data in self.messages(selected):
            if t != group_t and items:
                yield group_t, sorted(items, key=_group_rank)  # type: ignore[misc]
                items = []
            group_t = t
            items.append((topic, data))
        if items:
            yield group_t, sorted(items, key=_group_rank)  # type: ignore[misc]

    def first(self, topic: str, n: int) -> list[tuple[int, bytes]]:
        """The first ``n`` (timestamp ns, raw) of ``topic`` (stops reading there)."""
        with closing(self.messages([topic])) as stream:
            return [(t, d) for _, t, d in islice(stream, n)]

    def stats(self) -> dict[str, TopicStats]:
        """Per topic with messages: count, first and last timestamp (one streaming pass, then kept)."""
        if self._stats is None:
            acc: dict[str, list[int]] = {}
            for topic, t, _ in self.messages():
                a = acc.get(topic)
                if a is None:
                    acc[topic] = [1, t, t]
                else:
                    a[0] += 1
                    a[1] = min(a[1], t)
                    a[2] = max(a[2], t)
            self._stats = {topic: TopicStats(*a) for topic, a in acc.items()}
        return self._stats

    def span_ns(self) -> tuple[int, int]:
        """First and last timestamp in the bag (0, 0 when empty)."""
        stats = self.stats().values()
        return (min(s.first_ns for s in stats), max(s.last_ns for s in stats)) if stats else (0, 0)

    @property
    def control_period_ns(self) -> int | None:
        """Δt of the recorded run (from the run info, else from the first two /clock stamps)."""
        if 'control_period_s' in self.info:
            return round(float(self.info['control_period_s']) * 1e9)
        clock = [t for t, _ in self.first(CLOCK, 2)]
        return clock[1] - clock[0] if len(clock) > 1 else None


def _group_rank(item: tuple[str, bytes]) -> tuple[bool, str]:
    return item[0] != CLOCK, item[0]


def _storage_files(folder: Path) -> list[Path]:
    return sorted([*folder.glob('*.mcap'), *folder.glob('*.db3')])


def unfinished(path: Path | str) -> bool:
    """Whether ``path`` is a bag folder whose recorder never closed it (a storage file, no ``metadata.yaml``)."""
    path = Path(path)
    return path.is_dir() and not (path / 'metadata.yaml').exists() and bool(_storage_files(path))


def _read_info_file(folder: Path) -> dict[str, str]:
    """The sidecar's run description ({} when absent or unreadable: the messages are still readable)."""
    try:
        data = yaml.safe_load((folder / RUN_INFO_FILE).read_text())
    except (OSError, UnicodeDecodeError, yaml.YAMLError):
        return {}
    return {str(k): str(v) for k, v in data.items()} if isinstance(data, dict) else {}


def _locate(path: Path, use_metadata: bool) -> tuple[Path, Path | None]:
    """(bag folder, storage file to read directly, or None to read the folder through its metadata.yaml)."""
    if not path.exists():
        raise BagError(f'bag {path}: no such file or folder')
    if path.is_file():
        if path.name == 'metadata.yaml':
            return _locate(path.parent, use_metadata)
        if path.suffix not in STORAGE_SUFFIXES:
            raise BagError(f'bag {path}: not a bag (expected a bag folder, or its .mcap or .db3 storage file)')
        if path.stat().st_size == 0:
            raise BagError(f'bag {path}: empty file (0 bytes): no bag was ever written to it')
        if use_metadata and (path.parent / 'metadata.yaml').exists():
            return path.parent, None
        return path.parent, path
    if not path.is_dir():
        raise BagError(f'bag {path}: not a file or a folder')
    if use_metadata and (path / 'metadata.yaml').exists():
        return path, None
    files = _storage_files(path)
    if not files:
        raise BagError(f'bag {path}: not a bag (no metadata.yaml and no .mcap or .db3 storage file in it)')
    if len(files) > 1:
        raise BagError(f'bag {path}: {len(files)} storage files and no metadata.yaml: give the one to read')
    return _locate(files[0], use_metadata=False)


def _check_metadata(folder: Path) -> dict[str, Any]:
    """The rosbag2_bagfile_information of a bag's metadata.yaml; one line for a metadata.yaml that is not rosbag2
    metadata (truncated, edited, foreign)."""
    meta = folder / 'metadata.yaml'
    try:
        data = yaml.safe_load(meta.read_text())
    except OSError as exc:
        raise BagError(f'bag {folder}: cannot read its metadata.yaml: {exc.strerror or exc}') from None
    except UnicodeDecodeError:
        raise BagError(f'bag {folder}: its metadata.yaml is not text') from None
    except yaml.YAMLError as exc:
        mark = getattr(exc, 'problem_mark', None)
        where = f' at line {mark.line + 1}' if mark is not None else ''
        problem = getattr(exc, 'problem', None) or 'invalid YAML'
        raise BagError(f'bag {folder}: its metadata.yaml is not valid YAML (truncated?): {problem}{where}') from None
    info = data.get('rosbag2_bagfile_information') if isinstance(data, dict) else None
    if not isinstance(info, dict):
        raise BagError(f'bag {folder}: its metadata.yaml has no rosbag2_bagfile_information (truncated or not a bag)')
    missing = [k for k in ('version', 'storage_identifier', 'relative_file_paths', 'topics_with_message_count',
                           'duration', 'starting_time', 'message_count') if k not in info]
    if missing:
        raise BagError(f'bag {folder}: its metadata.yaml lacks {", ".join(missing)} (truncated?)')
    return info


def _describe(target: Any) -> tuple[dict[str, str], dict[str, list[Any]], dict[str, int], dict[str, str]]:
    """(types, offered QoS, message counts) per topic and the custom data, as rosbags reads them."""
    with Reader(target) as reader:  # the reader's connection list is emptied when it closes: copy inside
        conns = list(reader.connections)
        custom = dict(reader.storage.metadata.custom or {})  # type: ignore[attr-defined]
    return ({c.topic: c.msgtype for c in conns}, {c.topic: list(c.ext.offered_qos_profiles) for c in conns},
            {c.topic: c.msgcount for c in conns}, custom)


def _stderr_note(text: str) -> None:
    print(f'[acds] {text}', file=sys.stderr, flush=True)


def open_bag(path: Path | str, *, use_metadata: bool = True, note: Callable[[str], None] | None = None) -> Bag:
    """Open a bag read-only: a bag folder, or its storage file (MCAP or sqlite3).

    ``use_metadata=False`` reads the storage file even when ``metadata.yaml`` exists (how a repair reads).
    ``note`` receives the one line saying that an unclosed bag was read (default: stderr; not with
    ``use_metadata=False``, whose caller reports what it read).
    Raises :class:`BagError` (one line) for a bag being recorded and for anything that is not a readable bag.
    """
    note = note or _stderr_note
    path = Path(path)
    near = path if path.is_dir() else path.parent  # checked first: a fresh recording's file may still be empty
    if being_recorded(near):
        raise BagError(f'bag {near}: is being recorded (its writer holds {LOCK_FILE}); '
                       f'read it once the recording has ended')
    folder, file = _locate(path, use_metadata)
    if file is None:
        return _open_closed(folder)
    state = 'was not closed (no metadata.yaml: its recorder died?)'
    if file.suffix == '.mcap':
        try:
            source: Any = UnclosedMcap(file)
        except OSError as exc:
            raise BagError(f'bag {file}: cannot read it: {exc.strerror or exc}') from None
        types = {topic: ty for topic, ty, _ in source.channels.values()}
        qos = {topic: q for topic, _, q in source.channels.values()}
        counts = {t: source.counts.get(t, 0) for t in types}
        unclosed = 'up to its last complete chunk'
        if source.complete:
            state, unclosed = 'has no metadata.yaml', 'to its end (a complete MCAP file)'
    else:
        try:
            target, rolled_back = committed_view(file)
            types, qos, counts, _ = _describe(target)
        except Exception as exc:  # noqa: BLE001 (apsw / rosbags errors on a foreign or damaged file)
            raise BagError(f'bag {file}: not a readable sqlite3 bag ({_one_line(exc)})') from None
        source = _Rosbags(target)
        unclosed = 'up to its last committed transaction' + (
            ' (the interrupted one left out, from its journal)' if rolled_back else '')
    info = _read_info_file(folder)
    info.pop('storage', None)
    bag = Bag(folder, STORAGE_SUFFIXES[file.suffix], [file], types, qos, counts, info, unclosed, source)
    if use_metadata:
        note(f'bag {folder} {state}: read {unclosed}, {bag.total} messages, without changing it; '
             f'`acds recover {folder} DEST` writes a repaired copy')
    return bag


def _open_closed(folder: Path) -> Bag:
    names = _check_metadata(folder)['relative_file_paths']
    listed = [folder / n for n in names] if isinstance(names, list) and all(isinstance(n, str) for n in names) else []
    try:
        types, qos, counts, custom = _describe(folder)
    except Exception as exc:  # noqa: BLE001 (rosbags, apsw and OS errors: one line naming the bag)
        raise BagError(f'bag {folder}: cannot read it: {_one_line(exc)}') from None
    info = {k.removeprefix('acds.'): v for k, v in custom.items() if k.startswith('acds.')} or _read_info_file(folder)
    info.pop('storage', None)
    files = _storage_files(folder)
    storage = STORAGE_SUFFIXES[files[0].suffix] if files else ''
    one = listed[0] if len(listed) == 1 and listed == files and listed[0].suffix == '.mcap' else None
    source = IndexedMcap(one) if one is not None and indexed(one) else _Rosbags(folder)
    return Bag(folder, storage, files, types, qos, counts, info, None, source)


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
