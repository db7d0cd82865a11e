"""A study's journal: each finished sample appended and fsynced as it completes, so no interruption loses it (issue 24 §3).

``samples.jsonl`` in the study's output folder. Its first line is the study (``{"study": {...}}``: the
verb, scenario(s), seed, number of samples, draws, engine, run length, and a hash over every sample's
scenario text); each later line is one finished sample, ``{"index", "case", "scenario_hash", "summary"}``
(``case`` the scenario of a paired study's sample, '' in ``montecarlo``; ``scenario_hash`` the SHA-256 of
the sample's scenario YAML). Every line is written whole with one ``write`` and ``fsync``ed before the next
sample is counted, so a Ctrl-C, a closed terminal, SIGKILL or a full disk keeps every sample finished
before it; a line cut short by SIGKILL mid-write is dropped (and cut off) when the study resumes.

A resumed study (``--resume DIR``) is checked against its journal: the same study, key by key (a
mismatch names the key, :class:`JournalError`), and each kept sample's scenario hash against the sample
drawn now. The final outputs are built from the journal's summaries (JSON round trip: non-finite numbers
as null, :func:`acds_runtime.summary.summary_json`) in a clean run too, so a resumed study's outputs are
those of an uninterrupted one. The summaries stay on disk (:class:`KeptSummaries`: where each sample's line is,
read back when asked), so a study's memory does not grow with its samples.
"""

from __future__ import annotations

import hashlib
import json
import os
from collections.abc import Iterable, Iterator, MutableMapping
from pathlib import Path
from typing import Any

from .summary import summary_json

#: The journal's file name in the study's output folder.
JOURNAL = 'samples.jsonl'


class JournalError(ValueError):
    """The journal cannot be used for this study (another study's, unreadable, a sample drawn differently)."""


def text_hash(text: str) -> str:
    """SHA-256 (hex) of a sample's scenario YAML."""
    return hashlib.sha256(text.encode()).hexdigest()


def samples_hash(hashes: Iterable[str]) -> str:
    """One hash over the study's sample hashes in order: equal iff every sample is drawn the same."""
    h = hashlib.sha256()
    for one in hashes:
        h.update(one.encode())
    return h.hexdigest()


def _line(obj: Any) -> bytes:
    return summary_json(obj, indent=None)[0].encode()


#: Where a kept sample's record is in the journal: (byte offset, length, whether its summary is a failure).
Where = tuple[int, int, bool]


class KeptSummaries(MutableMapping[tuple[str, int], dict[str, Any]]):
    """The kept samples' summaries by (case, index), read from the journal when asked: held in memory is only where
    each record is (:data:`Where`, ~100 bytes a sample), not the summary (~2 kB), so a study of N samples does not
    hold N summaries. Removing a key forgets the record (the line stays in the file)."""

    def __init__(self, path: Path) -> None:
        self.path = path
        self.where: dict[tuple[str, int], Where] = {}

    def __getitem__(self, key: tuple[str, int]) -> dict[str, Any]:
        offset, length, _failed = self.where[key]
        fd = os.open(self.path, os.O_RDONLY)
        try:
            line = os.pread(fd, length, offset)
        finally:
            os.close(fd)
        return json.loads(line)['summary']

    def __setitem__(self, key: tuple[str, int], where: Where) -> None:  # type: ignore[override]
        self.where[key] = where

    def __delitem__(self, key: tuple[str, int]) -> None:
        del self.where[key]

    def __iter__(self) -> Iterator[tuple[str, int]]:
        return iter(self.where)

    def __len__(self) -> int:
        return len(self.where)

    def __contains__(self, key: object) -> bool:
        return key in self.where

    def failed(self, key: tuple[str, int]) -> bool:
        """Whether the kept summary of ``key`` is a failure (``{'scenario', 'error'}``), without reading it."""
        return self.where[key][2]


