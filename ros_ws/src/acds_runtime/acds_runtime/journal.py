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
those of an uninterrupted one.
"""

from __future__ import annotations

import hashlib
import json
import os
from collections.abc import Iterable
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


class Journal:
    """The open journal of one study (module doc). ``done[(case, index)]`` holds the kept summaries."""

    def __init__(self, folder: Path, study: dict[str, Any], hashes: dict[tuple[str, int], str], *,
                 resume: bool) -> None:
        self.path = Path(folder) / JOURNAL
        self.study = json.loads(_line(study))
        self.hashes = hashes
        self.done: dict[tuple[str, int], dict[str, Any]] = {}
        if resume:
            self._load()
            self._fd = os.open(self.path, os.O_WRONLY | os.O_APPEND)
        else:
            Path(folder).mkdir(parents=True, exist_ok=True)
            try:
                self._fd = os.open(self.path, os.O_WRONLY | os.O_APPEND | os.O_CREAT | os.O_EXCL, 0o644)
            except FileExistsError:
                raise JournalError(f'{self.path} exists: resume that study with --resume {folder}') from None
            self._append({'study': self.study})
            _fsync_dir(self.path.parent)

    def _load(self) -> None:
        try:
            data = self.path.read_bytes()
        except OSError as exc:
            raise JournalError(f'--resume {self.path.parent}: no study journal there ({exc.strerror})') from None
        whole = data[:data.rfind(b'\n') + 1]
        if len(whole) < len(data):  # the last line was cut by a kill mid-write: not a sample
            with open(self.path, 'r+b') as fh:
                fh.truncate(len(whole))
                os.fsync(fh.fileno())
        lines = whole.decode().splitlines()
        try:
            head = json.loads(lines[0])['study'] if lines else None
            records = [json.loads(line) for line in lines[1:]]
        except (json.JSONDecodeError, KeyError, TypeError) as exc:
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
        for n, rec in enumerate(records, start=2):
            if not (isinstance(rec, dict) and isinstance(rec.get('summary'), dict)
                    and {'case', 'index', 'scenario_hash'} <= rec.keys()):
                raise JournalError(f'--resume {self.path.parent}: {JOURNAL} line {n} is not a sample record '
                                   '({"index", "case", "scenario_hash", "summary"})')
        for rec in records:
            key = (rec['case'], rec['index'])
            if self.hashes.get(key) != rec['scenario_hash']:
                raise JournalError(f'--resume {self.path.parent}: sample {rec["index"]}{" of " + key[0] if key[0] else ""}'
                                   ' was run from another scenario text than the one drawn now')
            if key not in self.done or 'error' in self.done[key]:  # a sample run again after it failed: its last run
                self.done[key] = rec['summary']

    def _append(self, obj: Any) -> None:
        data = _line(obj)
        written = os.write(self._fd, data)
        if written != len(data):
            raise OSError(f'{self.path}: short write ({written} of {len(data)} bytes)')
        os.fsync(self._fd)

    def record(self, key: tuple[str, int], summary: dict[str, Any]) -> None:
        """Append a finished sample (fsynced before returning) and keep it as read back from JSON."""
        case, index = key
        rec = {'index': index, 'case': case, 'scenario_hash': self.hashes[key], 'summary': summary}
        kept = json.loads(_line(summary))
        self._append(rec)
        self.done[key] = kept

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