class Journal:
    """The open journal of one study (module doc). ``done[(case, index)]`` gives the kept summaries
    (:class:`KeptSummaries`, read from the file)."""

    def __init__(self, folder: Path, study: dict[str, Any], hashes: dict[tuple[str, int], str], *,
                 resume: bool) -> None:
        self.path = Path(folder) / JOURNAL
        self.study = json.loads(_line(study))
        self.hashes = hashes
        self.done = KeptSummaries(self.path)
        if resume:
            self._size = self._load()
            self._fd = os.open(self.path, os.O_WRONLY | os.O_APPEND)
        else:
            Path(folder).mkdir(parents=True, exist_ok=True)
            try:
                self._fd = os.open(self.path, os.O_WRONLY | os.O_APPEND | os.O_CREAT | os.O_EXCL, 0o644)
            except FileExistsError:
                raise JournalError(f'{self.path} exists: resume that study with --resume {folder}') from None
            self._size = 0
            self._append({'study': self.study})
            _fsync_dir(self.path.parent)

    def _load(self) -> int:
        """Check the journal against this study and index its samples (read line by line); its size in bytes."""
        try:
            fh = open(self.path, 'r+b')  # noqa: SIM115 (closed below, after the lines are read)
        except OSError as exc:
            raise JournalError(f'--resume {self.path.parent}: no study journal there ({exc.strerror})') from None
        with fh:
            return self._index(fh)

    def _index(self, fh: Any) -> int:
        first = fh.readline()
        try:
            head = json.loads(first)['study'] if first.endswith(b'\n') else None
        except (json.JSONDecodeError, UnicodeDecodeError, KeyError, TypeError) as exc:
            raise JournalError(f'--resume {self.path.parent}: {JOURNAL} is not a study journal ({exc})') from None
        if not isinstance(head, dict):
            raise JournalError(f'--resume {self.path.parent}: {JOURNAL} has no study line')
        # in the study's own order: the option the user gave (until_min) before what it implies (steps)
        for key in [k for k in [*self.study, *(k for k in head if k not in self.study)]
                    if k not in ('command', 'samples_hash')]:
            if head.get(key) != self.study.get(key):
                raise JournalError(f'--resume {self.path.parent}: the study there has {key} '
                                   f'{json.dumps(head.get(key))}, this command {json.dumps(self.study.get(key))}')
        if head.get('samples_hash') != self.study.get('samples_hash'):
            raise JournalError(f'--resume {self.path.parent}: the samples drawn now differ from the study\'s '
                               '(the scenario file or the sampler changed since it began)')
        offset, n = len(first), 1
        while (line := fh.readline()).endswith(b'\n'):
            n += 1
            try:
                rec = json.loads(line)
            except (json.JSONDecodeError, UnicodeDecodeError) as exc:
                raise JournalError(f'--resume {self.path.parent}: {JOURNAL} is not a study journal ({exc})') from None
            if not (isinstance(rec, dict) and isinstance(rec.get('summary'), dict)
                    and {'case', 'index', 'scenario_hash'} <= rec.keys()):
                raise JournalError(f'--resume {self.path.parent}: {JOURNAL} line {n} is not a sample record '
                                   '({"index", "case", "scenario_hash", "summary"})')
            key = (rec['case'], rec['index'])
            if self.hashes.get(key) != rec['scenario_hash']:
                raise JournalError(f'--resume {self.path.parent}: sample {rec["index"]}{" of " + key[0] if key[0] else ""}'
                                   ' was run from another scenario text than the one drawn now')
            if key not in self.done or self.done.failed(key):  # a sample run again after it failed: its last run
                self.done[key] = (offset, len(line), 'error' in rec['summary'])
            offset += len(line)
        if line:  # the last line was cut by a kill mid-write: not a sample
            fh.truncate(offset)
            os.fsync(fh.fileno())
        return offset

    def _append(self, obj: Any) -> Where:
        data = _line(obj)
        written = os.write(self._fd, data)
        if written != len(data):
            raise OSError(f'{self.path}: short write ({written} of {len(data)} bytes)')
        os.fsync(self._fd)
        where = (self._size, len(data), False)
        self._size += len(data)
        return where

    def record(self, key: tuple[str, int], summary: dict[str, Any]) -> None:
        """Append a finished sample (fsynced before returning) and keep where it is (read back from JSON)."""
        case, index = key
        offset, length, _ = self._append({'index': index, 'case': case, 'scenario_hash': self.hashes[key],
                                          'summary': summary})
        self.done[key] = (offset, length, 'error' in summary)

    def kept(self) -> int:
        """The samples the journal on disk holds (after an interruption: what a resume will keep)."""
        return _samples_in(_whole_lines(self.path.read_bytes())[1:])

    def close(self) -> None:
        os.close(self._fd)


def _whole_lines(data: bytes) -> list[str]:
    """The journal's complete lines (one cut short by a kill mid-write left out)."""
    return data[:data.rfind(b'\n') + 1].decode().splitlines()


def _samples_in(lines: list[str]) -> int:
    """The distinct samples of a journal's sample lines."""
    return len({(rec['case'], rec['index']) for rec in map(json.loads, lines)})


def journaled_study(folder: Path) -> tuple[dict[str, Any], int] | None:
    """The study line of the journal in ``folder`` and the samples it holds, read only (nothing cut or
    truncated); None when there is no readable journal."""
    try:
        lines = _whole_lines((Path(folder) / JOURNAL).read_bytes())
        return json.loads(lines[0])['study'], _samples_in(lines[1:])
    except (OSError, IndexError, KeyError, TypeError, ValueError):
        return None


def _fsync_dir(folder: Path) -> None:
    fd = os.open(folder, os.O_RDONLY)
    try:
        os.fsync(fd)
    finally:
        os.close(fd)
